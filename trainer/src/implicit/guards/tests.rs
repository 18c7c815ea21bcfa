//! Tests of the sign guards: the grid check, hidden crossings and stray pieces.

use super::*;
use crate::implicit::tests::torus_points;
use crate::implicit::to_blob;
use crate::implicit::{ImplicitOptions, Trained, TreeSpec, train};
use crate::points::PointSet;
use crate::render::{CoreField, Region};
use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::implicit::MAX_GUARDS;
use neurosurf_core::scalar::ScalarKind;

/// `count` torus points and a one-leaf network trained on them.
fn torus(count: usize, seed: u64) -> (PointSet, Trained) {
    let points = torus_points(count, seed);
    let trained = one_leaf(&points);
    (points, trained)
}

/// A one-leaf network trained on `points` with the default options.
fn one_leaf(points: &PointSet) -> Trained {
    train(
        points,
        &TreeSpec::Leaf(0),
        &ImplicitOptions::default(),
        None,
        &|_| {},
    )
    .expect("training")
}

/// `network` through the core in `f32`, within `regions`.
fn core_field(network: &ImplicitNetwork, regions: Vec<Region>) -> CoreField {
    let blob = to_blob(network, None, ScalarKind::F32).expect("blob");
    CoreField::new(&blob, regions).expect("field")
}

/// The pieces of `network`'s mesh within `regions`, as the guards see them.
fn count_pieces(network: &ImplicitNetwork, regions: Vec<Region>) -> usize {
    let field = core_field(network, regions);
    let mesh = extract_mesh(&field, GUARD_RESOLUTION, &|_, _| {}).expect("mesh");
    component_labels(&mesh.mesh).1
}

/// A torus network with a blob grown on purpose (a guard of the wrong sign, outside the
/// torus above its hole): placing guards must remove the blob and leave the field near
/// the points untouched.
#[test]
fn guards_remove_a_blob_and_leave_the_surface_alone() {
    let (points, trained) = torus(400, 3);
    let blob = Guard {
        center: [0.0, 0.0, 0.8],
        inverse_radius: 1.0 / 0.3,
        amplitude: 5.0,
    };
    let broken = trained.network.clone().with_guards(vec![blob]);
    assert!(broken.eval(blob.center).0 > 0.0, "the blob is there");
    let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
    let domain = Aabb {
        lo: [-1.8, -1.8, -1.2],
        hi: [1.8, 1.8, 1.2],
    };
    let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
    let added = place_guards(&broken, &oracle, &domain, diagonal, 5.0, MAX_GUARDS);
    assert!(!added.is_empty());
    let one = place_guards(&broken, &oracle, &domain, diagonal, 5.0, 1);
    assert_eq!(one.len(), 1, "the limit holds");
    let fixed = broken
        .clone()
        .with_guards([vec![blob], added.clone()].concat());
    // The blob is gone: outside everywhere on a line through it.
    for k in 0..=20 {
        let p = [0.0, 0.0, 0.5 + 0.03 * f64::from(k)];
        assert!(fixed.eval(p).0 < 0.0, "{p:?}: {}", fixed.eval(p).0);
    }
    // No added guard reaches a control point or its off-surface points.
    for (p, n) in points.positions.iter().zip(&points.normals) {
        for offset in [-0.01, 0.0, 0.01] {
            let q = [0, 1, 2].map(|k| p[k] + offset * diagonal * n[k]);
            for g in &added {
                assert_eq!(g.eval(q).0, 0.0, "{g:?} reaches {q:?}");
            }
        }
    }
    // Guards keep to their side: every added guard's centre is outside, like the blob.
    assert!(added.iter().all(|g| g.amplitude < 0.0), "{added:?}");
}

/// A steep bump inside out between grid points (narrower than a cell, as one saturated
/// neuron can grow) is found off the grid and guarded.
#[test]
fn a_bump_between_grid_points_is_found() {
    let (points, trained) = torus(400, 3);
    let domain = Aabb {
        lo: [-1.8, -1.8, -1.2],
        hi: [1.8, 1.8, 1.2],
    };
    let grid = Grid::over(&domain).expect("grid");
    // The centre of a cell above the torus's hole: every grid point is half a cell
    // diagonal away.
    let centre = [0, 1, 2].map(|k| {
        let h = grid.spacing[k];
        let near = [0.0, 0.0, 0.9][k];
        domain.lo[k] + h * ((near - domain.lo[k]) / h).floor() + 0.5 * h
    });
    let reach = norm(grid.spacing);
    let phi = trained.network.eval(centre).0;
    assert!(phi < 0.0, "outside the torus");
    let bump = Guard {
        center: centre,
        inverse_radius: 1.0 / (0.6 * reach),
        amplitude: -1.5 * phi / (1.0_f64 - 0.09).powi(3),
    };
    let own = trained.network.guards().to_vec();
    let broken = trained
        .network
        .clone()
        .with_guards([own.clone(), vec![bump]].concat());
    assert!(broken.eval(centre).0 > 0.0, "the bump is there");
    for i in 0..grid.len() {
        assert!(
            broken.eval(grid.point(i)).0 <= 0.0 || trained.network.eval(grid.point(i)).0 > 0.0,
            "no grid point lands in the bump"
        );
    }
    let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
    let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
    let added = place_guards(&broken, &oracle, &domain, diagonal, 5.0, MAX_GUARDS);
    let fixed = broken
        .clone()
        .with_guards([own, vec![bump], added].concat());
    for k in -10..=10 {
        let t = 0.1 * f64::from(k) * reach;
        for axis in 0..3 {
            let mut p = centre;
            p[axis] += t;
            assert!(fixed.eval(p).0 < 0.0, "{p:?}: {}", fixed.eval(p).0);
        }
    }
}

/// Guards go into the blob and come back; the core adds them as the network does.
#[test]
fn guards_survive_the_blob_and_the_core_adds_them() {
    let (_, trained) = torus(200, 5);
    let guard = Guard {
        center: [0.25, 0.0, 0.75],
        inverse_radius: 4.0,
        amplitude: -2.0,
    };
    let network = trained.network.with_guards(vec![guard]);
    let bytes = to_blob(&network, None, ScalarKind::F32).expect("blob");
    let back =
        crate::implicit::from_blob(&bytes, std::path::Path::new("test.nsb")).expect("decode");
    assert_eq!(back.network.guards().len(), 1);
    let core = ImplicitModel::<f32>::from_blob(&bytes).expect("the core loads it");
    assert_eq!(core.guard_count(), 1);
    for p in [[0.25, 0.0, 0.75], [0.3, 0.1, 0.7], [1.0, 0.0, 0.0]] {
        let expected = network.eval(p).0;
        let got = f64::from(core.field(p.map(|v| v as f32)));
        assert!(
            (got - expected).abs() < 1e-4,
            "{p:?}: {got} against {expected}"
        );
    }
}

/// A small blob just off the surface, nearer than the grid check looks, is a piece of the
/// mesh no control point supports: it gets a guard, and the mesh is one piece again.
#[test]
fn a_stray_piece_near_the_surface_gets_a_guard() {
    let (points, trained) = torus(400, 3);
    let blob = Guard {
        center: [1.0, 0.0, 0.53],
        inverse_radius: 1.0 / 0.05,
        amplitude: 3.0,
    };
    let broken = trained.network.clone().with_guards(vec![blob]);
    let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
    let half = [1.8, 1.8, 1.2];
    let regions = || {
        let normalization = crate::implicit::Normalization {
            center: [0.0; 3],
            matrix: [0, 1, 2].map(|r| [0, 1, 2].map(|c| if r == c { 1.0 / half[r] } else { 0.0 })),
        };
        Region::new(normalization, 2.0, 1.0)
            .into_iter()
            .collect::<Vec<_>>()
    };
    let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
    let pieces = |network: &ImplicitNetwork| count_pieces(network, regions());
    let clean = pieces(&trained.network);
    assert!(pieces(&broken) > clean, "the blob makes pieces of its own");
    let field = core_field(&broken, regions());
    let (found, added) = guard_stray_pieces(&broken, &field, &oracle, diagonal, 0.1);
    assert_eq!(found, pieces(&broken));
    assert!(!added.is_empty());
    let fixed = broken.with_guards([vec![blob], added].concat());
    // The blob's piece is gone (and any other piece no point belongs to): one torus.
    assert_eq!(pieces(&fixed), 1);
}

/// A part cut off at a gap narrower than the sample spacing (a limb at a sparsely sampled
/// joint) is joined back by inside guards along the shortest gap.
#[test]
fn a_part_cut_off_at_a_narrow_gap_is_joined() {
    let axes = [1.5, 0.5, 0.5];
    let shape = crate::sample::Shape::Ellipsoid { axes };
    let mut points = crate::sample::sample_shape(&shape, 200, 4).expect("points");
    points.features = Some(vec![0; points.positions.len()]);
    let trained = one_leaf(&points);
    // A slab of outside bumps across the middle (x = 0), thinnest on the axis: two
    // halves, each with points of its own.
    let mut cut = trained.network.guards().to_vec();
    let step = 0.08;
    for i in -7..=7 {
        for j in -7..=7 {
            let (y, z) = (step * f64::from(i), step * f64::from(j));
            let r = y.hypot(z);
            if r <= 0.56 {
                cut.push(Guard {
                    center: [0.0, y, z],
                    inverse_radius: 1.0 / (0.06 + 0.05 * r / 0.56),
                    amplitude: -50.0,
                });
            }
        }
    }
    let broken = trained.network.clone().with_guards(cut.clone());
    assert!(broken.eval([0.0; 3]).0 < 0.0, "the slab cuts the middle");
    let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
    let (nearest, _) = oracle.nearest([0.0, 0.0, 0.5]);
    assert!(
        oracle.gap(nearest) > 0.2,
        "the slab is narrower than the spacing"
    );
    let regions = || Region::of_network(&trained.network, 2.0, crate::render::DEFAULT_INFLATE);
    let pieces = |network: &ImplicitNetwork| count_pieces(network, regions());
    assert_eq!(pieces(&broken), 2, "two halves");
    let diagonal = 2.0 * (axes[0] * axes[0] + axes[1] * axes[1] + axes[2] * axes[2]).sqrt();
    let field = core_field(&broken, regions());
    let (found, added) = guard_stray_pieces(&broken, &field, &oracle, diagonal, 0.1);
    assert_eq!(found, 2);
    assert!(!added.is_empty());
    assert!(added.iter().all(|g| g.amplitude > 0.0), "inside guards");
    let fixed = broken.with_guards([cut, added].concat());
    assert_eq!(pieces(&fixed), 1, "joined");
}

/// A cavity carved inside the tube (where 96 torus points cannot tell the side by the
/// winding number) is filled from inside: what a stray piece encloses takes its
/// surroundings' sign.
#[test]
fn a_cavity_no_point_explains_is_filled() {
    let (points, trained) = torus(400, 3);
    let carve = Guard {
        center: [1.0, 0.0, 0.0],
        inverse_radius: 1.0 / 0.15,
        amplitude: -20.0,
    };
    let broken = trained.network.clone().with_guards(vec![carve]);
    assert!(broken.eval(carve.center).0 < 0.0, "the cavity is there");
    // Normals turned inward: the winding number now calls the tube outside, and the side
    // must come from the piece itself.
    let inward: Vec<[f64; 3]> = points.normals.iter().map(|n| n.map(|v| -v)).collect();
    let oracle = Oracle::new(&points.positions, &inward).expect("oracle");
    assert!(oracle.winding(carve.center) < CLEAR_WINDING);
    let regions = || Region::of_network(&trained.network, 2.0, crate::render::DEFAULT_INFLATE);
    let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
    let pieces = |network: &ImplicitNetwork| count_pieces(network, regions());
    assert_eq!(
        pieces(&broken),
        2,
        "the cavity's wall is a piece of its own"
    );
    let field = core_field(&broken, regions());
    let (_, added) = guard_stray_pieces(&broken, &field, &oracle, diagonal, 0.1);
    assert!(!added.is_empty());
    assert!(added.iter().all(|g| g.amplitude > 0.0), "inside guards");
    let fixed = broken.with_guards([vec![carve], added].concat());
    assert_eq!(pieces(&fixed), 1);
    assert!(fixed.eval(carve.center).0 > 0.0, "filled");
}

/// Ruling out whole blocks gives the point-by-point distances exactly, with most blocks
/// cleared (a torus's grid is mostly far from it), at bounds from tight to loose and on a
/// grid whose counts are not multiples of the block.
#[test]
fn block_distances_are_the_pointwise_ones() {
    let points = torus_points(300, 5);
    let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
    let domain = Aabb {
        lo: [-1.7, -1.6, -0.75],
        hi: [1.65, 1.7, 0.7],
    };
    let grid = Grid::over(&domain).expect("grid");
    assert!(grid.counts.iter().any(|c| c % 4 != 0), "{:?}", grid.counts);
    for (bound, far_share) in [(0.02, 0.3), (0.4, 0.05)] {
        let blocks = grid.disk_distances_below(&oracle, bound);
        let far = blocks.iter().filter(|d| d.is_nan()).count();
        // Every 7th point: the kd-tree queries of all 600 000 are slow in a debug build.
        for (i, &d) in blocks.iter().enumerate().step_by(7) {
            let pointwise = oracle.disk_distance_below(grid.point(i), bound);
            assert_eq!(d.to_bits(), pointwise.unwrap_or(f64::NAN).to_bits(), "{i}");
        }
        assert!(
            far as f64 > far_share * blocks.len() as f64,
            "{far} of {}",
            blocks.len()
        );
    }
}

/// The nearest member from a tree over a set's shell and the query's cell corners is the
/// nearest member from a tree over the whole set, bit for bit: for sets from a solid ball
/// (mostly interior) to scattered points (all shell), at grid points and between them.
#[test]
fn a_grid_set_finds_the_nearest_member_from_its_shell() {
    use rand::{Rng, SeedableRng};
    let domain = Aabb {
        lo: [-1.0, -0.8, -0.3],
        hi: [1.1, 0.9, 0.35],
    };
    let grid = Grid::over(&domain).expect("grid");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let scattered: Vec<bool> = (0..grid.len())
        .map(|_| rng.random::<f64>() < 0.01)
        .collect();
    let sets: [&(dyn Fn(usize) -> bool + Sync); 3] = [
        &|i| norm(grid.point(i)) > 0.6,
        &|i| norm(grid.point(i)) < 0.5,
        &|i| scattered[i],
    ];
    for keep in sets {
        let set = GridSet::new(&grid, keep);
        let all: Vec<[f64; 3]> = (0..grid.len())
            .filter(|&i| keep(i))
            .map(|i| grid.point(i))
            .collect();
        let tree = ImmutableKdTree::<f64, 3>::new_from_slice(&all).expect("tree");
        for n in 0..2000 {
            let q = if n % 2 == 0 {
                grid.point(rng.random_range(0..grid.len()))
            } else {
                [0, 1, 2].map(|k| rng.random_range(domain.lo[k]..domain.hi[k]))
            };
            let expected = tree
                .query(&q)
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute()
                .distance
                .sqrt();
            assert_eq!(set.nearest(&grid, q).to_bits(), expected.to_bits(), "{q:?}");
        }
    }
}

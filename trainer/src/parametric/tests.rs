use super::*;

fn lle_quality(surface: SampleSurface, count: usize, noise: f64) -> (f64, f64, f64, Embedding) {
    let sample = sample_surface(surface, count, noise, 7).unwrap();
    let embedding = embed_points(&sample.points, &LleOptions::default()).unwrap();
    let (aligned, r2) = align_affine(&sample.parameters, &embedding.parameters).unwrap();
    let keep = neighborhood_preservation(&sample.parameters, &aligned, 10).unwrap();
    let corr = distance_correlation(&sample.parameters, &aligned).unwrap();
    (r2, keep, corr, embedding)
}

/// LLE's (u, v) must be an affine image of the true parameters up to this unexplained
/// variance, keep this share of 10-neighbourhoods and correlate distances this well.
const MIN_R2: f64 = 0.97;
const MIN_NEIGHBORHOODS: f64 = 0.85;
const MIN_DISTANCE_CORRELATION: f64 = 0.97;

#[test]
fn lle_recovers_an_open_cylinder() {
    // Fig. 5's 1400 and 700 points (measured: R² 0.992, 93 % neighbourhoods, r 0.989 at 1400).
    for count in [1400, 700] {
        let (r2, keep, corr, e) = lle_quality(SampleSurface::OpenCylinder, count, 0.0);
        eprintln!(
            "cylinder {count}: R² {r2:.4} keep {keep:.3} corr {corr:.4} {:?} it {}",
            e.folds, e.iterations
        );
        assert!(r2 > MIN_R2 && keep > MIN_NEIGHBORHOODS && corr > MIN_DISTANCE_CORRELATION);
        assert!(e.folds.is_flat());
    }
}

#[test]
fn lle_recovers_a_swiss_roll_patch() {
    // Measured: R² 0.982, 90 % neighbourhoods, r 0.981.
    let (r2, keep, corr, e) = lle_quality(SampleSurface::SwissRoll, 2000, 0.0);
    eprintln!(
        "swiss roll: R² {r2:.4} keep {keep:.3} corr {corr:.4} {:?} it {}",
        e.folds, e.iterations
    );
    assert!(r2 > MIN_R2 && keep > MIN_NEIGHBORHOODS && corr > MIN_DISTANCE_CORRELATION);
}

#[test]
fn lle_with_noise_still_recovers_the_cylinder() {
    let (r2, keep, _, _) = lle_quality(SampleSurface::OpenCylinder, 1400, 0.005);
    eprintln!("noisy cylinder: R² {r2:.4} keep {keep:.3}");
    assert!(r2 > 0.95 && keep > 0.6);
}

/// 5 000 samples of a saddle with noise of 1 % of the diagonal fold at k = 10 and 12 (the
/// noise fills the small neighbourhoods: 7 % and 3 % of neighbour pairs flip); by default the
/// embedding goes on to wider ones and flattens, while a k the user chose is kept and the
/// refusal names --neighbors.
#[test]
fn a_dense_noisy_saddle_embeds_by_default() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let sigma = 0.01 * 8.0_f64.sqrt();
    let points: Vec<[f64; 3]> = (0..5_000)
        .map(|_| {
            let (x, y) = (
                2.0 * rng.random::<f64>() - 1.0,
                2.0 * rng.random::<f64>() - 1.0,
            );
            // A Gaussian from Box–Muller.
            let (a, b) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
            let noise = sigma * (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos();
            [x, y, 0.5 * (x * x - y * y) + noise]
        })
        .collect();
    let chosen = LleOptions {
        more_neighbors: false,
        ..LleOptions::default()
    };
    let refused = embed_points(&points, &chosen).unwrap_err().to_string();
    assert!(refused.contains("--neighbors"), "{refused}");
    let e = embed_points(&points, &LleOptions::default()).unwrap();
    println!("noisy saddle: k = {}, {:?}", e.neighbors, e.folds);
    assert!(e.neighbors > 10 && e.folds.is_flat());
}

#[test]
fn a_closed_sphere_is_rejected_as_folded() {
    let sample = sample_surface(SampleSurface::Sphere, 1000, 0.0, 7).unwrap();
    let options = LleOptions {
        check_folds: false,
        ..LleOptions::default()
    };
    let e = embed_points(&sample.points, &options).unwrap();
    eprintln!("sphere {:?}", e.folds);
    assert!(!e.folds.is_flat());
    let err = embed_points(&sample.points, &LleOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("cannot flatten"), "{err}");
}

#[test]
fn bad_point_sets_are_named_errors() {
    let options = LleOptions::default();
    let few: Vec<[f64; 3]> = (0..8).map(|i| [i as f64, (i * i) as f64, 0.0]).collect();
    let e = embed_points(&few, &options).unwrap_err().to_string();
    assert!(e.contains("too few"), "{e}");
    let mut dup = sample_surface(SampleSurface::Plane, 100, 0.0, 1)
        .unwrap()
        .points;
    dup[50] = dup[7];
    let e = embed_points(&dup, &options).unwrap_err().to_string();
    assert!(
        e.contains("coincide") && e.contains("7") && e.contains("50"),
        "{e}"
    );
    let line: Vec<[f64; 3]> = (0..100)
        .map(|i| [i as f64, 2.0 * i as f64, -(i as f64)])
        .collect();
    let e = embed_points(&line, &options).unwrap_err().to_string();
    assert!(e.contains("line"), "{e}");
    let mut nan = sample_surface(SampleSurface::Plane, 100, 0.0, 1)
        .unwrap()
        .points;
    nan[3][1] = f64::NAN;
    assert!(
        embed_points(&nan, &options)
            .unwrap_err()
            .to_string()
            .contains("non-finite")
    );
    let e = embed_points(
        &nan[..2],
        &LleOptions {
            neighbors: 2,
            ..options
        },
    )
    .unwrap_err();
    assert!(
        e.to_string().contains("too few") || e.to_string().contains("k = 2"),
        "{e}"
    );
}

#[test]
fn network_partials_match_central_differences() {
    let mut net = SurfaceNetwork::zeros(
        &[4, 3],
        Activation::TanSig,
        [0.1, -0.2],
        [1.5, 0.7],
        [1.0, 2.0, 3.0],
        2.0,
    )
    .unwrap();
    for act in Activation::ALL {
        net.activation = act;
        randomize(&mut net, 5);
        let (u, v, h) = (0.3, -0.4, 1e-6);
        let e = net.evaluate(u, v);
        let fu = net.position(u + h, v);
        let bu = net.position(u - h, v);
        let fv = net.position(u, v + h);
        let bv = net.position(u, v - h);
        for a in 0..3 {
            assert!((e.position[a] - net.position(u, v)[a]).abs() < 1e-12);
            assert!(
                (e.du[a] - (fu[a] - bu[a]) / (2.0 * h)).abs() < 1e-6,
                "{act:?} du"
            );
            assert!(
                (e.dv[a] - (fv[a] - bv[a]) / (2.0 * h)).abs() < 1e-6,
                "{act:?} dv"
            );
        }
    }
}

fn topology_of(surface: SampleSurface) -> TopologySearch {
    let sample = sample_surface(surface, 400, 0.0, 11).unwrap();
    let fit = fit_network(
        &sample.points,
        &sample.parameters,
        &TopologyOptions::default(),
    )
    .unwrap();
    for c in &fit.search.candidates {
        eprintln!(
            "{surface:?} {}x{} p{} tr {:.2e} va {:.2e} te {:.2e} it {}",
            c.layers,
            c.neurons,
            c.parameters,
            c.training_mse,
            c.validation_mse,
            c.test_mse,
            c.iterations
        );
    }
    eprintln!(
        "{surface:?} chosen {:?} rel rms {}",
        fit.search.best(),
        fit.relative_rms_error
    );
    fit.search
}

#[test]
fn topology_search_sizes_the_network_to_the_surface() {
    // Measured: the plane gets 1 × 2 (15 weights), the wavy surface 1 × 12 (75).
    let plane = topology_of(SampleSurface::Plane);
    let wavy = topology_of(SampleSurface::Wavy);
    assert!(
        plane.best().layers == 1 && plane.best().neurons <= 3,
        "{:?}",
        plane.best()
    );
    assert!(
        wavy.best().parameters >= 2 * plane.best().parameters,
        "{:?}",
        wavy.best()
    );
    assert!(plane.best().test_mse < 1e-5 && wavy.best().test_mse < 1e-4);
}

#[test]
fn the_search_gives_the_same_network_on_any_thread_count() {
    // 1 500 points: the candidates train on a 1 000-point subsample, then the chosen network
    // is refined on all training points, so both parallel paths run.
    let sample = sample_surface(SampleSurface::Wavy, 1500, 0.002, 5).unwrap();
    let fit_on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                fit_network(
                    &sample.points,
                    &sample.parameters,
                    &TopologyOptions {
                        max_neurons: 6,
                        ..TopologyOptions::default()
                    },
                )
                .unwrap()
            })
    };
    let (one, two) = (fit_on(1), fit_on(2));
    assert!(one.search.candidates.len() >= 4);
    assert_eq!(one.search, two.search);
    assert_eq!(one.network, two.network);
    assert_eq!(one.rms_error.to_bits(), two.rms_error.to_bits());
}

#[test]
fn reconstructs_a_wavy_patch_with_both_tessellations() {
    let sample = sample_surface(SampleSurface::Wavy, 500, 0.0, 3).unwrap();
    let mut options = ReconstructOptions::default();
    let coons = reconstruct(&sample.points, &options).unwrap();
    options.tessellation = Tessellation::Delaunay { vertices: 600 };
    let tri = reconstruct(&sample.points, &options).unwrap();
    let (cm, tm) = (&coons.surface.mesh, &tri.surface.mesh);
    eprintln!(
        "coons {} v, rel rms {}, delaunay {} v {} t",
        cm.vertex_count(),
        coons.fit.relative_rms_error,
        tm.vertex_count(),
        tm.triangle_count()
    );
    assert_eq!((cm.vertex_count(), cm.triangle_count()), (900, 2 * 29 * 29));
    // Both meshes are one open disk: a single boundary loop, every inner edge used twice.
    for mesh in [cm, tm] {
        let report = edge_report(mesh);
        assert_eq!((report.non_manifold, report.misoriented), (0, 0));
        assert_eq!(boundary_loops(&mesh.triangles).unwrap().len(), 1);
        // Every vertex lies on the true surface within 2 % of the 2.06 diagonal.
        for p in &mesh.positions {
            let z = SampleSurface::Wavy.height(p[0], p[1]).unwrap();
            assert!((p[2] - z).abs() < 0.04, "{p:?} vs {z}");
        }
    }
    assert!(tm.vertex_count() > 450 && tm.vertex_count() < 800);
}

/// The pillow: z = ±0.3·(1 − x²)(1 − y²) over [−1, 1]², two patches meeting along the square.
fn pillow_patch(sign: f64, resolution: usize, seed: u64) -> io::Mesh {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut points: Vec<[f64; 3]> = Vec::new();
    while points.len() < 300 {
        let (x, y) = (
            2.0 * rng.random::<f64>() - 1.0,
            2.0 * rng.random::<f64>() - 1.0,
        );
        points.push([x, y, sign * 0.3 * (1.0 - x * x) * (1.0 - y * y)]);
    }
    // Points on the rim, so both patches reach the seam.
    for k in 0..20 {
        let t = -1.0 + 2.0 * k as f64 / 20.0;
        for p in [[t, -1.0], [1.0, t], [-t, 1.0], [-1.0, -t]] {
            points.push([p[0], p[1], 0.0]);
        }
    }
    let options = ReconstructOptions {
        tessellation: Tessellation::Coons { resolution },
        topology: TopologyOptions {
            max_layers: 1,
            restarts: 1,
            ..TopologyOptions::default()
        },
        ..ReconstructOptions::default()
    };
    reconstruct(&points, &options).unwrap().surface.mesh
}

use crate::io;

#[test]
fn stitched_pillow_is_watertight_with_no_seam_gap() {
    // Different resolutions: 76 and 56 boundary vertices; each loop gets a vertex wherever
    // the other has one at a different arc-length fraction.
    let mut patches = vec![pillow_patch(1.0, 20, 1), pillow_patch(-1.0, 15, 2)];
    let seam = boundary_seam(&mut patches, 0, 1).unwrap();
    assert!(seam.vertices_a.len() >= 76 && seam.vertices_a.len() == seam.vertices_b.len());
    let bad = Seam {
        patch_a: 0,
        vertices_a: vec![0, 1],
        patch_b: 1,
        vertices_b: vec![0],
        whole_loop: false,
    };
    assert!(
        stitch(&patches, &[bad])
            .unwrap_err()
            .to_string()
            .contains("add vertices")
    );
    let bad = Seam {
        patch_a: 0,
        vertices_a: vec![0],
        patch_b: 5,
        vertices_b: vec![0],
        whole_loop: false,
    };
    assert!(stitch(&patches, &[bad]).is_err());
    let stitched = stitch(&patches, &[seam]).unwrap();
    let report = edge_report(&stitched.mesh);
    eprintln!(
        "pillow: {report:?} gap before {:.4} solved {:.2e} after {} moved {:.4} flipped {} volume {:.4}",
        stitched.gap_before,
        stitched.gap_solved,
        stitched.gap_after,
        stitched.max_displacement,
        stitched.flipped_triangles,
        signed_volume(&stitched.mesh)
    );
    assert!(report.is_watertight(), "{report:?}");
    assert_eq!(stitched.gap_after, 0.0);
    assert!(stitched.gap_solved < stitched.gap_before);
    // The true pillow's volume is 2 · 0.3 · (4/3)² = 1.0667 (measured 1.037; the seam gap of
    // 0.043 closed to 2.6·10⁻⁴ by the solve, no vertex moved more than 0.028).
    let volume = signed_volume(&stitched.mesh);
    assert!((volume - 1.0667).abs() < 0.06, "{volume}");
    assert!(stitched.max_displacement < 2.0 * stitched.gap_before);
}

#[test]
fn fills_a_hole_in_the_fandisk_watertight_and_on_the_surface() {
    let Ok(path) = io::data_file("fandisk.obj") else {
        eprintln!("fandisk.obj not found: skipped");
        return;
    };
    let original = io::read_mesh(&path).unwrap();
    assert!(edge_report(&original).is_watertight());
    let (lo, hi) =
        crate::parametric::fit::bounds(original.positions.iter().map(|p| p.as_slice()), 3);
    let diagonal = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt();
    // A machined part: creases run through the regions of all seeds but 100, whose new
    // vertices therefore go onto the smooth parts' own surfaces extended into the hole.
    // Measured over seeds 100, 500, …, 6000: 8 of 11 holes filled by LLE, all watertight,
    // worst new vertex 0.011 from the removed triangles (0.14 % of the 7.62 diagonal; 0.0196
    // with the network's surface alone); 1500, 2000 and 4000 lie across sharp creases whose
    // rings fold in LLE and are filled through Tutte's embedding (the last seeds below).
    for seed in [100u32, 1000, 3500, 6000, 1500, 2000, 4000] {
        let (holed, removed) = punch_hole(&original, seed, 3).unwrap();
        let hole = boundary_loops(&holed.triangles).unwrap();
        assert_eq!(hole.len(), 1);
        let filled = fill_hole(&holed, &hole[0], &HoleOptions::default()).unwrap();
        let report = edge_report(&filled.mesh);
        let worst = fill_deviation(&original, &hole[0], &removed, &filled).either;
        eprintln!(
            "seed {seed}: {} new vertices, {} new triangles, region {}, {report:?}, worst {worst:.4}",
            filled.new_vertices.len(),
            filled.new_triangles,
            filled.region_vertices
        );
        assert!(report.is_watertight(), "{report:?}");
        assert!(!filled.new_vertices.is_empty());
        let crease = [1500, 2000, 4000].contains(&seed);
        assert_eq!(filled.tutte, crease, "seed {seed}");
        // Fairing would round a crease off: the parts' surfaces meet where one runs.
        assert!(!(crease && filled.faired), "seed {seed}");
        assert_eq!(filled.followed_creases, seed != 100, "seed {seed}");
        let bound = if crease { 0.01 } else { 0.005 };
        assert!(worst < bound * diagonal, "seed {seed}: {worst}");
    }
    let (holed, _) = punch_hole(&original, 1500, 3).unwrap();
    let e = fill_hole(&holed, &[0, 1, 2], &HoleOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a boundary loop"), "{e}");
}

/// Holes punched 5 rings deep in spot whose regions 4 rings round them do not lie flat: at
/// vertex 2354 LLE's plane crosses the hole's outline, so Tutte's embedding takes over; at
/// 1939 and 1524 the region reaches round a thin part (not an annulus) and folds, so fewer
/// rings are tried. Measured: within 6.7 %, 5.5 % and 4.5 % of the hole's diameter of the
/// removed surface, with 4 rings (Tutte), 2 rings (Tutte) and 3 rings (LLE).
#[test]
fn holes_whose_regions_do_not_lie_flat_are_filled_with_tutte_or_fewer_rings() {
    let path = io::data_file("spot.obj").unwrap();
    let original = io::read_mesh(&path).unwrap();
    for (seed, tutte, fewer) in [
        (2354u32, true, false),
        (1939, true, true),
        (1524, false, true),
    ] {
        let (holed, removed) = punch_hole(&original, seed, 5).unwrap();
        let hole = boundary_loops(&holed.triangles).unwrap().remove(0);
        let filled = fill_hole(&holed, &hole, &HoleOptions::default()).unwrap();
        let deviation = fill_deviation(&original, &hole, &removed, &filled);
        eprintln!(
            "seed {seed}: rings {}, tutte {}, {:.3} of the diameter",
            filled.region_rings,
            filled.tutte,
            deviation.either / deviation.diameter
        );
        assert!(edge_report(&filled.mesh).is_watertight(), "seed {seed}");
        assert_eq!(filled.tutte, tutte, "seed {seed}");
        assert_eq!(
            filled.region_rings < HoleOptions::default().rings,
            fewer,
            "seed {seed}"
        );
        assert!(
            deviation.either < 0.08 * deviation.diameter,
            "seed {seed}: {deviation:?}"
        );
    }
}

/// Holes punched in spot (vertices other than those the fairing was measured on): the faired
/// fill bulges out less than the network's and lies closer to the removed surface.
#[test]
fn faired_hole_fills_bulge_less_than_the_network() {
    let path = io::data_file("spot.obj").unwrap();
    let original = io::read_mesh(&path).unwrap();
    let n = original.positions.len() as u64;
    let (mut network, mut faired) = (Vec::new(), Vec::new());
    for k in 40..48u64 {
        let seed = (k * 2_654_435_761 % n) as u32;
        let (holed, removed) = punch_hole(&original, seed, 3).unwrap();
        let hole = boundary_loops(&holed.triangles).unwrap().remove(0);
        for (fairing, into) in [(false, &mut network), (true, &mut faired)] {
            let options = HoleOptions {
                fairing,
                ..HoleOptions::default()
            };
            let filled = fill_hole(&holed, &hole, &options).unwrap();
            assert!(edge_report(&filled.mesh).is_watertight());
            let d = fill_deviation(&original, &hole, &removed, &filled);
            into.push((d.outwards / d.diameter, d.either / d.diameter));
        }
    }
    let over = |d: &[(f64, f64)]| d.iter().filter(|d| d.0 > 0.02).count();
    let mean = |d: &[(f64, f64)]| d.iter().map(|d| d.1).sum::<f64>() / d.len() as f64;
    eprintln!("network {network:.3?}\nfaired {faired:.3?}");
    assert!(
        over(&faired) < over(&network),
        "{} {}",
        over(&faired),
        over(&network)
    );
    assert!(
        mean(&faired) < mean(&network),
        "{} {}",
        mean(&faired),
        mean(&network)
    );
}

#[test]
fn comparison_network_is_smoother_than_interpolation() {
    let rows = compare_methods(SampleSurface::Wavy, 400, 0.01, 5).unwrap();
    for r in &rows {
        eprintln!(
            "{:>9} mse {:.2e} rms-truth {:.4} dihedral var {:.2e} v {} {:.3}s",
            r.method, r.mse_points, r.rms_truth, r.dihedral_variance, r.vertices, r.seconds
        );
    }
    let get = |m: &str| rows.iter().find(|r| r.method == m).unwrap();
    let (net, high, tri) = (get("network"), get("rbf-high"), get("delaunay"));
    assert_eq!(tri.mse_points, 0.0);
    assert!(
        net.dihedral_variance < tri.dihedral_variance
            && net.dihedral_variance < high.dihedral_variance
    );
    assert!(net.rms_truth < 0.02);
}

#[test]
fn bunny_back_patch_flattens() {
    let Ok(path) = io::data_file("stanford-bunny.obj") else {
        eprintln!("stanford-bunny.obj not found: skipped");
        return;
    };
    let mesh = io::read_mesh(&path).unwrap();
    let (points, source) = back_patch_points(&mesh, BACK_SEED, 2_000).unwrap();
    assert_eq!((points.len(), source), (2_000, "vertices"));
    let e = embed_points(&points, &LleOptions::default()).unwrap();
    assert!(e.folds.is_flat(), "{:?}", e.folds);
    // The Table 2 row of the whole scan's count: the subdivided patch flattens too.
    let (dense, source) = back_patch_points(&mesh, BACK_SEED, 35_947).unwrap();
    assert_eq!((dense.len(), source), (35_947, "subdivided"));
    let e = embed_points(&dense, &LleOptions::default()).unwrap();
    assert!(e.folds.is_flat(), "{:?}", e.folds);
}

#[test]
fn blobs_round_trip_and_the_core_evaluates_what_the_trainer_does() {
    use neurosurf_core::parametric::SurfaceNetworkModel;
    use neurosurf_core::scalar::{Q16, ScalarKind};
    let mut net = SurfaceNetwork::zeros(
        &[5, 4],
        Activation::TanSig,
        [0.1, -0.2],
        [1.5, 0.7],
        [1.0, 2.0, 3.0],
        2.0,
    )
    .unwrap();
    let path = std::path::Path::new("test.nsb");
    for act in Activation::ALL {
        net.activation = act;
        randomize(&mut net, 9);
        let summary = NetworkSummary {
            points: 10,
            candidates: 1,
            rms_error: 0.5,
            relative_rms_error: 0.1,
            seconds: 0.0,
            region: vec![[0.0, 0.0], [1.0, 0.0], [0.5, 1.0]],
        };
        for (scalar, storage) in [(ScalarKind::F32, 1e-5), (ScalarKind::Q16_16, 5e-3)] {
            let bytes = network_to_blob(&net, Some(&summary), scalar).unwrap();
            let decoded = network_from_blob(&bytes, path).unwrap();
            assert_eq!(decoded.summary.as_ref(), Some(&summary));
            assert_eq!(
                (decoded.stored_as, decoded.network.activation),
                (scalar, act)
            );
            let float = SurfaceNetworkModel::<f32>::from_blob(&bytes).unwrap();
            let fixed = SurfaceNetworkModel::<Q16>::from_blob(&bytes).unwrap();
            for i in 0..25 {
                let (u, v) = (-1.0 + 0.09 * i as f64, 0.7 - 0.05 * i as f64);
                let (u, v) = (f64::from(u as f32), f64::from(v as f32));
                let trained = net.evaluate(u, v);
                let read = decoded.network.evaluate(u, v);
                let f = float.eval([u as f32, v as f32]);
                let q = fixed.eval([Q16::from_num(u), Q16::from_num(v)]);
                for a in 0..3 {
                    // The blob rounds each word once: the read-back network is the trained
                    // one within that rounding.
                    assert!((read.position[a] - trained.position[a]).abs() < storage);
                    assert!((f64::from(f.position[a]) - read.position[a]).abs() < 1e-5);
                    assert!((f64::from(f.du[a]) - read.du[a]).abs() < 1e-4);
                    let dq = (q.position[a].to_num::<f64>() - read.position[a]).abs();
                    assert!(dq < 2e-3, "{act:?} {scalar:?} {dq:e}");
                }
            }
        }
    }
    let wide = SurfaceNetwork::zeros(&[40], Activation::TanSig, [0.0; 2], [1.0; 2], [0.0; 3], 1.0)
        .unwrap();
    let e = network_to_blob(&wide, None, ScalarKind::F32)
        .unwrap_err()
        .to_string();
    assert!(e.contains("at most 32"), "{e}");
    // The blob's frame keeps c_p and s_p of order one: large, small and far outputs store as
    // Q16.16 and evaluate within its rounding, relative to their size.
    for (scale, centre) in [
        (5000.0, [0.0; 3]),
        (1e-3, [0.0; 3]),
        (1.0, [2000.0, -300.0, 5.0]),
    ] {
        let mut moved = net.clone();
        moved.output_scale = scale;
        moved.output_center = centre;
        let bytes = network_to_blob(&moved, None, ScalarKind::Q16_16).unwrap();
        let read = network_from_blob(&bytes, path).unwrap().network;
        let fixed = SurfaceNetworkModel::<Q16>::from_blob(&bytes).unwrap();
        for i in 0..25 {
            let (u, v) = (-1.0 + 0.09 * i as f64, 0.7 - 0.05 * i as f64);
            let (u, v) = (f64::from(u as f32), f64::from(v as f32));
            let want = moved.evaluate(u, v).position;
            let got = read.evaluate(u, v).position;
            let q = fixed.eval([Q16::from_num(u), Q16::from_num(v)]).position;
            for a in 0..3 {
                assert!((got[a] - want[a]).abs() <= 5e-3 * scale + 1e-4, "×{scale}");
                let dq = (q[a].to_num::<f64>() - want[a]).abs();
                assert!(dq <= 5e-3 * scale + 1e-4, "×{scale} {centre:?}: {dq:e}");
            }
        }
    }
    // Beyond what Q16.16 represents, the refusal names the coordinate and the way out.
    let mut far = net.clone();
    far.output_center = [40_000.0, 0.0, 0.0];
    let e = network_to_blob(&far, None, ScalarKind::Q16_16)
        .unwrap_err()
        .to_string();
    for expected in ["centre x", "32767", "f32"] {
        assert!(e.contains(expected), "{e}");
    }
    assert!(network_to_blob(&far, None, ScalarKind::F32).is_ok());
}

/// The saddle z = xy over [−1, 1]², ten times sparser for x > 0 when `uneven`.
fn saddle_points(count: usize, uneven: bool, seed: u64) -> Vec<[f64; 3]> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut points = Vec::new();
    while points.len() < count {
        let (x, y): (f64, f64) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        if !uneven || x < 0.0 || rng.random_range(0.0..1.0) < 0.1 {
            points.push([x, y, x * y]);
        }
    }
    points
}

#[test]
fn a_patch_whose_density_changes_is_unrolled_and_covered() {
    // LLE squeezes the sparse half: up to 8 % of the true surface within the samples' reach
    // stays more than 1 % of the diagonal away from either tessellation.
    for seed in 1..=8 {
        let points = saddle_points(2_000, true, seed);
        for tessellation in [
            Tessellation::Coons { resolution: 30 },
            Tessellation::Delaunay { vertices: 900 },
        ] {
            let options = ReconstructOptions {
                tessellation,
                ..ReconstructOptions::default()
            };
            let result = reconstruct(&points, &options).unwrap();
            assert_eq!(
                result.embedding.parameterization,
                Parameterization::Unrolled
            );
            assert!(
                result.embedding.sparse_area > 0.3,
                "{}",
                result.embedding.sparse_area
            );
            assert_eq!(folded_triangles(&result.grid), 0, "seed {seed}");
            let model = crate::quality::Truth::from_mesh(&result.surface.mesh).unwrap();
            // The truth within the samples' convex hull (their Delaunay triangles in (x, y),
            // the saddle's own parameters).
            let plane: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
            let hull = delaunay(&plane).unwrap();
            let inside = |q: [f64; 2]| {
                hull.iter().any(|t| {
                    let c = t.map(|v| plane[v as usize]);
                    (0..3).all(|e| {
                        let (a, b) = (c[e], c[(e + 1) % 3]);
                        (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]) >= 0.0
                    })
                })
            };
            let side = 60;
            let reach: Vec<[f64; 2]> = (0..side * side)
                .map(|k| {
                    let at = |i: usize| -1.0 + 2.0 * i as f64 / (side - 1) as f64;
                    [at(k % side), at(k / side)]
                })
                .filter(|&q| inside(q))
                .collect();
            let far = reach
                .iter()
                .filter(|q| model.distance([q[0], q[1], q[0] * q[1]]) > 0.035)
                .count();
            // Measured: at most 1.3 % on seven seeds, 3.4 % on seed 4, where the unrolling
            // tears the sparse half (LLE: 8.0 % on seed 4, its mesh leaving the saddle).
            assert!(
                far * 25 <= reach.len(),
                "seed {seed}: {far} of {}",
                reach.len()
            );
            // The mesh stays on the saddle within 2 % of its 3.46 diagonal.
            for p in &result.surface.mesh.positions {
                assert!((p[2] - p[0] * p[1]).abs() < 0.07, "seed {seed}: {p:?}");
            }
        }
    }
}

#[test]
fn an_evenly_sampled_patch_keeps_the_lle_embedding() {
    let points = saddle_points(2_000, false, 13);
    let embedding = embed_points(&points, &LleOptions::default()).unwrap();
    assert_eq!(embedding.parameterization, Parameterization::Lle);
    assert!(embedding.sparse_area < 0.02, "{}", embedding.sparse_area);
}

/// The first `count` vertices of `mesh` in breadth-first order from `start` (rings of edge
/// hops): a patch around it.
fn hop_patch(mesh: &io::Mesh, start: usize, count: usize) -> Vec<[f64; 3]> {
    let rings = crate::geometry::mesh_graph::one_rings(mesh.positions.len(), &mesh.triangles);
    let mut taken = vec![start];
    let mut seen = vec![false; mesh.positions.len()];
    seen[start] = true;
    let mut next = 0;
    while taken.len() < count && next < taken.len() {
        for &w in &rings[taken[next]] {
            if !seen[w] && taken.len() < count {
                seen[w] = true;
                taken.push(w);
            }
        }
        next += 1;
    }
    taken.iter().map(|&v| mesh.positions[v]).collect()
}

/// A tenth of fandisk around vertex 5432 reaches round a crease: LLE folds it at every k
/// tried, and the embedding falls back to unrolling it, which does not fold. Measured over
/// 134 such patches (every 97th vertex, a tenth and a fifth of the mesh): LLE refused 40,
/// the fallback 4; on spot, 31 and 17 of 62.
#[test]
fn a_patch_that_lle_folds_at_every_k_is_unrolled() {
    let mesh = io::read_mesh(&io::data_file("fandisk.obj").unwrap()).unwrap();
    let points = hop_patch(&mesh, 5432, mesh.positions.len() / 10);
    let lle_only = LleOptions {
        unroll_uneven: false,
        ..LleOptions::default()
    };
    let refused = embed_points(&points, &lle_only).unwrap_err().to_string();
    assert!(refused.contains("--neighbors"), "{refused}");
    let e = embed_points(&points, &LleOptions::default()).unwrap();
    println!("fandisk patch: k = {}, {:?}", e.neighbors, e.folds);
    assert_eq!(e.parameterization, Parameterization::Unrolled);
    assert!(e.folds.is_flat());
}

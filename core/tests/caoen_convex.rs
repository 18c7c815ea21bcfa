//! The implicit form of convex Cao En surfaces (paper §9) and its ray intersections (§10.1):
//! inside/outside against the exact test of the polyhedron it rounds, and both intersections
//! against brute-force sampling along the ray.

mod caoen_support;

use caoen_support::{LSB, RefNet, Rng, dot, f32s, q16s, to_grid, unit_vector};
use neurosurf_core::caoen::{CaoEnModel, MAX_RAY_EVALUATIONS, Ray};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

/// A random convex polyhedron containing the origin: `faces` planes with foot points
/// tᵢ = dᵢ·uᵢ (unit normal uᵢ, distance dᵢ ∈ [0.8, 1.2]).
fn polyhedron(rng: &mut Rng, faces: usize) -> Vec<[f64; 3]> {
    (0..faces)
        .map(|_| {
            let u = unit_vector(rng, 3);
            let d = 0.8 + 0.4 * rng.unit();
            [0, 1, 2].map(|k| u[k] * d)
        })
        .collect()
}

/// The implicit network of eq. 17: wᵢ = tᵢ/|tᵢ|², one output, every target 1.
fn implicit_network(feet: &[[f64; 3]], blending: u8, q: f64) -> RefNet {
    RefNet {
        domain: 0,
        blending,
        normalized: false,
        weights: feet
            .iter()
            .map(|t| {
                let r2 = dot(t, t);
                t.iter().map(|c| to_grid(c / r2)).collect()
            })
            .collect(),
        targets: vec![vec![1.0]; feet.len()],
        sharpness: vec![q; feet.len()],
    }
}

/// maxᵢ x·wᵢ: the polyhedron (with the network's rounded weights) is {x : this ≤ 1}.
fn polyhedral_gauge(net: &RefNet, x: &[f64]) -> f64 {
    net.weights
        .iter()
        .map(|w| dot(w, x))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// f ≤ L is implied by gauge ≤ inner and implies gauge ≤ outer, because
/// max F ≤ Σ F ≤ n·max F: power F = s^q gives (L/n)^{1/q} and L^{1/q}, exponential
/// e^{q(s−1)} gives 1 + ln(L/n)/q and 1 + ln(L)/q.
fn gauge_bounds(net: &RefNet, level: f64) -> (f64, f64) {
    let n = net.weights.len() as f64;
    let q = net.sharpness[0];
    if net.blending == 0 {
        ((level / n).powf(1.0 / q), level.powf(1.0 / q))
    } else {
        (1.0 + (level / n).ln() / q, 1.0 + level.ln() / q)
    }
}

/// Random points of [−1.5, 1.5]³ classified by the network (f32, Q16.16) and by the exact
/// polyhedron test: points inside the inner polyhedron are inside, points outside the outer
/// one are outside, and the band between the two narrows as q grows.
#[test]
fn inside_outside_matches_the_polyhedron() {
    let mut rng = Rng::new(20);
    for blending in [0_u8, 1] {
        let feet = polyhedron(&mut rng, 12);
        let mut previous_band = 1.0;
        for q in [4.0, 8.0, 16.0] {
            let net = implicit_network(&feet, blending, q);
            let blob = net.blob(ScalarKind::Q16_16);
            let f = CaoEnModel::<f32>::from_blob(&blob).unwrap();
            let fixed = CaoEnModel::<Q16>::from_blob(&blob).unwrap();
            let level = 1.5;
            let (inner, outer) = gauge_bounds(&net, level);
            let (mut band, mut inside_count, total) = (0, 0, 4000);
            for _ in 0..total {
                let x: Vec<f64> = (0..3).map(|_| rng.grid(-1.5, 1.5)).collect();
                let gauge = polyhedral_gauge(&net, &x);
                let exact = net.position(&x)[0] <= level;
                let by_f32 = f.is_inside(&f32s::<3>(&x), level as f32);
                let by_q16 = fixed.is_inside(&q16s::<3>(&x), Q16::from_num(level));
                // Margins for rounding: f32 relative 1e-6, Q16 a few dozen LSB of the gauge.
                if gauge <= inner * (1.0 - 1e-4) {
                    assert!(exact && by_f32 && by_q16, "inner point outside: {x:?}");
                } else if gauge > outer * (1.0 + 1e-4) {
                    assert!(!exact && !by_f32 && !by_q16, "outer point inside: {x:?}");
                } else {
                    band += 1;
                }
                inside_count += usize::from(exact);
                // Away from the boundary both scalars agree with the f64 classification.
                let f_value = net.position(&x)[0];
                if (f_value - level).abs() > 1e-3 * level.max(f_value.abs()) {
                    assert_eq!(by_f32, exact);
                    if (f_value - level).abs() > 1e-2 {
                        assert_eq!(by_q16, exact, "{x:?} f = {f_value}");
                    }
                }
            }
            let band = band as f64 / total as f64;
            println!(
                "blending {blending}, q {q}: {inside_count} of {total} inside, {:.1}% between \
                 the inner and outer polyhedra",
                100.0 * band
            );
            assert!(inside_count > 0 && band < previous_band);
            previous_band = band;
        }
    }
}

/// Brute force along a ray in f64: the first and last of `steps + 1` samples with f ≤ level.
fn sampled_hit(
    net: &RefNet,
    origin: [f64; 3],
    direction: [f64; 3],
    far: f64,
    level: f64,
) -> Option<(f64, f64)> {
    let steps = 20_000;
    let mut hit: Option<(f64, f64)> = None;
    for i in 0..=steps {
        let t = far * i as f64 / steps as f64;
        let x: Vec<f64> = (0..3).map(|k| origin[k] + t * direction[k]).collect();
        if net.position(&x)[0] <= level {
            hit = Some(hit.map_or((t, t), |(a, _)| (a, t)));
        }
    }
    hit
}

/// Rays from random points of a sphere of radius 3 towards random points near the origin:
/// both intersections agree with sampling (within a sampling step plus rounding), misses are
/// misses, and the returned parameters are inside.
#[test]
fn both_ray_intersections_match_brute_force() {
    let mut rng = Rng::new(21);
    let (mut hits, mut misses, mut worst_f32, mut worst_q16) = (0, 0, 0.0_f64, 0.0_f64);
    for (blending, q) in [(0_u8, 8.0), (1, 8.0), (1, 16.0)] {
        let net = implicit_network(&polyhedron(&mut rng, 10), blending, q);
        let blob = net.blob(ScalarKind::Q16_16);
        let f = CaoEnModel::<f32>::from_blob(&blob).unwrap();
        let fixed = CaoEnModel::<Q16>::from_blob(&blob).unwrap();
        let level = 1.5;
        for _ in 0..60 {
            let start = unit_vector(&mut rng, 3)
                .iter()
                .map(|c| 3.0 * c)
                .collect::<Vec<_>>();
            let aim: Vec<f64> = (0..3).map(|_| rng.grid(-1.2, 1.2)).collect();
            let direction = [0, 1, 2].map(|k| to_grid((aim[k] - start[k]) / 6.0));
            let origin = [0, 1, 2].map(|k| to_grid(start[k]));
            let far = 12.0;
            let expected = sampled_hit(&net, origin, direction, far, level);
            let step = far / 20_000.0;
            let ray = Ray {
                origin: origin.map(|c| c as f32),
                direction: direction.map(|c| c as f32),
                near: 0.0,
                far: far as f32,
            };
            let fixed_ray = Ray {
                origin: origin.map(Q16::from_num),
                direction: direction.map(Q16::from_num),
                near: Q16::ZERO,
                far: Q16::from_num(far),
            };
            let got = f.ray_intersections(&ray, level as f32);
            let got_q = fixed.ray_intersections(&fixed_ray, Q16::from_num(level));
            match expected {
                None => {
                    misses += 1;
                    assert!(got.is_none() && got_q.is_none(), "{got:?} {got_q:?}");
                }
                Some((entry, exit)) if exit - entry > 4.0 * step => {
                    hits += 1;
                    let got = got.expect("f32 hit");
                    let got_q = got_q.expect("Q16 hit");
                    let e32 = (f64::from(got.entry) - entry)
                        .abs()
                        .max((f64::from(got.exit) - exit).abs());
                    let eq = (got_q.entry.to_f64() - entry)
                        .abs()
                        .max((got_q.exit.to_f64() - exit).abs());
                    worst_f32 = worst_f32.max(e32);
                    worst_q16 = worst_q16.max(eq);
                    assert!(e32 <= step + 1e-5, "f32 {got:?} vs {entry}..{exit}");
                    assert!(eq <= step + 64.0 * LSB, "Q16 {got_q:?} vs {entry}..{exit}");
                    // The returned parameters are inside points.
                    for t in [got.entry, got.exit] {
                        let x: [f32; 3] =
                            std::array::from_fn(|k| ray.origin[k] + t * ray.direction[k]);
                        assert!(f.is_inside(&x, level as f32));
                    }
                }
                Some(_) => {} // a grazing ray: either answer is right
            }
        }
    }
    println!(
        "{hits} hits, {misses} misses; worst parameter error f32 {worst_f32:.2e}, Q16 \
         {worst_q16:.2e} (sampling step {:.1e})",
        12.0 / 20_000.0
    );
    assert!(hits > 50 && misses > 10);
    const { assert!(MAX_RAY_EVALUATIONS <= 128) };
}

/// Degenerate rays never panic: empty or reversed ranges miss, a ray starting and ending
/// inside returns its own ends, non-finite values give `None` or a hit within the range.
#[test]
fn ray_edge_cases() {
    let mut rng = Rng::new(22);
    let net = implicit_network(&polyhedron(&mut rng, 8), 1, 8.0);
    let f = CaoEnModel::<f32>::from_blob(&net.blob(ScalarKind::F32)).unwrap();
    let ray = |near, far| Ray {
        origin: [0.0_f32; 3],
        direction: [1.0, 0.0, 0.0],
        near,
        far,
    };
    assert_eq!(f.ray_intersections(&ray(1.0, 0.0), 1.5), None);
    assert_eq!(f.ray_intersections(&ray(f32::NAN, 1.0), 1.5), None);
    let inside = f.ray_intersections(&ray(-0.1, 0.1), 1.5).unwrap();
    assert_eq!((inside.entry, inside.exit), (-0.1, 0.1));
    let _ = f.ray_intersections(&ray(-f32::INFINITY, f32::INFINITY), 1.5);
    let _ = f.ray_intersections(&ray(0.0, 1e30), f32::NAN);
    let fixed = CaoEnModel::<Q16>::from_blob(&net.blob(ScalarKind::Q16_16)).unwrap();
    let extreme = Ray {
        origin: [Q16::MIN; 3],
        direction: [Q16::MAX; 3],
        near: Q16::MIN,
        far: Q16::MAX,
    };
    let _ = fixed.ray_intersections(&extreme, Q16::from_num(1.5));
}

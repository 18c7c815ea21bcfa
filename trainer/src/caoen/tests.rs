//! Tests of the Cao En trainer: fitting through the targets, blob round trips through the
//! core, the reference normals against the core's, meshes, and the approximate-normal network.

use crate::geometry::vector::cross;
use std::collections::HashMap;
use std::path::Path;

use neurosurf_core::caoen::{Blending, CaoEnModel, Domain};
use neurosurf_core::scalar::{Q16, ScalarKind};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

fn unit(rng: &mut ChaCha8Rng, m: usize) -> Vec<f64> {
    loop {
        let v: Vec<f64> = (0..m).map(|_| rng.random_range(-1.0..1.0)).collect();
        let r = v.iter().map(|c| c * c).sum::<f64>().sqrt();
        if r > 0.2 && r <= 1.0 {
            return v.iter().map(|c| c / r).collect();
        }
    }
}

/// Key points spread over the sphere (a Fibonacci lattice) and targets on an ellipsoid with
/// radii 1, 1.5, 0.7.
fn ellipsoid(n: usize) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let keys = support::fibonacci(n);
    let targets = keys
        .iter()
        .map(|k| vec![k[0], 1.5 * k[1], 0.7 * k[2]])
        .collect();
    (keys, targets)
}

/// The fitted V reproduces every target within 1e-6 for both blendings and both forms; the
/// paper's unfitted network does not once the keys are dense.
#[test]
fn fitted_shape_passes_through_the_targets() {
    let mut rng = ChaCha8Rng::seed_from_u64(40);
    for (blending, normalized, q) in [
        (Blending::Power, false, 6.0),
        (Blending::Exponential, false, 8.0),
        (Blending::Exponential, true, 8.0),
        (Blending::Power, true, 4.0),
    ] {
        for n in [6, 26, 104] {
            let (keys, _) = ellipsoid(n);
            let targets: Vec<Vec<f64>> = (0..n)
                .map(|_| (0..3).map(|_| rng.random_range(-2.0..2.0)).collect())
                .collect();
            let built =
                from_key_points(Domain::Sphere, blending, normalized, &keys, &targets, q).unwrap();
            let before = rms_error(&built, &keys, &targets);
            let fitted = fit_shape(&built, &keys, &targets).unwrap();
            let worst = keys
                .iter()
                .zip(&targets)
                .flat_map(|(k, t)| {
                    let y = fitted.position(k);
                    (0..3).map(move |g| (y[g] - t[g]).abs()).collect::<Vec<_>>()
                })
                .fold(0.0, f64::max);
            assert!(worst < 1e-6, "blending {blending:?}, n {n}: {worst:e}");
            // With dense keys the paper's network only passes near its targets.
            assert!(n < 26 || before > 1e-3, "n {n}: unfitted error {before:e}");
        }
    }
}

/// Per-key q by coordinate search never does worse than the single q it starts from, and does
/// better between the keys of an ellipsoid.
#[test]
fn sharpness_search_lowers_the_error_between_keys() {
    let (keys, targets) = ellipsoid(26);
    let (samples, values) = ellipsoid(400);
    let mut points = keys.clone();
    points.extend(samples);
    let mut data = targets.clone();
    data.extend(values);
    let built = from_key_points(
        Domain::Sphere,
        Blending::Exponential,
        false,
        &keys,
        &targets,
        2.0,
    )
    .unwrap();
    let start = rms_error(&fit_shape(&built, &points, &data).unwrap(), &points, &data);
    let (best, error) = fit_sharpness(&built, &points, &data, &[1.0, 2.0, 3.0, 4.0, 6.0]).unwrap();
    println!("rms between keys: q = 2 for all {start:.3e}, per-key q {error:.3e}");
    assert!(error < start);
    assert!(best.sharpness.iter().any(|&q| q != 2.0));
}

/// to_blob → core (f32 and Q16.16) agrees with the f64 reference; from_blob gives back the
/// network (exactly, for f32 storage of grid-free values within f32 precision).
#[test]
fn blobs_round_trip_through_the_core() {
    let (keys, targets) = ellipsoid(26);
    let fitted = support::fitted(&keys, &targets, Blending::Exponential, true, 6.0);
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
        let blob = to_blob(&fitted, kind, b"ellipsoid").unwrap();
        let (back, metadata, stored) = from_blob(&blob, Path::new("test.nsb")).unwrap();
        assert_eq!((metadata.as_slice(), stored), (&b"ellipsoid"[..], kind));
        let tolerance = if kind == ScalarKind::F32 { 1e-6 } else { 1e-4 };
        for (a, b) in back
            .targets
            .iter()
            .flatten()
            .zip(fitted.targets.iter().flatten())
        {
            assert!((a - b).abs() <= tolerance * b.abs().max(1.0));
        }
        let f = CaoEnModel::<f32>::from_blob(&blob).unwrap();
        let q = CaoEnModel::<Q16>::from_blob(&blob).unwrap();
        for _ in 0..100 {
            let x = unit(&mut rng, 3);
            let exact = back.position(&x);
            let y: [f32; 3] = f.eval(&[x[0] as f32, x[1] as f32, x[2] as f32]);
            let z: [Q16; 3] = q.eval(&[x[0], x[1], x[2]].map(Q16::from_num));
            for g in 0..3 {
                assert!((f64::from(y[g]) - exact[g]).abs() < 1e-5);
                assert!((z[g].to_num::<f64>() - exact[g]).abs() < 2e-3);
            }
            let n = back.normal(&x).unwrap();
            let m = f.normal(&[x[0] as f32, x[1] as f32, x[2] as f32]).unwrap();
            let cos: f64 = (0..3).map(|k| n[k] * f64::from(m[k])).sum();
            assert!(cos > 1.0 - 1e-6, "{n:?} {m:?}");
        }
    }
    assert!(to_blob(&fitted, ScalarKind::F64, &[]).is_err());
    let mut huge = fitted.clone();
    huge.targets[0][0] = 5000.0;
    let e = to_blob(&huge, ScalarKind::Q16_16, &[])
        .unwrap_err()
        .to_string();
    // The refusal names the part, the limit and the way out.
    for expected in ["target word 0", "±1024", "f32", "scale or move"] {
        assert!(e.contains(expected), "{e}");
    }
    assert!(to_blob(&huge, ScalarKind::F32, &[]).is_ok());
}

/// Icosphere: 10·4ˢ + 2 vertices, every edge shared by two triangles, outward winding; mapped
/// through the identity network it stays the sphere.
#[test]
fn meshes_are_closed_and_outward() {
    for s in 0..=3 {
        let sphere = icosphere(s).unwrap();
        assert_eq!(sphere.vertex_count(), 10 * 4_usize.pow(s as u32) + 2);
        assert_eq!(sphere.triangle_count(), 20 * 4_usize.pow(s as u32));
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &sphere.triangles {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *edges.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
            }
            let [a, b, c] = t.map(|v| sphere.positions[v as usize]);
            let n = cross(
                [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
                [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
            );
            assert!(n[0] * a[0] + n[1] * a[1] + n[2] * a[2] > 0.0);
        }
        // Each edge appears once in each direction.
        assert!(edges.values().all(|&v| v == 0));
    }
    assert!(icosphere(MAX_SUBDIVISIONS + 1).is_err());
    let axes: Vec<Vec<f64>> = (0..6)
        .map(|i| {
            let mut k = vec![0.0; 3];
            k[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
            k
        })
        .collect();
    let identity =
        from_key_points(Domain::Sphere, Blending::Power, false, &axes, &axes, 1.0).unwrap();
    let mesh = sphere_mesh(&identity, 3).unwrap();
    for (p, n) in mesh.mesh.positions.iter().zip(&mesh.normals) {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        assert!((r - 1.0).abs() < 1e-12);
        assert!((0..3).all(|k| (n[k] - p[k]).abs() < 1e-6 || p.iter().any(|c| c.abs() < 1e-9)));
    }
    let grid = torus_grid(12, 8).unwrap();
    assert_eq!((grid.sources.len(), grid.triangles.len()), (96, 192));
    assert!(torus_grid(2, 8).is_err());
}

/// The paper's approximate-normal network (targets = exact normals at the key points, same
/// evaluator) approximates the exact normals of a fitted ellipsoid within a few degrees.
#[test]
fn approximate_normal_network_tracks_exact_normals() {
    let (keys, targets) = ellipsoid(104);
    let fitted = support::fitted(&keys, &targets, Blending::Exponential, true, 12.0);
    let normals = fitted.normal_network().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let (mut worst, mut mean) = (0.0_f64, 0.0);
    for _ in 0..500 {
        let x = unit(&mut rng, 3);
        let exact = fitted.normal(&x).unwrap();
        let approx = normals.position(&x);
        let len = approx.iter().map(|c| c * c).sum::<f64>().sqrt();
        let cos: f64 = (0..3).map(|k| exact[k] * approx[k] / len).sum();
        let angle = cos.clamp(-1.0, 1.0).acos();
        worst = worst.max(angle);
        mean += angle / 500.0;
    }
    println!(
        "approximate normals: mean {:.2}°, worst {:.2}°",
        mean.to_degrees(),
        worst.to_degrees()
    );
    assert!(worst.to_degrees() < 10.0 && mean.to_degrees() < 3.0);
}

/// A torus network fitted through key points on a standard torus: mesh normals outward.
#[test]
fn torus_network_mesh() {
    let mut keys = Vec::new();
    let mut targets = Vec::new();
    for i in 0..12 {
        for j in 0..6 {
            let (theta, phi) = (
                std::f64::consts::TAU * i as f64 / 12.0,
                std::f64::consts::TAU * j as f64 / 6.0,
            );
            keys.push(vec![theta.cos(), theta.sin(), phi.cos(), phi.sin()]);
            let r = 2.0 + 0.6 * phi.cos();
            targets.push(vec![r * theta.cos(), r * theta.sin(), 0.6 * phi.sin()]);
        }
    }
    // On the torus x·w ∈ [−2, 2]: weights halved keep s ≤ 1 at the key.
    let halved: Vec<Vec<f64>> = keys
        .iter()
        .map(|k| k.iter().map(|c| c / 2.0).collect())
        .collect();
    let mut built = from_key_points(
        Domain::Torus,
        Blending::Exponential,
        true,
        &keys,
        &targets,
        8.0,
    )
    .unwrap();
    built.weights = halved;
    let fitted = fit_shape(&built, &keys, &targets).unwrap();
    assert!(rms_error(&fitted, &keys, &targets) < 1e-9);
    let mesh = torus_mesh(&fitted, 48, 24).unwrap();
    for (x, n) in mesh.sources.iter().zip(&mesh.normals) {
        let outward = [x[0] * x[2], x[1] * x[2], x[3]];
        let cos: f64 = (0..3).map(|k| n[k] * outward[k]).sum();
        assert!(cos > 0.8, "{x:?}: {n:?}");
    }
}

/// Rippa's formula is the explicit leave-one-out for unnormalized blending: refitting
/// without key i and evaluating at wᵢ gives the same errors.
#[test]
fn leave_one_out_matches_refitting_without_each_key() {
    let (keys, targets) = star(30);
    let built = from_key_points(Domain::Sphere, Blending::Power, false, &keys, &targets, 6.0)
        .expect("network");
    let formula = leave_one_out(&built, &targets).expect("solvable");
    let mut total = 0.0;
    for i in 0..keys.len() {
        let others = |v: &[Vec<f64>]| -> Vec<Vec<f64>> {
            v.iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, x)| x.clone())
                .collect()
        };
        let without = from_key_points(
            Domain::Sphere,
            Blending::Power,
            false,
            &others(&keys),
            &others(&targets),
            6.0,
        )
        .expect("network");
        let fitted = fit_shape(&without, &without.weights.clone(), &others(&targets)).unwrap();
        let y = fitted.position(&built.weights[i]);
        total += y
            .iter()
            .zip(&targets[i])
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>();
    }
    let explicit = (total / keys.len() as f64).sqrt();
    assert!(
        (formula - explicit).abs() <= 1e-7 * explicit,
        "{formula} {explicit}"
    );
}

/// Targets on a five-armed star r(θ, φ) = 1 + 0.25·sin 5θ·sin⁵φ, stretched to 2 × 1.2 × 0.9,
/// at `n` keys of a Fibonacci lattice.
fn star(n: usize) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let keys = support::fibonacci(n);
    let targets = keys.iter().map(|k| star_point(k)).collect();
    (keys, targets)
}

fn star_point(k: &[f64]) -> Vec<f64> {
    let (theta, phi) = (k[1].atan2(k[0]), k[2].clamp(-1.0, 1.0).acos());
    let r = 1.0 + 0.25 * (5.0 * theta).sin() * phi.sin().powi(5);
    vec![2.0 * r * k[0], 1.2 * r * k[1], 0.9 * r * k[2]]
}

/// The Hausdorff distance between `network`'s surface and the star, over dense samples of
/// both, in % of the star's bounding diagonal.
fn star_hausdorff(network: &CaoEnNetwork) -> f64 {
    let truth: Vec<Vec<f64>> = support::fibonacci(4000)
        .iter()
        .map(|k| star_point(k))
        .collect();
    let surface: Vec<Vec<f64>> = support::fibonacci(2000)
        .iter()
        .map(|k| network.position(k))
        .collect();
    let one_way = |from: &[Vec<f64>], to: &[Vec<f64>]| {
        from.iter()
            .map(|a| {
                to.iter()
                    .map(|b| a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>())
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
            .sqrt()
    };
    let diagonal = between_keys(network, &truth).diagonal;
    100.0 * one_way(&surface, &truth).max(one_way(&truth, &surface)) / diagonal
}

/// The default fit of 45, 100 and 200 star targets stays within 7 % of the star (Hausdorff,
/// both ways); the paper's q = 4 fitted through the same targets swings far away.
#[test]
fn the_default_fit_follows_a_star_between_its_keys() {
    for n in [45, 100, 200] {
        let (keys, targets) = star(n);
        let built = from_key_points(Domain::Sphere, Blending::Power, true, &keys, &targets, 4.0)
            .expect("network");
        let (fitted, _) = fit_auto(&built, &targets).expect("fit");
        let h = star_hausdorff(&fitted);
        let q = &fitted.sharpness;
        println!("{n} keys: Hausdorff {h:.2} %, q {q:?}");
        assert!(h <= 7.0, "{n} keys: Hausdorff {h:.2} %, q {q:?}");
        let between = between_keys(&fitted, &targets);
        assert!(
            between.farthest_from_targets < between.target_gap,
            "{n} keys: {between:?}"
        );
        if n == 100 {
            let plain =
                from_key_points(Domain::Sphere, Blending::Power, false, &keys, &targets, 4.0)
                    .expect("network");
            let paper = fit_shape(&plain, &plain.weights.clone(), &targets).unwrap();
            let swing = star_hausdorff(&paper);
            assert!(
                swing > 3.0 * h,
                "q = 4 through 100 targets: {swing:.1} %, auto {h:.1} %"
            );
            let paper_between = between_keys(&paper, &targets);
            assert!(
                paper_between.farthest_from_targets > 2.0 * between.target_gap,
                "{paper_between:?}"
            );
        }
    }
}

/// `position` skips the Jacobian but keeps the sums of `evaluate` in their order: the same
/// bits, for every blending, normalized or not, on the sphere and the torus.
#[test]
fn position_alone_equals_the_full_evaluation_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let (keys, targets) = ellipsoid(30);
    for blending in [Blending::Power, Blending::Exponential, Blending::Compact] {
        for normalized in [false, true] {
            let network =
                from_key_points(Domain::Sphere, blending, normalized, &keys, &targets, 3.0)
                    .unwrap();
            for _ in 0..50 {
                let x = unit(&mut rng, 3);
                assert_eq!(network.position(&x), network.evaluate(&x).position);
            }
        }
    }
    let torus_keys: Vec<Vec<f64>> = (0..12)
        .map(|i| {
            let (a, b) = (i as f64 * 0.7, i as f64 * 1.9);
            vec![a.cos(), a.sin(), b.cos(), b.sin()]
        })
        .collect();
    let torus_targets: Vec<Vec<f64>> = torus_keys
        .iter()
        .map(|k| {
            vec![
                k[0] * (1.0 + 0.3 * k[2]),
                k[1] * (1.0 + 0.3 * k[2]),
                0.3 * k[3],
            ]
        })
        .collect();
    let torus = from_key_points(
        Domain::Torus,
        Blending::Exponential,
        true,
        &torus_keys,
        &torus_targets,
        4.0,
    )
    .unwrap();
    for _ in 0..50 {
        let (a, b) = (rng.random_range(0.0..6.3f64), rng.random_range(0.0..6.3f64));
        let x = [a.cos(), a.sin(), b.cos(), b.sin()];
        assert_eq!(torus.position(&x), torus.evaluate(&x).position);
    }
}

/// The paper's six-foot cube (power blending, q = 4, targets = keys, unfitted) is flat at its
/// keys: ∂y/∂x vanishes there and on the coordinate planes. The normal network takes the
/// limit normal around each key instead of refusing: the face normal ±eₖ.
#[test]
fn normal_network_takes_the_limit_normal_where_the_blending_is_flat() {
    let keys = support::axes();
    let cube = from_key_points(Domain::Sphere, Blending::Power, false, &keys, &keys, 4.0).unwrap();
    assert!(cube.normal(&keys[0]).is_none());
    let normals = cube.normal_network().unwrap();
    for (key, target) in keys.iter().zip(&normals.targets) {
        let cos: f64 = (0..3).map(|k| key[k] * target[k]).sum();
        assert!(cos > 1.0 - 1e-9, "{key:?}: {target:?}");
    }
}

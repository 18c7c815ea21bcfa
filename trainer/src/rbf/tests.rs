//! Tests of the RBF baseline: interpolation, gradient, fidelity on a torus, errors, blobs.
//!
//! One file for the baseline's tests (about 820 lines): each test builds on the same sampled
//! shapes and blob helpers.

use std::f64::consts::PI;
use std::path::Path;

use neurosurf_core::BlobError;
use neurosurf_core::blob::ModelKind;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::blob::encode;
use crate::error::Error;
use crate::points::PointSet;

/// Torus major radius (axis z).
const R: f64 = 1.0;
/// Torus minor radius.
const TUBE: f64 = 0.4;
/// Its diameter, the unit of the distance metric.
const DIAMETER: f64 = 2.0 * (R + TUBE);

/// `n` area-uniform points on the torus with exact outward normals.
fn torus(n: usize, seed: u64) -> PointSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut positions = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(n);
    while positions.len() < n {
        let u = rng.random_range(0.0..2.0 * PI);
        let v = rng.random_range(0.0..2.0 * PI);
        // Area element ∝ R + r·cos v: accept with that density.
        if rng.random_range(0.0..R + TUBE) > R + TUBE * v.cos() {
            continue;
        }
        let ring = R + TUBE * v.cos();
        positions.push([ring * u.cos(), ring * u.sin(), TUBE * v.sin()]);
        normals.push([v.cos() * u.cos(), v.cos() * u.sin(), v.sin()]);
    }
    PointSet {
        positions,
        normals,
        features: None,
    }
}

/// `n` Fibonacci points on the sphere of radius `radius`.
fn sphere(n: usize, radius: f64) -> PointSet {
    let golden = PI * (3.0 - 5.0_f64.sqrt());
    let normals: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let rho = (1.0 - z * z).sqrt();
            let t = golden * i as f64;
            [rho * t.cos(), rho * t.sin(), z]
        })
        .collect();
    PointSet {
        positions: normals.iter().map(|n| n.map(|c| radius * c)).collect(),
        normals,
        features: None,
    }
}

/// Medians over `held_out` of the distance estimate |f|/|∇f| (% of the diameter) and of the
/// angle (degrees) between −∇f/|∇f| and the true normal.
fn fidelity(model: &RbfModel, held_out: &PointSet) -> (f64, f64) {
    let f = crate::fidelity::Fidelity::measure(held_out, DIAMETER, |p| model.field_gradient(p))
        .expect("a non-empty held-out set");
    (f.median_distance_percent, f.median_angle_degrees)
}

fn offset(p: [f64; 3], n: [f64; 3], epsilon: f64) -> [f64; 3] {
    [
        p[0] + epsilon * n[0],
        p[1] + epsilon * n[1],
        p[2] + epsilon * n[2],
    ]
}

fn is_invalid(result: crate::Result<(RbfModel, RbfReport)>, needle: &str) -> bool {
    match result {
        Err(Error::InvalidInput(message)) => {
            assert!(message.contains(needle), "{message:?} lacks {needle:?}");
            true
        }
        Err(other) => panic!("unexpected error {other}"),
        Ok(_) => false,
    }
}

#[test]
fn sphere_constraints_are_interpolated() {
    let points = sphere(150, 0.8);
    let options = RbfOptions::default();
    let (model, report) = fit(&points, &options).unwrap();
    assert_eq!(report.points, 150);
    assert_eq!(report.unknowns, 454);
    assert_eq!(model.parameter_count(), 454);
    assert_eq!(model.centers().len(), 450);
    assert_eq!(model.kernel(), RbfKernel::Multiquadric);
    // Every length is a fraction of the bounding diagonal.
    let diagonal = report.diagonal;
    assert!(
        (diagonal - 0.8 * 12.0_f64.sqrt()).abs() < 0.02,
        "{report:?}"
    );
    assert!((report.epsilon - EPSILON_RELATIVE * diagonal).abs() < 1e-15);
    assert!((report.c2 - (C_RELATIVE * diagonal).powi(2)).abs() < 1e-15);
    assert_eq!((report.halved, report.min_epsilon), (0, report.epsilon));
    assert!(report.max_residual < 1e-10, "{report:?}");
    assert!(report.condition_estimate > 1.0 && report.condition_estimate.is_finite());
    let (epsilon, s) = (report.epsilon, options.slope);
    for (i, (p, n)) in points.positions.iter().zip(&points.normals).enumerate() {
        assert!(model.field(*p).abs() < 1e-10);
        // Two-sided, Hermite-style: −s·ε outside, +s·ε inside.
        let outside = offset(*p, *n, epsilon);
        let inside = offset(*p, *n, -epsilon);
        for (centre, expected) in [(150 + i, outside), (300 + i, inside)] {
            let c = model.centers()[centre];
            assert!((0..3).all(|k| (c[k] - expected[k]).abs() < 1e-15), "{c:?}");
        }
        assert!((model.field(outside) + s * epsilon).abs() < 1e-10);
        assert!((model.field(inside) - s * epsilon).abs() < 1e-10);
        // The surface normal points outward, and the slope is about s.
        let (_, g) = model.field_gradient(*p);
        let normal = model.normal(*p).unwrap();
        let cos: f64 = (0..3).map(|k| normal[k] * n[k]).sum();
        assert!(cos > 0.99, "{cos}");
        let slope = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        assert!((slope - s).abs() < 0.1 * s, "{slope}");
    }
    // Polynomial side conditions hold.
    let scale: f64 = model.weights().iter().map(|w| w.abs()).sum();
    let sum: f64 = model.weights().iter().sum();
    assert!(sum.abs() < 1e-12 * scale, "{sum} vs {scale}");
    for k in 0..3 {
        let moment: f64 = model
            .weights()
            .iter()
            .zip(model.centers())
            .map(|(w, c)| w * c[k])
            .sum();
        assert!(moment.abs() < 1e-12 * scale, "{moment}");
    }
    // Sign convention: positive inside, negative outside.
    assert!(model.field([0.0; 3]) > 0.0);
    assert!(model.field([2.0, 0.3, -0.1]) < 0.0);
    println!("sphere 150: {report:?}");
}

#[test]
fn default_c_is_carcenacs_on_the_table5_torus() {
    // The torus R = 1, r = 0.4 spans [−1.4, 1.4]² × [−0.4, 0.4]: D² = 16.32.
    let c = C_RELATIVE * 16.32_f64.sqrt();
    assert!((c * c - 1e-3).abs() < 1e-17, "{}", c * c);
    // A sample of it has a slightly shorter diagonal, so c² is within a few percent of 10⁻³.
    let (_, report) = fit(&torus(96, 3), &RbfOptions::default()).unwrap();
    assert!(report.c2 < 1e-3 && report.c2 > 0.95e-3, "{report:?}");
}

#[test]
fn gradient_matches_central_differences() {
    let (model, _) = fit(&torus(96, 3), &RbfOptions::default()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let h = 1e-5;
    for _ in 0..50 {
        let p: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.6..1.6));
        let (value, gradient) = model.field_gradient(p);
        assert_eq!(value.to_bits(), model.field(p).to_bits());
        for k in 0..3 {
            let (mut plus, mut minus) = (p, p);
            plus[k] += h;
            minus[k] -= h;
            let numeric = (model.field(plus) - model.field(minus)) / (2.0 * h);
            let tolerance = 1e-6 * (1.0 + gradient[k].abs());
            assert!(
                (numeric - gradient[k]).abs() < tolerance,
                "∂{k} at {p:?}: {numeric} vs {}",
                gradient[k]
            );
        }
    }
}

/// Fits `n` torus points and measures the fidelity on 2000 held-out surface points.
fn torus_fidelity(n: usize) -> (f64, f64, RbfReport) {
    let (model, report) = fit(&torus(n, 1), &RbfOptions::default()).unwrap();
    let (distance, angle) = fidelity(&model, &torus(2000, 99));
    println!(
        "torus {n}: median distance {distance:.3} % of D, median angle {angle:.2}°, \
         {:.1} ms, κ₁ ≈ {:.2e}, max residual {:.1e}",
        1e3 * report.seconds,
        report.condition_estimate,
        report.max_residual
    );
    (distance, angle, report)
}

#[test]
fn torus_96_fidelity() {
    let (distance, angle, report) = torus_fidelity(96);
    assert!(distance < 0.4 && angle < 4.0, "{distance} {angle}");
    assert!(report.max_residual < 1e-10);
}

#[test]
fn torus_336_fidelity() {
    let (distance, angle, report) = torus_fidelity(336);
    assert!(distance < 0.08 && angle < 1.2, "{distance} {angle}");
    assert!(report.max_residual < 1e-10);
}

#[test]
fn rejects_bad_input() {
    let options = RbfOptions::default();
    assert!(is_invalid(fit(&sphere(3, 1.0), &options), "at least 4"));

    let mut duplicate = sphere(20, 1.0);
    duplicate.positions[7] = duplicate.positions[3];
    duplicate.normals[7] = duplicate.normals[3];
    assert!(is_invalid(
        fit(&duplicate, &options),
        "control point 3 and control point 7 coincide"
    ));

    let mut nan = sphere(20, 1.0);
    nan.positions[4][1] = f64::NAN;
    assert!(is_invalid(fit(&nan, &options), "control point 4"));
    let mut nan = sphere(20, 1.0);
    nan.normals[6][2] = f64::NAN;
    assert!(is_invalid(fit(&nan, &options), "control point 6"));
    let mut zero = sphere(20, 1.0);
    zero.normals[1] = [0.0; 3];
    assert!(is_invalid(fit(&zero, &options), "control point 1"));

    let mut short = sphere(20, 1.0);
    short.normals.pop();
    assert!(is_invalid(
        fit(&short, &options),
        "20 positions but 19 normals"
    ));

    let huge = PointSet {
        positions: vec![[0.0; 3]; MAX_POINTS + 1],
        normals: vec![[0.0, 0.0, 1.0]; MAX_POINTS + 1],
        features: None,
    };
    assert!(is_invalid(
        fit(&huge, &options),
        &format!("at most {MAX_POINTS}")
    ));

    for bad in [
        RbfOptions {
            c_relative: 0.0,
            ..options.clone()
        },
        RbfOptions {
            epsilon_relative: f64::NAN,
            ..options.clone()
        },
        RbfOptions {
            slope: -1.0,
            ..options.clone()
        },
    ] {
        assert!(is_invalid(
            fit(&sphere(20, 1.0), &bad),
            "must be finite and positive"
        ));
    }
    for (bad, needle) in [
        (
            RbfOptions {
                epsilon_relative: 0.5,
                ..options.clone()
            },
            "below 0.5",
        ),
        (
            RbfOptions {
                c_relative: 2.0,
                ..options.clone()
            },
            "at most 1",
        ),
    ] {
        assert!(is_invalid(fit(&sphere(20, 1.0), &bad), needle));
    }

    // All points in one spot: no volume, no diagonal to measure lengths by.
    let spot = PointSet {
        positions: vec![[1.0, 2.0, 3.0]; 5],
        normals: vec![[0.0, 0.0, 1.0]; 5],
        features: None,
    };
    assert!(is_invalid(fit(&spot, &options), "span no volume"));
}

#[test]
fn near_duplicates_are_rejected_or_exact() {
    // Two points 10⁻⁷ apart: either rejected as singular or still interpolated.
    let mut close = sphere(40, 1.0);
    close.positions[9] = offset(close.positions[8], [1.0, 0.0, 0.0], 1e-7);
    close.normals[9] = close.normals[8];
    match fit(&close, &RbfOptions::default()) {
        Ok((_, report)) => assert!(report.max_residual < 1e-7, "{report:?}"),
        Err(e) => assert!(e.to_string().contains("singular"), "{e}"),
    }
}

#[test]
fn coplanar_control_points_fit_but_coplanar_centres_do_not() {
    // A planar patch with normals off the plane: the off-surface points leave it.
    let positions: Vec<[f64; 3]> = (0..25)
        .map(|i| [(i % 5) as f64 * 0.25, (i / 5) as f64 * 0.25, 0.0])
        .collect();
    let patch = PointSet {
        normals: vec![[0.0, 0.0, 1.0]; 25],
        positions,
        features: None,
    };
    let (model, report) = fit(&patch, &RbfOptions::default()).unwrap();
    assert!(report.max_residual < 1e-10);
    // Between the control points the plane is still (nearly) the zero set, with +z outward.
    let (f, g) = model.field_gradient([0.37, 0.61, 0.0]);
    assert!(f.abs() < 1e-3, "{f}");
    assert!(g[2] < 0.0);

    // A circle in z = 0 with in-plane normals: every centre lies in the plane.
    let flat = PointSet {
        positions: (0..12)
            .map(|i| {
                let t = i as f64 * PI / 6.0;
                [t.cos(), t.sin(), 0.0]
            })
            .collect(),
        normals: (0..12)
            .map(|i| {
                let t = i as f64 * PI / 6.0;
                [t.cos(), t.sin(), 0.0]
            })
            .collect(),
        features: None,
    };
    assert!(is_invalid(fit(&flat, &RbfOptions::default()), "coplanar"));
}

#[test]
fn blob_round_trip_is_bit_exact() {
    let (model, _) = fit(&torus(48, 5), &RbfOptions::default()).unwrap();
    let bytes = model.to_blob().unwrap();
    let path = Path::new("torus.rbf");
    let again = RbfModel::from_blob(&bytes, path).unwrap();
    assert_eq!(again, model);
    assert_eq!(again.to_blob().unwrap(), bytes);
    assert_eq!(again.c2().to_bits(), model.c2().to_bits());
    for (a, b) in again.weights().iter().zip(model.weights()) {
        assert_eq!(a.to_bits(), b.to_bits());
    }
    let p = [0.3, -1.1, 0.2];
    assert_eq!(again.field(p).to_bits(), model.field(p).to_bits());
    assert_eq!(bytes[6], ModelKind::Rbf.code());
    assert_eq!(bytes[7], RBF_SCALAR.code());
}

#[test]
fn blob_rejects_bad_bytes() {
    let (model, _) = fit(&sphere(10, 1.0), &RbfOptions::default()).unwrap();
    let bytes = model.to_blob().unwrap();
    let path = Path::new("bad.rbf");
    let blob_error = |bytes: &[u8]| match RbfModel::from_blob(bytes, path) {
        Err(Error::Blob { source, path: p }) => {
            assert_eq!(p, path);
            source
        }
        other => panic!("expected a blob error, got {other:?}"),
    };
    let mut corrupt = bytes.clone();
    corrupt[40] ^= 4;
    assert!(matches!(
        blob_error(&corrupt),
        BlobError::CrcMismatch { .. }
    ));
    assert!(matches!(
        blob_error(&bytes[..bytes.len() - 1]),
        BlobError::Truncated { .. }
    ));

    // Hand-built payloads: (centres, values, scalar, kind).
    let build = |m: u32, values: &[f64], kind: ModelKind| {
        let parameters: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        encode(
            kind,
            RBF_SCALAR,
            &(m, parameters.as_slice(), [0_u8; 0].as_slice()),
        )
        .unwrap()
    };
    let mut values = vec![1e-3, 0.1, 0.2, 0.3, 0.4, 0.0, 0.0, 0.0, 1.0];
    assert!(RbfModel::from_blob(&build(1, &values, ModelKind::Rbf), path).is_ok());
    assert!(matches!(
        blob_error(&build(1, &values, ModelKind::Implicit)),
        BlobError::WrongModelKind { .. }
    ));
    assert!(matches!(
        blob_error(&build(2, &values, ModelKind::Rbf)),
        BlobError::ShapeMismatch {
            expected: 13,
            found: 9,
            ..
        }
    ));
    values[6] = f64::INFINITY;
    assert!(matches!(
        blob_error(&build(1, &values, ModelKind::Rbf)),
        BlobError::NonFiniteParameter { index: 6 }
    ));
    values[6] = 0.0;
    // c² = 0 is the biharmonic kernel; negative is refused.
    values[0] = 0.0;
    let biharmonic = RbfModel::from_blob(&build(1, &values, ModelKind::Rbf), path).unwrap();
    assert_eq!(biharmonic.kernel(), RbfKernel::Biharmonic);
    values[0] = -1e-3;
    assert!(matches!(
        RbfModel::from_blob(&build(1, &values, ModelKind::Rbf), path),
        Err(Error::Format { .. })
    ));
    assert!(matches!(
        RbfModel::from_blob(&build(0, &values[..5], ModelKind::Rbf), path),
        Err(Error::Format { .. })
    ));
    let f32_blob = encode(
        ModelKind::Rbf,
        neurosurf_core::scalar::ScalarKind::F32,
        &(1_u32, [0_u8; 72].as_slice(), [0_u8; 0].as_slice()),
    )
    .unwrap();
    assert!(matches!(
        blob_error(&f32_blob),
        BlobError::UnsupportedStorage { .. }
    ));
    let trailing = encode(
        ModelKind::Rbf,
        RBF_SCALAR,
        &(1_u32, [0_u8; 72].as_slice(), [0_u8; 0].as_slice(), 7_u8),
    )
    .unwrap();
    assert!(matches!(blob_error(&trailing), BlobError::MalformedPayload));
}

#[test]
fn model_new_validates() {
    assert!(RbfModel::new(vec![[0.0; 3]], vec![1.0], [0.0; 3], 0.0, 1e-3).is_ok());
    assert!(RbfModel::new(vec![], vec![], [0.0; 3], 0.0, 1e-3).is_err());
    assert!(RbfModel::new(vec![[0.0; 3]], vec![1.0, 2.0], [0.0; 3], 0.0, 1e-3).is_err());
    assert!(RbfModel::new(vec![[0.0; 3]], vec![1.0], [0.0; 3], 0.0, -1e-3).is_err());
    assert!(RbfModel::new(vec![[f64::NAN; 3]], vec![1.0], [0.0; 3], 0.0, 1e-3).is_err());
    assert!(RbfModel::new(vec![[0.0; 3]], vec![1.0], [0.0; 3], f64::NAN, 1e-3).is_err());
    // φ(0) = c, so one unit weight at the origin gives f = √c² there.
    let model = RbfModel::new(vec![[0.0; 3]], vec![1.0], [0.0; 3], 0.0, 0.25).unwrap();
    assert_eq!(model.field([0.0; 3]), 0.5);
    assert_eq!(model.field_gradient([0.0; 3]).1, [0.0; 3]);
    assert_eq!(model.normal([0.0; 3]), None);
    // c² = 0: the biharmonic |x − c|, without a gradient at its centre (taken as 0).
    let model = RbfModel::new(vec![[1.0, 0.0, 0.0]], vec![2.0], [0.0; 3], 0.5, 0.0).unwrap();
    assert_eq!(model.kernel(), RbfKernel::Biharmonic);
    assert_eq!(model.field([1.0, 3.0, 4.0]), 10.5);
    assert_eq!(model.field_gradient([1.0, 0.0, 0.0]), (0.5, [0.0; 3]));
    let (_, g) = model.field_gradient([1.0, 3.0, 4.0]);
    assert!(
        (g[1] - 1.2).abs() < 1e-15 && (g[2] - 1.6).abs() < 1e-15,
        "{g:?}"
    );
}

#[test]
fn saddle_solver_matches_lu_and_condition_estimate_is_close() {
    use nalgebra::{DMatrix, DVector};

    use super::condition::symmetric_inverse_norm1;
    use super::solve::SaddleSolver;

    let points = torus(30, 8);
    let mut centers = points.positions.clone();
    for (p, n) in points.positions.iter().zip(&points.normals) {
        centers.push(offset(*p, *n, 0.05));
    }
    let m = centers.len();
    let kernel = |i: usize, j: usize| {
        let (a, b) = (centers[i], centers[j]);
        multiquadric([a[0] - b[0], a[1] - b[1], a[2] - b[2]], 1e-3)
    };
    let rows: Vec<[f64; 4]> = centers.iter().map(|c| [c[0], c[1], c[2], 1.0]).collect();
    let full = DMatrix::from_fn(m + 4, m + 4, |i, j| match (i < m, j < m) {
        (true, true) => kernel(i, j),
        (true, false) => rows[i][j - m],
        (false, true) => rows[j][i - m],
        (false, false) => 0.0,
    });
    let column_major = (0..m * m).map(|k| kernel(k % m, k / m)).collect();
    let solver = SaddleSolver::new(column_major, &rows).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let rhs: Vec<f64> = (0..m + 4).map(|_| rng.random_range(-1.0..1.0)).collect();
    let ours = solver.solve_stacked(&rhs);
    let lu = full.clone().lu().solve(&DVector::from_vec(rhs)).unwrap();
    let scale = lu.amax();
    for (a, b) in ours.iter().zip(lu.iter()) {
        assert!((a - b).abs() < 1e-7 * scale, "{a} vs {b}");
    }
    let inverse = full.clone().try_inverse().unwrap();
    let norm1 = |a: &DMatrix<f64>| {
        a.column_iter()
            .map(|c| c.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max)
    };
    assert!((solver.norm1() - norm1(&full)).abs() < 1e-12 * norm1(&full));
    let exact = norm1(&inverse);
    let estimate = symmetric_inverse_norm1(m + 4, |x| solver.solve_stacked(x));
    println!("‖M⁻¹‖₁ exact {exact:.4e}, estimate {estimate:.4e}");
    assert!(estimate <= exact * (1.0 + 1e-6) && estimate >= exact / 3.0);
}

/// The nearest control point (of the first `n` centres) to `q`, by brute force.
fn nearest_control_point(model: &RbfModel, n: usize, q: [f64; 3]) -> (usize, f64) {
    model.centers()[..n]
        .iter()
        .map(|c| (0..3).map(|k| (q[k] - c[k]).powi(2)).sum::<f64>())
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |best, (i, d)| if d < best.1 { (i, d) } else { best },
        )
}

/// Checks Carr et al.'s rule on every off-surface point of a fitted model: its nearest control
/// point is its own, it lies on its control point's normal line at εᵢ ≤ ε₀, and the field
/// there is ∓s·εᵢ. Returns the offsets (outside, inside).
fn check_offsets(model: &RbfModel, points: &PointSet, report: &RbfReport) -> Vec<[f64; 2]> {
    let n = points.len();
    let s = RbfOptions::default().slope;
    (0..n)
        .map(|i| {
            let p = points.positions[i];
            [1, 2].map(|side| {
                let q = model.centers()[side * n + i];
                let e = (0..3).map(|k| (q[k] - p[k]).powi(2)).sum::<f64>().sqrt();
                let (nearest, d2) = nearest_control_point(model, n, q);
                let own: f64 = (0..3).map(|k| (q[k] - p[k]).powi(2)).sum();
                assert!(
                    nearest == i || own <= d2,
                    "point {i} side {side}: nearest {nearest}"
                );
                assert!(e <= report.epsilon * (1.0 + 1e-12) && e >= report.min_epsilon * 0.999);
                let target = if side == 1 { -s * e } else { s * e };
                assert!((model.field(q) - target).abs() < 1e-9 * s * report.diagonal);
                e
            })
        })
        .collect()
}

#[test]
fn offsets_are_halved_until_their_nearest_control_point_is_their_own() {
    // A control point sitting exactly on another's outside off-surface point: that offset
    // must shrink (once is enough: at ε₀/2 the own point is nearer).
    let options = RbfOptions::default();
    let mut collide = sphere(20, 1.0);
    let (_, plain) = fit(&collide, &options).unwrap();
    assert_eq!(plain.halved, 0);
    collide.positions[5] = offset(collide.positions[2], collide.normals[2], plain.epsilon);
    let (model, report) = fit(&collide, &options).unwrap();
    let offsets = check_offsets(&model, &collide, &report);
    assert!(report.halved >= 1, "{report:?}");
    assert!(
        (offsets[2][0] - 0.5 * report.epsilon).abs() < 1e-12,
        "{:?}",
        offsets[2]
    );
    assert!(
        (offsets[2][1] - report.epsilon).abs() < 1e-15,
        "{:?}",
        offsets[2]
    );
    assert!(report.max_residual < 1e-10, "{report:?}");

    // A thin slab: two parallel 7×7 sheets 0.4 % of the diagonal apart, normals facing away.
    // Every inside offset (1 % of D) would reach past the other sheet; it is halved three
    // times (to 0.125 % of D: nearer its own point than the other sheet's, 0.4 % − 0.125 %
    // away; at 0.25 % it was not), the outside ones never.
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for (z, nz) in [(0.0, -1.0), (0.02, 1.0)] {
        for i in 0..49 {
            positions.push([(i % 7) as f64 * 0.6, (i / 7) as f64 * 0.6, z]);
            normals.push([0.0, 0.0, nz]);
        }
    }
    let slab = PointSet {
        positions,
        normals,
        features: None,
    };
    let (model, report) = fit(&slab, &options).unwrap();
    let offsets = check_offsets(&model, &slab, &report);
    assert_eq!(report.halved, 98, "{report:?}");
    for [outside, inside] in offsets {
        assert!((outside - report.epsilon).abs() < 1e-15, "{outside}");
        assert!(
            (inside - 0.125 * report.epsilon).abs() < 1e-12 * report.diagonal,
            "{inside}"
        );
    }
    // Inside the slab, between two control points, the field is positive; outside, negative.
    assert!(model.field([1.2, 1.8, 0.01]) > 0.0);
    assert!(model.field([1.2, 1.8, -0.01]) < 0.0 && model.field([1.2, 1.8, 0.03]) < 0.0);
}

/// `points` scaled by `scale` about the origin, then moved by `shift`.
fn transformed(points: &PointSet, scale: f64, shift: [f64; 3]) -> PointSet {
    PointSet {
        positions: points
            .positions
            .iter()
            .map(|p| [0, 1, 2].map(|k| scale * p[k] + shift[k]))
            .collect(),
        normals: points.normals.clone(),
        features: None,
    }
}

#[test]
fn scaled_and_moved_points_give_the_same_surface() {
    // f_T(T x) = λ·f(x) for T x = λx + t: the same zero set, mapped, with the same slope.
    let points = torus(96, 7);
    for kernel in [RbfKernel::Multiquadric, RbfKernel::Biharmonic] {
        let options = RbfOptions {
            kernel,
            ..RbfOptions::default()
        };
        let (model, report) = fit(&points, &options).unwrap();
        let unit = options.slope * report.diagonal;
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let probes: Vec<[f64; 3]> = (0..300)
            .map(|_| std::array::from_fn(|k| rng.random_range(-1.5..1.5) * [1.0, 1.0, 0.4][k]))
            .collect();
        for (scale, shift) in [
            (0.01, [0.0; 3]),
            (100.0, [0.0; 3]),
            (1.0, [1000.0, -1000.0, 500.0]),
            (0.01, [1000.0, -1000.0, 500.0]),
            (100.0, [1000.0, -1000.0, 500.0]),
        ] {
            let moved = transformed(&points, scale, shift);
            let (other, r) = fit(&moved, &options).unwrap();
            assert!(
                (r.diagonal / report.diagonal - scale).abs() < 1e-9 * scale,
                "{r:?}"
            );
            assert_eq!(r.halved, report.halved);
            assert!(
                (r.c2 / report.c2.max(1e-300) - scale * scale).abs() < 1e-9 * scale * scale
                    || r.c2 == 0.0
            );
            // Conditioning does not depend on units or position.
            let kappa = r.condition_estimate / report.condition_estimate;
            assert!((0.5..2.0).contains(&kappa), "{kappa}: {r:?} vs {report:?}");
            let mut worst: f64 = 0.0;
            for p in &probes {
                let q = [0, 1, 2].map(|k| scale * p[k] + shift[k]);
                let (f, g) = model.field_gradient(*p);
                let (fo, go) = other.field_gradient(q);
                worst = worst.max((fo / scale - f).abs() / unit);
                for k in 0..3 {
                    assert!(
                        (go[k] - g[k]).abs() < 1e-6 * options.slope,
                        "{g:?} vs {go:?}"
                    );
                }
            }
            // Field differences (relative to s·D) far below the fit's own error.
            assert!(worst < 1e-8, "{kernel:?} ×{scale} +{shift:?}: {worst:e}");
            println!("{kernel:?} ×{scale} +{shift:?}: largest difference {worst:.1e} s·D");
        }
    }
}

/// The Stanford bunny (a scan in metres, diagonal ≈ 0.25) of `data/`.
fn bunny(n: usize, seed: u64) -> PointSet {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/stanford-bunny.obj");
    let mesh = crate::io::read_mesh(&path).expect("the bunny ships in data/");
    crate::sample::sample_mesh(&mesh, n, seed, crate::sample::Spread::Random).unwrap()
}

#[test]
fn the_bunny_in_metres_fits() {
    // 1 000 points of the bunny: the absolute c² = 10⁻³ and ε = 0.01 of the one-sided fit
    // made this "numerically singular" (residual 3.7·10⁻⁷, limit 5·10⁻⁸); relative lengths
    // fit it cleanly.
    let points = bunny(1000, 1);
    let (model, report) = fit(&points, &RbfOptions::default()).unwrap();
    println!("bunny 1000: {report:?}");
    assert!(report.diagonal > 0.2 && report.diagonal < 0.3, "{report:?}");
    assert!(report.max_residual < 1e-10 * report.diagonal, "{report:?}");
    // Held-out points of the scan lie close to the zero set (median under 0.2 % of D).
    let held_out = bunny(2000, 77);
    let f =
        crate::fidelity::Fidelity::measure(&held_out, report.diagonal, |p| model.field_gradient(p))
            .unwrap();
    assert!(f.median_distance_percent < 0.2, "{f:?}");
    assert!(f.median_angle_degrees < 10.0, "{f:?}");
}

#[test]
fn biharmonic_interpolates_and_has_exact_gradients() {
    let options = RbfOptions {
        kernel: RbfKernel::Biharmonic,
        ..RbfOptions::default()
    };
    let points = torus(160, 2);
    let (model, report) = fit(&points, &options).unwrap();
    assert_eq!(
        (model.kernel(), report.kernel, report.c2),
        (RbfKernel::Biharmonic, RbfKernel::Biharmonic, 0.0)
    );
    assert!(report.max_residual < 1e-10, "{report:?}");
    let (distance, angle) = fidelity(&model, &torus(2000, 99));
    println!("biharmonic torus 160: {distance:.3} % of D, {angle:.2}°, {report:?}");
    assert!(distance < 0.1 && angle < 1.5, "{distance} {angle}");
    check_gradient(&|p| model.field_gradient(p), &|p| model.field(p), 1.6);
}

/// Central differences of `value` against `gradient` at random points of [−r, r]³.
fn check_gradient(
    gradient: &dyn Fn([f64; 3]) -> (f64, [f64; 3]),
    value: &dyn Fn([f64; 3]) -> f64,
    r: f64,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let h = 1e-5;
    for _ in 0..50 {
        let p: [f64; 3] = std::array::from_fn(|_| rng.random_range(-r..r));
        let (v, g) = gradient(p);
        assert_eq!(v.to_bits(), value(p).to_bits());
        for k in 0..3 {
            let (mut plus, mut minus) = (p, p);
            plus[k] += h;
            minus[k] -= h;
            let numeric = (value(plus) - value(minus)) / (2.0 * h);
            let tolerance = 1e-6 * (1.0 + g[k].abs());
            assert!(
                (numeric - g[k]).abs() < tolerance,
                "∂{k} at {p:?}: {numeric} vs {}",
                g[k]
            );
        }
    }
}

#[test]
fn rbf_field_evaluates_in_parallel_with_exact_gradients() {
    use crate::render::{DEFAULT_RBF_INFLATE, Field, RbfField};

    let (model, _) = fit(&torus(96, 3), &RbfOptions::default()).unwrap();
    let field = RbfField::new(&model, DEFAULT_RBF_INFLATE).unwrap();
    check_gradient(&|p| field.value_gradient(p), &|p| field.value(p), 1.6);
    // Batches (in parallel) agree bit for bit with single points.
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let points: Vec<[f64; 3]> = (0..1000)
        .map(|_| std::array::from_fn(|_| rng.random_range(-1.6..1.6)))
        .collect();
    let mut values = vec![0.0; points.len()];
    let mut gradients = vec![(0.0, [0.0; 3]); points.len()];
    field.values(&points, &mut values);
    field.value_gradients(&points, &mut gradients);
    for ((p, v), vg) in points.iter().zip(&values).zip(&gradients) {
        assert_eq!(v.to_bits(), model.field(*p).to_bits());
        assert_eq!(*vg, model.field_gradient(*p));
    }
    // The packed, vectorized sums agree with the plain kernel sum to rounding.
    for p in &points[..50] {
        let a = model.linear();
        let mut plain = model.constant() + a[0] * p[0] + a[1] * p[1] + a[2] * p[2];
        let mut plain_g = a;
        for (c, w) in model.centers().iter().zip(model.weights()) {
            let (phi, g) =
                multiquadric_gradient([p[0] - c[0], p[1] - c[1], p[2] - c[2]], model.c2());
            plain += w * phi;
            for k in 0..3 {
                plain_g[k] += w * g[k];
            }
        }
        let (v, g) = model.field_gradient(*p);
        assert!((v - plain).abs() < 1e-10, "{v} vs {plain}");
        assert!(
            (0..3).all(|k| (g[k] - plain_g[k]).abs() < 1e-9),
            "{g:?} vs {plain_g:?}"
        );
    }
    // One region: the centres' bounding box (which holds the off-surface points), grown.
    let [region] = field.regions() else {
        panic!("one region")
    };
    let (lo, hi) = model.bounds();
    for k in 0..3 {
        let half = 0.5 * (hi[k] - lo[k]);
        let grown = (region.bounds.hi[k] - region.bounds.lo[k]) * 0.5;
        assert!(
            (grown - DEFAULT_RBF_INFLATE * half).abs() < 1e-12,
            "{k}: {grown} vs {half}"
        );
    }
    assert!(RbfField::new(&model, 0.5).is_err());
}

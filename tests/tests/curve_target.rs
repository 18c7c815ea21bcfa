//! Curves and spline surfaces end to end: scattered points → Kohonen ordering → B-spline fit
//! (trainer, f64) → blob → core on the host (f32, Q16.16) → the same core on the simulated
//! Cortex-M4F. The target must compute exactly what the host computes, in both scalars, and
//! reject a damaged curve blob with the core's own error.

use neurosurf_core::curve::BSplineCurve;
use neurosurf_core::scalar::ScalarKind;
use neurosurf_firmware_sim::{Job, Mode, Op, SimError, Simulator, Status};
use neurosurf_trainer::curve::CurvePoints;
use neurosurf_trainer::curve::{
    CurveOptions, SampleCurve, SampleOptions, SurfaceOptions, curve_to_blob, fit_surface,
    reconstruct_curve, sample_curve, surface_to_blob,
};
use neurosurf_trainer::evaluate::{Geometry, LoadedModel, Precision};

fn simulator() -> Simulator {
    Simulator::prepare().unwrap_or_else(|e| panic!("simulator not ready: {e}"))
}

/// The approximating spline of a noisy trefoil knot (closed, 3-D).
fn trefoil_blob(scalar: ScalarKind) -> Vec<u8> {
    let options = SampleOptions {
        count: 150,
        seed: 3,
        ..SampleOptions::default()
    };
    let sample = sample_curve(SampleCurve::Trefoil, &options).unwrap();
    let points = sample.curve_points().unwrap();
    let result = reconstruct_curve(
        &points,
        &CurveOptions::new(SampleCurve::Trefoil.topology(), 3),
    )
    .unwrap();
    curve_to_blob(&result.approximation.curve, None, scalar).unwrap()
}

/// A bicubic fit of points on a saddle.
fn saddle_blob(scalar: ScalarKind) -> Vec<u8> {
    let mut points = Vec::new();
    for i in 0..20 {
        for j in 0..20 {
            let (x, y) = (
                f64::from(i) / 9.5 - 1.0,
                f64::from(j) / 9.5 - 1.0 + 0.01 * f64::from(i),
            );
            points.push([x, y, 0.5 * (x * x - y * y)]);
        }
    }
    let points = CurvePoints::from_3d(&points).unwrap();
    let fit = fit_surface(&points, &SurfaceOptions::default()).unwrap();
    surface_to_blob(&fit.surface, None, scalar).unwrap()
}

/// Parameters across the whole domain, with the ends and values outside [0, 1].
fn parameters() -> Vec<[f32; 3]> {
    let mut out: Vec<[f32; 3]> = (0..=96)
        .map(|i| {
            let t = i as f32 / 96.0;
            [t, (t * 7.0).fract(), 0.0]
        })
        .collect();
    out.extend([
        [-0.25, 1.5, 0.0],
        [1.0, 0.0, 0.0],
        [0.999_999, 0.000_001, 0.0],
    ]);
    out
}

fn host(bytes: &[u8], points: &[[f32; 3]], precision: Precision) -> Vec<Geometry> {
    let model = LoadedModel::from_bytes(bytes.to_vec(), "model.nsb".as_ref()).unwrap();
    let parameters: Vec<[f64; 3]> = points.iter().map(|p| p.map(f64::from)).collect();
    model.evaluate_geometry(&parameters, precision).unwrap()
}

fn bits(rows: &[Geometry]) -> Vec<u64> {
    rows.iter()
        .flat_map(|(p, d)| p.iter().chain(d).map(|v| v.to_bits()).collect::<Vec<_>>())
        .collect()
}

#[test]
fn curves_and_surfaces_on_the_target_equal_the_host_bit_for_bit() {
    let sim = simulator();
    let points = parameters();
    for (name, make) in [
        ("trefoil", trefoil_blob as fn(ScalarKind) -> Vec<u8>),
        ("saddle", saddle_blob),
    ] {
        for (scalar, precision) in [
            (ScalarKind::Q16_16, Precision::Q16),
            (ScalarKind::F32, Precision::F32),
        ] {
            let bytes = make(scalar);
            let expected = host(&bytes, &points, precision);
            for mode in [Mode::Batch, Mode::Single] {
                let job = Job {
                    mode,
                    ..Job::position_direction(&bytes, scalar, &points)
                };
                let run = sim.run(&job).unwrap();
                assert_eq!(
                    bits(&run.geometry()),
                    bits(&expected),
                    "{name} {scalar:?} {mode:?}"
                );
                assert!(run.instructions_per_point() > 0.0);
            }
            // The whole f64 reference is close: the fit is what the target evaluates.
            let reference = host(&bytes, &points, Precision::F64);
            for ((p, _), (r, _)) in expected.iter().zip(&reference) {
                let error = (0..3).map(|k| (p[k] - r[k]).abs()).fold(0.0, f64::max);
                assert!(error < 2e-4, "{name} {scalar:?}: position error {error}");
            }
        }
    }
}

#[test]
fn a_damaged_curve_blob_is_rejected_with_the_cores_error_and_ops_must_match_the_kind() {
    let sim = simulator();
    let good = trefoil_blob(ScalarKind::F32);
    let points = [[0.5_f32, 0.0, 0.0]];
    let mut corrupt = good.clone();
    let middle = corrupt.len() / 2;
    corrupt[middle] ^= 0x08;
    let truncated = good[..good.len() - 5].to_vec();
    for (name, bytes) in [("corrupt", &corrupt), ("truncated", &truncated)] {
        let host_error = BSplineCurve::<f32>::from_blob(bytes).unwrap_err();
        match sim.run(&Job::position_direction(bytes, ScalarKind::F32, &points)) {
            Err(SimError::BlobRejected { error }) => assert_eq!(error, host_error, "{name}"),
            other => panic!("{name}: expected a rejection, got {other:?}"),
        }
    }
    // A field op on a curve, or a curve op on a field model, is a bad request.
    let job = Job {
        op: Op::FieldGradient,
        ..Job::position_direction(&good, ScalarKind::F32, &points)
    };
    match sim.run(&job) {
        Err(SimError::Firmware { code, .. }) => {
            assert_eq!(code, i32::from(Status::BadRequest.code()));
        }
        other => panic!("expected a bad request, got {other:?}"),
    }
}

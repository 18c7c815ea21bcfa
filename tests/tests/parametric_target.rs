//! Parametric models end to end — B-spline curves and surfaces fitted to scattered points,
//! Cao En networks on the sphere, the torus and a 5-D hypersphere, and Yumer & Kara surface
//! networks (tan-sig and rad-bas) fitted to a wavy patch: trainer (f64) → blob →
//! core on the host (f32, Q16.16) → the same core on the simulated Cortex-M4F. The target must
//! compute exactly what the host computes, in both scalars and both modes, and reject a damaged
//! blob with the core's own error.

use std::f64::consts::FRAC_PI_2;

use neurosurf_core::caoen::{Blending, CaoEnModel, Domain};
use neurosurf_core::curve::BSplineCurve;
use neurosurf_core::parametric::SurfaceNetworkModel;
use neurosurf_core::scalar::{Q16, ScalarKind};
use neurosurf_firmware_sim::{Job, Mode, Op, SimError, Simulator, Status};
use neurosurf_trainer::caoen;
use neurosurf_trainer::compare::fibonacci_sphere;
use neurosurf_trainer::curve::CurvePoints;
use neurosurf_trainer::curve::{
    CurveOptions, SampleCurve, SampleOptions, SurfaceOptions, curve_to_blob, fit_surface,
    reconstruct_curve, sample_curve, surface_to_blob,
};
use neurosurf_trainer::evaluate::{Geometry, LoadedModel, Precision};
use neurosurf_trainer::parametric::{
    Activation, SampleSurface, TopologyOptions, fit_network, network_to_blob, sample_surface,
};

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

/// A Cao En shape on the sphere: 26 key points (cube corners, edge and face centres), targets
/// on a bent ellipsoid, power blending q = 3, V fitted so the surface passes through them.
fn caoen_sphere_blob(scalar: ScalarKind) -> Vec<u8> {
    let mut keys = Vec::new();
    for i in -1..=1 {
        for j in -1..=1 {
            for k in -1..=1 {
                if (i, j, k) != (0, 0, 0) {
                    let v = [f64::from(i), f64::from(j), f64::from(k)];
                    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    keys.push(v.map(|c| c / n).to_vec());
                }
            }
        }
    }
    let targets: Vec<Vec<f64>> = keys
        .iter()
        .map(|k| vec![1.2 * k[0], 0.8 * k[1], 0.6 * k[2] + 0.1 * k[0] * k[1]])
        .collect();
    let built =
        caoen::from_key_points(Domain::Sphere, Blending::Power, false, &keys, &targets, 3.0)
            .unwrap();
    let fitted = caoen::fit_shape(&built, &keys, &targets).unwrap();
    caoen::to_blob(&fitted, scalar, b"test").unwrap()
}

/// A Cao En shape on the sphere with local support: 104 Fibonacci key points, compact
/// blending (q = 6: each key reaches about 33°, so most groups of keys are skipped), targets on
/// a bent ellipsoid, V fitted through them.
fn caoen_compact_blob(scalar: ScalarKind) -> Vec<u8> {
    let keys = fibonacci_sphere(104);
    let targets: Vec<Vec<f64>> = keys
        .iter()
        .map(|k| vec![1.2 * k[0], 0.8 * k[1], 0.6 * k[2] + 0.1 * k[0] * k[1]])
        .collect();
    let built = caoen::from_key_points(
        Domain::Sphere,
        Blending::Compact,
        false,
        &keys,
        &targets,
        6.0,
    )
    .unwrap();
    let fitted = caoen::fit_shape(&built, &keys, &targets).unwrap();
    caoen::to_blob(&fitted, scalar, b"test").unwrap()
}

/// A Cao En torus (source (cos θ, sin θ, cos φ, sin φ)) with 16 key points, exponential
/// blending.
fn caoen_torus_blob(scalar: ScalarKind) -> Vec<u8> {
    let mut keys = Vec::new();
    let mut targets = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            let (a, b) = (f64::from(i) * FRAC_PI_2, f64::from(j) * FRAC_PI_2);
            keys.push(vec![a.cos(), a.sin(), b.cos(), b.sin()]);
            let r = 1.0 + 0.35 * b.cos();
            targets.push(vec![r * a.cos(), r * a.sin(), 0.35 * b.sin()]);
        }
    }
    let built = caoen::from_key_points(
        Domain::Torus,
        Blending::Exponential,
        false,
        &keys,
        &targets,
        4.0,
    )
    .unwrap();
    caoen::to_blob(&built, scalar, b"").unwrap()
}

/// A 5-D → 5-D network (the paper's image compression layout), normalized exponential.
fn caoen_image_blob(scalar: ScalarKind) -> Vec<u8> {
    let keys: Vec<Vec<f64>> = (0..10)
        .map(|i| {
            let mut k = vec![0.0; 5];
            k[i % 5] = if i < 5 { 1.0 } else { -1.0 };
            k
        })
        .collect();
    let targets: Vec<Vec<f64>> = (0..10_u32)
        .map(|i| {
            (0..5)
                .map(|c| f64::from((i * 7 + c * 3) % 11) / 11.0)
                .collect()
        })
        .collect();
    let built = caoen::from_key_points(
        Domain::Sphere,
        Blending::Exponential,
        true,
        &keys,
        &targets,
        6.0,
    )
    .unwrap();
    caoen::to_blob(&built, scalar, b"").unwrap()
}

/// Parameters across a curve's or surface's whole domain, with the ends and values outside
/// [0, 1].
fn parameters() -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = (0..=96)
        .map(|i| {
            let t = f64::from(i) / 96.0;
            vec![t, (t * 7.0).fract()]
        })
        .collect();
    out.extend([vec![-0.25, 1.5], vec![1.0, 0.0], vec![0.999_999, 0.000_001]]);
    out
}

/// `n` source points of the unit sphere in `m` dimensions (deterministic), exact in `f32`.
fn source_points(n: usize, m: usize) -> Vec<Vec<f64>> {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    (0..n)
        .map(|_| {
            let mut v: Vec<f64> = (0..m)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
                })
                .collect();
            let n = v.iter().map(|c| c * c).sum::<f64>().sqrt();
            v.iter_mut().for_each(|c| *c = f64::from((*c / n) as f32));
            v
        })
        .collect()
}

/// Torus source points (cos θ, sin θ, cos φ, sin φ), exact in `f32`.
fn torus_points(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|i| {
            let (a, b) = (i as f64 * 0.37, i as f64 * 0.91);
            [a.cos(), a.sin(), b.cos(), b.sin()]
                .map(|c| f64::from(c as f32))
                .to_vec()
        })
        .collect()
}

fn host(bytes: &[u8], points: &[Vec<f64>], precision: Precision) -> Vec<Geometry> {
    let model = LoadedModel::from_bytes(bytes.to_vec(), "model.nsb".as_ref()).unwrap();
    model.evaluate_geometry(points, precision).unwrap()
}

fn bits(rows: &[Geometry]) -> Vec<u64> {
    rows.iter()
        .flat_map(|g| g.output.iter().chain(&g.direction).map(|v| v.to_bits()))
        .collect()
}

/// Runs `points` through the blob on the target in both modes and checks every bit against
/// the host's core; returns the host's rows.
fn same_on_target(
    sim: &Simulator,
    name: &str,
    bytes: &[u8],
    (points, arity): (&[Vec<f64>], usize),
    (scalar, precision): (ScalarKind, Precision),
) -> Vec<Geometry> {
    let expected = host(bytes, points, precision);
    let inputs: Vec<f32> = points.iter().flatten().map(|&c| c as f32).collect();
    for mode in [Mode::Batch, Mode::Single] {
        let job = Job {
            mode,
            ..Job::position_direction(bytes, scalar, &inputs, arity)
        };
        let run = sim
            .run(&job)
            .unwrap_or_else(|e| panic!("{name} {scalar:?} {mode:?}: {e}"));
        let rows: Vec<Geometry> = run.geometry().into_iter().map(Geometry::from).collect();
        assert_eq!(bits(&rows), bits(&expected), "{name} {scalar:?} {mode:?}");
        assert!(run.instructions_per_point() > 0.0);
        // The position alone: the same outputs, without the direction.
        let job = Job {
            op: Op::Position,
            mode,
            ..Job::position_direction(bytes, scalar, &inputs, arity)
        };
        let run = sim
            .run(&job)
            .unwrap_or_else(|e| panic!("{name} position: {e}"));
        let outputs: Vec<u64> = run.rows().iter().flatten().map(|v| v.to_bits()).collect();
        let expected_outputs: Vec<u64> = expected
            .iter()
            .flat_map(|g| g.output.iter().map(|v| v.to_bits()))
            .collect();
        assert_eq!(
            outputs, expected_outputs,
            "{name} {scalar:?} {mode:?} position"
        );
    }
    expected
}

const SCALARS: [(ScalarKind, Precision); 2] = [
    (ScalarKind::Q16_16, Precision::Q16),
    (ScalarKind::F32, Precision::F32),
];

/// Largest coordinate difference between two evaluations' outputs.
fn max_error(a: &[Geometry], b: &[Geometry]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, r)| p.output.iter().zip(&r.output).map(|(x, y)| (x - y).abs()))
        .fold(0.0, f64::max)
}

#[test]
fn curves_and_surfaces_on_the_target_equal_the_host_bit_for_bit() {
    let sim = simulator();
    let points = parameters();
    for (name, make, arity) in [
        ("trefoil", trefoil_blob as fn(ScalarKind) -> Vec<u8>, 1),
        ("saddle", saddle_blob, 2),
    ] {
        let points: Vec<Vec<f64>> = points.iter().map(|p| p[..arity].to_vec()).collect();
        for (scalar, precision) in SCALARS {
            let bytes = make(scalar);
            let expected =
                same_on_target(&sim, name, &bytes, (&points, arity), (scalar, precision));
            // The whole f64 reference is close: the fit is what the target evaluates.
            let error = max_error(&expected, &host(&bytes, &points, Precision::F64));
            assert!(error < 2e-4, "{name} {scalar:?}: position error {error}");
        }
    }
}

#[test]
fn cao_en_networks_on_the_target_equal_the_host_bit_for_bit() {
    let sim = simulator();
    let cases = [
        (
            "sphere",
            caoen_sphere_blob as fn(ScalarKind) -> Vec<u8>,
            source_points(120, 3),
            3,
        ),
        ("torus", caoen_torus_blob, torus_points(120), 4),
        (
            "compact sphere",
            caoen_compact_blob,
            source_points(120, 3),
            3,
        ),
        (
            "5-D image layout",
            caoen_image_blob,
            source_points(120, 5),
            5,
        ),
    ];
    for (name, make, points, arity) in cases {
        for (scalar, precision) in SCALARS {
            let bytes = make(scalar);
            let expected =
                same_on_target(&sim, name, &bytes, (&points, arity), (scalar, precision));
            let reference = host(&bytes, &points, Precision::F64);
            // Q16.16: within 13 LSB (2·10⁻⁴) per unit of output size.
            let size = reference
                .iter()
                .flat_map(|g| g.output.iter().map(|v| v.abs()))
                .fold(1.0, f64::max);
            let error = max_error(&expected, &reference);
            assert!(
                error < 2e-4 * size,
                "{name} {scalar:?}: output error {error} for outputs up to {size}"
            );
            let width = expected[0].output.len();
            assert_eq!(width, if arity == 5 { 5 } else { 3 }, "{name}");
            if arity != 5 {
                let with_normal = expected.iter().filter(|g| g.direction != [0.0; 3]).count();
                assert!(
                    with_normal > 100,
                    "{name} {scalar:?}: {with_normal} normals"
                );
            }
        }
    }
}

#[test]
fn damaged_curve_and_cao_en_blobs_are_rejected_with_the_cores_error_and_ops_must_match() {
    let sim = simulator();
    let good = trefoil_blob(ScalarKind::F32);
    let points = [0.5_f32];
    let damaged = |good: &[u8]| {
        let mut corrupt = good.to_vec();
        let middle = corrupt.len() / 2;
        corrupt[middle] ^= 0x08;
        [
            ("corrupt", corrupt),
            ("truncated", good[..good.len() - 5].to_vec()),
        ]
    };
    for (name, bytes) in damaged(&good) {
        let host_error = BSplineCurve::<f32>::from_blob(&bytes).unwrap_err();
        match sim.run(&Job::position_direction(
            &bytes,
            ScalarKind::F32,
            &points,
            1,
        )) {
            Err(SimError::BlobRejected { error }) => assert_eq!(error, host_error, "{name}"),
            other => panic!("curve {name}: expected a rejection, got {other:?}"),
        }
    }
    let source = [0.0_f32, 0.6, 0.8];
    for (name, bytes) in damaged(&caoen_sphere_blob(ScalarKind::Q16_16)) {
        let host_error = CaoEnModel::<Q16>::from_blob(&bytes).unwrap_err();
        match sim.run(&Job::position_direction(
            &bytes,
            ScalarKind::Q16_16,
            &source,
            3,
        )) {
            Err(SimError::BlobRejected { error }) => assert_eq!(error, host_error, "{name}"),
            other => panic!("Cao En {name}: expected a rejection, got {other:?}"),
        }
    }
    // A field op on a curve, or a curve op on a field model, is a bad request.
    let job = Job {
        op: Op::FieldGradient,
        ..Job::position_direction(&good, ScalarKind::F32, &points, 1)
    };
    match sim.run(&job) {
        Err(SimError::Firmware { code, .. }) => {
            assert_eq!(code, i32::from(Status::BadRequest.code()));
        }
        other => panic!("expected a bad request, got {other:?}"),
    }
}

/// A surface network fitted to 300 points of the wavy test patch at their true parameters
/// (a small search: one hidden layer of up to 6 neurons).
fn wavy_network_blob(activation: Activation, scalar: ScalarKind) -> Vec<u8> {
    let sample = sample_surface(SampleSurface::Wavy, 300, 0.0, 5).unwrap();
    let options = TopologyOptions {
        activation,
        max_layers: 1,
        max_neurons: 6,
        ..TopologyOptions::default()
    };
    let fit = fit_network(&sample.points, &sample.parameters, &options).unwrap();
    network_to_blob(&fit.network, None, scalar).unwrap()
}

#[test]
fn surface_networks_on_the_target_equal_the_host_bit_for_bit() {
    let sim = simulator();
    // (u, v) over the wavy patch's parameter box [−1, 1]² and a little beyond.
    let points: Vec<Vec<f64>> = (0..100)
        .map(|i| {
            let (a, b) = (f64::from(i % 10), f64::from(i / 10));
            [a / 4.5 - 1.05, b / 4.5 - 1.0]
                .map(|c| f64::from(c as f32))
                .to_vec()
        })
        .collect();
    for activation in [Activation::TanSig, Activation::RadBas] {
        for (scalar, precision) in SCALARS {
            let bytes = wavy_network_blob(activation, scalar);
            let expected = same_on_target(
                &sim,
                activation.name(),
                &bytes,
                (&points, 2),
                (scalar, precision),
            );
            let reference = host(&bytes, &points, Precision::F64);
            let error = max_error(&expected, &reference);
            assert!(
                error < 5e-4,
                "{activation:?} {scalar:?}: position error {error}"
            );
            let with_normal = expected.iter().filter(|g| g.direction != [0.0; 3]).count();
            assert_eq!(with_normal, points.len(), "{activation:?} {scalar:?}");
        }
    }
    let good = wavy_network_blob(Activation::TanSig, ScalarKind::Q16_16);
    let truncated = &good[..good.len() - 5];
    let host_error = SurfaceNetworkModel::<Q16>::from_blob(truncated).unwrap_err();
    let uv = [0.25_f32, -0.5];
    match sim.run(&Job::position_direction(
        truncated,
        ScalarKind::Q16_16,
        &uv,
        2,
    )) {
        Err(SimError::BlobRejected { error }) => assert_eq!(error, host_error),
        other => panic!("truncated surface network: expected a rejection, got {other:?}"),
    }
}

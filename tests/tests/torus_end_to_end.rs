//! The foundation's end-to-end promise: a torus (R = 1, r = 0.4) learned from 96 control
//! points trains to the threshold, goes through a blob, and the core evaluates it in f32 and
//! Q16.16 as faithfully as the trainer's f64 reference — measured on 2000 fresh points of the
//! true torus: median |Φ|/|∇Φ| ≤ 0.5 % of the diameter and median normal error ≤ 3°.

use std::path::Path;

use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::scalar::{Q16, ScalarKind};
use neurosurf_trainer::evaluate::{LoadedModel, Precision};
use neurosurf_trainer::fidelity::Fidelity;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions, Trained};
use neurosurf_trainer::sample::{Shape, sample_shape};
use neurosurf_trainer::solve::StopReason;

const TORUS: Shape = Shape::Torus {
    major: 1.0,
    minor: 0.4,
};
const DIAMETER: f64 = 2.8;

/// The torus from `count` area-uniform control points, trained with the paper's defaults.
fn train_torus(count: usize, seed: u64) -> Trained {
    let points = sample_shape(&TORUS, count, seed).unwrap();
    implicit::fit(
        points,
        &FitRequest::default(),
        &ImplicitOptions::default(),
        &|_| {},
    )
    .unwrap()
}

#[test]
fn torus_from_96_points_is_faithful_in_f64_f32_and_q16() {
    let trained = train_torus(96, 11);
    let report = &trained.summary.modules[0];
    assert_eq!(report.lm.stop, StopReason::Converged, "{report:?}");
    assert!(report.lm.error <= 1e-5);

    let held_out = sample_shape(&TORUS, 2000, 12).unwrap();
    let reference = Fidelity::measure(&held_out, DIAMETER, |p| trained.network.eval(p)).unwrap();
    let mut results = vec![(Precision::F64, reference)];
    for (precision, scalar) in [
        (Precision::F32, ScalarKind::F32),
        (Precision::Q16, ScalarKind::Q16_16),
    ] {
        let bytes = implicit::to_blob(&trained.network, Some(&trained.summary), scalar).unwrap();
        let model = LoadedModel::from_bytes(bytes, Path::new("torus.nsb")).unwrap();
        let samples = model.evaluate(&held_out.positions, precision).unwrap();
        results.push((
            precision,
            Fidelity::from_samples(&held_out, DIAMETER, &samples).unwrap(),
        ));
    }
    for (precision, f) in &results {
        eprintln!(
            "{precision}: median {:.4} %D, median normal error {:.3}°",
            f.median_distance_percent, f.median_angle_degrees
        );
        assert!(f.median_distance_percent <= 0.5, "{precision}: {f:?}");
        assert!(f.median_angle_degrees <= 3.0, "{precision}: {f:?}");
    }
    // Rounding the weights must not move the surface noticeably.
    for (_, f) in &results[1..] {
        assert!((f.median_distance_percent - reference.median_distance_percent).abs() < 0.05);
        assert!((f.median_angle_degrees - reference.median_angle_degrees).abs() < 0.5);
    }
}

#[test]
fn blob_round_trip_keeps_the_f32_parameters_exactly() {
    let trained = train_torus(48, 3);
    let bytes =
        implicit::to_blob(&trained.network, Some(&trained.summary), ScalarKind::F32).unwrap();
    let decoded = implicit::from_blob(&bytes, Path::new("m.nsb")).unwrap();
    assert_eq!(decoded.stored_as, ScalarKind::F32);
    assert_eq!(decoded.network.kinds(), trained.network.kinds());
    // Weights and biases exactly as f32; each normalization as the blob's frame stores it,
    // (c − origin)·2ˢ and A·2⁻ˢ rounded to f32, so within f32 rounding of the value.
    let (got, want) = (&decoded.network, &trained.network);
    for module in 0..want.module_count() {
        for (a, b) in got
            .trained_params(module)
            .iter()
            .zip(want.trained_params(module))
        {
            assert_eq!(*a, f64::from(*b as f32));
        }
        let (a, b) = (got.normalization(module), want.normalization(module));
        let (a, b) = (a.unwrap(), b.unwrap());
        let close = |x: f64, y: f64| (x - y).abs() <= 1e-6 * (1.0 + y.abs());
        for k in 0..3 {
            assert!(close(a.center[k], b.center[k]), "{a:?} {b:?}");
            for j in 0..3 {
                assert!(close(a.matrix[k][j], b.matrix[k][j]), "{a:?} {b:?}");
            }
        }
    }
    let metadata = decoded.metadata.unwrap();
    assert_eq!(metadata.summary.unwrap(), trained.summary.without_timings());
    // The core accepts the same bytes in both scalars.
    assert!(ImplicitModel::<f32>::from_blob(&bytes).is_ok());
    assert!(ImplicitModel::<Q16>::from_blob(&bytes).is_ok());
    // Encoding again is byte-identical (deterministic format).
    let again = implicit::to_blob(
        &decoded.network,
        metadata_summary(&bytes).as_ref(),
        ScalarKind::F32,
    )
    .unwrap();
    assert_eq!(again, bytes);
}

fn metadata_summary(bytes: &[u8]) -> Option<neurosurf_trainer::implicit::TrainingSummary> {
    implicit::from_blob(bytes, Path::new("m.nsb"))
        .unwrap()
        .metadata
        .and_then(|m| m.summary)
}

#[test]
fn training_is_deterministic_for_a_seed_even_with_parallel_leaves() {
    use neurosurf_trainer::implicit::TreeSpec;
    let points = sample_shape(&Shape::Head, 99, 5).unwrap();
    let request = FitRequest {
        tree: Some("((0,1),2)".parse::<TreeSpec>().unwrap()),
        ..FitRequest::default()
    };
    let run = |seed| {
        let options = ImplicitOptions {
            seed,
            ..ImplicitOptions::default()
        };
        let trained = implicit::fit(points.clone(), &request, &options, &|_| {}).unwrap();
        implicit::to_blob(&trained.network, None, ScalarKind::F32).unwrap()
    };
    let first = run(3);
    assert_eq!(first, run(3), "same seed, different model");
    assert_ne!(first, run(4), "the seed does not reach the initialization");
}

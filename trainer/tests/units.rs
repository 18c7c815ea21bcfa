//! Any units: the same shape at ×0.01, ×1 and ×100, and moved far from the origin, trains to
//! the same model relative to its size with the default settings, has no stray surface, and
//! evaluates in the user's units in f64, f32 and Q16.16.

use std::path::Path;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::evaluate::{LoadedModel, Precision};
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions};
use neurosurf_trainer::quality::{MEASURE_RESOLUTION, STRAY_RESOLUTION, Truth, two_sided};
use neurosurf_trainer::render::{Aabb, DEFAULT_BOX_SIZE, DEFAULT_INFLATE, NetworkField};
use neurosurf_trainer::sample::{Shape, sample_shape};

/// A torus that is not one of the repository's shapes: R = 1, r = 0.3, tilted.
fn torus_distance(p: [f64; 3]) -> f64 {
    let (c, s) = (0.6_f64.cos(), 0.6_f64.sin());
    let q = [p[0], c * p[1] - s * p[2], s * p[1] + c * p[2]];
    (q[0].hypot(q[1]) - 1.0).hypot(q[2]) - 0.3
}

/// `count` oriented points on the tilted torus (projected from a torus sample).
fn torus_points(count: usize, seed: u64) -> neurosurf_trainer::PointSet {
    let base = sample_shape(
        &Shape::Torus {
            major: 1.0,
            minor: 0.3,
        },
        count,
        seed,
    )
    .unwrap();
    let (c, s) = (0.6_f64.cos(), 0.6_f64.sin());
    let rotate = |v: [f64; 3]| [v[0], c * v[1] + s * v[2], -s * v[1] + c * v[2]];
    neurosurf_trainer::PointSet {
        positions: base.positions.iter().map(|&p| rotate(p)).collect(),
        normals: base.normals.iter().map(|&n| rotate(n)).collect(),
        features: None,
    }
}

/// `points` moved by `to_world`, trained with the default settings.
fn fit_default(
    mut points: neurosurf_trainer::PointSet,
    to_world: &dyn Fn([f64; 3]) -> [f64; 3],
) -> implicit::Trained {
    points.positions = points.positions.iter().map(|&p| to_world(p)).collect();
    implicit::fit(
        points,
        &FitRequest::default(),
        &ImplicitOptions::default(),
        &|_| {},
    )
    .unwrap()
}

struct Outcome {
    median_percent: f64,
    f32_median_percent: f64,
    q16_median_percent: f64,
}

/// Trains on the torus scaled by `scale` and moved by `offset`, and measures it in its units.
fn train_in_units(scale: f64, offset: [f64; 3]) -> Outcome {
    let to_world = |p: [f64; 3]| [0, 1, 2].map(|k| scale * p[k] + offset[k]);
    let trained = fit_default(torus_points(160, 7), &to_world);

    let bounds = Aabb {
        lo: to_world([-1.5; 3]),
        hi: to_world([1.5; 3]),
    };
    let truth = Truth::from_signed_distance(
        |p| scale * torus_distance([0, 1, 2].map(|k| (p[k] - offset[k]) / scale)),
        bounds,
        128,
    )
    .unwrap();
    let field = NetworkField::new(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE).unwrap();
    let measure = two_sided(&field, &truth, MEASURE_RESOLUTION, STRAY_RESOLUTION).unwrap();
    assert!(measure.stray.is_clean(), "×{scale} +{offset:?}: {measure}");
    assert_eq!(
        measure.mesh.components, 1,
        "×{scale} +{offset:?}: {measure}"
    );

    // In the core, in the user's units: first-order distance |Φ|/|∇Φ| at true surface points.
    let held_out = torus_points(500, 99);
    let surface: Vec<[f64; 3]> = held_out.positions.iter().map(|&p| to_world(p)).collect();
    let median = |kind: ScalarKind, precision: Precision| {
        let blob = implicit::to_blob(&trained.network, None, kind).unwrap();
        let model = LoadedModel::from_bytes(blob, Path::new("units.nsb")).unwrap();
        let mut d: Vec<f64> = model
            .evaluate(&surface, precision)
            .unwrap()
            .iter()
            .map(|(v, g)| v.abs() / g[0].hypot(g[1]).hypot(g[2]))
            .collect();
        d.sort_by(f64::total_cmp);
        100.0 * d[d.len() / 2] / truth.diagonal()
    };
    Outcome {
        median_percent: measure.truth_to_model.median_percent,
        f32_median_percent: median(ScalarKind::F32, Precision::F32),
        q16_median_percent: median(ScalarKind::Q16_16, Precision::Q16),
    }
}

#[test]
fn the_same_shape_in_any_units_gives_the_same_model() {
    let unit = train_in_units(1.0, [0.0; 3]);
    assert!(unit.median_percent < 0.1, "{}", unit.median_percent);
    for (scale, offset) in [
        (0.01, [0.0; 3]),
        (100.0, [0.0; 3]),
        (1.0, [1000.0, -1000.0, 500.0]),
    ] {
        let other = train_in_units(scale, offset);
        eprintln!(
            "×{scale} +{offset:?}: {:.4} % (×1: {:.4} %), f32 {:.4} %, Q16.16 {:.4} %",
            other.median_percent,
            unit.median_percent,
            other.f32_median_percent,
            other.q16_median_percent
        );
        let ratio = other.median_percent / unit.median_percent;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "×{scale} +{offset:?}: {} % against {} % at ×1",
            other.median_percent,
            unit.median_percent
        );
        // f32 and Q16.16 in the user's units stay near the surface too (Q16.16 has 1/65536
        // steps, which at ×0.01 is 0.04 % of this torus' diagonal).
        assert!(
            other.f32_median_percent < 0.2,
            "f32 ×{scale}: {}",
            other.f32_median_percent
        );
        assert!(
            other.q16_median_percent < 0.5,
            "Q16.16 ×{scale}: {}",
            other.q16_median_percent
        );
    }
}

/// Fixed point refuses only what it cannot hold. The blob's frame keeps the stored model of
/// order one, so data 10⁻⁴ the size stores as Q16.16 as well as f32 (where the frame's
/// power-of-two scale absorbs what the normalizations could not hold). Data farther from the
/// origin than Q16.16 reaches is refused as Q16.16 with the coordinate, the limit and the way
/// out named, and stored as f32.
#[test]
fn fixed_point_refuses_only_what_it_cannot_hold() {
    let tiny = fit_default(torus_points(96, 3), &|p| p.map(|v| 1e-4 * v));
    for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
        let blob = implicit::to_blob(&tiny.network, None, kind).unwrap();
        let model = LoadedModel::from_bytes(blob, Path::new("tiny.nsb")).unwrap();
        // On the torus' core circle (inside, Φ > 0) and well outside (Φ < 0).
        let points = [[1e-4, 0.0, 0.0], [0.0, 0.0, 2e-4]];
        for precision in [Precision::F32, Precision::Q16] {
            let values = model.evaluate(&points, precision).unwrap();
            assert!(
                values[0].0 > 0.0 && values[1].0 < 0.0,
                "{kind:?} {precision:?}: {values:?}"
            );
        }
    }

    let moved = |p: [f64; 3]| [p[0] + 40_000.0, p[1], p[2]];
    let positions: Vec<[f64; 3]> = torus_points(96, 3)
        .positions
        .into_iter()
        .map(moved)
        .collect();
    // Refused before training, and by `to_blob` after.
    let early = implicit::check_storable(&positions, ScalarKind::Q16_16)
        .unwrap_err()
        .to_string();
    assert!(
        early.contains("centre x") && early.contains("32767"),
        "{early}"
    );
    assert!(implicit::check_storable(&positions, ScalarKind::F32).is_ok());
    let far = fit_default(torus_points(96, 3), &moved);
    let error = implicit::to_blob(&far.network, None, ScalarKind::Q16_16)
        .unwrap_err()
        .to_string();
    for expected in ["centre x", "q16.16", "32767", "f32", "move the points"] {
        assert!(error.contains(expected), "{error}");
    }
    assert!(implicit::to_blob(&far.network, None, ScalarKind::F32).is_ok());
}

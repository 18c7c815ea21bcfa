//! The built-in subjects, trained: a torus leaf, the 3-feature head (alone and with its sign
//! guards), a spiral curve of degree 3 and of degree 5, a wavy surface network and four Cao En
//! spheres, each with fixed
//! seeds and stored in both scalars.
//!
//! Training calls the host's `libm`, whose last bits depend on the CPU (glibc picks FMA or
//! plain code at run time), so the same seeds give slightly different weights on different
//! machines. `sim-bench` therefore measures the subjects stored in `subjects.json`
//! ([`super::stored`]); this module only writes that file again (`--retrain`).

use std::path::PathBuf;

use anyhow::{Context, Result};
use neurosurf_core::caoen::{Blending, Domain, MAX_SHARPNESS};
use neurosurf_core::scalar::ScalarKind;
use neurosurf_firmware_sim::Op;
use neurosurf_trainer::caoen::{self, cube_directions, fit_shape, from_key_points};
use neurosurf_trainer::compare::fibonacci_sphere;
use neurosurf_trainer::curve::{
    CurveOptions, SampleCurve, SampleOptions, curve_to_blob, reconstruct_curve, sample_curve,
};
use neurosurf_trainer::geometry::vector::inner;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions};
use neurosurf_trainer::parametric::{
    SampleSurface, TopologyOptions, fit_network, network_to_blob, sample_surface,
};
use neurosurf_trainer::sample::{Shape, sample_shape};

use super::{POINTS, Subject, box_size, points};

/// The two built-in models, trained with fixed seeds, stored in both scalars: the networks
/// alone, and the head again with its sign guards.
pub(super) fn train() -> Result<Vec<Subject>> {
    let torus = Shape::Torus {
        major: 1.0,
        minor: 0.4,
    };
    let specs = [
        ("torus (1 leaf, N=9)", torus, 96, 11, None),
        ("head ((0,1),2), N=9", Shape::Head, 99, 5, Some("((0,1),2)")),
    ];
    let mut subjects = Vec::new();
    for (name, shape, count, seed, tree) in specs {
        let request = FitRequest {
            tree: tree.map(str::parse).transpose()?,
            ..FitRequest::default()
        };
        let options = ImplicitOptions {
            width: 9,
            ..ImplicitOptions::default()
        };
        let trained = implicit::fit(
            sample_shape(&shape, count, seed)?,
            &request,
            &options,
            &|_| {},
        )
        .with_context(|| format!("cannot train the {name} model"))?;
        // The network alone (the kernels' yardstick), then, for the head, with the sign
        // guards training gave it: what they add.
        let guards = trained.network.guards().len();
        let alone = trained.network.clone().with_guards(Vec::new());
        let mut variants = vec![(name.to_string(), &alone)];
        if tree.is_some() && guards > 0 {
            variants.push((format!("{name} + {guards} sign guards"), &trained.network));
        }
        for (name, network) in variants {
            let blobs = [ScalarKind::F32, ScalarKind::Q16_16]
                .into_iter()
                .map(|scalar| {
                    Ok((
                        scalar,
                        implicit::to_blob(network, Some(&trained.summary), scalar)?,
                    ))
                })
                .collect::<Result<Vec<_>>>()?;
            subjects.push(Subject {
                path: PathBuf::from(format!("<built-in {name}>")),
                name,
                points: points(network, box_size(Some(&trained.summary))),
                arity: 3,
                blobs,
                ops: [Op::Field, Op::FieldGradient],
            });
        }
    }
    subjects.push(spiral_curve(3)?);
    subjects.push(spiral_curve(5)?);
    subjects.push(wavy_network()?);
    for (keys, blending) in [
        (26, Blending::Exponential),
        (26, Blending::Compact),
        (104, Blending::Exponential),
        (104, Blending::Compact),
    ] {
        subjects.push(cao_en_sphere(keys, blending)?);
    }
    Ok(subjects)
}

/// A Cao En sphere network with `n` key points (26: the paper's cube directions; otherwise a
/// Fibonacci set), targets on a bent ellipsoid, V fitted through them, in both scalars, at
/// [`POINTS`] Fibonacci sphere points. Exponential blending with q = 4 (26 keys) or 12 (104);
/// compact blending, normalized, with q from the spacing, each cap reaching √3 times the widest gap between
/// a key and its nearest neighbour.
fn cao_en_sphere(n: usize, blending: Blending) -> Result<Subject> {
    let keys = if n == 26 {
        cube_directions()
    } else {
        fibonacci_sphere(n)
    };
    let targets: Vec<Vec<f64>> = keys
        .iter()
        .map(|k| vec![1.3 * k[0], 0.8 * k[1] + 0.25 * k[0] * k[0], 0.6 * k[2]])
        .collect();
    let q = match blending {
        Blending::Compact => {
            // The widest gap to a nearest key, at angle d: the cap edge 1 − cos r = 3 (1 − cos d).
            let nearest = keys
                .iter()
                .enumerate()
                .map(|(i, a)| {
                    keys.iter()
                        .enumerate()
                        .filter(|&(j, _)| j != i)
                        .map(|(_, b)| inner(a, b))
                        .fold(-1.0_f64, f64::max)
                })
                .fold(1.0_f64, f64::min);
            (1.0 / (3.0 * (1.0 - nearest))).clamp(0.5, MAX_SHARPNESS)
        }
        _ if n == 26 => 4.0,
        _ => 12.0,
    };
    // Compact blending in the rational form, as recommended for it (see `Blending::Compact`).
    let normalized = blending == Blending::Compact;
    let built = from_key_points(Domain::Sphere, blending, normalized, &keys, &targets, q)?;
    let network = fit_shape(&built, &keys, &targets)?;
    let blobs = [ScalarKind::F32, ScalarKind::Q16_16]
        .into_iter()
        .map(|scalar| Ok((scalar, caoen::to_blob(&network, scalar, &[])?)))
        .collect::<Result<Vec<_>>>()?;
    let kind = match blending {
        Blending::Compact => "compact normalized",
        _ => "exponential",
    };
    let name = format!("Cao En sphere, {n} keys, {kind} q = {q:.2}");
    Ok(Subject {
        path: PathBuf::from(format!("<built-in {name}>")),
        name,
        blobs,
        points: fibonacci_sphere(POINTS)
            .iter()
            .flatten()
            .map(|&c| c as f32)
            .collect(),
        arity: 3,
        ops: [Op::Position, Op::PositionDirection],
    })
}

/// The approximating spline of `degree` (3 or 5) of 200 noisy points on a two-turn spiral
/// (fixed seed), in both scalars, at [`POINTS`] parameters spread over [0, 1].
fn spiral_curve(degree: usize) -> Result<Subject> {
    let sample = sample_curve(
        SampleCurve::Spiral,
        &SampleOptions {
            count: 200,
            seed: 3,
            ..SampleOptions::default()
        },
    )?;
    let mut options = CurveOptions::new(SampleCurve::Spiral.topology(), 3);
    options.approximation.degree = degree;
    let fit = reconstruct_curve(&sample.curve_points()?, &options)?;
    let curve = &fit.approximation.curve;
    let blobs = [ScalarKind::F32, ScalarKind::Q16_16]
        .into_iter()
        .map(|scalar| Ok((scalar, curve_to_blob(curve, None, scalar)?)))
        .collect::<Result<Vec<_>>>()?;
    let name = if degree == 3 {
        format!("spiral curve ({} control points)", curve.control.len())
    } else {
        format!(
            "spiral curve of degree {degree} ({} control points)",
            curve.control.len()
        )
    };
    Ok(Subject {
        path: PathBuf::from(format!("<built-in {name}>")),
        name,
        blobs,
        points: (0..POINTS)
            .map(|i| i as f32 / (POINTS - 1) as f32)
            .collect(),
        arity: 1,
        ops: [Op::Position, Op::PositionDirection],
    })
}

/// A surface network (Yumer & Kara) fitted to 400 points of the wavy test patch at their
/// true parameters (fixed seed; the search's pick), in both scalars, at [`POINTS`] parameters
/// over its (u, v) box.
fn wavy_network() -> Result<Subject> {
    let sample = sample_surface(SampleSurface::Wavy, 400, 0.0, 3)?;
    let fit = fit_network(
        &sample.points,
        &sample.parameters,
        &TopologyOptions::default(),
    )?;
    let blobs = [ScalarKind::F32, ScalarKind::Q16_16]
        .into_iter()
        .map(|scalar| Ok((scalar, network_to_blob(&fit.network, None, scalar)?)))
        .collect::<Result<Vec<_>>>()?;
    let hidden: Vec<String> = fit
        .network
        .hidden_sizes()
        .iter()
        .map(usize::to_string)
        .collect();
    let name = format!("wavy surface network ({}, tan-sig)", hidden.join(" × "));
    let side = (POINTS as f64).sqrt().ceil() as usize;
    Ok(Subject {
        path: PathBuf::from(format!("<built-in {name}>")),
        name,
        blobs,
        points: (0..POINTS)
            .flat_map(|i| {
                let t = |k: usize| (2 * k) as f32 / (side - 1) as f32 - 1.0;
                [t(i % side), t(i / side)]
            })
            .collect(),
        arity: 2,
        ops: [Op::Position, Op::PositionDirection],
    })
}

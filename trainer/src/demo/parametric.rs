//! The demo's parametric models: a Hoffmann–Várady curve recovered from scattered points, and
//! a Cao En surface fitted through its targets — each stored in both scalars and measured
//! against its f64 reference.

use std::path::{Path, PathBuf};
use std::time::Instant;

use neurosurf_core::caoen::{Blending, Domain};
use neurosurf_core::scalar::ScalarKind;
use serde::Serialize;

use crate::caoen::{self, fit_shape, from_key_points};
use crate::compare::{Deviation, ParameterSet};
use crate::curve::{
    CurveOptions, PlotLayers, PlotOptions, SampleCurve, SampleOptions, adjacency_fraction,
    curve_to_blob, hausdorff_distance, reconstruct_curve, sample_curve, write_plot,
};
use crate::error::Result;
use crate::evaluate::{Geometry, LoadedModel, Precision};
use crate::io::write_mesh;

/// One parametric demo model: how well it was recovered, and how far f32 and Q16.16 are from
/// its f64 reference.
#[derive(Clone, Debug, Serialize)]
pub struct ParametricDemo {
    /// Short name (`curve`, `cao-en`).
    pub name: String,
    /// What it is, in words.
    pub description: String,
    /// Fitting wall time, seconds.
    pub seconds: f64,
    /// Named quality measures of the fit (e.g. adjacency, Hausdorff distance).
    pub quality: Vec<(String, f64)>,
    /// Per precision: the deviation of the core's outputs and directions from f64.
    pub deviation: Vec<(Precision, Deviation)>,
    /// Files written, with their sizes in bytes.
    pub files: Vec<(PathBuf, usize)>,
}

/// Stores `blob_for(scalar)` in both scalars under `out_dir/{name}-{scalar}.nsb`, and measures
/// each against the f64 reference at the model's covering parameters.
fn store_and_measure(
    out_dir: &Path,
    name: &str,
    blob_for: impl Fn(ScalarKind) -> Result<Vec<u8>>,
    files: &mut Vec<(PathBuf, usize)>,
) -> Result<Vec<(Precision, Deviation)>> {
    let mut deviation = Vec::new();
    for (precision, scalar) in [
        (Precision::F32, ScalarKind::F32),
        (Precision::Q16, ScalarKind::Q16_16),
    ] {
        let bytes = blob_for(scalar)?;
        let path = out_dir.join(format!("{name}-{}.nsb", scalar.name()));
        crate::blob::write_checked(&path, &bytes)?;
        files.push((path.clone(), bytes.len()));
        let model = LoadedModel::from_bytes(bytes, &path)?;
        let Some(set) = ParameterSet::covering(&model) else {
            continue;
        };
        let reference: Vec<Geometry> = model.evaluate_geometry(&set.points, Precision::F64)?;
        let core = model.evaluate_geometry(&set.points, precision)?;
        deviation.push((precision, Deviation::measure(&reference, &core)?));
    }
    Ok(deviation)
}

/// The figure-eight curve: 150 noisy, shuffled points (the tests' noise level), ordered by a Kohonen ring and
/// approximated by a closed cubic B-spline; writes the blobs and `curve-peanut.png`.
///
/// # Errors
/// I/O errors; fitting errors (none expected on built-in data).
pub fn curve(out_dir: &Path, seed: u64) -> Result<ParametricDemo> {
    let options = SampleOptions {
        count: 150,
        seed,
        ..SampleOptions::default()
    };
    let sample = sample_curve(SampleCurve::Peanut, &options)?;
    let points = sample.curve_points()?;
    let start = Instant::now();
    let result = reconstruct_curve(
        &points,
        &CurveOptions::new(SampleCurve::Peanut.topology(), seed),
    )?;
    let seconds = start.elapsed().as_secs_f64();
    let curve = &result.approximation.curve;
    let adjacency = adjacency_fraction(&result.ordering.order, &sample.parameters, true)?;
    let spline = curve.polyline(curve.segments() * 16);
    let hausdorff = hausdorff_distance(&spline, &sample.truth) / sample.size;
    let mut files = Vec::new();
    let deviation = store_and_measure(
        out_dir,
        "curve",
        |scalar| curve_to_blob(curve, None, scalar),
        &mut files,
    )?;
    let picture = out_dir.join("curve-peanut.png");
    let layers = PlotLayers {
        points: points.points(),
        order: Some(&result.ordering.order),
        closed: true,
        curve: Some(curve),
        ..PlotLayers::default()
    };
    let plot = PlotOptions {
        width: 720,
        height: 330,
        ..PlotOptions::default()
    };
    write_plot(&picture, &layers, &plot)?;
    files.push((picture.clone(), file_size(&picture)));
    Ok(ParametricDemo {
        name: "curve".into(),
        description: format!(
            "{} scattered points on a figure-eight → {}-neuron ring → closed B-spline of {} \
             control points",
            points.len(),
            result.training.neurons,
            curve.control.len()
        ),
        seconds,
        quality: vec![
            ("adjacent pairs in the recovered order".into(), adjacency),
            ("Hausdorff distance / curve size".into(), hausdorff),
        ],
        deviation,
        files,
    })
}

/// A Cao En "bean": 26 key points on the sphere (cube directions), targets on a bent
/// ellipsoid, V fitted so the surface passes through them; writes the blobs and `cao-en.obj`.
///
/// # Errors
/// I/O and fitting errors (none expected).
pub fn cao_en(out_dir: &Path) -> Result<ParametricDemo> {
    let keys = caoen::cube_directions();
    let targets: Vec<Vec<f64>> = keys
        .iter()
        .map(|k| vec![1.3 * k[0], 0.8 * k[1] + 0.25 * k[0] * k[0], 0.6 * k[2]])
        .collect();
    let start = Instant::now();
    let built = from_key_points(Domain::Sphere, Blending::Power, false, &keys, &targets, 4.0)?;
    let network = fit_shape(&built, &keys, &targets)?;
    let seconds = start.elapsed().as_secs_f64();
    let at_keys = caoen::rms_error(&network, &keys, &targets);
    let mut files = Vec::new();
    let deviation = store_and_measure(
        out_dir,
        "cao-en",
        |scalar| caoen::to_blob(&network, scalar, b"neurosurf demo"),
        &mut files,
    )?;
    let mesh = caoen::sphere_mesh(&network, 4)?;
    let path = out_dir.join("cao-en.obj");
    write_mesh(&path, &mesh.mesh, Some(&mesh.normals))?;
    files.push((path.clone(), file_size(&path)));
    Ok(ParametricDemo {
        name: "cao-en".into(),
        description: format!(
            "{} key points on the sphere, power blending q = 4, V fitted through the targets",
            keys.len()
        ),
        seconds,
        quality: vec![(
            "RMS distance to the targets at the key points".into(),
            at_keys,
        )],
        deviation,
        files,
    })
}

fn file_size(path: &Path) -> usize {
    std::fs::metadata(path).map_or(0, |m| m.len() as usize)
}

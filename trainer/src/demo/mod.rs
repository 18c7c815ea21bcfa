//! The main job on built-in data: sample a torus and the 3-feature head, train both, write
//! their blobs, and measure each in `f64`, `f32` and Q16.16 against the true surface; then a
//! curve recovered from scattered points and a Cao En surface (`parametric`); then the tour
//! of Carcenac §6–7 (`tour`: the body, its animation, pictures, Tables 2–4, and Table 5's
//! torus against the RBF, `table5`) and a static
//! `index.html` report of it all (`report`).

mod animation;
mod body;
mod parametric;
mod pictures;
mod report;
mod table5;
mod tour;
mod woody;

pub use animation::{Animation, FrameReport, PAPER_FRAMES, Spread, animate};
pub use body::{
    BODY_HELD_OUT, BODY_TRUTH_RESOLUTION, BodyModule, body_fidelity, body_points, body_tree,
    body_two_sided, modules, train_body,
};
pub use parametric::{ParametricDemo, cao_en, curve};
pub use pictures::{FEATURE_INFLATE, Picture, feature_regions, framing, picture, point_bounds};
pub use report::{INDEX, html, write_index};
pub use table5::{
    PAPER_TABLE5, PaperTable5Row, TABLE5_DIAMETER, TABLE5_HELD_OUT, TABLE5_TORUS, Table5Row,
    paper_points, table5, table5_held_out, table5_row,
};
pub use tour::{AnimationDemo, BodyDemo, PaperTiming, Tour, TourModels, TourSize, tour};
pub use woody::{WOODY_ITERATIONS, WOODY_POINTS, WoodyDemo, extrude, woody, woody_mesh};

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::Result;
use crate::evaluate::{LoadedModel, Precision};
use crate::fidelity::{Fidelity, diameter};
use crate::implicit::{
    self, FitRequest, ImplicitOptions, Outcome, Progress, TrainingSummary, TreeSpec,
};
use crate::io::{PlyEncoding, write_points_ply};
use crate::sample::{Shape, sample_shape};
use neurosurf_core::scalar::ScalarKind;

/// Held-out surface points each model is measured on.
pub const HELD_OUT: usize = 2000;

/// One demo model.
#[derive(Clone, Debug, Serialize)]
pub struct DemoModel {
    /// Short name (`torus`, `head`).
    pub name: String,
    /// Control points trained on.
    pub control_points: usize,
    /// The tree.
    pub tree: String,
    /// Training iterations over all modules.
    pub iterations: usize,
    /// Training wall time, seconds.
    pub seconds: f64,
    /// How the training ended: converged, stalled at E_s = …, or cut by the iteration cap.
    pub outcome: Outcome,
    /// Blob files written, with their sizes in bytes.
    pub blobs: Vec<(PathBuf, usize)>,
    /// Fidelity on held-out true-surface points, per precision.
    pub fidelity: Vec<(Precision, Fidelity)>,
    /// Largest |Φ − Φ_f64| over the held-out points, per precision.
    pub max_field_deviation: Vec<(Precision, f64)>,
}

/// Everything the demo did.
#[derive(Clone, Debug, Serialize)]
pub struct DemoReport {
    /// Output folder.
    pub out_dir: PathBuf,
    /// The models.
    pub models: Vec<DemoModel>,
    /// The curve and the Cao En surface.
    pub parametric: Vec<ParametricDemo>,
    /// The §6–7 tour, when asked for.
    pub tour: Option<Tour>,
    /// The report page, when a tour was made.
    pub index: Option<PathBuf>,
}

/// Runs the demo into `out_dir` (created if missing) with `seed`; with `tour`, also the
/// §6–7 tour at that size and the `index.html` report.
///
/// # Errors
/// I/O errors writing into `out_dir`; training and rendering errors (none expected on
/// built-in data).
pub fn run(
    out_dir: &Path,
    seed: u64,
    tour_size: Option<TourSize>,
    progress: &(dyn Fn(&str, Progress) + Sync),
) -> Result<DemoReport> {
    std::fs::create_dir_all(out_dir).map_err(|e| crate::Error::io(out_dir, e))?;
    let torus = Shape::Torus {
        major: 1.0,
        minor: 0.4,
    };
    let jobs = [
        ("torus", torus, 96, None),
        ("head", Shape::Head, 99, Some("((0,1),2)")),
    ];
    let mut models = Vec::new();
    let mut networks = Vec::new();
    for (name, shape, count, tree) in jobs {
        let points = sample_shape(&shape, count, seed)?;
        write_points_ply(
            &out_dir.join(format!("{name}.ply")),
            &points,
            PlyEncoding::Ascii,
        )?;
        let request = FitRequest {
            tree: tree.map(str::parse::<TreeSpec>).transpose()?,
            ..FitRequest::default()
        };
        let options = ImplicitOptions {
            seed,
            ..ImplicitOptions::default()
        };
        let trained = implicit::fit(points, &request, &options, &|p| progress(name, p))?;
        let held_out = sample_shape(&shape, HELD_OUT, seed.wrapping_add(1_000_003))?;
        let d = diameter(&held_out.positions);
        let summary: &TrainingSummary = &trained.summary;
        let mut blobs = Vec::new();
        let mut fidelity = Vec::new();
        let reference: Vec<_> = held_out
            .positions
            .iter()
            .map(|&p| trained.network.eval(p))
            .collect();
        let mut deviation = Vec::new();
        if let Some(f) = Fidelity::measure(&held_out, d, |p| trained.network.eval(p)) {
            fidelity.push((Precision::F64, f));
        }
        for (precision, scalar) in [
            (Precision::F32, ScalarKind::F32),
            (Precision::Q16, ScalarKind::Q16_16),
        ] {
            let bytes = implicit::to_blob(&trained.network, Some(summary), scalar)?;
            let path = out_dir.join(format!("{name}-{}.nsb", scalar.name()));
            crate::blob::write_checked(&path, &bytes)?;
            blobs.push((path.clone(), bytes.len()));
            let model = LoadedModel::from_bytes(bytes, &path)?;
            let samples = model.evaluate(&held_out.positions, precision)?;
            if let Some(f) = Fidelity::from_samples(&held_out, d, &samples) {
                fidelity.push((precision, f));
            }
            let worst = samples
                .iter()
                .zip(&reference)
                .map(|(s, r)| (s.0 - r.0).abs())
                .fold(0.0, f64::max);
            deviation.push((precision, worst));
        }
        models.push(DemoModel {
            name: name.to_string(),
            control_points: count,
            tree: summary.tree.clone(),
            iterations: summary.iterations(),
            seconds: summary.seconds,
            outcome: summary.outcome(),
            blobs,
            fidelity,
            max_field_deviation: deviation,
        });
        networks.push(trained);
    }
    let parametric = vec![curve(out_dir, seed)?, cao_en(out_dir)?];
    let mut report = DemoReport {
        out_dir: out_dir.to_path_buf(),
        models,
        parametric,
        tour: None,
        index: None,
    };
    if let (Some(size), [torus, head]) = (tour_size, networks.as_slice()) {
        let models = TourModels { torus, head };
        report.tour = Some(tour(out_dir, seed, size, &models, progress)?);
        report.index = Some(write_index(&report, out_dir)?);
    }
    Ok(report)
}

//! The demo's tour of Carcenac §6–7: the 17-feature body, its 50-frame animation learned
//! incrementally, pictures (torus, head, the head's gradual memorization, the body, three
//! animation frames), the paper's Tables 2–4 next to this machine's times, and Table 5 (the
//! torus by the network and by the RBF) measured again.

use std::path::Path;

use serde::Serialize;

use super::animation::{FrameReport, PAPER_FRAMES, Spread, animate};
use super::body::{BodyModule, body_fidelity, body_points, body_two_sided, modules, train_body};
use super::pictures::{
    FEATURE_INFLATE, Picture, feature_regions, framing, picture, point_bounds, rbf_picture,
};
use super::table5::{TABLE5_TORUS, Table5Row, table5};
use super::woody::{WoodyDemo, woody};
use crate::error::Result;
use crate::fidelity::Fidelity;
use crate::implicit::{ImplicitOptions, Outcome, Progress, Trained};
use crate::points::PointSet;
use crate::quality::TwoSided;
use crate::sample::{BODY_FEATURES, BODY_TREE, Pose};

/// How big the tour is: the paper's sizes, or a quick one for tests.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize)]
pub struct TourSize {
    /// Animation frames (the cold rest pose included).
    pub frames: usize,
    /// Rays per pixel.
    pub samples: u32,
    /// Side of the square torus, head and memorization pictures.
    pub square: u32,
    /// The head picture of Table 2 (the paper: 256).
    pub head: u32,
    /// Width of the body and animation pictures (height twice that; the paper: 128 × 256).
    pub body_width: u32,
    /// Control-point counts of Table 5 (one seed each).
    pub table5_points: &'static [usize],
}

impl TourSize {
    /// The paper's: 50 frames, 4 rays per pixel, 256 × 256 head, 128 × 256 body, every row
    /// of Table 5.
    pub const PAPER: TourSize = TourSize {
        frames: PAPER_FRAMES,
        samples: 4,
        square: 160,
        head: 256,
        body_width: 128,
        table5_points: &[48, 96, 160, 336, 576],
    };

    /// A few seconds: 6 frames, 1 ray per pixel, small pictures, Table 5's first three rows.
    pub const QUICK: TourSize = TourSize {
        frames: 6,
        samples: 1,
        square: 48,
        head: 64,
        body_width: 48,
        table5_points: &[48, 96, 160],
    };
}

/// The trained body (Carcenac's Fig. 7–9, Table 3).
#[derive(Clone, Debug, Serialize)]
pub struct BodyDemo {
    /// Control points.
    pub control_points: usize,
    /// Feature names.
    pub features: Vec<String>,
    /// The tree.
    pub tree: String,
    /// Learning time, seconds (all modules).
    pub seconds: f64,
    /// LM iterations over all modules.
    pub iterations: usize,
    /// How the training ended: converged, stalled at E_s = …, or cut by the iteration cap.
    pub outcome: Outcome,
    /// Against the true body on held-out points.
    pub fidelity: Fidelity,
    /// Against the true body both ways, with stray surface and mesh pieces.
    pub two_sided: TwoSided,
    /// Per module (Fig. 9).
    pub modules: Vec<BodyModule>,
}

/// The animation (Table 4).
#[derive(Clone, Debug, Serialize)]
pub struct AnimationDemo {
    /// Frames including the cold rest pose.
    pub frames: usize,
    /// Seconds per incremental frame.
    pub seconds: Spread,
    /// Iterations per incremental frame.
    pub iterations: Spread,
    /// The cold-trained rest pose's iterations, for comparison.
    pub cold_iterations: usize,
    /// How the frames' trainings ended, the worst of them.
    pub outcome: Outcome,
    /// The last frame against its true body.
    pub last_fidelity: Fidelity,
    /// The last frame against its true body both ways, with stray surface and mesh pieces.
    pub last_two_sided: TwoSided,
    /// Every incremental frame.
    pub per_frame: Vec<FrameReport>,
}

/// One row of the paper's timing tables beside ours.
#[derive(Clone, Debug, Serialize)]
pub struct PaperTiming {
    /// "Table 2" …
    pub table: String,
    /// What is timed.
    pub what: String,
    /// The paper's seconds (500 MHz Pentium III).
    pub paper_seconds: f64,
    /// Ours.
    pub seconds: f64,
    /// Conditions that differ, if any.
    pub note: String,
}

/// Everything the tour did.
#[derive(Clone, Debug, Serialize)]
pub struct Tour {
    /// The sizes used.
    pub size: TourSize,
    /// The body.
    pub body: BodyDemo,
    /// The animation.
    pub animation: AnimationDemo,
    /// Torus, head, body and animation frames.
    pub pictures: Vec<Picture>,
    /// The head after each of its modules (Fig. 6).
    pub memorization: Vec<Picture>,
    /// Tables 2–4.
    pub timings: Vec<PaperTiming>,
    /// Table 5: the torus by the network and by the RBF, one seed, one thread.
    pub table5: Vec<Table5Row>,
    /// The body from `woody.obj` with automatic features; `None` when the data file is not
    /// there (see `io::data_file`).
    pub woody: Option<WoodyDemo>,
}

/// The demo's torus and head, already trained.
#[derive(Debug)]
pub struct TourModels<'a> {
    /// The torus.
    pub torus: &'a Trained,
    /// The head (tree ((0,1),2)).
    pub head: &'a Trained,
}

/// Control points of the Fig. 11 torus (Table 5's fewest).
const FIG11_POINTS: usize = 48;

/// The animation frames pictured: first, middle, last.
fn pictured_frames(frames: usize) -> [usize; 3] {
    [0, frames / 2, frames.saturating_sub(1)]
}

/// Runs the tour into `out_dir`. `progress` gets a stage name and training events.
///
/// # Errors
/// Training, rendering and I/O errors (none expected on the built-in data).
pub fn tour(
    out_dir: &Path,
    seed: u64,
    size: TourSize,
    models: &TourModels<'_>,
    progress: &(dyn Fn(&str, Progress) + Sync),
) -> Result<Tour> {
    let options = ImplicitOptions {
        seed,
        ..ImplicitOptions::default()
    };
    let rest_points = body_points(&Pose::REST, seed)?;
    let body = train_body(&rest_points, &options, None, &|p| progress("body", p))?;
    let body_demo = BodyDemo {
        control_points: rest_points.len(),
        features: BODY_FEATURES.iter().map(|s| (*s).to_string()).collect(),
        tree: BODY_TREE.to_string(),
        seconds: body.summary.seconds,
        iterations: body.summary.iterations(),
        outcome: body.summary.outcome(),
        fidelity: body_fidelity(&body.network, &Pose::REST, seed)?,
        two_sided: body_two_sided(&body.network, &Pose::REST)?,
        modules: modules(&body),
    };

    let keep = pictured_frames(size.frames);
    let animation = animate(&body, size.frames, seed, &options, &keep, &|_, p| {
        progress("animation", p)
    })?;
    let (_, last_pose, last_network) = animation
        .kept
        .last()
        .cloned()
        .ok_or_else(|| crate::Error::invalid("the animation kept no frame"))?;
    let animation_demo = AnimationDemo {
        frames: size.frames,
        seconds: animation.seconds(),
        iterations: animation.iterations(),
        cold_iterations: body_demo.iterations,
        outcome: animation
            .frames
            .iter()
            .map(|f| f.outcome)
            .fold(Outcome::Converged, Outcome::worst),
        last_fidelity: body_fidelity(&last_network, &last_pose, seed)?,
        last_two_sided: body_two_sided(&last_network, &last_pose)?,
        per_frame: animation.frames.clone(),
    };

    let mut pictures = Vec::new();
    let square = |w: u32| -> Result<crate::render::Camera> {
        framing(
            &point_bounds(
                &crate::sample::sample_shape(&crate::sample::Shape::Head, 400, seed)?.positions,
            ),
            35.0,
            20.0,
            w,
            w,
        )
    };
    let torus_bounds = crate::render::bounds_of(&crate::render::Region::of_network(
        &models.torus.network,
        crate::render::DEFAULT_BOX_SIZE,
        1.0,
    ))
    .ok_or_else(|| crate::Error::invalid("the torus has no region"))?;
    let torus_camera = framing(&torus_bounds, 30.0, 35.0, size.square, size.square)?;
    pictures.push(picture(
        &models.torus.network,
        Vec::new(),
        &torus_camera,
        size.samples,
        out_dir,
        "torus.png",
        "The torus: one leaf module, 96 control points",
    )?);
    // Fig. 11: the torus from Table 5's fewest points, by the network and by the RBF.
    let few = crate::sample::sample_shape(&TABLE5_TORUS, FIG11_POINTS, seed)?;
    let network = crate::implicit::fit(
        few.clone(),
        &crate::implicit::FitRequest::default(),
        &options,
        &|_| {},
    )?;
    pictures.push(picture(
        &network.network,
        Vec::new(),
        &torus_camera,
        size.samples,
        out_dir,
        "fig11-network.png",
        &format!("Fig. 11: the torus from {FIG11_POINTS} control points, by the network"),
    )?);
    let (rbf_model, _) = crate::rbf::fit(&few, &crate::rbf::RbfOptions::default())?;
    pictures.push(rbf_picture(
        &rbf_model,
        &torus_camera,
        size.samples,
        out_dir,
        "fig11-rbf.png",
        &format!("Fig. 11: the same {FIG11_POINTS} points, by the multiquadric RBF"),
    )?);
    pictures.push(picture(
        &models.head.network,
        Vec::new(),
        &square(size.head)?,
        size.samples,
        out_dir,
        "head.png",
        "The head: 3 features (head, nose, mouth), 99 control points, tree ((0,1),2)",
    )?);
    let mut memorization = Vec::new();
    let head_steps = [
        (0, "the bare head (leaf 0)"),
        (2, "+ the nose (node over leaves 0 and 1)"),
        (4, "+ the mouth (the root)"),
    ];
    for (step, (module, caption)) in head_steps.into_iter().enumerate() {
        if let Some(sub) = models.head.network.subtree(module) {
            memorization.push(picture(
                &sub,
                Vec::new(),
                &square(size.square)?,
                size.samples,
                out_dir,
                &format!("head-memorization-{}.png", step + 1),
                caption,
            )?);
        }
    }
    let (w, h) = (size.body_width, 2 * size.body_width);
    let body_bounds = point_bounds(&rest_points.positions);
    let regions = feature_regions(&rest_points, FEATURE_INFLATE);
    for (file, azimuth, caption) in [
        (
            "body-front.png",
            20.0,
            "The body, front: 17 features, 316 control points",
        ),
        ("body-side.png", 110.0, "The body, side"),
    ] {
        pictures.push(picture(
            &body.network,
            regions.clone(),
            &framing(&body_bounds, azimuth, 10.0, w, h)?,
            size.samples,
            out_dir,
            file,
            caption,
        )?);
    }
    let raised_points = body_points(&Pose::animation(size.frames - 1, size.frames), seed)?;
    let frame_bounds = point_bounds(rest_points.positions.iter().chain(&raised_points.positions));
    let frame_camera = framing(&frame_bounds, 20.0, 10.0, w, h)?;
    for (frame, pose, network) in &animation.kept {
        let points: PointSet = body_points(pose, seed)?;
        pictures.push(picture(
            network,
            feature_regions(&points, FEATURE_INFLATE),
            &frame_camera,
            size.samples,
            out_dir,
            &format!("frame-{frame:02}.png"),
            &format!("Animation frame {frame} of {}", size.frames),
        )?);
    }

    let woody = match crate::io::data_file("woody.obj") {
        Ok(_) => {
            let (demo, trained, points) = woody(seed, &|p| progress("woody", p))?;
            pictures.push(picture(
                &trained.network,
                feature_regions(&points, FEATURE_INFLATE),
                &framing(&point_bounds(&points.positions), 20.0, 10.0, w, h)?,
                size.samples,
                out_dir,
                "woody.png",
                "woody.obj extruded into a cookie: 17 automatic features, balanced tree",
            )?);
            Some(demo)
        }
        Err(_) => None,
    };
    let timings = paper_timings(models.head, &body_demo, &animation_demo, &pictures, size);
    let table5 = table5(size.table5_points, &[seed])?;
    Ok(Tour {
        size,
        body: body_demo,
        animation: animation_demo,
        pictures,
        memorization,
        timings,
        table5,
        woody,
    })
}

fn render_seconds(pictures: &[Picture], prefix: &str) -> Vec<f64> {
    pictures
        .iter()
        .filter(|p| p.file.starts_with(prefix))
        .map(|p| p.stats.seconds)
        .collect()
}

fn paper_timings(
    head: &Trained,
    body: &BodyDemo,
    animation: &AnimationDemo,
    pictures: &[Picture],
    size: TourSize,
) -> Vec<PaperTiming> {
    let body_size = format!(
        "{} × {}, {} ray(s)/pixel",
        size.body_width,
        2 * size.body_width,
        size.samples
    );
    let paper_body = size == TourSize::PAPER;
    let note = |same: bool, what: &str| {
        if same {
            String::new()
        } else {
            format!("quick tour: {what}")
        }
    };
    let mut rows = vec![
        PaperTiming {
            table: "Table 2".into(),
            what: "head learning (99 points, 5 modules)".into(),
            paper_seconds: 69.0,
            seconds: head.summary.seconds,
            note: String::new(),
        },
        PaperTiming {
            table: "Table 3".into(),
            what: "body learning (316 points, 33 modules)".into(),
            paper_seconds: 352.0,
            seconds: body.seconds,
            note: String::new(),
        },
        PaperTiming {
            table: "Table 4".into(),
            what: format!(
                "frame learning, average of {} incremental frames",
                animation.per_frame.len()
            ),
            paper_seconds: 38.0,
            seconds: animation.seconds.average,
            note: note(animation.frames == PAPER_FRAMES, "fewer frames"),
        },
        PaperTiming {
            table: "Table 4".into(),
            what: "frame learning, minimum".into(),
            paper_seconds: 15.0,
            seconds: animation.seconds.min,
            note: String::new(),
        },
        PaperTiming {
            table: "Table 4".into(),
            what: "frame learning, maximum".into(),
            paper_seconds: 62.0,
            seconds: animation.seconds.max,
            note: String::new(),
        },
    ];
    if let Some(&head_render) = render_seconds(pictures, "head.png").first() {
        rows.push(PaperTiming {
            table: "Table 2".into(),
            what: format!(
                "head render, {0} × {0}, {1} ray(s)/pixel",
                size.head, size.samples
            ),
            paper_seconds: 229.0,
            seconds: head_render,
            note: note(paper_body, "smaller image, 1 ray/pixel"),
        });
    }
    for (i, (paper, view)) in [(238.0, "front"), (272.0, "side")].into_iter().enumerate() {
        if let Some(&s) = render_seconds(pictures, "body-").get(i) {
            rows.push(PaperTiming {
                table: "Table 3".into(),
                what: format!("body render, {view}, {body_size}"),
                paper_seconds: paper,
                seconds: s,
                note: note(paper_body, "smaller image"),
            });
        }
    }
    let frames = render_seconds(pictures, "frame-");
    if !frames.is_empty() {
        rows.push(PaperTiming {
            table: "Table 4".into(),
            what: format!("animation frame render, average, {body_size}"),
            paper_seconds: 235.0,
            seconds: frames.iter().sum::<f64>() / frames.len() as f64,
            note: note(paper_body, "smaller image"),
        });
    }
    rows
}

//! `neurosurf caoen perspective`: the paper's perspective approximation (§8), a network whose
//! outputs are screen coordinates and depth, with its error against the exact projection.

use std::path::PathBuf;

use anyhow::Result;
use serde::Serialize;

use neurosurf_trainer::caoen::{PerspectiveCamera, perspective_network};

use super::super::output::comma_list;
use super::derived::{BlobOut, Written};
use super::read_network;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A Cao En shape blob (sphere or torus, p ≥ 3: the first three outputs are the position).
    model: PathBuf,
    /// Where the eye is, `X,Y,Z`.
    #[arg(long, value_parser = comma_list::<f64, 3>, allow_hyphen_values = true)]
    eye: [f64; 3],
    /// The point the eye looks at, `X,Y,Z`.
    #[arg(long, value_parser = comma_list::<f64, 3>, default_value = "0,0,0", allow_hyphen_values = true)]
    look_at: [f64; 3],
    /// Roughly up on the screen, `X,Y,Z`.
    #[arg(long, value_parser = comma_list::<f64, 3>, default_value = "0,1,0", allow_hyphen_values = true)]
    up: [f64; 3],
    /// Focal length: a point at depth z and lateral offset a appears at focal·a/z.
    #[arg(long, default_value_t = 1.0)]
    focal: f64,
    /// The blob gets the same key points and blending, and outputs screen x, y (up) and
    /// depth.
    #[command(flatten)]
    output: BlobOut,
}

#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    written: Written<'a>,
    /// Largest screen distance from the exact projection at the key points.
    max_error_at_keys: f64,
    /// Largest and RMS screen distance from the exact projection over the check points.
    max_screen_error: f64,
    rms_screen_error: f64,
    /// The larger side of the exact picture's bounding box, to read the errors against.
    screen_extent: f64,
    max_depth_error: f64,
    checked_points: usize,
}

pub fn run(args: &Args) -> Result<()> {
    let scalar = args.output.prepare()?;
    let network = read_network(&args.model, "perspective")?;
    let camera = PerspectiveCamera::new(args.eye, args.look_at, args.up, args.focal)?;
    let fit = perspective_network(&network, &camera)?;
    let written = args
        .output
        .write(&fit.network, scalar, b"neurosurf caoen perspective")?;
    let report = Report {
        written,
        max_error_at_keys: fit.max_error_at_keys,
        max_screen_error: fit.max_screen_error,
        rms_screen_error: fit.rms_screen_error,
        screen_extent: fit.screen_extent,
        max_depth_error: fit.max_depth_error,
        checked_points: fit.checked,
    };
    let summary = || {
        format!(
            "{} key points: screen coordinates within {:.1e} of the exact perspective at the \
             key points, {:.2e} (RMS {:.2e}) between them over {} source points, on a picture \
             {:.3} across; depth within {:.1e}",
            report.written.key_points,
            report.max_error_at_keys,
            report.max_screen_error,
            report.rms_screen_error,
            report.checked_points,
            report.screen_extent,
            report.max_depth_error
        )
    };
    args.output.finish(&report, summary, &report.written)
}

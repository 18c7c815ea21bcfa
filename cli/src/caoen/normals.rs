//! `neurosurf caoen normals`: the paper's approximate-normal network (§7), with its angle
//! error against the exact normals.

use std::path::PathBuf;

use anyhow::Result;
use serde::Serialize;

use neurosurf_trainer::caoen::approximate_normals;

use super::derived::{BlobOut, Written};
use super::read_network;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A Cao En shape blob (sphere or torus, p ≥ 3: the first three outputs are the position).
    model: PathBuf,
    /// The blob gets the same key points and blending, three outputs along the normal
    /// (normalize before shading).
    #[command(flatten)]
    output: BlobOut,
}

#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    written: Written<'a>,
    /// Angle between the normalized output and the exact normal, over the check points.
    mean_error_degrees: f64,
    median_error_degrees: f64,
    max_error_degrees: f64,
    checked_points: usize,
}

pub fn run(args: &Args) -> Result<()> {
    let scalar = args.output.prepare()?;
    let network = read_network(&args.model, "normals")?;
    let fit = approximate_normals(&network)?;
    let written = args
        .output
        .write(&fit.network, scalar, b"neurosurf caoen normals")?;
    let report = Report {
        written,
        mean_error_degrees: fit.mean_degrees,
        median_error_degrees: fit.median_degrees,
        max_error_degrees: fit.max_degrees,
        checked_points: fit.checked,
    };
    let summary = || {
        format!(
            "{} key points: the approximate normal is {:.2}° from the exact one on average \
             (median {:.2}°, at most {:.2}°) over {} source points",
            report.written.key_points,
            report.mean_error_degrees,
            report.median_error_degrees,
            report.max_error_degrees,
            report.checked_points
        )
    };
    args.output.finish(&report, summary, &report.written)
}

//! `neurosurf caoen shade`: the cosine law for fixed lights folded into extra outputs of a
//! shape network (paper §12.3–12.4).

use std::path::PathBuf;

use anyhow::Result;
use serde::Serialize;

use neurosurf_trainer::caoen::{LIGHTING_CHECK_SUBDIVISIONS, fold_lighting};

use super::super::output::comma_list;
use super::derived::{BlobOut, Written};
use super::read_network;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A Cao En shape blob (sphere or torus, p ≥ 3: the first three outputs are kept).
    model: PathBuf,
    /// A light direction `X,Y,Z` (towards the light; normalized). Repeat for up to five
    /// lights: output 3 + j is N·Lⱼ (unclamped: shade with max(0, ·)).
    #[arg(long = "light", value_parser = comma_list::<f64, 3>, required = true, allow_hyphen_values = true)]
    lights: Vec<[f64; 3]>,
    /// The blob gets p = 3 + the number of lights.
    #[command(flatten)]
    output: BlobOut,
}

#[derive(Serialize)]
struct Report<'a> {
    #[serde(flatten)]
    written: Written<'a>,
    target_dimension: usize,
    lights: &'a [[f64; 3]],
    /// Largest |output − N·L| at the key points (f64).
    max_error_at_keys: f64,
    /// Largest and RMS |output − N·L| over an icosphere of source points (f64).
    max_error_between: f64,
    rms_error_between: f64,
    check_subdivisions: usize,
}

pub fn run(args: &Args) -> Result<()> {
    let scalar = args.output.prepare()?;
    let network = read_network(&args.model, "shade")?;
    let fit = fold_lighting(&network, &args.lights)?;
    let written = args
        .output
        .write(&fit.network, scalar, b"neurosurf caoen shade")?;
    let report = Report {
        written,
        target_dimension: fit.network.target_dimension(),
        lights: &fit.lights,
        max_error_at_keys: fit.max_error_at_keys,
        max_error_between: fit.max_error_between,
        rms_error_between: fit.rms_error_between,
        check_subdivisions: LIGHTING_CHECK_SUBDIVISIONS,
    };
    let summary = || {
        format!(
            "{} key points, {} outputs (position, then N·L per light): |output − N·L| ≤ {:.1e} \
             at the key points, ≤ {:.4} (RMS {:.4}) between them",
            report.written.key_points,
            report.target_dimension,
            report.max_error_at_keys,
            report.max_error_between,
            report.rms_error_between
        )
    };
    args.output.finish(&report, summary, &report.written)
}

//! `neurosurf sim`: `neurosurf eval`, but on the simulated Cortex-M4F.

use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use neurosurf_firmware_sim::{Footprint, Job, Op};
use serde::Serialize;

use neurosurf_trainer::evaluate::{Geometry, LoadedModel, Precision};
use neurosurf_trainer::io::{read_parameters, read_query_points};

use super::eval::{write_csv, write_geometry};
use super::output;
use super::target::{self, ModeArg};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob: modular implicit, curve, spline surface or Cao En network (RBF models
    /// are host-only).
    model: PathBuf,
    /// Query points: PLY, or text with 3 (or 6) numbers per line; t per line for a curve,
    /// `u v` for a spline surface, the m source coordinates for a Cao En network.
    #[arg(long)]
    points: PathBuf,
    /// `f32` or `q16.16` (the target has no `f64`).
    #[arg(long)]
    scalar: Precision,
    /// Evaluate in lane batches or one point at a time (same results, different cost).
    #[arg(long, value_enum, default_value_t = ModeArg::Batch)]
    mode: ModeArg,
    /// Print the cost summary (instructions, MACs, memory, target log) as JSON instead of the
    /// CSV.
    #[arg(long)]
    json: bool,
}

/// What one run cost on the target.
#[derive(Serialize)]
struct Cost<'a> {
    model: &'a Path,
    scalar: &'static str,
    op: &'static str,
    mode: &'static str,
    points: usize,
    instructions_per_point: f64,
    mac_count: usize,
    instructions_per_mac: f64,
    stack_bytes: u32,
    #[serde(flatten)]
    footprint: Footprint,
    log: &'a [String],
}

pub fn run(args: &Args) -> Result<()> {
    let scalar = target::scalar(args.scalar)?;
    let bytes = target::read_blob(&args.model)?;
    // Parametric models are recognized here; anything else goes to the target as a field
    // model, so a corrupt blob is judged by the target's own core.
    let parametric = LoadedModel::from_bytes(bytes.clone(), &args.model)
        .ok()
        .filter(|m| m.geometry_columns().is_some());
    let (points, arity) = match &parametric {
        Some(model) => (
            read_parameters(&args.points, model.query_arity())?,
            model.query_arity(),
        ),
        None => (
            read_query_points(&args.points)?
                .iter()
                .map(|p| p.to_vec())
                .collect(),
            3,
        ),
    };
    let inputs: Vec<f32> = points.iter().flatten().map(|&c| c as f32).collect();
    let simulator = target::simulator()?;
    let job = Job {
        mode: args.mode.mode(),
        op: if parametric.is_some() {
            Op::PositionDirection
        } else {
            Op::FieldGradient
        },
        ..Job::position_direction(&bytes, scalar, &inputs, arity)
    };
    let run = target::run(&simulator, &job, &args.model)?;
    if args.json {
        let mac_count = target::mac_count(&bytes, scalar, true, &args.model)?;
        let instructions = run.instructions_per_point();
        return output::json(&Cost {
            model: &args.model,
            scalar: scalar.name(),
            op: target::op_name(job.op),
            mode: target::mode_name(run.mode),
            points: run.count(),
            instructions_per_point: instructions,
            mac_count,
            instructions_per_mac: instructions / mac_count.max(1) as f64,
            stack_bytes: run.stack_bytes,
            footprint: simulator.firmware().footprint,
            log: &run.log,
        });
    }
    if let Some(columns) = parametric.as_ref().and_then(LoadedModel::geometry_columns) {
        let rows: Vec<Geometry> = run.geometry().into_iter().map(Geometry::from).collect();
        return write_geometry(&columns, &points, &rows, false);
    }
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let points: Vec<[f64; 3]> = points.iter().map(|p| [p[0], p[1], p[2]]).collect();
    write_csv(&mut out, &points, &run.samples()).context("cannot write to stdout")?;
    Ok(())
}

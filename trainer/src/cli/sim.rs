//! `neurosurf sim`: `neurosurf eval`, but on the simulated Cortex-M4F.

use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use neurosurf_firmware_sim::{Footprint, Job, Op};
use serde::Serialize;

use neurosurf_trainer::evaluate::Precision;
use neurosurf_trainer::io::read_query_points;

use super::eval::write_csv;
use super::output;
use super::target::{self, ModeArg};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob (modular implicit; RBF models are host-only).
    model: PathBuf,
    /// Query points: PLY, or text with 3 (or 6) numbers per line.
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
    let points = read_query_points(&args.points)?;
    let inputs: Vec<[f32; 3]> = points.iter().map(|p| p.map(|c| c as f32)).collect();
    let simulator = target::simulator()?;
    let job = Job {
        mode: args.mode.mode(),
        ..Job::field_gradient(&bytes, scalar, &inputs)
    };
    let run = target::run(&simulator, &job, &args.model)?;
    if args.json {
        let mac_count = target::mac_count(&bytes, scalar, true, &args.model)?;
        let instructions = run.instructions_per_point();
        return output::json(&Cost {
            model: &args.model,
            scalar: scalar.name(),
            op: target::op_name(Op::FieldGradient),
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
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    write_csv(&mut out, &points, &run.samples()).context("cannot write to stdout")?;
    Ok(())
}

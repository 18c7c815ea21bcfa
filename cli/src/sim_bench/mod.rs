//! `neurosurf sim-bench`: what an evaluation costs on the simulated Cortex-M4F — instructions
//! and estimated cycles per evaluation against multiply–accumulates, for f32 and Q16.16, field
//! and field+gradient (position and position+direction for parametric models), single points
//! and lane batches, with the firmware's flash, RAM and stack.

use neurosurf_trainer::io::write_atomic;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use neurosurf_core::scalar::ScalarKind;
use neurosurf_firmware_sim::{Footprint, Job, Mode, Op, Simulator, TARGET_MACHINE};
use rayon::prelude::*;
use serde::Serialize;

use neurosurf_trainer::compare::{EvaluationPoints, ParameterSet, SURFACE_SAMPLES};
use neurosurf_trainer::evaluate::LoadedModel;
use neurosurf_trainer::implicit::{self, ImplicitNetwork, ImplicitOptions, TrainingSummary};
use neurosurf_trainer::table::{Align, Table};

use super::output;
use super::target;

mod built_in;
mod check;
mod stored;

/// Points per run: one timed chunk of the firmware.
const POINTS: usize = 64;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Extra model blobs to measure after the built-in ones (a torus, one leaf of width 9; the
    /// 3-feature head with tree ((0,1),2); a cubic and a quintic curve, a surface network and
    /// four Cao En spheres,
    /// stored in `cli/src/sim_bench/subjects.json`). Each is run as it is stored, in both
    /// scalars.
    models: Vec<PathBuf>,
    /// Print JSON instead of the tables.
    #[arg(long)]
    json: bool,
    /// Write the report as Markdown to this file (`docs/performance/target.md`).
    #[arg(long, value_name = "FILE")]
    markdown: Option<PathBuf>,
    /// With `--markdown`: write nothing, fail unless the file matches this run.
    #[arg(long, requires = "markdown")]
    check: bool,
    /// Instead of the cost table: compare the estimated cycles of the implicit models with
    /// each group of Cortex-M4F kernels against firmware builds without it (the portable
    /// loops instead), and write that comparison as Markdown to this file
    /// (`docs/performance/kernels.md`). Builds one firmware per group.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["markdown", "json"])]
    kernel_comparison: Option<PathBuf>,
    /// Instead of measuring: train the built-in subjects again (fixed seeds) and write them to
    /// this file (`cli/src/sim_bench/subjects.json`, built into the binary). Training is not
    /// bit-for-bit the same on every machine, so the committed subjects, not fresh ones, are
    /// what `docs/performance/target.md` measures.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["markdown", "json", "kernel_comparison", "models"])]
    retrain: Option<PathBuf>,
}

/// The groups of Cortex-M4F kernels `--kernel-comparison` turns off one group at a time
/// (names as in the core's `src/arch/m4f.rs`), with the scalar they serve and the part of an
/// evaluation their win is measured on.
const KERNEL_GROUPS: &[(&str, ScalarKind, Part, &[&str])] = &[
    (
        "Q16.16 forward layers (9×9, 9×3, 1×9)",
        ScalarKind::Q16_16,
        Part::Evaluation,
        &["q16_layer_9x9", "q16_layer_9x3", "q16_layer_1x9"],
    ),
    (
        "Q16.16 backward pass (transposes with the chain rule, 9×3 transpose, chain rule)",
        ScalarKind::Q16_16,
        Part::Backward,
        &[
            "q16_transposed_slope_9x9",
            "q16_transposed_slope_1x9",
            "q16_transposed_9x3",
            "q16_times_slope_9",
        ],
    ),
];

/// The part of an evaluation whose estimated cycles a kernel group's win is measured on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    /// The whole evaluation, every row where the group runs. The group's own loops are only
    /// part of it, so the win on them is at least this.
    Evaluation,
    /// The backward pass alone, where the group's kernels all run: field+gradient − field of
    /// the same model and mode, in each build.
    Backward,
}

impl Part {
    /// How the part is named in the tables.
    fn name(self) -> &'static str {
        match self {
            Part::Evaluation => "evaluation",
            Part::Backward => "backward pass",
        }
    }
}

/// The estimated cycles of `part` in each row of `rows` where it is defined, as (model, what
/// was measured, mode, cycles), in row order.
fn part_cycles(rows: &[Row], part: Part) -> Vec<(String, &'static str, &'static str, f64)> {
    match part {
        Part::Evaluation => rows
            .iter()
            .map(|r| (r.model.clone(), r.op, r.mode, r.cycles_per_eval))
            .collect(),
        Part::Backward => rows
            .iter()
            .filter(|r| r.op == target::op_name(Op::FieldGradient))
            .filter_map(|r| {
                let field = rows.iter().find(|f| {
                    f.model == r.model && f.mode == r.mode && f.op == target::op_name(Op::Field)
                })?;
                Some((
                    r.model.clone(),
                    "field+gradient − field",
                    r.mode,
                    r.cycles_per_eval - field.cycles_per_eval,
                ))
            })
            .collect(),
    }
}

/// Smallest estimated-cycle win, over the portable loops, that keeps a kernel group.
const KEEP_WIN: f64 = 0.10;

/// One run: a subject in a scalar, an op and a mode.
type BenchJob<'a> = (&'a Subject, ScalarKind, &'a [u8], Op, Mode);

/// Every (scalar, op, mode) of the subjects, for the scalars `scalar` accepts.
fn jobs(subjects: &[Subject], scalar: impl Fn(ScalarKind) -> bool) -> Vec<BenchJob<'_>> {
    let mut jobs = Vec::new();
    for subject in subjects {
        for (kind, blob) in &subject.blobs {
            if !scalar(*kind) {
                continue;
            }
            for op in subject.ops {
                for mode in [Mode::Single, Mode::Batch] {
                    jobs.push((subject, *kind, blob.as_slice(), op, mode));
                }
            }
        }
    }
    jobs
}

/// Runs the jobs on `simulator`, in parallel, one row each.
fn measure(simulator: &Simulator, jobs: &[BenchJob<'_>]) -> Result<Vec<Row>> {
    jobs.par_iter()
        .map(|&(subject, scalar, blob, op, mode)| {
            let job = Job {
                op,
                mode,
                ..Job::position_direction(blob, scalar, &subject.points, subject.arity)
            };
            let run = target::run(simulator, &job, &subject.path)?;
            let derivative = matches!(op, Op::FieldGradient | Op::PositionDirection);
            let macs = target::mac_count(blob, scalar, derivative, &subject.path)?;
            let instructions = run.instructions_per_point();
            Ok(Row {
                model: subject.name.clone(),
                scalar: scalar.name(),
                op: target::op_name(op),
                mode: target::mode_name(mode),
                points: run.count(),
                instructions_per_eval: instructions,
                cycles_per_eval: run.cycles_per_point(),
                macs,
                instructions_per_mac: instructions / macs.max(1) as f64,
                stack_bytes: run.stack_bytes,
            })
        })
        .collect()
}

/// `--kernel-comparison`: the implicit subjects' estimated cycles with every kernel, and with
/// each of [`KERNEL_GROUPS`] turned off, written as Markdown to `path`.
fn kernel_comparison(simulator: &Simulator, subjects: &[Subject], path: &Path) -> Result<()> {
    let implicit: Vec<Subject> = subjects
        .iter()
        .filter(|s| s.ops[0] == Op::Field)
        .cloned()
        .collect();
    let mut table = Table::new([
        ("kernels turned off", Align::Left),
        ("model", Align::Left),
        ("cycles of", Align::Left),
        ("mode", Align::Left),
        ("est. cycles/eval", Align::Right),
        ("portable", Align::Right),
        ("win", Align::Right),
    ]);
    let mut verdicts = Table::new([
        ("kernels", Align::Left),
        ("scalar", Align::Left),
        ("win on", Align::Left),
        ("est. cycles, all rows", Align::Right),
        ("portable", Align::Right),
        ("win", Align::Right),
        ("verdict", Align::Left),
    ]);
    for (group, scalar, part, kernels) in KERNEL_GROUPS {
        let jobs = jobs(&implicit, |kind| kind == *scalar);
        let with = measure(simulator, &jobs)?;
        let portable = target::portable_simulator(kernels)?;
        let without = measure(&portable, &jobs)?;
        let (mut total_with, mut total_without) = (0.0, 0.0);
        for (w, p) in part_cycles(&with, *part)
            .into_iter()
            .zip(part_cycles(&without, *part))
        {
            let (model, measured, mode, cycles) = w;
            let portable_cycles = p.3;
            if cycles == portable_cycles {
                continue; // the group does not run here
            }
            total_with += cycles;
            total_without += portable_cycles;
            table.push([
                group.to_string(),
                model,
                measured.to_string(),
                mode.to_string(),
                format!("{cycles:.1}"),
                format!("{portable_cycles:.1}"),
                percent(1.0 - cycles / portable_cycles),
            ]);
        }
        let win = 1.0 - total_with / total_without;
        verdicts.push([
            group.to_string(),
            scalar.name().to_string(),
            part.name().to_string(),
            format!("{total_with:.1}"),
            format!("{total_without:.1}"),
            percent(win),
            if win >= KEEP_WIN { "keep" } else { "delete" }.to_string(),
        ]);
    }
    let text = format!(
        "# The Cortex-M4F kernels against the portable loops\n\nWritten by `neurosurf sim-bench \
         --kernel-comparison docs/performance/kernels.md`: the implicit models of \
         `docs/performance/target.md` (the width-9 modules the kernels serve) on the simulated \
         Cortex-M4F, once with every kernel and once per group with that group turned off \
         (`--cfg neurosurf_portable=\"<kernel>\"`; the core's portable loops run instead, with \
         the same results). Cycles are the estimate of `docs/target.md` (the Cortex-M4 TRM's \
         timings on zero-wait-state memory), per evaluation.\n\nA group is kept when its \
         kernels save at least {:.0} % of the portable build's cycles on the part of the \
         evaluation the group replaces, summed over every row where it runs. For the backward \
         pass that part is the backward pass itself: field+gradient − field of the same model \
         and mode, in each build (its kernels run only there, so the field rows are the same in \
         both builds). For the forward layers it is the whole evaluation, field and \
         field+gradient: their own loops are only part of it, so the win on those loops is at \
         least the win shown.\n\nThe `f32` layer products and the Q16.16 input normalization \
         have no kernel: in estimated cycles, `vldmia` + `vmla` kernels for the f32 products \
         (affine and transposed; 9×9, 9×3, 1×9) were 6.9–24.6 % slower than the portable loops \
         on every row (11.1 % over all rows), and a normalization kernel saved between −2.7 % \
         and +1.5 % of an evaluation (1.1 % over all rows).\n\n{}\n{}",
        KEEP_WIN * 100.0,
        verdicts.to_markdown(),
        table.to_markdown()
    );
    write_atomic(path, text.as_bytes())?;
    println!("wrote {}", path.display());
    Ok(())
}

/// `x` as a signed percentage with one decimal.
fn percent(x: f64) -> String {
    format!("{:+.1} %", 100.0 * x)
}

/// A model to measure: its blob for each scalar, its evaluation points (or parameters), and
/// its two ops (the value alone, and with its derivative).
#[derive(Clone, Debug)]
struct Subject {
    name: String,
    path: PathBuf,
    blobs: Vec<(ScalarKind, Vec<u8>)>,
    /// `arity` coordinates per point, one point after the other.
    points: Vec<f32>,
    arity: usize,
    ops: [Op; 2],
}

#[derive(Serialize)]
struct Row {
    model: String,
    scalar: &'static str,
    op: &'static str,
    mode: &'static str,
    points: usize,
    instructions_per_eval: f64,
    /// Estimated Cortex-M4 cycles (the TRM's table, see `neurosurf_firmware_sim::plugin`).
    cycles_per_eval: f64,
    macs: usize,
    instructions_per_mac: f64,
    stack_bytes: u32,
}

#[derive(Serialize)]
struct Ratio {
    model: String,
    op: &'static str,
    mode: &'static str,
    q16_over_f32: f64,
}

#[derive(Serialize)]
struct Bench {
    machine: &'static str,
    footprint: Footprint,
    rows: Vec<Row>,
    ratios: Vec<Ratio>,
}

pub fn run(args: &Args) -> Result<()> {
    if let Some(path) = &args.retrain {
        stored::write(&built_in::train()?, path)?;
        println!(
            "wrote {}; build `neurosurf` again to measure these subjects",
            path.display()
        );
        return Ok(());
    }
    let simulator = target::simulator()?;
    let mut subjects = stored::load()?;
    for path in &args.models {
        let bytes = target::read_blob(path)?;
        if let Some(parametric) = parametric(path, &bytes)? {
            subjects.push(parametric);
            continue;
        }
        let decoded = implicit::from_blob(&bytes, path)?;
        subjects.push(Subject {
            name: path.display().to_string(),
            path: path.clone(),
            arity: 3,
            points: points(
                &decoded.network,
                box_size(decoded.metadata.as_ref().and_then(|m| m.summary.as_ref())),
            ),
            blobs: vec![
                (ScalarKind::F32, bytes.clone()),
                (ScalarKind::Q16_16, bytes),
            ],
            ops: [Op::Field, Op::FieldGradient],
        });
    }
    if let Some(path) = &args.kernel_comparison {
        return kernel_comparison(&simulator, &subjects, path);
    }
    let rows = measure(&simulator, &jobs(&subjects, |_| true))?;
    let ratios = ratios(&rows);
    let bench = Bench {
        machine: TARGET_MACHINE,
        footprint: simulator.firmware().footprint,
        rows,
        ratios,
    };
    if args.json {
        return output::json(&bench);
    }
    if let Some(path) = &args.markdown {
        let text = report(&bench, true);
        if args.check {
            let committed = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            if let Err(first_difference) = check::compare(&committed, &text) {
                anyhow::bail!(
                    "{} does not match this run; regenerate it with `neurosurf sim-bench \
                     --markdown {}` and commit it (a change of instruction counts or stack \
                     is a change of the core or the firmware){first_difference}",
                    path.display(),
                    path.display()
                );
            }
            println!("{} matches this run", path.display());
            return Ok(());
        }
        write_atomic(path, text.as_bytes())?;
        println!("wrote {}", path.display());
        return Ok(());
    }
    print!("{}", report(&bench, false));
    Ok(())
}

/// A parametric blob (curve, spline surface, Cao En network, surface network) as a subject, measured at the
/// first [`POINTS`] parameters of its default covering set; `None` for any other kind.
fn parametric(path: &std::path::Path, bytes: &[u8]) -> Result<Option<Subject>> {
    let model = LoadedModel::from_bytes(bytes.to_vec(), path)?;
    let Some(set) = ParameterSet::covering(&model) else {
        return Ok(None);
    };
    // Every POINTS-th point of a long set, so the run spans the domain.
    let stride = (set.points.len() / POINTS).max(1);
    Ok(Some(Subject {
        name: path.display().to_string(),
        path: path.to_path_buf(),
        blobs: vec![
            (ScalarKind::F32, bytes.to_vec()),
            (ScalarKind::Q16_16, bytes.to_vec()),
        ],
        points: set
            .points
            .iter()
            .step_by(stride)
            .take(POINTS)
            .flatten()
            .map(|&c| c as f32)
            .collect(),
        arity: model.query_arity(),
        ops: [Op::Position, Op::PositionDirection],
    }))
}

fn box_size(summary: Option<&TrainingSummary>) -> f64 {
    summary.map_or(ImplicitOptions::default().box_size, |s| s.options.box_size)
}

/// The first [`POINTS`] points on the model's surface, as the core receives them.
fn points(network: &ImplicitNetwork, box_size: f64) -> Vec<f32> {
    EvaluationPoints::on_surface(network, box_size, SURFACE_SAMPLES)
        .points
        .iter()
        .take(POINTS)
        .flatten()
        .map(|&c| c as f32)
        .collect()
}

/// Q16.16 instructions over f32 instructions for every (model, op, mode) measured in both.
fn ratios(rows: &[Row]) -> Vec<Ratio> {
    rows.iter()
        .filter(|r| r.scalar == ScalarKind::F32.name())
        .filter_map(|f| {
            let q = rows.iter().find(|q| {
                q.scalar == ScalarKind::Q16_16.name()
                    && q.model == f.model
                    && q.op == f.op
                    && q.mode == f.mode
            })?;
            Some(Ratio {
                model: f.model.clone(),
                op: f.op,
                mode: f.mode,
                q16_over_f32: q.instructions_per_eval / f.instructions_per_eval,
            })
        })
        .collect()
}

/// The report: the cost table, the Q16.16 ÷ f32 ratios and the firmware's footprint, as
/// aligned text or (for `--markdown`, a page of `docs/performance/`) Markdown.
fn report(bench: &Bench, markdown: bool) -> String {
    let render = |t: &Table| {
        if markdown {
            t.to_markdown()
        } else {
            t.to_text()
        }
    };
    let mut out = String::new();
    if markdown {
        out.push_str(
            "# The core on the simulated Cortex-M4F\n\nWritten by `neurosurf sim-bench --markdown \
             docs/performance/target.md`; `scripts/test.sh` checks that the file matches a fresh \
             run (instruction counts and stack are exact and repeatable for the models and points \
             stored in `cli/src/sim_bench/subjects.json`; the cycle estimates made from them, \
             within 2 %, as they move slightly with where the code lands). Estimated cycles price every executed instruction with the Cortex-M4 \
             TRM's timing tables on zero-wait-state memory; see `docs/target.md` for the \
             assumptions. ",
        );
    }
    out.push_str(&format!(
        "Cost of one evaluation on the simulated Cortex-M4F ({}), {POINTS} points (or parameters) \
         per run.\n\n",
        bench.machine
    ));
    let mut table = Table::new([
        ("model", Align::Left),
        ("scalar", Align::Left),
        ("op", Align::Left),
        ("mode", Align::Left),
        ("instr/eval", Align::Right),
        ("est. cycles/eval", Align::Right),
        ("MACs", Align::Right),
        ("instr/MAC", Align::Right),
        ("stack B", Align::Right),
    ]);
    for r in &bench.rows {
        table.push([
            r.model.clone(),
            r.scalar.to_string(),
            r.op.to_string(),
            r.mode.to_string(),
            format!("{:.1}", r.instructions_per_eval),
            format!("{:.1}", r.cycles_per_eval),
            r.macs.to_string(),
            format!("{:.2}", r.instructions_per_mac),
            r.stack_bytes.to_string(),
        ]);
    }
    out.push_str(&render(&table));
    let mut ratios = Table::new([
        ("model", Align::Left),
        ("op", Align::Left),
        ("mode", Align::Left),
        ("q16.16 / f32 instructions", Align::Right),
    ]);
    for r in &bench.ratios {
        ratios.push([
            r.model.clone(),
            r.op.to_string(),
            r.mode.to_string(),
            format!("{:.2}", r.q16_over_f32),
        ]);
    }
    out.push('\n');
    out.push_str(&render(&ratios));
    let f = &bench.footprint;
    out.push_str(&format!(
        "\nFirmware: flash {} of {} bytes ({:.1} %), static RAM {} of {} bytes ({:.1} %); \
         the stack column is each run's high-water mark.\n",
        f.flash_bytes,
        f.flash_budget,
        100.0 * f.flash_bytes as f64 / f.flash_budget as f64,
        f.static_ram_bytes,
        f.ram_budget,
        100.0 * f.static_ram_bytes as f64 / f.ram_budget as f64
    ));
    out
}

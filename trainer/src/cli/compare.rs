//! `neurosurf compare`: the fixed-versus-float report — f32 and Q16.16, on the host and on the
//! simulated Cortex-M4F, against the trainer's f64 reference.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use neurosurf_core::scalar::ScalarKind;
use neurosurf_firmware_sim::Job;
use serde::Serialize;

use neurosurf_trainer::compare::{
    CompareRow, EvaluationPoints, PointSource, SURFACE_SAMPLES, comparison_table,
};
use neurosurf_trainer::evaluate::{LoadedModel, Precision};
use neurosurf_trainer::implicit::ImplicitOptions;
use neurosurf_trainer::io::{read_query_points, write_atomic};

use super::output;
use super::target;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob (modular implicit).
    model: PathBuf,
    /// Query points: PLY, or text with 3 (or 6) numbers per line. Default: points on the
    /// model's own surface (see above).
    #[arg(long)]
    points: Option<PathBuf>,
    /// Print the report as JSON instead of the table.
    #[arg(long)]
    json: bool,
    /// Also write the report as a Markdown table to FILE (atomically).
    #[arg(long, value_name = "FILE")]
    markdown: Option<PathBuf>,
}

#[derive(Serialize)]
struct Report<'a> {
    model: &'a Path,
    stored_as: &'static str,
    reference: &'static str,
    points: usize,
    point_source: PointSource,
    box_samples: usize,
    box_samples_on_surface: usize,
    rows: Vec<CompareRow>,
    markdown: Option<&'a Path>,
}

pub fn run(args: &Args) -> Result<()> {
    let model = LoadedModel::read(&args.model)?;
    let LoadedModel::Implicit { bytes, decoded } = &model else {
        bail!(
            "{}: the RBF baseline is a host-only model; compare needs a modular implicit model",
            args.model.display()
        );
    };
    let points = match &args.points {
        Some(path) => EvaluationPoints::from_file(&read_query_points(path)?),
        None => {
            let box_size = decoded
                .metadata
                .as_ref()
                .and_then(|m| m.summary.as_ref())
                .map_or(ImplicitOptions::default().box_size, |s| s.options.box_size);
            EvaluationPoints::on_surface(&decoded.network, box_size, SURFACE_SAMPLES)
        }
    };
    if points.points.is_empty() {
        bail!("no points to compare at");
    }
    let evaluate = |precision: Precision| {
        model
            .evaluate(&points.points, precision)
            .with_context(|| format!("cannot evaluate {} in {precision}", args.model.display()))
    };
    let reference = evaluate(Precision::F64)?;
    let inputs: Vec<[f32; 3]> = points.points.iter().map(|p| p.map(|c| c as f32)).collect();
    let simulator = target::simulator()?;
    let mut rows = Vec::new();
    for (precision, scalar) in [
        (Precision::F32, ScalarKind::F32),
        (Precision::Q16, ScalarKind::Q16_16),
    ] {
        let host = evaluate(precision)?;
        let job = Job::field_gradient(bytes, scalar, &inputs);
        let on_target = target::run(&simulator, &job, &args.model)?.samples();
        rows.push(CompareRow::host(scalar, &reference, &host)?);
        rows.push(CompareRow::target(scalar, &reference, &on_target, &host)?);
    }
    let report = Report {
        model: &args.model,
        stored_as: decoded.stored_as.name(),
        reference: Precision::F64.name(),
        points: points.points.len(),
        point_source: points.source,
        box_samples: points.sampled,
        box_samples_on_surface: points.projected,
        rows,
        markdown: args.markdown.as_deref(),
    };
    let table = comparison_table(&report.rows);
    if let Some(path) = &args.markdown {
        let text = format!(
            "Fixed point against float: `{}` (stored as {}), {}, against the f64 reference.\n\n{}\n{}\n",
            args.model.display(),
            report.stored_as,
            describe_points(&points, args.points.as_deref()),
            table.to_markdown(),
            LEGEND
        );
        write_atomic(path, text.as_bytes())?;
    }
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} (stored as {}): {}, against the f64 reference\n",
        args.model.display(),
        report.stored_as,
        describe_points(&points, args.points.as_deref())
    );
    print!("{table}");
    println!("\n{LEGEND}");
    if let Some(path) = &args.markdown {
        println!("wrote {}", path.display());
    }
    Ok(())
}

const LEGEND: &str = "ΔΦ = Φ − Φ_f64; angle = between the normals −∇Φ/|∇Φ|; no normal = points \
skipped because a gradient is zero; = host bits, max ulp: the target against the host in the same \
scalar (ulp = one f32 ulp, or 2⁻¹⁶ in Q16.16).";

/// Where the points came from, in words.
fn describe_points(points: &EvaluationPoints, file: Option<&Path>) -> String {
    let n = points.points.len();
    match points.source {
        PointSource::File => format!(
            "{n} points from {} (rounded to f32)",
            file.map_or_else(|| "a file".to_string(), |f| f.display().to_string())
        ),
        PointSource::Surface => format!(
            "{n} points on the model's surface (Newton-projected from {} box samples)",
            points.sampled
        ),
        PointSource::Boxes => format!(
            "{n} points in the leaves' boxes, NOT on the surface (only {} of {} samples reached \
             it)",
            points.projected, points.sampled
        ),
    }
}

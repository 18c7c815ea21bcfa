//! `neurosurf compare`: the fixed-versus-float report — f32 and Q16.16, on the host and on the
//! simulated Cortex-M4F, against the trainer's f64 reference.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use neurosurf_core::scalar::ScalarKind;
use neurosurf_firmware_sim::{Job, Simulator};
use serde::Serialize;

use neurosurf_trainer::compare::{
    CompareRow, EvaluationPoints, Measured, ParameterSet, PointSource, Quantities, SURFACE_SAMPLES,
    comparison_table, comparison_table_of,
};
use neurosurf_trainer::evaluate::{Geometry, LoadedModel, Precision};
use neurosurf_trainer::implicit::ImplicitOptions;
use neurosurf_trainer::io::read_mesh;
use neurosurf_trainer::io::{read_parameters, read_query_points, write_atomic};
use neurosurf_trainer::quality::{
    MEASURE_RESOLUTION, STRAY_RESOLUTION, Truth, TwoSided, two_sided,
};
use neurosurf_trainer::render::{
    CoreField, DEFAULT_INFLATE, Field, NetworkField, Q16Field, Region,
};
use neurosurf_trainer::table::Table;

use super::output;
use super::target;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob: modular implicit, curve, spline surface or Cao En network.
    model: PathBuf,
    /// Query points: PLY, or text with 3 (or 6) numbers per line. Default: points on the
    /// model's own surface (see above). For a curve: t per line (default: 1001 uniform
    /// values); for a spline surface: `u v` per line (default: a 33 × 33 grid); for a Cao En
    /// network: its m source coordinates (default: points spread over its sphere or torus).
    #[arg(long)]
    points: Option<PathBuf>,
    /// The true surface (OBJ or PLY mesh) of an implicit model: also measure the model both
    /// ways against it, in f64 and in the core's f32 and Q16.16 (distances, normals, stray sign
    /// changes, mesh pieces).
    #[arg(long, value_name = "MESH")]
    truth: Option<PathBuf>,
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
    /// Against `--truth`, per precision.
    truth: Vec<(&'static str, TwoSided)>,
    markdown: Option<&'a Path>,
}

pub fn run(args: &Args) -> Result<()> {
    let model = LoadedModel::read(&args.model)?;
    if model.geometry_columns().is_some() {
        return run_parametric(args, &model);
    }
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
    let inputs: Vec<[f32; 3]> = points.points.iter().map(|p| p.map(|c| c as f32)).collect();
    let rows = measure_rows(args, evaluate, |simulator, scalar| {
        let job = Job::field_gradient(bytes, scalar, &inputs);
        Ok(target::run(simulator, &job, &args.model)?.samples())
    })?;
    let truth = match &args.truth {
        Some(path) => {
            let truth = Truth::from_mesh(&read_mesh(path)?)
                .with_context(|| format!("cannot use {} as the true surface", path.display()))?;
            let box_size = decoded
                .metadata
                .as_ref()
                .and_then(|m| m.summary.as_ref())
                .map_or(ImplicitOptions::default().box_size, |s| s.options.box_size);
            let f64_field = NetworkField::new(&decoded.network, box_size, DEFAULT_INFLATE)?;
            let regions = Region::of_network(&decoded.network, box_size, DEFAULT_INFLATE);
            let f32_field = CoreField::new(bytes, regions.clone())?;
            let q16_field = Q16Field::new(bytes, regions)?;
            let measure =
                |field: &dyn Field| two_sided(field, &truth, MEASURE_RESOLUTION, STRAY_RESOLUTION);
            vec![
                (Precision::F64.name(), measure(&f64_field)?),
                (Precision::F32.name(), measure(&f32_field)?),
                (Precision::Q16.name(), measure(&q16_field)?),
            ]
        }
        None => Vec::new(),
    };
    let report = Report {
        model: &args.model,
        stored_as: decoded.stored_as.name(),
        reference: Precision::F64.name(),
        points: points.points.len(),
        point_source: points.source,
        box_samples: points.sampled,
        box_samples_on_surface: points.projected,
        rows,
        truth,
        markdown: args.markdown.as_deref(),
    };
    let table = comparison_table(&report.rows);
    let heading = format!(
        "{} (stored as {}): {}",
        args.model.display(),
        report.stored_as,
        describe_points(&points, args.points.as_deref())
    );
    publish(args, &heading, &table, LEGEND, &report)?;
    if !args.json {
        for (precision, measure) in &report.truth {
            println!("against the true surface, {precision}: {measure}");
        }
    }
    Ok(())
}

/// The f32 and Q16.16 rows, host and target, against the f64 reference: `evaluate` runs the
/// host (and the reference), `on_target` the simulated Cortex-M4F.
fn measure_rows<T: Measured>(
    args: &Args,
    evaluate: impl Fn(Precision) -> Result<Vec<T>>,
    on_target: impl Fn(&Simulator, ScalarKind) -> Result<Vec<T>>,
) -> Result<Vec<CompareRow>> {
    let reference = evaluate(Precision::F64)?;
    let simulator = target::simulator()?;
    let mut rows = Vec::new();
    for (precision, scalar) in [
        (Precision::F32, ScalarKind::F32),
        (Precision::Q16, ScalarKind::Q16_16),
    ] {
        let host = evaluate(precision)?;
        let target = on_target(&simulator, scalar)
            .with_context(|| format!("{} on the target", args.model.display()))?;
        rows.push(CompareRow::host(scalar, &reference, &host)?);
        rows.push(CompareRow::target(scalar, &reference, &target, &host)?);
    }
    Ok(rows)
}

/// Writes the Markdown file when asked, then prints the JSON report or the table and its
/// legend. `heading` names the model and the points.
fn publish(
    args: &Args,
    heading: &str,
    table: &Table,
    legend: &str,
    report: &impl Serialize,
) -> Result<()> {
    if let Some(path) = &args.markdown {
        let text = format!(
            "Fixed point against float: {heading}, against the f64 reference.\n\n{}\n{legend}\n",
            table.to_markdown(),
        );
        write_atomic(path, text.as_bytes())?;
    }
    if args.json {
        return output::json(report);
    }
    println!("{heading}, against the f64 reference\n");
    print!("{table}");
    println!("\n{legend}");
    if let Some(path) = &args.markdown {
        println!("wrote {}", path.display());
    }
    Ok(())
}

#[derive(Serialize)]
struct ParametricReport<'a> {
    model: &'a Path,
    kind: &'static str,
    stored_as: &'static str,
    reference: &'static str,
    points: usize,
    rows: Vec<CompareRow>,
    markdown: Option<&'a Path>,
}

/// `compare` for the parametric kinds: outputs and tangents or normals.
fn run_parametric(args: &Args, model: &LoadedModel) -> Result<()> {
    let (quantities, stored_as) = match model {
        LoadedModel::Curve { decoded, .. } => (Quantities::CURVE, decoded.stored_as),
        LoadedModel::SplineSurface { decoded, .. } => (Quantities::SURFACE, decoded.stored_as),
        LoadedModel::CaoEn { decoded, .. } => (Quantities::SURFACE, decoded.stored_as),
        LoadedModel::SurfaceNetwork { decoded, .. } => (Quantities::SURFACE, decoded.stored_as),
        _ => bail!("not a parametric model"),
    };
    let bytes = model.bytes().unwrap_or_default();
    let arity = model.query_arity();
    let (parameters, source) = match &args.points {
        Some(path) => {
            let points = read_parameters(path, arity)?;
            let source = format!("{} parameters from {}", points.len(), path.display());
            (points, source)
        }
        None => {
            let set = ParameterSet::covering(model).context("not a parametric model")?;
            (set.points, set.description)
        }
    };
    if parameters.is_empty() {
        bail!("no parameters to compare at");
    }
    let evaluate = |precision: Precision| {
        model
            .evaluate_geometry(&parameters, precision)
            .with_context(|| format!("cannot evaluate {} in {precision}", args.model.display()))
    };
    let inputs: Vec<f32> = parameters.iter().flatten().map(|&c| c as f32).collect();
    let rows = measure_rows(args, evaluate, |simulator, scalar| {
        let job = Job::position_direction(bytes, scalar, &inputs, arity);
        let run = target::run(simulator, &job, &args.model)?;
        Ok(run.geometry().into_iter().map(Geometry::from).collect())
    })?;
    let report = ParametricReport {
        model: &args.model,
        kind: model.kind().name(),
        stored_as: stored_as.name(),
        reference: Precision::F64.name(),
        points: parameters.len(),
        rows,
        markdown: args.markdown.as_deref(),
    };
    let table = comparison_table_of(&report.rows, quantities);

    let legend = format!(
        "Δp = distance from the f64 position; angle = between the {dir}s and the f64 {dir}s; \
         no {dir} = points skipped because a {dir} is zero; = host bits, max ulp: the target \
         against the host in the same scalar (ulp = one f32 ulp, or 2⁻¹⁶ in Q16.16).",
        dir = quantities.direction
    );
    let heading = format!(
        "{} ({}, stored as {}): {source}",
        args.model.display(),
        report.kind,
        report.stored_as
    );
    publish(args, &heading, &table, &legend, &report)
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

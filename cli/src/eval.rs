//! `neurosurf eval`: Φ and ∇Φ of a model at query points, as CSV (or JSON).

use std::io::{BufWriter, Write};
use std::path::PathBuf;

use anyhow::{Context, Result};
use serde::Serialize;

use neurosurf_trainer::evaluate::{Geometry, LoadedModel, Precision};
use neurosurf_trainer::io::{read_parameters, read_query_points};

use super::output;

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob.
    model: PathBuf,
    /// Query points: PLY, or text with 3 (or 6) numbers per line. For a curve, text with one
    /// parameter t ∈ [0, 1] per line; for a spline surface, two (u v); for a Cao En network,
    /// its m source coordinates.
    #[arg(long)]
    points: PathBuf,
    /// `f64` (the trainer's reference), `f32` or `q16.16` (through neurosurf-core).
    #[arg(long, default_value = "f64")]
    scalar: Precision,
    /// Print JSON objects instead of CSV.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Row {
    x: f64,
    y: f64,
    z: f64,
    phi: f64,
    gx: f64,
    gy: f64,
    gz: f64,
}

pub fn run(args: &Args) -> Result<()> {
    let model = LoadedModel::read(&args.model)?;
    if let Some(columns) = model.geometry_columns() {
        let parameters = read_parameters(&args.points, model.query_arity())?;
        if let LoadedModel::SurfaceNetwork { decoded, .. } = &model
            && let Some(summary) = &decoded.summary
        {
            let outside = parameters
                .iter()
                .filter(|p| !summary.covers(p[0], p[1]))
                .count();
            if outside > 0 {
                eprintln!(
                    "warning: {outside} of {} parameter points lie outside the region the \
                     network was fitted on ({} corners, stored in {}): there it extrapolates",
                    parameters.len(),
                    summary.region.len(),
                    args.model.display()
                );
            }
        }
        let rows = model
            .evaluate_geometry(&parameters, args.scalar)
            .with_context(|| format!("cannot evaluate {}", args.model.display()))?;
        return write_geometry(&columns, &parameters, &rows, args.json);
    }
    let points = read_query_points(&args.points)?;
    let samples = model
        .evaluate(&points, args.scalar)
        .with_context(|| format!("cannot evaluate {}", args.model.display()))?;
    if args.json {
        let rows: Vec<Row> = points
            .iter()
            .zip(&samples)
            .map(|(p, (phi, g))| Row {
                x: p[0],
                y: p[1],
                z: p[2],
                phi: *phi,
                gx: g[0],
                gy: g[1],
                gz: g[2],
            })
            .collect();
        return output::json(&rows);
    }
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    write_csv(&mut out, &points, &samples).context("cannot write to stdout")?;
    Ok(())
}

/// Prints parametric rows: the parameters, the outputs and the direction, as CSV under
/// `columns`, or as JSON objects keyed by them.
pub fn write_geometry(
    columns: &[String],
    parameters: &[Vec<f64>],
    rows: &[Geometry],
    json: bool,
) -> Result<()> {
    let values = |p: &Vec<f64>, g: &Geometry| {
        let mut row = p.clone();
        row.extend(&g.output);
        row.extend(g.direction);
        row
    };
    if json {
        let objects: Vec<serde_json::Map<String, serde_json::Value>> = parameters
            .iter()
            .zip(rows)
            .map(|(p, g)| {
                columns
                    .iter()
                    .zip(values(p, g))
                    .map(|(c, v)| (c.clone(), serde_json::Value::from(v)))
                    .collect()
            })
            .collect();
        return output::json(&objects);
    }
    let stdout = std::io::stdout();
    let mut out = BufWriter::new(stdout.lock());
    let mut write = || -> std::io::Result<()> {
        writeln!(out, "{}", columns.join(","))?;
        for (p, g) in parameters.iter().zip(rows) {
            let line: Vec<String> = values(p, g).iter().map(f64::to_string).collect();
            writeln!(out, "{}", line.join(","))?;
        }
        out.flush()
    };
    write().context("cannot write to stdout")
}

/// Writes the CSV: header `x,y,z,phi,gx,gy,gz`, then one line per point with every number in
/// its shortest exact decimal form (f32 and Q16.16 results are exact in f64).
pub fn write_csv(
    out: &mut impl Write,
    points: &[[f64; 3]],
    samples: &[(f64, [f64; 3])],
) -> std::io::Result<()> {
    writeln!(out, "x,y,z,phi,gx,gy,gz")?;
    for (p, (phi, g)) in points.iter().zip(samples) {
        writeln!(
            out,
            "{},{},{},{},{},{},{}",
            p[0], p[1], p[2], phi, g[0], g[1], g[2]
        )?;
    }
    out.flush()
}

//! `neurosurf curve`: Hoffmann & Várady's curves from scattered points — sample test data,
//! fit a curve or a surface, plot, benchmark.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Subcommand, ValueEnum};
use serde::Serialize;

use neurosurf_trainer::curve::{
    BENCHMARK_SIZES, BSplineCurve, BandReport, CurveOptions, CurvePoints, FitSummary, LongSteps,
    MIN_POINTS, PlotLayers, PlotOptions, SampleCurve, SampleOptions, SurfaceOptions, Topology,
    TrainingReport, benchmark, curve_svg, curve_to_blob, curves_dxf, export_curve, export_surface,
    fit_surface, interpolation_parameter, point_groups, reconstruct_curve, sample_curve,
    surface_mesh, surface_to_blob, write_plot,
};
use neurosurf_trainer::evaluate::{LoadedModel, Precision};
use neurosurf_trainer::io::{read_scattered_points, write_atomic, write_mesh};
use neurosurf_trainer::table::{Align, Table};

use super::output::{self, blob_scalar, comma_list, wrote_blob};

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Scattered, shuffled, noisy points on a known curve (text: `x y` or `x y z` per line).
    Sample(SampleArgs),
    /// Order scattered points with a Kohonen chain and fit a uniform cubic B-spline; write its
    /// blob (and a plot).
    Fit(FitArgs),
    /// Parametrize scattered 3-D points with a 2-D Kohonen map and fit a tensor-product cubic
    /// B-spline surface; write its blob (and a mesh).
    Surface(SurfaceArgs),
    /// Plot a curve blob (and, optionally, the points it was fitted to) as SVG or PNG.
    Plot(PlotArgs),
    /// Time ordering and fitting on noisy ellipses of 20 to 20 000 points.
    Bench(BenchArgs),
    /// Export a curve or spline surface blob for CAD: degree, knots and control points as
    /// JSON, and a 2-D curve as an SVG path of cubic Béziers in model coordinates.
    Export(ExportArgs),
}

pub fn run(command: &Command) -> Result<()> {
    match command {
        Command::Sample(args) => sample(args),
        Command::Fit(args) => fit(args),
        Command::Surface(args) => surface(args),
        Command::Plot(args) => plot(args),
        Command::Bench(args) => bench(args),
        Command::Export(args) => export(args),
    }
}

/// The built-in test curves.
#[derive(Copy, Clone, Debug, ValueEnum)]
pub enum CurveName {
    /// Closed, 2-D.
    Ellipse,
    /// Open, 2-D, two turns.
    Spiral,
    /// Closed, 2-D: a figure-eight whose branches come within 0.15 at the waist.
    Peanut,
    /// Closed, 3-D: the trefoil knot.
    Trefoil,
}

impl CurveName {
    fn curve(self) -> SampleCurve {
        match self {
            CurveName::Ellipse => SampleCurve::Ellipse,
            CurveName::Spiral => SampleCurve::Spiral,
            CurveName::Peanut => SampleCurve::Peanut,
            CurveName::Trefoil => SampleCurve::Trefoil,
        }
    }
}

/// Where and how a fit writes its blob.
#[derive(Debug, clap::Args)]
pub struct BlobArgs {
    /// Random seed of the Kohonen training (same seed, same result).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// How the blob stores the control points: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    scalar: Precision,
    /// Output blob.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// Which curve.
    #[arg(value_enum)]
    curve: CurveName,
    /// Number of points.
    #[arg(long = "points", short = 'n', default_value_t = 200)]
    count: usize,
    /// Gaussian noise, as a fraction of the mean point spacing.
    #[arg(long, default_value_t = SampleOptions::default().noise)]
    noise: f64,
    /// Random seed (same seed, same points).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output text file.
    #[arg(long)]
    out: PathBuf,
}

fn sample(args: &SampleArgs) -> Result<()> {
    let options = SampleOptions {
        count: args.count,
        noise: args.noise,
        seed: args.seed,
        ..SampleOptions::default()
    };
    let curve = args.curve.curve();
    let sample = sample_curve(curve, &options)?;
    let mut text = format!(
        "# {:?}: {} shuffled points, noise {} of the spacing, seed {}\n",
        curve, args.count, args.noise, args.seed
    );
    text.push_str(&rows_text(&sample.points, curve.dimension()));
    write_atomic(&args.out, text.as_bytes())?;
    eprintln!("wrote {} points to {}", args.count, args.out.display());
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Scattered points: text with `x y` or `x y z` per line, or PLY.
    points: PathBuf,
    /// The curve closes on itself (a ring of neurons); without it the curve is open.
    #[arg(long)]
    closed: bool,
    /// Fit the spline through every ordered point instead of a least-squares approximation.
    #[arg(long)]
    interpolate: bool,
    /// Control points of the approximation (default: a fifth of the points, 8 to 512; the
    /// core holds at most 512).
    #[arg(long)]
    control: Option<usize>,
    /// Smoothing weight λ of the approximation: a penalty λ·Σ|P_{k−1} − 2P_k + P_{k+1}|² on
    /// the control polygon's second differences, relative to the data term. The default only
    /// keeps spans without data well-posed; larger values bend the curve less where the data
    /// leave it free.
    #[arg(long, value_name = "LAMBDA", default_value_t = CurveOptions::default().approximation.smoothing)]
    smoothing: f64,
    /// Neurons per input point in the chain (the paper: 4).
    #[arg(long, default_value_t = CurveOptions::default().kohonen.neurons_per_point)]
    neurons_per_point: usize,
    /// Most points the chain learns from: beyond it, a random sample of this many (drawn
    /// with the seed) sets the curve's course and every point is ordered along it. Training
    /// time grows about as the square of this count.
    #[arg(long, value_name = "COUNT", default_value_t = CurveOptions::default().kohonen.max_trained_points)]
    chain_points: usize,
    /// Keep the paper's order as the chain gives it (no 2-opt repair).
    #[arg(long)]
    no_refine: bool,
    /// Use the fewest control points that keep every point within this distance of the
    /// curve (in the points' units) instead of the default count.
    #[arg(long, value_name = "DISTANCE", conflicts_with = "control")]
    tolerance: Option<f64>,
    /// Round every corner: without it, points where the data turns sharply between two
    /// straight arms become sharp corners of the approximation.
    #[arg(long)]
    no_corners: bool,
    #[command(flatten)]
    blob: BlobArgs,
    /// Also draw the points, their order and the curve (`.svg` or `.png`).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Also write the fitted curve as a polyline: text, one vertex per line (16 per segment).
    #[arg(long, value_name = "FILE")]
    polyline: Option<PathBuf>,
    /// Also write the recovered order: text, one 0-based point index per line (points counted
    /// in file order, comments skipped), in order along the curve.
    #[arg(long, value_name = "FILE")]
    order: Option<PathBuf>,
    /// Size of the plot in pixels, `WIDTH,HEIGHT`.
    #[arg(long, value_parser = comma_list::<u32, 2>, default_value = "800,800")]
    plot_size: [u32; 2],
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct FitReport<'a> {
    out: &'a Path,
    stored_as: &'static str,
    blob_bytes: usize,
    dimension: usize,
    closed: bool,
    control_points: usize,
    segments: usize,
    chain_iterations: usize,
    chain_trained_points: usize,
    chain_converged: bool,
    /// Steps of the order longer than three times its median step.
    order_long_steps: LongSteps,
    /// How a band of noise wider than the spacing was parametrized, if it was.
    band: Option<BandReport>,
    /// The points kept as sharp corners of the approximation, in order along it.
    corners: Vec<Vec<f64>>,
    /// Sizes of the separate groups the points form (largest first; one entry when they
    /// form one curve), counting groups of at least 1 % of the points.
    groups: Vec<usize>,
    /// Points in smaller groups: stray points far from the others.
    stray_points: usize,
    refine_reversals: Option<usize>,
    refine_insertions: Option<usize>,
    #[serde(flatten)]
    fit: FitSummary,
}

fn fit(args: &FitArgs) -> Result<()> {
    let scalar = blob_scalar(args.blob.scalar)?;
    neurosurf_trainer::io::check_output(&args.blob.out)?;
    let (dimension, raw) = read_scattered_points(&args.points)?;
    let points = CurvePoints::new(dimension, raw)
        .with_context(|| format!("cannot fit a curve to {}", args.points.display()))?;
    neurosurf_trainer::curve::check_curve_capacity(
        points.len(),
        args.closed,
        args.control,
        args.interpolate,
    )?;
    let topology = if args.closed {
        Topology::Closed
    } else {
        Topology::Open
    };
    let mut options = CurveOptions::new(topology, args.blob.seed);
    options.kohonen.neurons_per_point = args.neurons_per_point;
    options.kohonen.max_trained_points = args.chain_points;
    options.approximation.control_points = args.control;
    if !(args.smoothing.is_finite() && (0.0..=1e6).contains(&args.smoothing)) {
        anyhow::bail!(
            "--smoothing {}: give a finite weight from 0 to 1e6 (the default is {:e})",
            args.smoothing,
            CurveOptions::default().approximation.smoothing
        );
    }
    options.approximation.smoothing = args.smoothing;
    options.approximation.corners = !args.no_corners;
    if let Some(tolerance) = args.tolerance {
        if !(tolerance.is_finite() && tolerance > 0.0) {
            anyhow::bail!("--tolerance {tolerance}: give a positive distance in the points' units");
        }
        options.approximation.tolerance = Some(tolerance);
    }
    if args.no_refine {
        options.refine = None;
    }
    let significant = (points.len() / 100).max(MIN_POINTS);
    let (groups, strays): (Vec<Vec<usize>>, Vec<Vec<usize>>) = point_groups(points.points())
        .into_iter()
        .partition(|g| g.len() >= significant);
    let groups: Vec<usize> = groups.iter().map(Vec::len).collect();
    let stray_points: usize = strays.iter().map(Vec::len).sum();
    let start = Instant::now();
    let result = reconstruct_curve(&points, &options)?;
    let seconds = start.elapsed().as_secs_f64();
    let ordered = result.ordering.ordered_points(&points);
    let (curve, method, rms, max) = if args.interpolate {
        let (rms, max) = interpolation_residual(&result.interpolation, &ordered);
        (&result.interpolation, "interpolation", rms, max)
    } else {
        let a = &result.approximation;
        (&a.curve, "approximation", a.rms_residual, a.max_residual)
    };
    let summary = FitSummary {
        method: method.into(),
        points: points.len(),
        neurons: result.training.neurons,
        seed: args.blob.seed,
        rms_residual: rms,
        max_residual: max,
        seconds,
    };
    let blob = curve_to_blob(curve, Some(&summary), scalar)?;
    if let Some(path) = &args.plot {
        check_picture_path(path)?;
    }
    neurosurf_trainer::blob::write_checked(&args.blob.out, &blob)?;
    if let Some(path) = &args.plot {
        let layers = PlotLayers {
            points: points.points(),
            order: Some(&result.ordering.order),
            closed: result.ordering.closed,
            curve: Some(curve),
            ..PlotLayers::default()
        };
        let options = PlotOptions {
            width: args.plot_size[0],
            height: args.plot_size[1],
            ..PlotOptions::default()
        };
        write_plot(path, &layers, &options)?;
    }
    if let Some(path) = &args.polyline {
        let vertices = curve.polyline(curve.segments().max(1) * 16);
        write_atomic(path, rows_text(&vertices, dimension).as_bytes())?;
    }
    if let Some(path) = &args.order {
        let text: String = result
            .ordering
            .order
            .iter()
            .map(|i| format!("{i}\n"))
            .collect();
        write_atomic(path, text.as_bytes())?;
    }
    let report = FitReport {
        out: &args.blob.out,
        stored_as: scalar.name(),
        blob_bytes: blob.len(),
        dimension,
        closed: curve.closed,
        control_points: curve.control.len(),
        segments: curve.segments(),
        chain_iterations: result.training.iterations,
        chain_trained_points: result.training.trained_points,
        chain_converged: result.training.convergence.converged(),
        order_long_steps: result.ordering.long_steps(&points, LONG_STEP),
        band: result.band.clone(),
        corners: if args.interpolate {
            Vec::new()
        } else {
            result
                .approximation
                .corners
                .iter()
                .map(|&i| ordered[i][..dimension].to_vec())
                .collect()
        },
        groups,
        stray_points,
        refine_reversals: result.refinement.as_ref().map(|r| r.reversals),
        refine_insertions: result.refinement.as_ref().map(|r| r.insertions),
        fit: summary,
    };
    if args.json {
        return output::json(&report);
    }
    let sample = if report.chain_trained_points < report.fit.points {
        format!(" trained on {} of them", report.chain_trained_points)
    } else {
        String::new()
    };
    println!(
        "{} {}-D points → {} chain of {} neurons{} ({} iterations) → {} of {} control points",
        report.fit.points,
        dimension,
        if report.closed { "closed" } else { "open" },
        report.fit.neurons,
        sample,
        report.chain_iterations,
        method,
        report.control_points
    );
    println!(
        "{}",
        convergence_text(&result.training, report.order_long_steps, report.closed)
    );
    if let Some(band) = &report.band {
        println!(
            "noise across the curve {:.3e} ({:.1}× the spacing along it): fitted at parameters \
             along the band's middle (±{} points averaged) with {} control points",
            band.noise,
            band.noise / band.spacing,
            band.window,
            report.control_points
        );
    }
    if report.groups.len() > 1 {
        println!(
            "warning: the points form {} separate groups ({} points): one curve bridges them; \
             fit each group on its own",
            report.groups.len(),
            report
                .groups
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if report.stray_points > 0 {
        println!(
            "warning: {} stray point{} far from the others: the curve reaches out to {}; \
             remove {} if noise",
            report.stray_points,
            if report.stray_points == 1 { "" } else { "s" },
            if report.stray_points == 1 {
                "it"
            } else {
                "them"
            },
            if report.stray_points == 1 {
                "it"
            } else {
                "them"
            }
        );
    }
    if !report.corners.is_empty() {
        println!(
            "{} sharp corner{} kept (--no-corners rounds them)",
            report.corners.len(),
            if report.corners.len() == 1 { "" } else { "s" }
        );
    }
    println!(
        "residual RMS {:.3e}, max {:.3e}; {:.3} s; wrote {} ({} bytes, {})",
        rms,
        max,
        seconds,
        args.blob.out.display(),
        blob.len(),
        scalar.name()
    );
    if let Some(path) = &args.plot {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// Refuses a picture path the plot writer cannot write, before anything else is written.
fn check_picture_path(path: &Path) -> Result<()> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(extension.as_deref(), Some("svg" | "png")) {
        anyhow::bail!("{}: pictures are written as .svg or .png", path.display());
    }
    Ok(())
}

/// Points as text, `x y` (2-D) or `x y z` per line.
fn rows_text(points: &[[f64; 3]], dimension: usize) -> String {
    points
        .iter()
        .map(|p| match dimension {
            2 => format!("{} {}\n", p[0], p[1]),
            _ => format!("{} {} {}\n", p[0], p[1], p[2]),
        })
        .collect()
}

/// RMS and largest distance from each ordered point to the interpolating spline at its
/// parameter (zero up to rounding: the spline passes through every point).
fn interpolation_residual(curve: &BSplineCurve, ordered: &[[f64; 3]]) -> (f64, f64) {
    let n = ordered.len();
    let mut square_sum = 0.0_f64;
    let mut max = 0.0_f64;
    for (j, q) in ordered.iter().enumerate() {
        let p = curve.point(interpolation_parameter(j, n, curve.closed));
        let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
        square_sum += d * d;
        max = max.max(d);
    }
    ((square_sum / n.max(1) as f64).sqrt(), max)
}

#[derive(Debug, clap::Args)]
pub struct SurfaceArgs {
    /// Scattered 3-D points: text with `x y z` per line, or PLY.
    points: PathBuf,
    /// Map neurons along u and v, `COLUMNS,ROWS`.
    #[arg(long, value_parser = comma_list::<usize, 2>, default_value = "12,12")]
    map: [usize; 2],
    /// Control points of the surface along u and v, `U,V`.
    #[arg(long, value_parser = comma_list::<usize, 2>, default_value = "8,8")]
    control: [usize; 2],
    #[command(flatten)]
    blob: BlobArgs,
    /// Also write a triangle mesh of the surface (`.obj`, `.ply` or `.stl`).
    #[arg(long, value_name = "FILE")]
    mesh: Option<PathBuf>,
    /// Grid cells per direction of the mesh.
    #[arg(long, default_value_t = 32)]
    resolution: usize,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct SurfaceReport<'a> {
    out: &'a Path,
    stored_as: &'static str,
    blob_bytes: usize,
    control: [usize; 2],
    map_iterations: usize,
    mesh: Option<&'a Path>,
    #[serde(flatten)]
    fit: FitSummary,
}

fn surface(args: &SurfaceArgs) -> Result<()> {
    let scalar = blob_scalar(args.blob.scalar)?;
    neurosurf_trainer::io::check_output(&args.blob.out)?;
    let (dimension, raw) = read_scattered_points(&args.points)?;
    if dimension != 3 {
        anyhow::bail!(
            "{}: a surface is fitted to 3-D points, these are {dimension}-D",
            args.points.display()
        );
    }
    let points = CurvePoints::new(3, raw)
        .with_context(|| format!("cannot fit a surface to {}", args.points.display()))?;
    let mut options = SurfaceOptions::default();
    options.map.columns = args.map[0];
    options.map.rows = args.map[1];
    options.map.seed = args.blob.seed;
    options.control_u = args.control[0];
    options.control_v = args.control[1];
    let start = Instant::now();
    let fit = fit_surface(&points, &options)?;
    let seconds = start.elapsed().as_secs_f64();
    let summary = FitSummary {
        method: "surface".into(),
        points: points.len(),
        neurons: fit.map.columns * fit.map.rows,
        seed: args.blob.seed,
        rms_residual: fit.rms_residual,
        max_residual: fit.max_residual,
        seconds,
    };
    let blob = surface_to_blob(&fit.surface, Some(&summary), scalar)?;
    // Mesh first: a mesh that cannot be made or written leaves no new blob behind.
    if let Some(path) = &args.mesh {
        let mesh = surface_mesh(&fit.surface, args.resolution, args.resolution)?;
        write_mesh(path, &mesh.mesh, Some(&mesh.normals))?;
    }
    neurosurf_trainer::blob::write_checked(&args.blob.out, &blob)?;
    let report = SurfaceReport {
        out: &args.blob.out,
        stored_as: scalar.name(),
        blob_bytes: blob.len(),
        control: [fit.surface.count_u, fit.surface.count_v],
        map_iterations: fit.map_report.iterations,
        mesh: args.mesh.as_deref(),
        fit: summary,
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} points → {} × {} map ({} iterations) → {} × {} control points; residual RMS {:.3e}, \
         max {:.3e}; {:.3} s",
        report.fit.points,
        fit.map.columns,
        fit.map.rows,
        report.map_iterations,
        report.control[0],
        report.control[1],
        fit.rms_residual,
        fit.max_residual,
        seconds
    );
    wrote_blob(&args.blob.out, blob.len(), scalar, args.mesh.as_deref());
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct ExportArgs {
    /// A curve or spline surface blob.
    model: PathBuf,
    /// Write degree, knots and control points as JSON: a standard (unclamped) B-spline whose
    /// evaluation by de Boor's algorithm over its domain is `eval --scalar f64`.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write a 2-D curve as an SVG path of cubic Béziers, one per segment, in the model's
    /// coordinates.
    #[arg(long, value_name = "FILE")]
    svg: Option<PathBuf>,
    /// Write a curve as a DXF (R2000) `SPLINE` entity: degree 3, clamped knots over the
    /// parameter range [0, 1], in the model's coordinates.
    #[arg(long, value_name = "FILE")]
    dxf: Option<PathBuf>,
}

fn export(args: &ExportArgs) -> Result<()> {
    if args.json.is_none() && args.svg.is_none() && args.dxf.is_none() {
        anyhow::bail!("nothing to export: give --json FILE, --svg FILE, --dxf FILE or several");
    }
    for path in [&args.json, &args.svg, &args.dxf].into_iter().flatten() {
        neurosurf_trainer::io::check_output(path)?;
    }
    let model = LoadedModel::read(&args.model)?;
    let (json, svg, dxf) = match &model {
        LoadedModel::Curve { decoded, .. } => {
            let json = serde_json::to_string_pretty(&export_curve(&decoded.curve)?)?;
            let svg = match &args.svg {
                Some(_) => Some(curve_svg(&decoded.curve)?),
                None => None,
            };
            let dxf = match &args.dxf {
                Some(_) => Some(curves_dxf(std::slice::from_ref(&decoded.curve))?),
                None => None,
            };
            (json, svg, dxf)
        }
        LoadedModel::SplineSurface { decoded, .. } => {
            for (given, form) in [(&args.svg, "SVG"), (&args.dxf, "DXF")] {
                if given.is_some() {
                    anyhow::bail!(
                        "{}: a spline surface has no {form} form here; export it with --json",
                        args.model.display()
                    );
                }
            }
            (
                serde_json::to_string_pretty(&export_surface(&decoded.surface)?)?,
                None,
                None,
            )
        }
        other => anyhow::bail!(
            "{}: a {} model; `curve export` exports curves and spline surfaces",
            args.model.display(),
            other.kind().name()
        ),
    };
    if let Some(path) = &args.json {
        write_atomic(path, format!("{json}\n").as_bytes())?;
        println!("wrote {}", path.display());
    }
    if let (Some(path), Some(svg)) = (&args.svg, svg) {
        write_atomic(path, svg.as_bytes())?;
        println!("wrote {}", path.display());
    }
    if let (Some(path), Some(dxf)) = (&args.dxf, dxf) {
        write_atomic(path, &dxf)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct PlotArgs {
    /// A curve blob.
    model: PathBuf,
    /// The scattered points to draw with it (text or PLY).
    #[arg(long)]
    points: Option<PathBuf>,
    /// Also draw the control polygon.
    #[arg(long)]
    control_polygon: bool,
    /// Picture size in pixels, `WIDTH,HEIGHT`.
    #[arg(long, value_parser = comma_list::<u32, 2>, default_value = "800,800")]
    size: [u32; 2],
    /// Output picture (`.svg` or `.png`).
    #[arg(long)]
    out: PathBuf,
}

fn plot(args: &PlotArgs) -> Result<()> {
    let model = LoadedModel::read(&args.model)?;
    let LoadedModel::Curve { decoded, .. } = &model else {
        anyhow::bail!(
            "{}: a {} model; `curve plot` draws curves (mesh surfaces with `curve surface \
             --mesh`)",
            args.model.display(),
            model.kind().name()
        );
    };
    let points = match &args.points {
        Some(path) => read_scattered_points(path)?.1,
        None => Vec::new(),
    };
    let layers = PlotLayers {
        points: &points,
        curve: Some(&decoded.curve),
        control_polygon: args.control_polygon,
        ..PlotLayers::default()
    };
    let options = PlotOptions {
        width: args.size[0],
        height: args.size[1],
        title: Some(args.model.display().to_string()),
        ..PlotOptions::default()
    };
    write_plot(&args.out, &layers, &options)?;
    println!("wrote {}", args.out.display());
    Ok(())
}

/// A step of the order this many times its median step counts as a jump.
const LONG_STEP: f64 = 3.0;

/// What the chain's convergence tests say, and whether it matters: the tests judge the chain;
/// the order read off it is judged by its jumps.
fn convergence_text(training: &TrainingReport, jumps: LongSteps, closed: bool) -> String {
    let c = &training.convergence;
    let spacings = |d: f64| d / training.spacing;
    let chain = if c.converged() {
        "chain: converged (both of the paper's tests)".to_string()
    } else {
        let mut failed = Vec::new();
        if !c.within_epsilon {
            failed.push(format!(
                "a point lies {:.2} spacings from its nearest neuron (ε = {:.2})",
                spacings(c.worst_input_distance),
                spacings(c.epsilon)
            ));
        }
        if !c.on_neighbour_lines {
            failed.push(format!(
                "an idle neuron lies {:.2} spacings off its neighbours' line (tolerance {:.2})",
                spacings(c.worst_line_distance),
                spacings(c.line_tolerance)
            ));
        }
        format!(
            "chain: the paper's tests are not met ({}); they judge the chain, not the order",
            failed.join("; ")
        )
    };
    let order = if jumps.count == 0 {
        format!(
            "order: no step longer than {LONG_STEP}× the median step (longest {:.1}×), so the \
             fit is not affected",
            jumps.longest_ratio
        )
    } else {
        format!(
            "order: {} steps longer than {LONG_STEP}× the median step (longest {:.1}×): gaps \
             in the data, or points out of order there (try another --seed or more \
             --neurons-per-point)",
            jumps.count, jumps.longest_ratio
        )
    };
    // An open order whose ends are a step or so apart went round a closed curve; a closed
    // order with one step far longer than all others bridges the ends of an open one.
    let topology = if !closed && jumps.ends_ratio <= LONG_STEP {
        format!(
            "\nwarning: the order's ends are {:.1} median steps apart: the curve looks closed; \
             fit it with --closed",
            jumps.ends_ratio
        )
    } else if closed && jumps.count == 1 && jumps.longest_ratio > 2.0 * LONG_STEP {
        format!(
            "\nwarning: one step of the ring is {:.1}× the median, all others under {LONG_STEP}×: \
             it bridges the ends of an open curve; fit it without --closed",
            jumps.longest_ratio
        )
    } else {
        String::new()
    };
    format!("{chain}\n{order}{topology}")
}

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Point counts to time.
    #[arg(long, value_delimiter = ',', default_values_t = BENCHMARK_SIZES.to_vec())]
    sizes: Vec<usize>,
    /// Random seed of the samples and chains.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print JSON rows instead of the table.
    #[arg(long)]
    json: bool,
    /// Also write the table as Markdown to this file (`docs/performance/curve.md`).
    #[arg(long, value_name = "FILE")]
    markdown: Option<PathBuf>,
}

fn bench(args: &BenchArgs) -> Result<()> {
    let rows = benchmark(&args.sizes, args.seed)?;
    if args.json {
        return output::json(&rows);
    }
    let mut table = Table::new([
        ("points", Align::Right),
        ("chain learns from", Align::Right),
        ("neurons", Align::Right),
        ("iterations", Align::Right),
        ("seconds", Align::Right),
        ("µs per presentation", Align::Right),
        ("time vs first row", Align::Right),
    ]);
    let baseline = rows.first().map_or(1.0, |r| r.seconds.max(1e-12));
    for row in &rows {
        let per = row.seconds * 1e6 / row.iterations.max(1) as f64;
        table.push([
            row.points.to_string(),
            row.trained_points.to_string(),
            row.neurons.to_string(),
            row.iterations.to_string(),
            format!("{:.4}", row.seconds),
            format!("{per:.3}"),
            format!("{:.1}×", row.seconds / baseline),
        ]);
    }
    print!("{table}");
    if let Some(path) = &args.markdown {
        let sizes: Vec<String> = args.sizes.iter().map(ToString::to_string).collect();
        let text = format!(
            "# Curve fitting time\n\nWritten by `neurosurf curve bench --markdown {}`{}: \
             Kohonen training, ordering, refinement and both fits on noisy ellipses (seed {}), \
             one run each on one thread, sampling not timed. Beyond {} points the chain \
             learns from a sample of {} and every point is ordered along it.\n\n{}",
            path.display(),
            if args.sizes == BENCHMARK_SIZES {
                String::new()
            } else {
                format!(" --sizes {}", sizes.join(","))
            },
            args.seed,
            CurveOptions::default().kohonen.max_trained_points,
            CurveOptions::default().kohonen.max_trained_points,
            table.to_markdown(),
        );
        write_atomic(path, text.as_bytes())?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

//! `neurosurf curve`: Hoffmann & Várady's curves from scattered points — sample test data,
//! fit a curve or a surface, plot, benchmark.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Subcommand, ValueEnum};
use serde::Serialize;

use neurosurf_trainer::curve::{
    BENCHMARK_SIZES, CurveOptions, CurvePoints, FitSummary, InterpolationReport, PlotLayers,
    PlotOptions, SampleCurve, SampleOptions, SurfaceOptions, TUBE_STRAY, TubeCheck, TubeMode,
    benchmark, curve_svg, curves_dxf, export_curve, export_surface, fit_unrolled_surface, iges,
    sample_curve, shaped_grid, surface_mesh, surface_to_blob, unroll, write_plot,
};
use neurosurf_trainer::evaluate::{LoadedModel, Precision};
use neurosurf_trainer::io::{read_scattered_points, write_atomic, write_mesh};
use neurosurf_trainer::table::{Align, Table};

use super::output::{self, blob_scalar, comma_list, wrote_blob};

mod fit;
pub use fit::FitArgs;

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
        Command::Fit(args) => fit::run(args),
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
    pub(super) seed: u64,
    /// How the blob stores the control points: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    pub(super) scalar: Precision,
    /// Output blob.
    #[arg(long)]
    pub(super) out: PathBuf,
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
pub struct SurfaceArgs {
    /// Scattered 3-D points: text with `x y z` per line, or PLY.
    points: PathBuf,
    /// Map neurons along u and v, `COLUMNS,ROWS` [default: about 144, in the ratio of the
    /// patch's length to its width measured along it]
    #[arg(long, value_parser = comma_list::<usize, 2>)]
    map: Option<[usize; 2]>,
    /// Control points of the surface along u and v, `U,V` [default: about 64, in the ratio
    /// of the map's sides]
    #[arg(long, value_parser = comma_list::<usize, 2>)]
    control: Option<[usize; 2]>,
    /// The points are a tube (an open cylinder, a pipe): fit a surface closed around u, with
    /// parameters from the two edges instead of a map. Without `--tube` or `--patch`, points
    /// with two separate edges are fitted both ways and the tube is kept unless one patch
    /// fits them far better
    #[arg(long, conflicts_with_all = ["map", "patch"])]
    tube: bool,
    /// The points are one patch, never a tube
    #[arg(long)]
    patch: bool,
    /// Pass through every point: once the least-squares fit has settled each point's (u, v),
    /// the smoothest surface through the points replaces it, on a grid of about two control
    /// points per point (so at most 512 points for the core's 1024). Refused when it would
    /// swing far from the fit between the points (noisy points)
    #[arg(long, conflicts_with = "control")]
    interpolate: bool,
    /// Polynomial degree of the surface in both directions, 2 to 5.
    #[arg(long, default_value_t = 3)]
    degree: usize,
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
    /// The surface's degrees along u and v.
    degrees: [usize; 2],
    /// The patch's length over its width, measured along it, when the map was shaped by it.
    aspect: Option<f64>,
    map_iterations: usize,
    /// Whether the points were fitted as a tube, closed around u.
    tube: bool,
    /// When the points had two separate edges and neither `--tube` nor `--patch` was given:
    /// the residual RMS as a tube and as one patch that decided.
    tube_check: Option<TubeCheck>,
    /// With `--interpolate`: the least-squares fit's residual RMS, the rounds taken and
    /// whether every point was met.
    interpolation: Option<InterpolationReport>,
    mesh: Option<&'a Path>,
    #[serde(flatten)]
    fit: FitSummary,
}

fn surface(args: &SurfaceArgs) -> Result<()> {
    let scalar = blob_scalar(args.blob.scalar)?;
    neurosurf_trainer::io::check_output(&args.blob.out)?;
    neurosurf_trainer::curve::check_degree(args.degree)?;
    let (dimension, raw) = read_scattered_points(&args.points)?;
    if dimension != 3 {
        anyhow::bail!(
            "{}: a surface is fitted to 3-D points, these are {dimension}-D",
            args.points.display()
        );
    }
    let points = CurvePoints::new(3, raw)
        .with_context(|| format!("cannot fit a surface to {}", args.points.display()))?;
    // Unrolled once: for the map's shape here and its start in the fit.
    let unrolled = match args.map {
        Some(_) => None,
        None if args.tube => None,
        None => unroll(points.points()),
    };
    let aspect = unrolled.as_ref().map(|u| u.aspect);
    let mut options = SurfaceOptions::shaped(aspect.unwrap_or(1.0));
    if let Some([columns, rows]) = args.map {
        options.map.columns = columns;
        options.map.rows = rows;
        let ratio = columns.max(rows) as f64 / columns.min(rows).max(1) as f64;
        let [short, long] = shaped_grid(ratio, options.control_u * options.control_v);
        [options.control_u, options.control_v] = if columns <= rows {
            [short, long]
        } else {
            [long, short]
        };
    }
    if let Some([u, v]) = args.control {
        options.control_u = u;
        options.control_v = v;
    }
    options.map.seed = args.blob.seed;
    options.tube = match (args.tube, args.patch) {
        (true, _) => TubeMode::Tube,
        // A map is a patch's.
        (false, true) | (false, false) if args.map.is_some() => TubeMode::Patch,
        (false, true) => TubeMode::Patch,
        (false, false) => TubeMode::Auto,
    };
    options.degree = args.degree;
    options.interpolate = args.interpolate;
    let start = Instant::now();
    let fit = fit_unrolled_surface(&points, &options, unrolled.as_ref())
        .with_context(|| format!("cannot fit a surface to {}", args.points.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    let summary = FitSummary {
        method: "surface".into(),
        points: points.len(),
        neurons: fit.map.as_ref().map_or(0, |map| map.columns * map.rows),
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
        degrees: [fit.surface.degree_u, fit.surface.degree_v],
        aspect,
        map_iterations: fit
            .map_report
            .as_ref()
            .map_or(0, |report| report.iterations),
        tube: fit.surface.closed_u,
        tube_check: fit.tube_check,
        interpolation: fit.interpolation,
        mesh: args.mesh.as_deref(),
        fit: summary,
    };
    if args.json {
        return output::json(&report);
    }
    let ordering = match &fit.map {
        Some(map) => {
            let shape = match aspect {
                Some(aspect) => format!(" ({aspect:.1} times as long as wide along the patch)"),
                None => String::new(),
            };
            format!(
                "{shape} → {} × {} map ({} iterations)",
                map.columns, map.rows, report.map_iterations
            )
        }
        None => " → a tube, closed around u".to_string(),
    };
    let ordering = match fit.tube_check {
        Some(TubeCheck {
            tube_rms,
            stray,
            patch_rms: Some(patch_rms),
        }) if stray > TUBE_STRAY => format!(
            "{ordering} (two separate edges, but open around: closed around, the surface gets \
             {stray:.1} point spacings from the points; residual RMS {tube_rms:.3e} as a tube, \
             {patch_rms:.3e} as one patch)"
        ),
        Some(TubeCheck {
            tube_rms,
            patch_rms: Some(patch_rms),
            ..
        }) => format!(
            "{ordering} (two separate edges: residual RMS {tube_rms:.3e} as a tube, \
             {patch_rms:.3e} as one patch)"
        ),
        Some(TubeCheck {
            patch_rms: None, ..
        }) => format!("{ordering} (two separate edges; one patch could not be fitted)"),
        None => ordering,
    };
    let through = match fit.interpolation {
        Some(InterpolationReport { swing, .. }) => format!(
            " through every point (at most {swing:.3e} from the least-squares fit between them)"
        ),
        None => String::new(),
    };
    println!(
        "{} points{ordering} → {} × {} control points{through}; residual RMS {:.3e}, max \
         {:.3e}; {:.3} s",
        report.fit.points,
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
    /// Write a curve or a spline surface as IGES 5.3: a B-spline curve (entity 126, clamped
    /// knots over [0, 1]) or surface (entity 128, over [0, 1]²), in the model's coordinates
    /// taken as millimetres.
    #[arg(long, value_name = "FILE")]
    iges: Option<PathBuf>,
}

fn export(args: &ExportArgs) -> Result<()> {
    let outputs = [&args.json, &args.svg, &args.dxf, &args.iges];
    if outputs.iter().all(|o| o.is_none()) {
        anyhow::bail!(
            "nothing to export: give --json FILE, --svg FILE, --dxf FILE, --iges FILE or several"
        );
    }
    for path in outputs.into_iter().flatten() {
        neurosurf_trainer::io::check_output(path)?;
    }
    let model = LoadedModel::read(&args.model)?;
    let (json, svg, dxf, iges) = match &model {
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
            let iges = iges(std::slice::from_ref(&decoded.curve), &[])?;
            (json, svg, dxf, iges)
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
                iges(&[], std::slice::from_ref(&decoded.surface))?,
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
    if let Some(path) = &args.iges {
        write_atomic(path, &iges)?;
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

/// Points as text, `x y` (2-D) or `x y z` per line.
pub(super) fn rows_text(points: &[[f64; 3]], dimension: usize) -> String {
    points
        .iter()
        .map(|p| match dimension {
            2 => format!("{} {}\n", p[0], p[1]),
            _ => format!("{} {} {}\n", p[0], p[1], p[2]),
        })
        .collect()
}

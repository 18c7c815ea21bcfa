//! `neurosurf curve fit`: order scattered points with a Kohonen chain and fit a B-spline, one
//! per separate group of points.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use serde::Serialize;

use neurosurf_trainer::curve::{
    BSplineCurve, BandReport, CurveOptions, CurvePoints, CurveReconstruction, FitSummary,
    LongSteps, MIN_POINTS, PlotLayers, PlotOptions, Topology, TrainingReport, curve_to_blob,
    interpolation_parameter, point_groups, reconstruct_curve, write_plot,
};
use neurosurf_trainer::io::{read_scattered_points, write_atomic};

use super::{BlobArgs, rows_text};
use crate::output::{self, blob_scalar, comma_list};

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
    /// Polynomial degree of the spline, 2 to 5 (`--interpolate` is cubic only).
    #[arg(long, default_value_t = 3)]
    degree: usize,
    #[command(flatten)]
    blob: BlobArgs,
    /// Also draw the points, their order and the curve (`.svg` or `.png`).
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Also write the fitted curve as a polyline: text, one vertex per line (16 per segment).
    #[arg(long, value_name = "FILE")]
    polyline: Option<PathBuf>,
    /// Also write the recovered order: text, one 0-based point index per line (points counted
    /// in file order, comments skipped), in order along the curve; with separate groups, one
    /// block per curve, separated by an empty line (and so for `--polyline`).
    #[arg(long, value_name = "FILE")]
    order: Option<PathBuf>,
    /// Size of the plot in pixels, `WIDTH,HEIGHT`.
    #[arg(long, value_parser = comma_list::<u32, 2>, default_value = "800,800")]
    plot_size: [u32; 2],
    /// Fit one curve through every point even when they form separate groups (it bridges
    /// them). Without it, each group gets its own curve: the largest in `--out`, the others
    /// in `--out` numbered (`ring.nsb`, `ring-2.nsb`, …), and stray points are left out.
    #[arg(long)]
    join_groups: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct FitReport<'a> {
    out: &'a Path,
    stored_as: &'static str,
    blob_bytes: usize,
    /// The curves of the other separate groups, largest first.
    more_curves: Vec<MoreCurve>,
    dimension: usize,
    closed: bool,
    /// The spline's polynomial degree.
    degree: usize,
    control_points: usize,
    segments: usize,
    chain_iterations: usize,
    chain_trained_points: usize,
    chain_converged: bool,
    /// Steps of the order longer than three times its median step.
    order_long_steps: LongSteps,
    /// How a band of noise wider than the spacing was parametrized, if it was.
    band: Option<BandReport>,
    /// The sharp corners of the approximation (where the arms on either side meet), in
    /// order along it.
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

pub fn run(args: &FitArgs) -> Result<()> {
    let scalar = blob_scalar(args.blob.scalar)?;
    neurosurf_trainer::io::check_output(&args.blob.out)?;
    neurosurf_trainer::curve::check_degree(args.degree)?;
    if args.interpolate && args.degree != 3 {
        anyhow::bail!(
            "--interpolate fits a cubic through every point; drop --degree {} or --interpolate",
            args.degree
        );
    }
    let (dimension, raw) = read_scattered_points(&args.points)?;
    let points = CurvePoints::new(dimension, raw)
        .with_context(|| format!("cannot fit a curve to {}", args.points.display()))?;
    neurosurf_trainer::curve::check_curve_capacity(
        points.len(),
        args.closed,
        args.control,
        args.interpolate,
    )?;
    if let Some(control) = args.control {
        let (fewest, _) =
            neurosurf_trainer::curve::control_range(points.len(), args.closed, args.degree);
        if control < fewest {
            anyhow::bail!(
                "--control {control}: a{} curve of degree {} needs at least {fewest} control \
                 points; give --control {fewest} or more, or a lower --degree",
                if args.closed { " closed" } else { "n open" },
                args.degree
            );
        }
    }
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
    options.approximation.degree = args.degree;
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
    let (group_members, strays): (Vec<Vec<usize>>, Vec<Vec<usize>>) = point_groups(points.points())
        .into_iter()
        .partition(|g| g.len() >= significant);
    let groups: Vec<usize> = group_members.iter().map(Vec::len).collect();
    let stray_points: usize = strays.iter().map(Vec::len).sum();
    // Separate groups get a curve each (the largest in --out, the others numbered beside
    // it); stray points are then left out. --join-groups fits one curve through everything.
    let separate = group_members.len() > 1 && !args.join_groups;
    let members: Vec<Vec<usize>> = if separate {
        group_members
    } else {
        vec![(0..points.len()).collect()]
    };
    let more_outs: Vec<PathBuf> = (2..=members.len())
        .map(|k| numbered(&args.blob.out, k))
        .collect();
    for path in &more_outs {
        neurosurf_trainer::io::check_output(path)?;
    }
    if let Some(path) = &args.plot {
        check_picture_path(path)?;
    }
    let fits = members
        .into_iter()
        .map(|m| fit_group(&points, m, &options, args.interpolate))
        .collect::<Result<Vec<GroupFit>>>()
        .with_context(|| format!("cannot fit a curve to {}", args.points.display()))?;
    let blobs = fits
        .iter()
        .map(|g| curve_to_blob(&g.curve, Some(&g.summary(args.blob.seed)), scalar))
        .collect::<neurosurf_trainer::Result<Vec<Vec<u8>>>>()?;
    let main = &fits[0];
    let (result, curve, method, rms, max, seconds) = (
        &main.result,
        &main.curve,
        main.method,
        main.rms,
        main.max,
        main.seconds,
    );
    let group_points = &main.points;
    let summary = main.summary(args.blob.seed);
    let blob = &blobs[0];
    neurosurf_trainer::blob::write_checked(&args.blob.out, blob)?;
    for (path, bytes) in more_outs.iter().zip(&blobs[1..]) {
        neurosurf_trainer::blob::write_checked(path, bytes)?;
    }
    if let Some(path) = &args.plot {
        let order: Vec<usize> = main.in_file_order(&result.ordering.order);
        let more: Vec<BSplineCurve> = fits[1..].iter().map(|g| g.curve.clone()).collect();
        let layers = PlotLayers {
            points: points.points(),
            order: Some(&order),
            closed: result.ordering.closed,
            curve: Some(curve),
            more_curves: &more,
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
        let text: Vec<String> = fits
            .iter()
            .map(|g| rows_text(&g.curve.polyline(g.curve.segments().max(1) * 16), dimension))
            .collect();
        write_atomic(path, text.join("\n").as_bytes())?;
    }
    if let Some(path) = &args.order {
        let text: Vec<String> = fits
            .iter()
            .map(|g| {
                g.in_file_order(&g.result.ordering.order)
                    .iter()
                    .map(|i| format!("{i}\n"))
                    .collect()
            })
            .collect();
        write_atomic(path, text.join("\n").as_bytes())?;
    }
    let more_curves: Vec<MoreCurve> = fits[1..]
        .iter()
        .zip(&more_outs)
        .zip(&blobs[1..])
        .map(|((g, out), bytes)| MoreCurve {
            out: out.clone(),
            blob_bytes: bytes.len(),
            points: g.points.len(),
            topology_warning: topology_warning(
                g.result.ordering.long_steps(&g.points, LONG_STEP),
                g.curve.closed,
            ),
            closed: g.curve.closed,
            control_points: g.curve.control.len(),
            rms_residual: g.rms,
            max_residual: g.max,
        })
        .collect();
    let report = FitReport {
        out: &args.blob.out,
        stored_as: scalar.name(),
        blob_bytes: blob.len(),
        more_curves,
        dimension,
        closed: curve.closed,
        degree: curve.degree,
        control_points: curve.control.len(),
        segments: curve.segments(),
        chain_iterations: result.training.iterations,
        chain_trained_points: result.training.trained_points,
        chain_converged: result.training.convergence.converged(),
        order_long_steps: result.ordering.long_steps(group_points, LONG_STEP),
        band: result.band.clone(),
        corners: if args.interpolate {
            Vec::new()
        } else {
            result
                .approximation
                .corner_points
                .iter()
                .map(|p| p[..dimension].to_vec())
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
        "{} {}-D points → {} chain of {} neurons{} ({} iterations) → {} of {} control points, \
         degree {}",
        report.fit.points,
        dimension,
        if report.closed { "closed" } else { "open" },
        report.fit.neurons,
        sample,
        report.chain_iterations,
        method,
        report.control_points,
        report.degree
    );
    println!(
        "{}",
        convergence_text(&result.training, report.order_long_steps, report.closed)
    );
    if let Some(band) = &report.band {
        println!(
            "noise across the curve {:.3e} ({:.1}× the spacing along it): the curve follows \
             the band's middle ({} rounds of ordering the points along the fit) with {} \
             control points",
            band.noise,
            band.noise / band.spacing,
            band.rounds,
            report.control_points
        );
    }
    if report.groups.len() > 1 && args.join_groups {
        println!(
            "warning: the points form {} separate groups ({} points): one curve bridges them \
             (without --join-groups, each gets its own curve)",
            report.groups.len(),
            report
                .groups
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if report.stray_points > 0 && separate {
        println!(
            "{} stray point{} far from the others left out",
            report.stray_points,
            if report.stray_points == 1 { "" } else { "s" }
        );
    } else if report.stray_points > 0 {
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
    for (k, more) in report.more_curves.iter().enumerate() {
        println!(
            "group {}: {} points → {} curve of {} control points, residual RMS {:.3e}, max \
             {:.3e}; wrote {} ({} bytes)",
            k + 2,
            more.points,
            if more.closed { "closed" } else { "open" },
            more.control_points,
            more.rms_residual,
            more.max_residual,
            more.out.display(),
            more.blob_bytes
        );
        if let Some(warning) = &more.topology_warning {
            println!("warning: group {}: {warning}", k + 2);
        }
    }
    if let Some(path) = &args.plot {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The curve of one separate group.
#[derive(Serialize)]
struct MoreCurve {
    out: PathBuf,
    blob_bytes: usize,
    points: usize,
    /// Whether its order says it is closed though fitted open, or the reverse.
    topology_warning: Option<String>,
    closed: bool,
    control_points: usize,
    rms_residual: f64,
    max_residual: f64,
}

/// One group's ordering and fit.
struct GroupFit {
    /// The group's points' indices in the file.
    members: Vec<usize>,
    points: CurvePoints,
    result: CurveReconstruction,
    /// The curve written: the approximation or the interpolation.
    curve: BSplineCurve,
    method: &'static str,
    rms: f64,
    max: f64,
    seconds: f64,
}

impl GroupFit {
    fn summary(&self, seed: u64) -> FitSummary {
        FitSummary {
            method: self.method.into(),
            points: self.points.len(),
            neurons: self.result.training.neurons,
            seed,
            rms_residual: self.rms,
            max_residual: self.max,
            seconds: self.seconds,
        }
    }

    /// Indices into the group as indices into the file.
    fn in_file_order(&self, order: &[usize]) -> Vec<usize> {
        order.iter().map(|&i| self.members[i]).collect()
    }
}

/// Orders and fits the points of `all` at `members`.
fn fit_group(
    all: &CurvePoints,
    members: Vec<usize>,
    options: &CurveOptions,
    interpolate: bool,
) -> Result<GroupFit> {
    let points = CurvePoints::new(
        all.dimension(),
        members.iter().map(|&i| all.points()[i]).collect(),
    )?;
    let start = Instant::now();
    let result = reconstruct_curve(&points, options)?;
    let seconds = start.elapsed().as_secs_f64();
    let (curve, method, rms, max) = if interpolate {
        let ordered = result.ordering.ordered_points(&points);
        let (rms, max) = interpolation_residual(&result.interpolation, &ordered);
        (result.interpolation.clone(), "interpolation", rms, max)
    } else {
        let a = &result.approximation;
        (
            a.curve.clone(),
            "approximation",
            a.rms_residual,
            a.max_residual,
        )
    };
    Ok(GroupFit {
        members,
        points,
        result,
        curve,
        method,
        rms,
        max,
        seconds,
    })
}

/// `out` with `-k` before its extension: `ring.nsb` → `ring-2.nsb`.
fn numbered(out: &Path, k: usize) -> PathBuf {
    let stem = out
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let name = match out.extension() {
        Some(e) => format!("{stem}-{k}.{}", e.to_string_lossy()),
        None => format!("{stem}-{k}"),
    };
    out.with_file_name(name)
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
    let topology =
        topology_warning(jumps, closed).map_or_else(String::new, |w| format!("\nwarning: {w}"));
    format!("{chain}\n{order}{topology}")
}

/// Whether the order says the curve's topology is the other one: an open order whose ends are
/// a step or so apart went round a closed curve; a closed order with one or two steps far
/// longer than all others bridges the ends of an open one (the ring's neurons cross the gap
/// once or twice).
fn topology_warning(jumps: LongSteps, closed: bool) -> Option<String> {
    if !closed && jumps.ends_ratio <= LONG_STEP {
        Some(format!(
            "the order's ends are {:.1} median steps apart: the curve looks closed; fit it with \
             --closed",
            jumps.ends_ratio
        ))
    } else if closed && jumps.count <= 2 && jumps.longest_ratio > 2.0 * LONG_STEP {
        Some(format!(
            "a step of the ring is {:.1}× the median, all but one other under {LONG_STEP}×: it \
             bridges the ends of an open curve; fit it without --closed",
            jumps.longest_ratio
        ))
    } else {
        None
    }
}

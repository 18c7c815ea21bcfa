//! `neurosurf implicit fit|rbf`: control points in, blob out.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Subcommand, ValueEnum};
use serde::Serialize;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::implicit::{
    self, BoxScaling, DecodedImplicit, FitRequest, ImplicitOptions, TrainingSummary, TreeSpec,
};
use neurosurf_trainer::io::read_points;
use neurosurf_trainer::rbf::{self, RbfKernel, RbfOptions, RbfReport};

use super::{output, progress};

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Carcenac's modular implicit surface: a tree of small MLP modules trained by
    /// Levenberg–Marquardt (defaults: the paper's Table 1). (`implicit` is the same command.)
    #[command(alias = "implicit")]
    Fit(ImplicitArgs),
    /// The RBF baseline (Carcenac §9's multiquadric, or the biharmonic): Hermite-style
    /// off-surface points on both sides, lengths relative to the bounding diagonal, one dense
    /// solve; host-only model (`render` and `mesh` draw it).
    Rbf(RbfArgs),
}

#[derive(Debug, clap::Args)]
pub struct ImplicitArgs {
    /// Control points: PLY with x y z nx ny nz and an optional integer `feature`.
    #[arg(long)]
    points: PathBuf,
    /// Split unlabelled points into K spatial features (ignored when the points have labels).
    #[arg(long, value_name = "K")]
    features: Option<usize>,
    /// Module tree over the features, e.g. `((0,1),2)`; default: balanced by proximity.
    #[arg(long, value_name = "SPEC")]
    tree: Option<TreeSpec>,
    /// Warm start from a model of the same tree (animation frames).
    #[arg(long, value_name = "M0.nsb")]
    init: Option<PathBuf>,
    /// Leave out the sign guards (bumps that fix Φ's sign where the network has it wrong
    /// away from the points): Carcenac's procedure alone.
    #[arg(long)]
    no_guards: bool,
    /// Output blob.
    #[arg(long, short)]
    out: PathBuf,
    /// How the blob stores parameters.
    #[arg(long, value_enum, default_value_t = Storage::F32)]
    scalar: Storage,
    /// Hidden width N.
    #[arg(long, default_value_t = 9)]
    width: usize,
    /// Slope s of Φ at the surface (target ∇Φ = −s·n).
    #[arg(long, default_value_t = 5.0)]
    slope: f64,
    /// Weight γ of the gradient residuals.
    #[arg(long, default_value_t = 0.05)]
    gamma: f64,
    /// Weight decay λ.
    #[arg(long, default_value_t = 1.2e-4)]
    lambda: f64,
    /// Initial weights uniform in [−w₀, w₀].
    #[arg(long = "init-range", default_value_t = 0.5, value_name = "W0")]
    init_range: f64,
    /// Side H of the normalization box [−H/2, H/2]³.
    #[arg(long = "box-size", default_value_t = 2.0, value_name = "H")]
    box_size: f64,
    /// PCA box scaling: one scale (keeps the shape) or per axis (the paper's literal reading).
    #[arg(long = "box-scaling", value_enum, default_value_t = Scaling::Isotropic)]
    box_scaling: Scaling,
    /// Initial LM damping μ₀.
    #[arg(long, default_value_t = 1e-4)]
    mu0: f64,
    /// LM damping ratio θ.
    #[arg(long, default_value_t = 2.0)]
    theta: f64,
    /// Stop when the criterion E_s reaches this.
    #[arg(long, default_value_t = 1e-5)]
    threshold: f64,
    /// Iteration cap per module.
    #[arg(long = "max-iterations", default_value_t = 2000)]
    max_iterations: usize,
    /// Plain LM steps, as in the paper: no geodesic acceleration (which costs one more
    /// residual evaluation per trial step and usually halves the iterations).
    #[arg(long = "no-acceleration")]
    no_acceleration: bool,
    /// Train every module on all its points from the start, as in the paper: no coarse start
    /// on a thinned quarter of a module's points (modules of 256 points or more).
    #[arg(long = "no-coarse-start")]
    no_coarse_start: bool,
    /// Fewest control points per feature.
    #[arg(long = "min-points", default_value_t = 4)]
    min_points: usize,
    /// Off-surface offset ε as a fraction of the points' bounding diagonal (0 turns the
    /// off-surface points off).
    #[arg(long, default_value_t = ImplicitOptions::default().offset, value_name = "ε/D")]
    offset: f64,
    /// Sign points per control point of a module (0 turns them off).
    #[arg(long = "sign-points", default_value_t = ImplicitOptions::default().sign_points)]
    sign_points: f64,
    /// How far sign points keep from the control points, as a fraction of the diagonal.
    #[arg(long, default_value_t = ImplicitOptions::default().clearance, value_name = "FRACTION")]
    clearance: f64,
    /// |Φ| a sign point at distance d asks for, as a fraction of s·d.
    #[arg(long = "sign-margin", default_value_t = ImplicitOptions::default().sign_margin)]
    sign_margin: f64,
    /// Weight of a sign point at the clearance distance (grows with the distance, up to 1).
    #[arg(long = "sign-weight", default_value_t = ImplicitOptions::default().sign_weight)]
    sign_weight: f64,
    /// Seed of the weight initialization (and of the feature decomposition).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print a JSON summary instead of text.
    #[arg(long)]
    json: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum Storage {
    F32,
    #[value(name = "q16.16")]
    Q16,
}

impl Storage {
    fn kind(self) -> ScalarKind {
        match self {
            Storage::F32 => ScalarKind::F32,
            Storage::Q16 => ScalarKind::Q16_16,
        }
    }
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum Scaling {
    Isotropic,
    PerAxis,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum Kernel {
    Multiquadric,
    Biharmonic,
}

#[derive(Debug, clap::Args)]
pub struct RbfArgs {
    /// Control points: PLY with x y z nx ny nz.
    #[arg(long)]
    points: PathBuf,
    /// Output blob (host-only model kind `rbf`).
    #[arg(long, short)]
    out: PathBuf,
    /// The radial function: Carcenac's multiquadric √(r² + c²), or the biharmonic r.
    #[arg(long, value_enum, default_value_t = Kernel::Multiquadric)]
    kernel: Kernel,
    /// The multiquadric's c as a fraction of the points' bounding diagonal D (the default
    /// gives c² = 10⁻³ on the Table 5 torus, Carcenac's value).
    #[arg(long = "c-relative", default_value_t = rbf::C_RELATIVE, value_name = "C/D")]
    c_relative: f64,
    /// Offset of the off-surface points as a fraction of D (halved per point until the point's
    /// nearest control point is its own).
    #[arg(long = "epsilon-relative", default_value_t = rbf::EPSILON_RELATIVE, value_name = "ε/D")]
    epsilon_relative: f64,
    /// Slope s of the field across the surface (f = ∓s·ε at the off-surface points).
    #[arg(long, default_value_t = 5.0)]
    slope: f64,
    /// Print a JSON summary instead of text.
    #[arg(long)]
    json: bool,
}

pub fn run(command: &Command) -> Result<()> {
    match command {
        Command::Fit(args) => implicit(args),
        Command::Rbf(args) => rbf(args),
    }
}

#[derive(Serialize)]
struct ImplicitSummary<'a> {
    out: &'a Path,
    blob_bytes: usize,
    scalar: &'static str,
    parameters: usize,
    /// Sign guards added where the network alone had the wrong sign away from the data.
    guards: usize,
    converged: bool,
    /// How the training ended: converged, stalled at E_s = …, or cut by the iteration cap.
    outcome: String,
    iterations: usize,
    /// Iterations the warm start saved against the cold start of its chain.
    iterations_saved: Option<i64>,
    training: &'a TrainingSummary,
}

fn implicit(args: &ImplicitArgs) -> Result<()> {
    neurosurf_trainer::io::check_output(&args.out)?;
    let points = read_points(&args.points)?;
    implicit::check_storable(&points.positions, args.scalar.kind())
        .with_context(|| format!("cannot train on {}", args.points.display()))?;
    let init = args.init.as_deref().map(read_init).transpose()?;
    let mut options = ImplicitOptions {
        width: args.width,
        slope: args.slope,
        gamma: args.gamma,
        init_range: args.init_range,
        box_size: args.box_size,
        box_scaling: match args.box_scaling {
            Scaling::Isotropic => BoxScaling::Isotropic,
            Scaling::PerAxis => BoxScaling::PerAxis,
        },
        seed: args.seed,
        min_points: args.min_points,
        offset: args.offset,
        sign_points: args.sign_points,
        clearance: args.clearance,
        sign_margin: args.sign_margin,
        sign_weight: args.sign_weight,
        coarse_start: !args.no_coarse_start,
        ..ImplicitOptions::default()
    };
    options.lm.lambda = args.lambda;
    options.lm.mu0 = args.mu0;
    options.lm.theta = args.theta;
    options.lm.threshold = args.threshold;
    options.lm.max_iterations = args.max_iterations;
    options.lm.acceleration = !args.no_acceleration;
    let request = FitRequest {
        features: args.features,
        tree: args.tree.clone(),
        init,
        unguarded: args.no_guards,
    };
    let bar = progress::training_bar("training", args.quiet || args.json);
    let trained = implicit::fit(points, &request, &options, &|event| {
        progress::update(&bar, event);
    })
    .with_context(|| format!("cannot train on {}", args.points.display()))?;
    bar.finish_and_clear();
    let summary = &trained.summary;
    let bytes = implicit::to_blob(&trained.network, Some(summary), args.scalar.kind())?;
    neurosurf_trainer::blob::write_checked(&args.out, &bytes)?;
    let saved = (request.init.is_some() && !summary.cold_iterations.is_empty()).then(|| {
        summary.cold_iterations.iter().sum::<usize>() as i64 - summary.iterations() as i64
    });
    let report = ImplicitSummary {
        out: &args.out,
        blob_bytes: bytes.len(),
        scalar: args.scalar.kind().name(),
        parameters: trained.network.params().len(),
        guards: trained.network.guards().len(),
        converged: summary.converged(),
        outcome: summary.outcome().to_string(),
        iterations: summary.iterations(),
        iterations_saved: saved,
        training: summary,
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "trained {} ({} modules, {} parameters) in {:.3} s, {} iterations{}",
        summary.tree,
        summary.modules.len(),
        report.parameters,
        summary.seconds,
        report.iterations,
        match saved {
            Some(s) => format!(" ({s} fewer than the cold start)"),
            None => String::new(),
        }
    );
    for m in &summary.modules {
        println!(
            "  module {:>2} {:<4} {:>5} points {:>4} iterations  E {:.2e}  {:?}",
            m.module,
            if m.node { "node" } else { "leaf" },
            m.points,
            m.lm.iterations,
            m.lm.error,
            m.lm.stop
        );
    }
    println!("training {}", summary.outcome());
    if report.guards > 0 {
        println!(
            "{} sign guards fix the field's sign where the network had it wrong away from the points",
            report.guards
        );
    }
    if !summary.outcome().settled() {
        eprintln!(
            "warning: a module ran into the iteration cap ({}); raise --max-iterations",
            options.lm.max_iterations
        );
    }
    println!(
        "wrote {} ({} bytes, {})",
        args.out.display(),
        bytes.len(),
        report.scalar
    );
    Ok(())
}

fn read_init(path: &Path) -> Result<DecodedImplicit> {
    let bytes = std::fs::read(path)
        .with_context(|| format!("cannot read the initial model {}", path.display()))?;
    let decoded = implicit::from_blob(&bytes, path)
        .with_context(|| format!("cannot use {} as the initial model", path.display()))?;
    Ok(decoded)
}

#[derive(Serialize)]
struct RbfSummary<'a> {
    out: &'a Path,
    blob_bytes: usize,
    report: &'a RbfReport,
}

fn rbf(args: &RbfArgs) -> Result<()> {
    neurosurf_trainer::io::check_output(&args.out)?;
    let points = read_points(&args.points)?.validated()?;
    let options = RbfOptions {
        kernel: match args.kernel {
            Kernel::Multiquadric => RbfKernel::Multiquadric,
            Kernel::Biharmonic => RbfKernel::Biharmonic,
        },
        c_relative: args.c_relative,
        epsilon_relative: args.epsilon_relative,
        slope: args.slope,
    };
    let (model, report) = rbf::fit(&points, &options)
        .with_context(|| format!("cannot fit an RBF to {}", args.points.display()))?;
    let bytes = model.to_blob()?;
    neurosurf_trainer::blob::write_checked(&args.out, &bytes)?;
    let summary = RbfSummary {
        out: &args.out,
        blob_bytes: bytes.len(),
        report: &report,
    };
    if args.json {
        return output::json(&summary);
    }
    println!(
        "fitted a {} RBF on {} points ({} unknowns) in {:.3} s ({:.3} s factoring); condition \
         estimate {:.2e}, max residual {:.1e}",
        report.kernel.name(),
        report.points,
        report.unknowns,
        report.seconds,
        report.factorization_seconds,
        report.condition_estimate,
        report.max_residual
    );
    println!(
        "  diagonal D {:.4e}, c² {:.3e}, ε {:.3e} ({} of {} off-surface offsets halved, smallest \
         {:.3e})",
        report.diagonal,
        report.c2,
        report.epsilon,
        report.halved,
        2 * report.points,
        report.min_epsilon
    );
    println!("wrote {} ({} bytes)", args.out.display(), bytes.len());
    Ok(())
}

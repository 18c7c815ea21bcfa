//! `neurosurf parametric`: Yumer & Kara's parametric surfaces from point sets — sample test data,
//! embed points in the plane, fit a surface network, tessellate it, stitch patches, fill holes,
//! and time the pipeline (Table 2).
//!
//! The `patch` subcommands share their argument types and output helpers here; `compare` has
//! its own file.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Subcommand, ValueEnum};
use serde::Serialize;

use neurosurf_trainer::evaluate::{LoadedModel, Precision};
use neurosurf_trainer::geometry::drop_unused_vertices;
use neurosurf_trainer::io::{
    Mesh, data_file, read_mesh, read_obj_vertices, read_parameters, read_query_points,
    write_atomic, write_mesh,
};
use neurosurf_trainer::parametric::{
    Activation, BACK_SEED, BENCHMARK_SIZES, BoundaryOptions, HoleOptions, LleOptions,
    NetworkSummary, OutlierOptions, Parameterization, SampleSurface, Seam, SurfaceNetwork,
    TopologyOptions, benchmark, boundary_loops, boundary_seam, coons_boundary,
    coons_boundary_of_polygon, coons_grid, delaunay_grid, edge_report, embed_points, fill_hole,
    fill_polygon, find_seams, fit_robustly, network_to_blob, parameter_region, punch_hole,
    sample_surface, stitch, synthesize, wireframe,
};
use neurosurf_trainer::plot::write_picture;
use neurosurf_trainer::table::{Align, Table};

use super::output::{self, blob_scalar, wrote_blob};

mod closed;
mod compare;

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Points on a known surface (text, `x y z` per line), shuffled, with optional noise.
    Sample(SampleArgs),
    /// Locally linear embedding of unstructured 3-D points to (u, v) (text, `u v` per line).
    Embed(EmbedArgs),
    /// Fit a surface network (u, v) → (x, y, z) to points (embedding them first unless
    /// parameters are given), with the §5.2 topology search; write its blob.
    Fit(FitArgs),
    /// Tessellate a surface network: a Coons quad grid or a Delaunay triangulation of the
    /// parameter region, pushed through the network (OBJ, PLY or STL with normals).
    Tessellate(TessellateArgs),
    /// Stitch open patches into one mesh, along whole boundary loops or stretches of them.
    Stitch(StitchArgs),
    /// Rebuild a closed mesh (holes capped) from surface-network patches: cut it into
    /// discs, fit each, tessellate them with shared seams and stitch them watertight.
    Closed(closed::ClosedArgs),
    /// Fill the holes of a mesh: one-ring embedding of the rings around each hole, a network
    /// on them, new vertices inside, constrained Delaunay.
    FillHole(FillHoleArgs),
    /// Compare the network with thin-plate RBF fits and direct Delaunay triangulation on any
    /// patch (the paper's §7.1), on points held out of every fit and from each mesh back to
    /// the data.
    Compare(compare::CompareArgs),
    /// Time embedding and fitting on a patch of the Stanford bunny (the paper's Table 2).
    Bench(BenchArgs),
}

pub fn run(command: &Command) -> Result<()> {
    match command {
        Command::Sample(args) => sample(args),
        Command::Embed(args) => embed(args),
        Command::Fit(args) => fit(args),
        Command::Tessellate(args) => tessellate(args),
        Command::Stitch(args) => stitch_patches(args),
        Command::Closed(args) => closed::run(args),
        Command::FillHole(args) => fill_holes(args),
        Command::Compare(args) => compare::run(args),
        Command::Bench(args) => bench(args),
    }
}

/// The built-in test surfaces.
#[derive(Copy, Clone, Debug, ValueEnum)]
pub enum SurfaceName {
    /// A tilted plane over [−1, 1]².
    Plane,
    /// z = 0.25·sin(2.5x)·cos(2y) over [−1, 1]².
    Wavy,
    /// An open cylinder (a "C" in plan), radius 1, height 2.5.
    Cylinder,
    /// A swiss-roll patch.
    SwissRoll,
    /// The unit sphere (closed: cannot be flattened; for trying the error).
    Sphere,
}

impl SurfaceName {
    fn surface(self) -> SampleSurface {
        match self {
            SurfaceName::Plane => SampleSurface::Plane,
            SurfaceName::Wavy => SampleSurface::Wavy,
            SurfaceName::Cylinder => SampleSurface::OpenCylinder,
            SurfaceName::SwissRoll => SampleSurface::SwissRoll,
            SurfaceName::Sphere => SampleSurface::Sphere,
        }
    }
}

/// The hidden activation.
#[derive(Copy, Clone, Debug, ValueEnum)]
pub enum ActivationArg {
    /// 1/(1 + e⁻ᵃ).
    LogSig,
    /// 2/(1 + e⁻ᵃ) − 1 (smooth surfaces; the default).
    TanSig,
    /// e^(−a²).
    RadBas,
    /// max(0, 1 − |a|) (piecewise-planar surfaces).
    TriBas,
}

impl ActivationArg {
    fn activation(self) -> Activation {
        match self {
            ActivationArg::LogSig => Activation::LogSig,
            ActivationArg::TanSig => Activation::TanSig,
            ActivationArg::RadBas => Activation::RadBas,
            ActivationArg::TriBas => Activation::TriBas,
        }
    }
}

/// How the parameter region is tessellated.
#[derive(Copy, Clone, Debug, ValueEnum)]
pub enum MethodArg {
    /// A resolution × resolution quad grid of the bilinear Coons patch between four Bézier
    /// sides of the region.
    Coons,
    /// The boundary loop resampled, a uniform grid inside it, constrained Delaunay (about
    /// resolution² vertices).
    Delaunay,
}

#[derive(Debug, clap::Args)]
pub struct EmbeddingArgs {
    /// Neighbours per point k. Default: 10, or the first of 12, 14, 16, 20 whose embedding
    /// does not fold.
    #[arg(long)]
    neighbors: Option<usize>,
    /// Gram regularization δ (C + δ·tr(C)·I).
    #[arg(long, default_value_t = LleOptions::default().regularization)]
    regularization: f64,
}

impl EmbeddingArgs {
    pub(super) fn options(&self) -> LleOptions {
        let default = LleOptions::default();
        LleOptions {
            neighbors: self.neighbors.unwrap_or(default.neighbors),
            regularization: self.regularization,
            more_neighbors: self.neighbors.is_none(),
            ..default
        }
    }
}

/// The network's topology search.
#[derive(Debug, clap::Args)]
pub struct NetworkArgs {
    /// Hidden activation.
    #[arg(long, value_enum, default_value = "tan-sig")]
    activation: ActivationArg,
    /// Most hidden layers the search tries.
    #[arg(long, default_value_t = TopologyOptions::default().max_layers)]
    max_layers: usize,
    /// Most neurons per hidden layer the search tries.
    #[arg(long, default_value_t = TopologyOptions::default().max_neurons)]
    max_neurons: usize,
}

impl NetworkArgs {
    /// The search settings with `seed`, once the core is known to hold the largest network
    /// they allow.
    pub(super) fn options(&self, seed: u64) -> Result<TopologyOptions> {
        neurosurf_trainer::parametric::check_capacity(self.max_layers, self.max_neurons)?;
        Ok(TopologyOptions {
            activation: self.activation.activation(),
            max_layers: self.max_layers,
            max_neurons: self.max_neurons,
            seed,
            ..TopologyOptions::default()
        })
    }
}

#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// Which surface.
    #[arg(value_enum)]
    surface: SurfaceName,
    /// Number of points.
    #[arg(long, default_value_t = 800)]
    points: usize,
    /// Gaussian noise, as a fraction of the surface's size.
    #[arg(long, default_value_t = 0.0)]
    noise: f64,
    /// Random seed (same seed, same points).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output text file (`x y z` per line).
    #[arg(long)]
    out: PathBuf,
    /// Also write the true parameters (`s t` per line, same order).
    #[arg(long, value_name = "FILE")]
    parameters: Option<PathBuf>,
}

fn sample(args: &SampleArgs) -> Result<()> {
    let surface = args.surface.surface();
    let sample = sample_surface(surface, args.points, args.noise, args.seed)?;
    let header = format!(
        "# {surface:?}: {} points, noise {}, seed {}\n",
        args.points, args.noise, args.seed
    );
    write_atomic(
        &args.out,
        (header.clone() + &rows(&sample.points)).as_bytes(),
    )?;
    println!("wrote {} points to {}", args.points, args.out.display());
    if let Some(path) = &args.parameters {
        write_atomic(path, (header + &rows(&sample.parameters)).as_bytes())?;
        println!("wrote their parameters to {}", path.display());
    }
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct EmbedArgs {
    /// Points: text (`x y z` per line), PLY, or OBJ (its vertices).
    points: PathBuf,
    #[command(flatten)]
    embedding: EmbeddingArgs,
    /// Output text file (`u v` per line, the points' order).
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct EmbedReport<'a> {
    out: &'a Path,
    points: usize,
    neighbors: usize,
    /// `lle`, or `unrolled` where the sampling density changes.
    parameterization: Parameterization,
    eigenvalues: [f64; 2],
    eigen_iterations: usize,
    flipped_fraction: f64,
    collapsed_fraction: f64,
    seconds: f64,
}

fn embed(args: &EmbedArgs) -> Result<()> {
    let points = read_points(&args.points)?;
    let start = Instant::now();
    let embedding = embed_points(&points, &args.embedding.options())
        .with_context(|| format!("cannot embed {}", args.points.display()))?;
    let seconds = start.elapsed().as_secs_f64();
    write_atomic(&args.out, rows(&embedding.parameters).as_bytes())?;
    let report = EmbedReport {
        out: &args.out,
        points: points.len(),
        neighbors: embedding.neighbors,
        parameterization: embedding.parameterization,
        eigenvalues: embedding.eigenvalues,
        eigen_iterations: embedding.iterations,
        flipped_fraction: embedding.folds.flipped_pairs,
        collapsed_fraction: embedding.folds.collapsed_points,
        seconds,
    };
    if args.json {
        return output::json(&report);
    }
    match report.parameterization {
        Parameterization::Lle => println!(
            "embedded {} points (k = {}) in {seconds:.3} s: λ₂ = {:.3e}, λ₃ = {:.3e}, {} \
             iterations, {:.2} % of neighbour pairs flipped",
            report.points,
            report.neighbors,
            report.eigenvalues[0],
            report.eigenvalues[1],
            report.eigen_iterations,
            100.0 * report.flipped_fraction
        ),
        Parameterization::Unrolled => println!(
            "unrolled {} points (k = {}) in {seconds:.3} s: their density changes, so LLE \
             would squeeze the sparse part, or LLE folds them at every k; {:.2} % of neighbour \
             pairs flipped",
            report.points,
            report.neighbors,
            100.0 * report.flipped_fraction
        ),
    }
    println!("wrote {}", args.out.display());
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Points: text (`x y z` per line), PLY, or OBJ (its vertices).
    points: PathBuf,
    /// Their parameters (`u v` per line, same order; e.g. from `parametric embed`). Without it the
    /// points are embedded first.
    #[arg(long, value_name = "FILE")]
    parameters: Option<PathBuf>,
    #[command(flatten)]
    embedding: EmbeddingArgs,
    #[command(flatten)]
    network: NetworkArgs,
    /// Seed of the split and the initial weights.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// How the blob stores the network: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    scalar: Precision,
    /// Output blob.
    #[arg(long)]
    out: PathBuf,
    /// Also write the parameters used (`u v` per line, for `parametric tessellate`): those of
    /// the points fitted, without the outliers.
    #[arg(long, value_name = "FILE")]
    parameters_out: Option<PathBuf>,
    /// Fit every point. By default, points off the surface (off their neighbours' planes, or
    /// isolated) are left out, then those the first fit misses by far more than their
    /// neighbours (the network is refined without them), and the summary counts both.
    #[arg(long)]
    keep_outliers: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct FitReport<'a> {
    out: &'a Path,
    stored_as: &'static str,
    blob_bytes: usize,
    points: usize,
    /// Points left out before the embedding: off their neighbours' planes, or isolated.
    outliers: usize,
    /// Points left out after the first fit: off the network by more than their neighbours.
    off_fit: usize,
    embedded: bool,
    /// `lle` or `unrolled` when the points were embedded.
    #[serde(skip_serializing_if = "Option::is_none")]
    parameterization: Option<Parameterization>,
    embedding_seconds: f64,
    fitting_seconds: f64,
    hidden_layers: Vec<usize>,
    activation: &'static str,
    parameters: usize,
    candidates: usize,
    rms_error: f64,
    relative_rms_error: f64,
    /// Corners of the parameter region stored in the blob (0: none could be traced).
    region_corners: usize,
}

fn fit(args: &FitArgs) -> Result<()> {
    let scalar = blob_scalar(args.scalar)?;
    neurosurf_trainer::io::check_output(&args.out)?;
    // What the core holds, checked before any embedding or fitting.
    let options = args.network.options(args.seed)?;
    let points = read_points(&args.points)?;
    let given = match &args.parameters {
        Some(path) => Some(
            read_parameters(path, 2)?
                .into_iter()
                .map(|p| [p[0], p[1]])
                .collect::<Vec<_>>(),
        ),
        None => None,
    };
    let outliers = (!args.keep_outliers).then(OutlierOptions::default);
    let robust = fit_robustly(
        &points,
        given.as_deref(),
        &args.embedding.options(),
        &options,
        outliers.as_ref(),
    )
    .with_context(|| format!("cannot fit a network to {}", args.points.display()))?;
    let fit = &robust.fit;
    let (embedding_seconds, fitting_seconds) = (robust.embedding_seconds, robust.fitting_seconds);
    let mut summary =
        NetworkSummary::of(fit, robust.kept.len(), embedding_seconds + fitting_seconds);
    // The region the points cover, for `tessellate` and `eval`; a point set whose boundary
    // cannot be traced keeps the whole trained box.
    summary.region = parameter_region(&robust.parameters).unwrap_or_default();
    let bytes = network_to_blob(&fit.network, Some(&summary), scalar)?;
    neurosurf_trainer::blob::write_checked(&args.out, &bytes)?;
    if let Some(path) = &args.parameters_out {
        write_atomic(path, rows(&robust.parameters).as_bytes())?;
    }
    let report = FitReport {
        out: &args.out,
        stored_as: scalar.name(),
        blob_bytes: bytes.len(),
        points: points.len(),
        outliers: robust.off_surface.len(),
        off_fit: robust.off_fit.len(),
        embedded: args.parameters.is_none(),
        parameterization: robust.parameterization,
        embedding_seconds,
        fitting_seconds,
        hidden_layers: fit.network.hidden_sizes(),
        activation: fit.network.activation.name(),
        parameters: fit.network.parameter_count(),
        candidates: summary.candidates,
        rms_error: fit.rms_error,
        relative_rms_error: fit.relative_rms_error,
        region_corners: summary.region.len(),
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} points{}{}: hidden layers {:?} ({}, {} parameters) after {} configurations, RMS \
         error {:.3e} ({:.2e} of the diagonal); {:.3} s embedding, {:.3} s fitting",
        report.points,
        match (report.outliers, report.off_fit) {
            (0, 0) => String::new(),
            (n, 0) => format!(" less {n} off the surface (--keep-outliers fits them)"),
            (n, m) => format!(
                " less {n} off the surface and {m} off the first fit (--keep-outliers fits \
                 them)"
            ),
        },
        match report.parameterization {
            Some(Parameterization::Unrolled) => {
                " unrolled (their density changes, or LLE folds them at every k)"
            }
            Some(Parameterization::Lle) => " embedded",
            None => "",
        },
        report.hidden_layers,
        report.activation,
        report.parameters,
        report.candidates,
        report.rms_error,
        report.relative_rms_error,
        report.embedding_seconds,
        report.fitting_seconds
    );
    wrote_blob(
        &args.out,
        bytes.len(),
        scalar,
        args.parameters_out.as_deref(),
    );
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct TessellateArgs {
    /// A surface-network blob.
    model: PathBuf,
    /// The parameters of the points the network was fitted to (`u v` per line): their
    /// boundary bounds the tessellated region. Without it, the region stored in the blob
    /// (the boundary of the points `fit` saw), or for a blob without one, the network's
    /// trained (u, v) box.
    #[arg(long, value_name = "FILE")]
    parameters: Option<PathBuf>,
    /// Coons quad grid or Delaunay.
    #[arg(long, value_enum, default_value = "coons")]
    method: MethodArg,
    /// Vertices per side (Coons), or about its square in total (Delaunay).
    #[arg(long, default_value_t = 30)]
    resolution: usize,
    /// Output mesh (`.obj`, `.ply` or `.stl`), with the network's normals.
    #[arg(long)]
    out: PathBuf,
    /// Also draw the mesh's edges in an oblique view (`.png` or `.svg`), with the points of
    /// `--show-points` as dots.
    #[arg(long, value_name = "FILE")]
    picture: Option<PathBuf>,
    /// Points to draw on the picture (text, PLY or OBJ).
    #[arg(long, value_name = "FILE")]
    show_points: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct MeshReport<'a> {
    out: &'a Path,
    vertices: usize,
    triangles: usize,
    boundary_edges: usize,
    non_manifold_edges: usize,
    watertight: bool,
}

impl<'a> MeshReport<'a> {
    fn of(out: &'a Path, mesh: &Mesh) -> Self {
        let edges = edge_report(mesh);
        MeshReport {
            out,
            vertices: mesh.vertex_count(),
            triangles: mesh.triangle_count(),
            boundary_edges: edges.boundary,
            non_manifold_edges: edges.non_manifold,
            watertight: edges.is_watertight(),
        }
    }

    fn print(&self) {
        println!(
            "wrote {}: {} vertices, {} triangles, {} boundary edges{}",
            self.out.display(),
            self.vertices,
            self.triangles,
            self.boundary_edges,
            if self.watertight { " (watertight)" } else { "" }
        );
    }
}

fn tessellate(args: &TessellateArgs) -> Result<()> {
    let model = LoadedModel::read(&args.model)?;
    let LoadedModel::SurfaceNetwork { decoded, .. } = &model else {
        bail!(
            "{} holds a {} model, not a surface network",
            args.model.display(),
            model.kind().name()
        );
    };
    if args.resolution < 2 {
        bail!("--resolution must be at least 2");
    }
    let stored = decoded
        .summary
        .as_ref()
        .map(|s| s.region.clone())
        .filter(|r| r.len() >= 4);
    let boundary = BoundaryOptions::default();
    let (columns, vertices) = (args.resolution, args.resolution * args.resolution);
    let grid = match (&args.parameters, stored) {
        (None, Some(region)) => match args.method {
            MethodArg::Coons => coons_grid(&coons_boundary_of_polygon(&region)?, columns, columns)?,
            MethodArg::Delaunay => fill_polygon(&region, vertices)?,
        },
        (given, _) => {
            let parameters: Vec<[f64; 2]> = match given {
                Some(path) => read_parameters(path, 2)?
                    .into_iter()
                    .map(|p| [p[0], p[1]])
                    .collect(),
                None => box_samples(&decoded.network),
            };
            match args.method {
                MethodArg::Coons => {
                    coons_grid(&coons_boundary(&parameters, &boundary)?, columns, columns)?
                }
                MethodArg::Delaunay => delaunay_grid(&parameters, vertices, &boundary)?,
            }
        }
    };
    let surface = synthesize(&decoded.network, &grid);
    write_mesh(&args.out, &surface.mesh, Some(&surface.normals))?;
    if let Some(path) = &args.picture {
        let points = match &args.show_points {
            Some(p) => read_points(p)?,
            None => Vec::new(),
        };
        write_picture(path, &wireframe(&surface.mesh, &points, 640))?;
    }
    let report = MeshReport::of(&args.out, &surface.mesh);
    if args.json {
        return output::json(&report);
    }
    report.print();
    Ok(())
}

/// A 21 × 21 grid of the network's trained (u, v) box: its boundary is the box.
fn box_samples(network: &SurfaceNetwork) -> Vec<[f64; 2]> {
    let n = 21;
    (0..n * n)
        .map(|k| {
            let t = |i: usize, a: usize| {
                network.input_center[a]
                    + network.input_scale[a] * (2.0 * i as f64 / (n - 1) as f64 - 1.0)
            };
            [t(k % n, 0), t(k / n, 1)]
        })
        .collect()
}

#[derive(Debug, clap::Args)]
pub struct StitchArgs {
    /// Two or more open patches (OBJ or PLY).
    #[arg(required = true, num_args = 2..)]
    patches: Vec<PathBuf>,
    /// Seam only patches A and B (0-based, in argument order): `A,B`. Repeat for more. By
    /// default every pair whose boundaries meet is seamed, along whole loops or stretches.
    #[arg(long = "seam", value_parser = super::output::comma_list::<usize, 2>)]
    seams: Vec<[usize; 2]>,
    /// The largest gap a seam closes [default: the longer of the two boundaries' median
    /// edges, at most 25 % of the smaller patch].
    #[arg(long)]
    reach: Option<f64>,
    /// Output mesh (`.obj`, `.ply` or `.stl`).
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct StitchReport<'a> {
    #[serde(flatten)]
    mesh: MeshReport<'a>,
    seams: usize,
    /// Seams along a stretch of a boundary loop rather than all of it.
    partial_seams: usize,
    boundary_loops: usize,
    gap_before: f64,
    gap_solved: f64,
    gap_after: f64,
    max_displacement: f64,
    flipped_triangles: usize,
}

fn stitch_patches(args: &StitchArgs) -> Result<()> {
    let mut patches = args
        .patches
        .iter()
        .map(|p| read_mesh(p))
        .collect::<neurosurf_trainer::Result<Vec<Mesh>>>()?;
    let before: Vec<usize> = patches.iter().map(|p| p.positions.len()).collect();
    let mut seams = find_seams(&mut patches, &args.seams, args.reach)?;
    // A named pair whose boundaries are farther apart than the reach: align their whole loops
    // (up to 25 % of the smaller patch apart), or say why not.
    for &[a, b] in &args.seams {
        let joined =
            |s: &Seam| (s.patch_a, s.patch_b) == (a, b) || (s.patch_a, s.patch_b) == (b, a);
        let touched = |s: &Seam| [a, b].iter().any(|p| s.patch_a == *p || s.patch_b == *p);
        if !seams.iter().any(joined) {
            if seams.iter().any(touched) {
                bail!(
                    "patches {a} and {b} do not meet within reach, and one of them is seamed to \
                     another patch already: pass a larger --reach"
                );
            }
            let seam = boundary_seam(&mut patches, a, b).with_context(|| {
                format!(
                    "cannot seam patch {a} ({}) to patch {b} ({})",
                    name(&args.patches, a),
                    name(&args.patches, b)
                )
            })?;
            seams.push(seam);
        }
    }
    if seams.is_empty() {
        if patches.len() == 2 {
            // Two patches: their whole loops, or the reason they do not meet.
            seams.push(boundary_seam(&mut patches, 0, 1).with_context(|| {
                format!(
                    "no boundary stretch of {} lies within reach of {}",
                    name(&args.patches, 0),
                    name(&args.patches, 1)
                )
            })?);
        } else {
            bail!(
                "the {} patches' boundaries do not meet: no stretch of one lies within reach of \
                 another; pass a larger --reach, or name the pairs to seam with --seam A,B",
                patches.len()
            );
        }
    }
    let partial_seams = seams.iter().filter(|s| !s.whole_loop).count();
    let stitched = stitch(&patches, &seams)?;
    write_mesh(&args.out, &stitched.mesh, None)?;
    let report = StitchReport {
        mesh: MeshReport::of(&args.out, &stitched.mesh),
        seams: seams.len(),
        partial_seams,
        boundary_loops: boundary_loops(&stitched.mesh.triangles)
            .with_context(|| "the stitched mesh's boundary is not a set of simple loops")?
            .len(),
        gap_before: stitched.gap_before,
        gap_solved: stitched.gap_solved,
        gap_after: stitched.gap_after,
        max_displacement: stitched.max_displacement,
        flipped_triangles: stitched.flipped_triangles,
    };
    let added: usize = patches
        .iter()
        .zip(&before)
        .map(|(p, n)| p.positions.len() - n)
        .sum();
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} seams ({} along stretches of a loop, {added} vertices added to pair them): gap \
         {:.3e} before, {:.3e} after the solve, {} after welding; vertices moved at most {:.3e}",
        report.seams,
        report.partial_seams,
        report.gap_before,
        report.gap_solved,
        report.gap_after,
        report.max_displacement
    );
    if report.boundary_loops > 0 {
        println!(
            "{} boundary loops are left open (no patch meets them)",
            report.boundary_loops
        );
    }
    report.mesh.print();
    Ok(())
}

fn name(paths: &[PathBuf], index: usize) -> String {
    paths
        .get(index)
        .map_or_else(|| "missing".to_string(), |p| p.display().to_string())
}

#[derive(Debug, clap::Args)]
pub struct FillHoleArgs {
    /// A mesh with holes (OBJ or PLY).
    mesh: PathBuf,
    /// Rings of vertices around a hole that train its network.
    #[arg(long, default_value_t = HoleOptions::default().rings)]
    rings: usize,
    /// First punch a hole: remove the triangles within RINGS edges of VERTEX (`VERTEX,RINGS`),
    /// to try the filling on a closed mesh.
    #[arg(long, value_name = "VERTEX,RINGS", value_parser = super::output::comma_list::<u32, 2>)]
    punch: Option<[u32; 2]>,
    /// Also write the holed mesh (with --punch).
    #[arg(long, value_name = "FILE")]
    holed: Option<PathBuf>,
    /// Keep the network's surface in every hole, instead of fairing it or, where a sharp
    /// crease runs through the region, putting it on the smooth parts' surfaces.
    #[arg(long)]
    no_fairing: bool,
    /// Output mesh (`.obj`, `.ply` or `.stl`).
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct FillReport<'a> {
    #[serde(flatten)]
    mesh: MeshReport<'a>,
    holes: usize,
    filled: usize,
    /// The holes left open, each with why.
    unfilled: Vec<Unfilled>,
    new_vertices: usize,
    new_triangles: usize,
    region_vertices: usize,
    /// Holes whose region LLE folded, embedded by Tutte's method instead.
    tutte_embeddings: usize,
    /// Holes whose new vertices were faired: all but those a sharp crease runs through (none
    /// with `--no-fairing`).
    faired: usize,
    /// Holes a sharp crease runs through whose new vertices went onto the smooth parts'
    /// surfaces meeting at the crease (none with `--no-fairing`).
    creases_followed: usize,
    /// Vertices no triangle used (left by a punched hole or in the input), removed.
    removed_unused_vertices: usize,
}

/// A hole that stays open.
#[derive(Serialize)]
struct Unfilled {
    /// Its number among the mesh's boundary loops.
    hole: usize,
    boundary_vertices: usize,
    /// The mean of its boundary vertices, to find it.
    centre: [f64; 3],
    reason: String,
}

/// Fills every hole it can (best effort): the holes that cannot be filled are reported with
/// the reason and stay open; it fails only when none could be filled.
fn fill_holes(args: &FillHoleArgs) -> Result<()> {
    let mut mesh = read_mesh(&args.mesh)?;
    if let Some([vertex, rings]) = args.punch {
        mesh = punch_hole(&mesh, vertex, rings as usize)?.0;
        if let Some(path) = &args.holed {
            write_mesh(path, &mesh, None)?;
        }
    }
    let options = HoleOptions {
        rings: args.rings,
        fairing: !args.no_fairing,
        ..HoleOptions::default()
    };
    let holes = boundary_loops(&mesh.triangles)?;
    if holes.is_empty() {
        bail!("{} has no holes (no boundary edges)", args.mesh.display());
    }
    let (mut new_vertices, mut new_triangles, mut region_vertices) = (0, 0, 0);
    let mut tutte_embeddings = 0;
    let (mut faired, mut creases_followed) = (0, 0);
    let mut unfilled = Vec::new();
    for (index, hole) in holes.iter().enumerate() {
        // Filling appends vertices and triangles, so the other loops keep their indices.
        match fill_hole(&mesh, hole, &options) {
            Ok(filled) => {
                new_vertices += filled.new_vertices.len();
                new_triangles += filled.new_triangles;
                region_vertices += filled.region_vertices;
                tutte_embeddings += usize::from(filled.tutte);
                faired += usize::from(filled.faired);
                creases_followed += usize::from(filled.followed_creases);
                mesh = filled.mesh;
            }
            Err(e) => {
                let count = hole.len().max(1) as f64;
                let centre = hole.iter().fold([0.0; 3], |c, &v| {
                    let p = mesh.positions[v as usize];
                    [0, 1, 2].map(|k| c[k] + p[k] / count)
                });
                unfilled.push(Unfilled {
                    hole: index,
                    boundary_vertices: hole.len(),
                    centre,
                    reason: e.to_string(),
                });
            }
        }
    }
    if unfilled.len() == holes.len() {
        let reasons: Vec<String> = unfilled
            .iter()
            .map(|u| {
                format!(
                    "hole {} ({} boundary vertices): {}",
                    u.hole, u.boundary_vertices, u.reason
                )
            })
            .collect();
        bail!(
            "{}: none of its {} holes could be filled (try another --rings):\n  {}",
            args.mesh.display(),
            holes.len(),
            reasons.join("\n  ")
        );
    }
    let (mesh, removed_unused_vertices) = drop_unused_vertices(&mesh);
    write_mesh(&args.out, &mesh, None)?;
    let report = FillReport {
        mesh: MeshReport::of(&args.out, &mesh),
        holes: holes.len(),
        filled: holes.len() - unfilled.len(),
        unfilled,
        new_vertices,
        new_triangles,
        region_vertices,
        tutte_embeddings,
        faired,
        creases_followed,
        removed_unused_vertices,
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "filled {} of {} hole(s) ({} faired, {} across creases on the parts' surfaces, the others \
         on their networks): {} new vertices, {} new triangles, networks trained on {} \
         vertices; {} unused vertices removed",
        report.filled,
        report.holes,
        report.faired,
        report.creases_followed,
        report.new_vertices,
        report.new_triangles,
        report.region_vertices,
        report.removed_unused_vertices
    );
    for u in &report.unfilled {
        println!(
            "left open: hole {} ({} boundary vertices, around {:.4}, {:.4}, {:.4}): {}",
            u.hole, u.boundary_vertices, u.centre[0], u.centre[1], u.centre[2], u.reason
        );
    }
    report.mesh.print();
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Point counts (default: 100, 1000, 10000, 35947).
    #[arg(long, value_delimiter = ',')]
    sizes: Vec<usize>,
    /// The Stanford bunny (default: `stanford-bunny.obj` in the data folder).
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Print the rows as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct BenchRow {
    points: usize,
    source: &'static str,
    embedding_seconds: Option<f64>,
    fitting_seconds: Option<f64>,
    search_seconds: Option<f64>,
    refinement_seconds: Option<f64>,
    total_seconds: Option<f64>,
    search_steps: Option<usize>,
    search_trials: Option<usize>,
    eigen_iterations: Option<usize>,
    hidden_layers: Option<usize>,
    neurons: Option<usize>,
    relative_rms_error: Option<f64>,
    error: Option<String>,
}

fn bench(args: &BenchArgs) -> Result<()> {
    let path = match &args.mesh {
        Some(path) => path.clone(),
        None => data_file("stanford-bunny.obj")?,
    };
    let mesh = read_mesh(&path)?;
    let sizes = if args.sizes.is_empty() {
        BENCHMARK_SIZES.to_vec()
    } else {
        args.sizes.clone()
    };
    let mut rows = Vec::new();
    for size in sizes {
        let row = match benchmark(
            &mesh,
            BACK_SEED,
            &[size],
            &LleOptions::default(),
            &TopologyOptions::default(),
        ) {
            Ok(found) => {
                let r = &found[0];
                BenchRow {
                    points: r.points,
                    source: r.source,
                    embedding_seconds: Some(r.embedding_seconds),
                    fitting_seconds: Some(r.fitting_seconds),
                    search_seconds: Some(r.search_seconds),
                    refinement_seconds: Some(r.refinement_seconds),
                    total_seconds: Some(r.embedding_seconds + r.fitting_seconds),
                    search_steps: Some(r.search_steps),
                    search_trials: Some(r.search_trials),
                    eigen_iterations: Some(r.eigen_iterations),
                    hidden_layers: Some(r.layers),
                    neurons: Some(r.neurons),
                    relative_rms_error: Some(r.relative_rms_error),
                    error: None,
                }
            }
            Err(e) => BenchRow {
                points: size,
                source: if size <= neurosurf_trainer::parametric::PATCH_VERTICES {
                    "vertices"
                } else {
                    "subdivided"
                },
                embedding_seconds: None,
                fitting_seconds: None,
                search_seconds: None,
                refinement_seconds: None,
                total_seconds: None,
                search_steps: None,
                search_trials: None,
                eigen_iterations: None,
                hidden_layers: None,
                neurons: None,
                relative_rms_error: None,
                error: Some(e.to_string()),
            },
        };
        if !args.json {
            eprintln!("{} points done", row.points);
        }
        rows.push(row);
    }
    if args.json {
        return output::json(&rows);
    }
    let seconds = |s: Option<f64>| s.map_or("—".to_string(), |s| format!("{s:.3} s"));
    let mut table = Table::new([
        ("points", Align::Right),
        ("source", Align::Left),
        ("embedding", Align::Right),
        ("fitting", Align::Right),
        ("total", Align::Right),
        ("network", Align::Left),
        ("rel. RMS", Align::Left),
    ]);
    for r in &rows {
        table.push([
            r.points.to_string(),
            r.source.to_string(),
            seconds(r.embedding_seconds),
            seconds(r.fitting_seconds),
            seconds(r.total_seconds),
            match (r.hidden_layers, r.neurons) {
                (Some(l), Some(n)) => format!("{l} × {n}"),
                _ => "—".to_string(),
            },
            match (&r.error, r.relative_rms_error) {
                (Some(e), _) => format!("refused: {e}"),
                (None, Some(x)) => format!("{x:.2e}"),
                _ => "—".to_string(),
            },
        ]);
    }
    print!("{}", table.to_text());
    Ok(())
}

/// Points from text, PLY or OBJ (its vertices).
pub(super) fn read_points(path: &Path) -> Result<Vec<[f64; 3]>> {
    if path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        return Ok(read_obj_vertices(path)?);
    }
    Ok(read_query_points(path)?)
}

/// One line of space-separated numbers per row.
fn rows<const N: usize>(values: &[[f64; N]]) -> String {
    let mut text = String::new();
    for row in values {
        let line: Vec<String> = row.iter().map(|c| format!("{c}")).collect();
        text.push_str(&line.join(" "));
        text.push('\n');
    }
    text
}

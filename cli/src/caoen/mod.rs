//! `neurosurf caoen`: Cao En surfaces (Wyvill, Cao & Trotman 1992) — build or fit a network
//! from key and target points, mesh it, fit the teapot, render, morph, distort, compress
//! images.

mod derived;
mod distort;
mod fit_mesh;
mod image;
mod morph;
mod normals;
mod perspective;
mod render;
mod shade;
mod teapot;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Subcommand, ValueEnum};
use neurosurf_core::caoen::{Blending, Domain};
use serde::Serialize;

use neurosurf_trainer::caoen::{
    self, BetweenKeys, CaoEnNetwork, between_keys, fit_auto, fit_shape, fit_sharpness,
    from_key_points, leave_one_out, rms_error,
};
use neurosurf_trainer::evaluate::{LoadedModel, Precision};
use neurosurf_trainer::io::{read_rows, write_mesh, write_textured_obj};

use super::output::{self, blob_scalar, comma_list, wrote_blob};

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Build a network from key and target points (the paper's construction) and, by
    /// default, fit V so the surface passes through the targets; write its blob.
    Fit(FitArgs),
    /// Map a subdivided sphere (or a torus grid) through a network: a polygon mesh with exact
    /// normals (OBJ or PLY), optionally with the source's texture coordinates (OBJ `vt`).
    Mesh(MeshArgs),
    /// Fold the cosine law for fixed lights into extra outputs of a shape network (p = 3 + k),
    /// fitted at the key points; reports the error against the direct computation.
    Shade(shade::Args),
    /// Fit a network to a closed genus-0 mesh through its spherical parameterization.
    FitMesh(fit_mesh::Args),
    /// The teapot as four Cao En surfaces on the sphere (body, lid, spout, handle): four
    /// blobs, the combined mesh, its distance to the mesh by what shows, optionally a picture.
    Teapot(teapot::Args),
    /// The paper's approximate-normal network: the same key points, the exact normals at
    /// them as targets; reports its angle error against the exact normals.
    Normals(normals::Args),
    /// The paper's perspective approximation: a network whose outputs are the screen
    /// coordinates and depth of a pinhole camera's view; reports its error.
    Perspective(perspective::Args),
    /// Depth-buffer picture (PNG) of Cao En surfaces with gap filling, or with --ray-march
    /// the implicit form of convex shapes, alone or combined (CSG).
    Render(render::Args),
    /// Metamorphosis between two networks (any key counts): a sequence of meshes and
    /// optionally pictures.
    Morph(morph::Args),
    /// Distort a mesh through a 4-D hypersphere → 3-D network with point controls.
    Distort(distort::Args),
    /// Image compression on a 5-D hypersphere: compress, decompress, sample picture.
    #[command(subcommand)]
    Image(image::Command),
}

pub fn run(command: &Command) -> Result<()> {
    match command {
        Command::Fit(args) => fit(args),
        Command::Mesh(args) => mesh(args),
        Command::Shade(args) => shade::run(args),
        Command::FitMesh(args) => fit_mesh::run(args),
        Command::Teapot(args) => teapot::run(args),
        Command::Normals(args) => normals::run(args),
        Command::Perspective(args) => perspective::run(args),
        Command::Render(args) => render::run(args),
        Command::Morph(args) => morph::run(args),
        Command::Distort(args) => distort::run(args),
        Command::Image(command) => image::run(command),
    }
}

/// The Cao En network in the blob at `path`, for `command`.
fn read_network(path: &Path, command: &str) -> Result<CaoEnNetwork> {
    let model = LoadedModel::read(path)?;
    match model {
        LoadedModel::CaoEn { decoded, .. } => Ok(decoded.network),
        other => bail!(
            "{}: a {} model; `caoen {command}` takes Cao En networks",
            path.display(),
            other.kind().name()
        ),
    }
}

/// The source domain.
#[derive(Copy, Clone, Debug, ValueEnum)]
pub enum DomainArg {
    /// The unit sphere (or a hypersphere with --source-dimension > 3).
    Sphere,
    /// The torus: source (cos θ, sin θ, cos φ, sin φ).
    Torus,
}

/// The blending function of every key point.
#[derive(Copy, Clone, Debug, ValueEnum)]
pub enum BlendingArg {
    /// s^q for s > 0, else 0 (q whole).
    Power,
    /// e^{q(s − 1)}.
    Exponential,
    /// (1 + q(s − 1))³ where positive, else 0: local support, only the cap s > 1 − 1/q
    /// around each key point; groups of keys out of reach are skipped by the core. Best with
    /// --normalized (a partition of unity): unnormalized, the surface sags toward the centre
    /// where few caps overlap.
    Compact,
}

#[derive(Debug, clap::Args)]
pub struct FitArgs {
    /// Text, one key point per line: its m source coordinates, then its target's p
    /// coordinates. A line of 3 numbers is a target alone on the sphere: its key point is
    /// its direction from the targets' centroid.
    points: PathBuf,
    /// The source domain.
    #[arg(long, value_enum, default_value_t = DomainArg::Sphere)]
    domain: DomainArg,
    /// Source coordinates per key point (3 on the sphere, 4 on the torus, more for a
    /// hypersphere).
    #[arg(long)]
    source_dimension: Option<usize>,
    /// The blending function.
    #[arg(long, value_enum, default_value_t = BlendingArg::Power)]
    blending: BlendingArg,
    /// Use the rational (normalized) form: y is a weighted mean of V. The default when V is
    /// fitted: it follows star-shaped targets more closely between the keys.
    #[arg(long, conflicts_with = "plain")]
    normalized: bool,
    /// Use the plain (unnormalized) form, y = Σ F·v. The default with --no-fit (the
    /// paper's construction).
    #[arg(long)]
    plain: bool,
    /// q of every key point (whole for power blending). Default: when V is fitted, the q of
    /// 1 … 64 that predicts left-out targets best (leave-one-out); with --no-fit, 4.
    #[arg(long)]
    sharpness: Option<f64>,
    /// Keep V = the targets, as the paper does (the surface passes near them, not through).
    #[arg(long)]
    no_fit: bool,
    /// Also choose q per key point from these candidates (comma-separated), scored between the
    /// key points.
    #[arg(long, value_delimiter = ',', conflicts_with = "no_fit")]
    fit_sharpness: Vec<f64>,
    /// How the blob stores the network: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    scalar: Precision,
    /// Output blob.
    #[arg(long)]
    out: PathBuf,
    /// Also write the mapped icosphere (`.obj` or `.ply`).
    #[arg(long, value_name = "FILE")]
    mesh: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct FitReport<'a> {
    out: &'a Path,
    stored_as: &'static str,
    blob_bytes: usize,
    key_points: usize,
    source_dimension: usize,
    target_dimension: usize,
    fitted: bool,
    /// The rational (normalized) form.
    normalized: bool,
    /// The q of every key point, `None` when the keys have different q.
    sharpness: Option<f64>,
    /// The smallest and largest q of the keys.
    sharpness_range: [f64; 2],
    /// How q was set: `given`, `leave-one-out` (one q, or q scaled by each key's spacing) or
    /// `per key` (--fit-sharpness).
    sharpness_from: &'static str,
    /// RMS distance from y(wᵢ) to tᵢ over the key points.
    rms_at_keys: f64,
    /// RMS distance from each target to the surface fitted through the others, at its key
    /// point (`None` for the paper's construction or a singular fit).
    leave_one_out: Option<f64>,
    /// The surface between the keys, on dense samples of the domain.
    between_keys: BetweenKeys,
    mesh: Option<&'a Path>,
}

/// Key points and their targets, one row each.
type KeysAndTargets = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// Key points and targets from the rows of the point file.
fn keys_and_targets(rows: &[Vec<f64>], m: usize) -> Result<KeysAndTargets> {
    let width = rows.first().map_or(0, Vec::len);
    if width == 3 && m == 3 {
        let n = rows.len().max(1) as f64;
        let centroid: Vec<f64> = (0..3)
            .map(|k| rows.iter().map(|r| r[k]).sum::<f64>() / n)
            .collect();
        let keys = rows
            .iter()
            .map(|r| {
                let d: Vec<f64> = (0..3).map(|k| r[k] - centroid[k]).collect();
                let length = d.iter().map(|c| c * c).sum::<f64>().sqrt();
                if length > 0.0 {
                    Ok(d.iter().map(|c| c / length).collect())
                } else {
                    bail!("a target sits at the targets' centroid: it has no direction")
                }
            })
            .collect::<Result<Vec<_>>>()?;
        return Ok((keys, rows.to_vec()));
    }
    if width <= m {
        bail!("each line needs {m} source coordinates and at least one target coordinate");
    }
    Ok(rows
        .iter()
        .map(|r| (r[..m].to_vec(), r[m..].to_vec()))
        .unzip())
}

fn fit(args: &FitArgs) -> Result<()> {
    let scalar = blob_scalar(args.scalar)?;
    neurosurf_trainer::io::check_output(&args.out)?;
    let (domain, default_m) = match args.domain {
        DomainArg::Sphere => (Domain::Sphere, 3),
        DomainArg::Torus => (Domain::Torus, 4),
    };
    let m = args.source_dimension.unwrap_or(default_m);
    let blending = match args.blending {
        BlendingArg::Power => Blending::Power,
        BlendingArg::Exponential => Blending::Exponential,
        BlendingArg::Compact => Blending::Compact,
    };
    let rows = read_rows(&args.points)?;
    if rows.is_empty() {
        bail!("{}: no key points", args.points.display());
    }
    let (keys, targets) = keys_and_targets(&rows, m)
        .with_context(|| format!("cannot read key points from {}", args.points.display()))?;
    neurosurf_trainer::caoen::check_key_count(keys.len(), &args.points.display().to_string())?;
    let normalized = args.normalized || (!args.plain && !args.no_fit);
    let built = from_key_points(
        domain,
        blending,
        normalized,
        &keys,
        &targets,
        args.sharpness.unwrap_or(PAPER_SHARPNESS),
    )?;
    // The fit takes the keys as they sit on the domain (the network normalizes them).
    let on_domain = built.weights.clone();
    let (network, sharpness_from): (CaoEnNetwork, _) =
        match (args.no_fit, args.sharpness, args.fit_sharpness.is_empty()) {
            (true, _, _) => (built, "given"),
            (false, Some(_), true) => (fit_shape(&built, &on_domain, &targets)?, "given"),
            (false, None, true) => (fit_auto(&built, &targets)?.0, "leave-one-out"),
            (false, given, false) => {
                let start = match given {
                    Some(_) => built,
                    None => fit_auto(&built, &targets)?.0,
                };
                let candidates = &args.fit_sharpness;
                (
                    fit_sharpness(&start, &on_domain, &targets, candidates)?.0,
                    "per key",
                )
            }
        };
    let blob = caoen::to_blob(&network, scalar, b"neurosurf caoen fit")?;
    if args.mesh.is_some() && !matches!(network.source_dimension(), 3 | 4) {
        bail!("--mesh maps sphere (m = 3) and torus (m = 4) networks, this one has m = {m}");
    }
    neurosurf_trainer::blob::write_checked(&args.out, &blob)?;
    if let Some(path) = &args.mesh {
        write_network_mesh(&network, path, 4, [48, 24])?;
    }
    let report = FitReport {
        out: &args.out,
        stored_as: scalar.name(),
        blob_bytes: blob.len(),
        key_points: network.key_count(),
        source_dimension: network.source_dimension(),
        target_dimension: network.target_dimension(),
        fitted: !args.no_fit,
        normalized,
        sharpness: network
            .sharpness
            .iter()
            .all(|&q| q == network.sharpness[0])
            .then(|| network.sharpness[0]),
        sharpness_range: network
            .sharpness
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |[lo, hi], &q| {
                [lo.min(q), hi.max(q)]
            }),
        sharpness_from,
        rms_at_keys: rms_error(&network, &on_domain, &targets),
        leave_one_out: (!args.no_fit)
            .then(|| leave_one_out(&network, &targets))
            .flatten(),
        between_keys: between_keys(&network, &targets),
        mesh: args.mesh.as_deref(),
    };
    if args.json {
        return output::json(&report);
    }
    print_fit_report(&report);
    wrote_blob(&args.out, blob.len(), scalar, args.mesh.as_deref());
    Ok(())
}

/// q of every key point in the paper's construction (--no-fit) when none is given.
const PAPER_SHARPNESS: f64 = 4.0;

fn print_fit_report(report: &FitReport<'_>) {
    let form = if report.normalized {
        "rational form"
    } else {
        "plain form"
    };
    let q = match report.sharpness {
        Some(q) => format!("q = {q}"),
        None => format!(
            "q {} … {} by key",
            report.sharpness_range[0], report.sharpness_range[1]
        ),
    };
    let q = match report.sharpness_from {
        "leave-one-out" => format!("{q} (chosen by leave-one-out)"),
        _ => q,
    };
    let v = if report.fitted {
        "V fitted through the targets"
    } else {
        "V = the targets (the paper's construction)"
    };
    println!(
        "{} key points, {}-D → {}-D, {form}, {q}, {v}: RMS distance to the targets at the key \
         points {:.3e}",
        report.key_points, report.source_dimension, report.target_dimension, report.rms_at_keys
    );
    let b = &report.between_keys;
    let percent = |d: f64| 100.0 * d / b.diagonal.max(f64::MIN_POSITIVE);
    if let Some(loo) = report.leave_one_out {
        println!(
            "  a target left out is predicted within {loo:.3e} RMS ({:.2} % of the targets' \
             diagonal)",
            percent(loo)
        );
    }
    println!(
        "  between the keys the surface stays within {:.3e} of a target ({:.2} % of the \
         diagonal; neighbouring targets are up to {:.3e} apart)",
        b.farthest_from_targets,
        percent(b.farthest_from_targets),
        b.target_gap
    );
}

#[derive(Debug, clap::Args)]
pub struct MeshArgs {
    /// A Cao En blob (p ≥ 3 outputs: the first three are the position).
    model: PathBuf,
    /// Icosphere subdivisions for a sphere network (level s: 10·4ˢ + 2 vertices).
    #[arg(long, default_value_t = 4)]
    subdivisions: usize,
    /// Grid of a torus network, `AROUND,ACROSS`.
    #[arg(long, value_parser = comma_list::<usize, 2>, default_value = "48,24")]
    grid: [usize; 2],
    /// Also write texture coordinates (`vt`, OBJ only): each vertex's source point as
    /// longitude/latitude on the sphere, (θ, φ)/2π on the torus, so a texture defined on the
    /// sphere is carried onto the surface.
    #[arg(long)]
    texture: bool,
    /// Output mesh (`.obj` or `.ply`), with the exact normals.
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct MeshReport<'a> {
    out: &'a Path,
    vertices: usize,
    triangles: usize,
    /// `vt` entries written (0 without --texture): one per vertex, plus the extra ones of
    /// triangles across the seam or at a pole.
    texture_coordinates: usize,
}

fn mesh(args: &MeshArgs) -> Result<()> {
    let network = read_network(&args.model, "mesh")?;
    let is_obj = args
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if args.texture && !is_obj {
        bail!(
            "{}: texture coordinates are written to OBJ files only",
            args.out.display()
        );
    }
    let mapped = map_network(&network, args.subdivisions, args.grid)?;
    let texture = args
        .texture
        .then(|| caoen::mesh_texture(network.domain, &mapped));
    if texture.is_some() {
        write_textured_obj(
            &args.out,
            &mapped.mesh,
            Some(&mapped.normals),
            texture.as_ref(),
        )?;
    } else {
        write_mesh(&args.out, &mapped.mesh, Some(&mapped.normals))?;
    }
    let report = MeshReport {
        out: &args.out,
        vertices: mapped.mesh.vertex_count(),
        triangles: mapped.mesh.triangle_count(),
        texture_coordinates: texture.map_or(0, |t| t.coordinates.len()),
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "wrote {} ({} vertices, {} triangles{})",
        args.out.display(),
        report.vertices,
        report.triangles,
        if args.texture {
            format!(", {} texture coordinates", report.texture_coordinates)
        } else {
            String::new()
        }
    );
    Ok(())
}

/// Maps a sphere network (icosphere) or a torus network (grid).
fn map_network(
    network: &CaoEnNetwork,
    subdivisions: usize,
    [around, across]: [usize; 2],
) -> Result<caoen::CaoEnMesh> {
    Ok(
        match (
            network.source_dimension(),
            network.domain == Domain::Torus.code(),
        ) {
            (4, true) => caoen::torus_mesh(network, around, across)?,
            (3, false) => caoen::sphere_mesh(network, subdivisions)?,
            (m, _) => bail!(
                "only sphere (m = 3) and torus (m = 4) networks are meshed, this one has m = {m}"
            ),
        },
    )
}

/// Meshes a sphere or torus network and writes it with its normals.
fn write_network_mesh(
    network: &CaoEnNetwork,
    path: &Path,
    subdivisions: usize,
    grid: [usize; 2],
) -> Result<()> {
    let mapped = map_network(network, subdivisions, grid)?;
    write_mesh(path, &mapped.mesh, Some(&mapped.normals))?;
    Ok(())
}

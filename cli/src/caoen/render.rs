//! `neurosurf caoen render`: depth-buffer pictures of Cao En surfaces (paper §10.3), or the
//! ray-marched implicit form of a convex shape, alone or combined with a second one (§9,
//! §10.1).

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use neurosurf_core::caoen::{Blending, Domain};
use serde::Serialize;

use neurosurf_trainer::caoen::{
    self, CaoEnNetwork, ConvexSolid, Csg, Rendering, View, convex_implicit, depth_buffer_image,
    ray_march_framing, ray_marched_image,
};
use neurosurf_trainer::plot::Rgb;
use neurosurf_trainer::render::write_png;

use super::super::output::{self, comma_list};
use super::read_network;

/// Colours of the first models, in order (then repeated).
pub(super) const PALETTE: [Rgb; 5] = [
    Rgb(214, 120, 60),
    Rgb(70, 130, 200),
    Rgb(90, 170, 90),
    Rgb(200, 170, 60),
    Rgb(160, 90, 180),
];

/// Where the camera looks from and how big the picture is.
#[derive(Debug, Clone, clap::Args)]
pub struct Camera {
    /// Picture size, `WIDTH,HEIGHT`.
    #[arg(long, value_parser = comma_list::<u32, 2>, default_value = "480,480")]
    size: [u32; 2],
    /// The direction the camera looks along, `X,Y,Z`.
    #[arg(long, value_parser = comma_list::<f64, 3>, default_value = "-0.5,-0.45,-1", allow_hyphen_values = true)]
    direction: [f64; 3],
    /// Roughly up on the screen, `X,Y,Z`.
    #[arg(long, value_parser = comma_list::<f64, 3>, default_value = "0,1,0", allow_hyphen_values = true)]
    up: [f64; 3],
}

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Cao En blobs (sphere or torus networks, p = 3); with --ray-march one, or two with
    /// --csg, whose targets are the feet of a convex polyhedron's face planes.
    #[arg(required = true)]
    models: Vec<PathBuf>,
    #[command(flatten)]
    camera: Camera,
    /// Starting grid of the depth buffer: icosphere level (torus: 10·2ˢ × 5·2ˢ), refined per
    /// triangle until its screen edges are at most 3 pixels, then rasterized.
    #[arg(long, default_value_t = 3)]
    subdivisions: usize,
    /// Ray-march the implicit form f(x) = Σ (x·wᵢ)₊^q with wᵢ = tᵢ/|tᵢ|² (the solid f ≤ level)
    /// instead of mapping the sphere.
    #[arg(long)]
    ray_march: bool,
    /// q of the implicit form (power blending, whole).
    #[arg(long, default_value_t = 16.0, requires = "ray_march")]
    sharpness: f64,
    /// The level s of the implicit form's surface f = s.
    #[arg(long, default_value_t = 1.0, requires = "ray_march")]
    level: f64,
    /// How two ray-marched solids A and B (the first and second model) combine: where either
    /// is, where both are, or where A is and B is not.
    #[arg(long, value_enum, requires = "ray_march")]
    csg: Option<CsgArg>,
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

/// `--csg` values.
#[derive(Copy, Clone, Debug, clap::ValueEnum)]
enum CsgArg {
    Union,
    Intersection,
    Difference,
}

#[derive(Serialize)]
struct Report<'a> {
    out: &'a Path,
    mode: &'static str,
    models: usize,
    width: u32,
    height: u32,
    /// Pixels the surfaces cover.
    covered_pixels: usize,
}

pub fn run(args: &Args) -> Result<()> {
    let networks = args
        .models
        .iter()
        .map(|p| read_network(p, "render"))
        .collect::<Result<Vec<_>>>()?;
    let (mode, rendering) = if args.ray_march {
        let csg = match (networks.len(), args.csg) {
            (1, None) => Csg::Union,
            (1, Some(_)) => bail!("--csg combines two models, got one: give a second blob"),
            (2, Some(CsgArg::Union)) => Csg::Union,
            (2, Some(CsgArg::Intersection)) => Csg::Intersection,
            (2, Some(CsgArg::Difference)) => Csg::Difference,
            (2, None) => bail!(
                "--ray-march draws one model, or two combined by --csg \
                 union|intersection|difference; got two and no --csg"
            ),
            (n, _) => bail!("--ray-march draws one model, or two with --csg; got {n}"),
        };
        let mode = match (networks.len(), csg) {
            (1, _) => "ray-marched implicit form",
            (_, Csg::Union) => "ray-marched union",
            (_, Csg::Intersection) => "ray-marched intersection",
            (_, Csg::Difference) => "ray-marched difference",
        };
        (mode, ray_march(&networks, csg, args)?)
    } else {
        if args.csg.is_some() {
            bail!("--csg needs --ray-march");
        }
        (
            "depth buffer",
            depth_picture(&networks, &args.camera, args.subdivisions)?,
        )
    };
    write_png(&args.out, &rendering.image)?;
    let report = Report {
        out: &args.out,
        mode,
        models: networks.len(),
        width: rendering.image.width(),
        height: rendering.image.height(),
        covered_pixels: rendering.covered(),
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "wrote {} ({} × {}, {mode}, {} pixels covered)",
        args.out.display(),
        report.width,
        report.height,
        report.covered_pixels
    );
    Ok(())
}

/// Points spread over a network's surface (a coarse mesh), for framing.
fn sample_points(network: &CaoEnNetwork) -> Result<Vec<[f64; 3]>> {
    let mapped = match (
        network.domain == Domain::Torus.code(),
        network.source_dimension(),
        network.target_dimension(),
    ) {
        (true, 4, 3) => caoen::torus_mesh(network, 40, 20)?,
        (false, 3, 3) => caoen::sphere_mesh(network, 3)?,
        (_, m, p) => bail!(
            "rendering needs sphere (m = 3) or torus networks with p = 3 outputs, got m = {m}, \
             p = {p}"
        ),
    };
    Ok(mapped.mesh.positions)
}

/// A view of `camera` framing the bounding sphere of `points`.
fn framing(points: &[[f64; 3]], camera: &Camera) -> Result<View> {
    let [width, height] = camera.size;
    Ok(View::framing_points(
        points,
        camera.direction,
        camera.up,
        width,
        height,
    )?)
}

/// The depth-buffer picture of `networks` (each in its [`PALETTE`] colour), framed to show
/// them all.
pub(super) fn depth_picture(
    networks: &[CaoEnNetwork],
    camera: &Camera,
    subdivisions: usize,
) -> Result<Rendering> {
    depth_picture_framed(networks, networks, camera, subdivisions)
}

/// As [`depth_picture`], framed on the surfaces of `frame` instead (e.g. both ends of a
/// morph, so every frame has the same camera).
pub(super) fn depth_picture_framed(
    networks: &[CaoEnNetwork],
    frame: &[CaoEnNetwork],
    camera: &Camera,
    subdivisions: usize,
) -> Result<Rendering> {
    let mut points = Vec::new();
    for network in frame.iter().chain(networks) {
        points.extend(sample_points(network)?);
    }
    let view = framing(&points, camera)?;
    let models: Vec<(&CaoEnNetwork, Rgb)> = networks
        .iter()
        .zip(PALETTE.iter().cycle())
        .map(|(n, &c)| (n, c))
        .collect();
    Ok(depth_buffer_image(&models, &view, subdivisions)?)
}

/// Ray-marches the implicit forms of sphere networks whose targets are the feet of convex
/// polyhedra's face planes (checked: every target lies on its polyhedron), combined by `csg`
/// when there are two.
fn ray_march(networks: &[CaoEnNetwork], csg: Csg, args: &Args) -> Result<Rendering> {
    if !(args.sharpness >= 1.0 && args.sharpness.fract() == 0.0) {
        bail!(
            "--sharpness must be a whole number ≥ 1 for power blending, got {}",
            args.sharpness
        );
    }
    let mut implicit = Vec::with_capacity(networks.len());
    for (i, network) in networks.iter().enumerate() {
        if network.domain != Domain::Sphere.code()
            || network.source_dimension() != 3
            || network.target_dimension() != 3
        {
            bail!(
                "--ray-march needs sphere networks with m = 3 and p = 3 (their targets are the \
                 face feet); model {} is m = {}, p = {}",
                i + 1,
                network.source_dimension(),
                network.target_dimension()
            );
        }
        let feet: Vec<[f64; 3]> = network.targets.iter().map(|t| [t[0], t[1], t[2]]).collect();
        check_convex(&feet)?;
        implicit.push(convex_implicit(&feet, Blending::Power, args.sharpness)?);
    }
    let solids = implicit
        .iter()
        .map(|network| ConvexSolid::new(network, args.level))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let [width, height] = args.camera.size;
    let view = ray_march_framing(
        &solids,
        args.camera.direction,
        args.camera.up,
        width,
        height,
    )?;
    let colored: Vec<(&ConvexSolid, Rgb)> = solids
        .iter()
        .zip(PALETTE[1..].iter())
        .map(|(s, &c)| (s, c))
        .collect();
    Ok(ray_marched_image(&colored, csg, &view)?)
}

/// Every foot tᵢ must lie in every face's half-space x·tⱼ ≤ |tⱼ|² (else face i is cut off
/// by face j: the feet do not describe a convex polyhedron around the origin).
fn check_convex(feet: &[[f64; 3]]) -> Result<()> {
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for (i, a) in feet.iter().enumerate() {
        if dot(a, a) <= 0.0 || !dot(a, a).is_finite() {
            bail!("target {i} is at the origin: it is no face's foot point");
        }
        for (j, b) in feet.iter().enumerate() {
            if dot(a, b) > dot(b, b) * (1.0 + 1e-9) {
                bail!(
                    "not convex: target {i} {a:?} lies outside the face plane of target {j} \
                     {b:?} (x·t{j} ≤ |t{j}|² fails), so the targets are not the face feet of a \
                     convex polyhedron around the origin"
                );
            }
        }
    }
    Ok(())
}

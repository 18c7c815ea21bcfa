//! `neurosurf caoen fit-mesh`: a Cao En surface fitted to a genus-0 mesh (spot, a scan with
//! holes such as the Stanford bunny: unused vertices are dropped and holes capped first).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use neurosurf_trainer::caoen::{
    self, Closing, MeshFitOptions, SurfaceDistance, close_for_sphere, fit_parameterized,
    spherical_parameterization,
};
use neurosurf_trainer::evaluate::Precision;
use neurosurf_trainer::io::read_mesh;

use super::super::output::{self, blob_scalar, wrote_blob};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// A genus-0 triangle mesh (`.obj` or `.ply`); holes are capped.
    mesh: PathBuf,
    /// Key points (farthest-first on the surface; at most 256 for the core).
    #[arg(long, default_value_t = 200)]
    keys: usize,
    /// How the blob stores the network: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    scalar: Precision,
    /// Output blob.
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    out: &'a Path,
    blob_bytes: usize,
    key_points: usize,
    vertices: usize,
    /// What was repaired before the map: unused vertices removed, holes capped.
    closing: &'a Closing,
    /// The sphere map's largest per-vertex stretch (1 for an area-preserving map).
    area_distortion: f64,
    /// RMS of |y(xⱼ) − pⱼ| at the mesh vertices, of the bounding diagonal.
    vertex_rms: f64,
    /// Surface against the mesh, of the bounding diagonal.
    distance: SurfaceDistance,
}

pub fn run(args: &Args) -> Result<()> {
    let scalar = blob_scalar(args.scalar)?;
    neurosurf_trainer::io::check_output(&args.out)?;
    neurosurf_trainer::caoen::check_key_count(args.keys, "--keys")?;
    let mesh = read_mesh(&args.mesh)?;
    let (mesh, closing) = close_for_sphere(&mesh)
        .with_context(|| format!("preparing {} for a sphere map", args.mesh.display()))?;
    let map = spherical_parameterization(&mesh)
        .with_context(|| format!("mapping {} onto the sphere", args.mesh.display()))?;
    let fit = fit_parameterized(&mesh, &map.points, args.keys, &MeshFitOptions::default())?;
    let blob = caoen::to_blob(&fit.network, scalar, b"neurosurf caoen fit-mesh")?;
    neurosurf_trainer::blob::write_checked(&args.out, &blob)?;
    let report = Report {
        out: &args.out,
        blob_bytes: blob.len(),
        key_points: fit.network.key_count(),
        vertices: mesh.vertex_count(),
        closing: &closing,
        area_distortion: map.area_distortion,
        vertex_rms: fit.vertex_rms,
        distance: fit.distance,
    };
    if args.json {
        return output::json(&report);
    }
    if closing.unused_vertices > 0 || !closing.holes.is_empty() {
        println!(
            "removed {} unused vertices; capped {} holes ({} boundary edges)",
            closing.unused_vertices,
            closing.holes.len(),
            closing
                .holes
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    println!(
        "{} key points on {} vertices: RMS {:.4} at the vertices, two-sided RMS {:.4}, \
         Hausdorff {:.4} (of the bounding diagonal)",
        report.key_points,
        report.vertices,
        report.vertex_rms,
        report.distance.rms,
        report.distance.hausdorff
    );
    wrote_blob(&args.out, blob.len(), scalar, None);
    Ok(())
}

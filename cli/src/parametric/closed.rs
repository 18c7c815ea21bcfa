//! `neurosurf parametric closed`: a closed mesh rebuilt from patches of surface networks,
//! stitched watertight; the patches' blobs and their seams are kept.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use neurosurf_trainer::evaluate::Precision;
use neurosurf_trainer::io::{
    MeshOrPoints, check_output, read_mesh_or_points, write_atomic, write_mesh,
};
use neurosurf_trainer::parametric::{
    ClosedOptions, MAX_REGION_VERTICES, NetworkSummary, SeamCurve, network_to_blob,
    reconstruct_closed, reconstruct_closed_points,
};

use super::{MeshReport, NetworkArgs};
use crate::output::{self, blob_scalar};

#[derive(Debug, clap::Args)]
pub struct ClosedArgs {
    /// A closed mesh (OBJ or PLY; open boundary loops, a scan's holes, are capped first) or a
    /// closed point cloud (text rows of x y z, or a PLY or OBJ file without faces), which is
    /// meshed first.
    mesh: PathBuf,
    /// Output mesh (`.obj`, `.ply` or `.stl`).
    #[arg(long)]
    out: PathBuf,
    /// Also keep every patch's blob (`patch-NN.nsb`) and the seams between them
    /// (`seams.json`: for each pair of patches that meet, the seam points' (u, v) in both) in
    /// this folder.
    #[arg(long, value_name = "DIR")]
    blobs: Option<PathBuf>,
    /// Patches of the first cut; regions that are not discs facing one way are split further.
    #[arg(long, default_value_t = ClosedOptions::default().patches)]
    patches: usize,
    /// About this many vertices in the output mesh.
    #[arg(long, default_value_t = ClosedOptions::default().vertices)]
    vertices: usize,
    #[command(flatten)]
    network: NetworkArgs,
    /// Seed of every patch's split and initial weights.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// How the blobs store the networks: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    scalar: Precision,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct ClosedReport<'a> {
    #[serde(flatten)]
    mesh: MeshReport<'a>,
    patches: usize,
    seams: usize,
    capped_holes: usize,
    /// Two-sided RMS distance to the (capped) input over its bounding diagonal.
    relative_rms_error: f64,
    /// The largest of those distances (vertex-sampled Hausdorff), over the diagonal.
    relative_hausdorff: f64,
    /// The worst patch's network RMS error over its points' diagonal.
    worst_patch_error: f64,
    /// Mean distance between the two blobs of a seam at its points, over the diagonal.
    seam_gap: f64,
    /// The largest such distance.
    max_seam_gap: f64,
    gap_before_stitch: f64,
    max_displacement: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    blobs: Option<&'a Path>,
    /// How a point cloud was meshed before the cut; absent for a mesh.
    #[serde(skip_serializing_if = "Option::is_none")]
    from_points: Option<PointsReport>,
}

#[derive(Serialize)]
struct PointsReport {
    points: usize,
    duplicates: usize,
    /// Cells along the longest side of the meshing grid.
    resolution: usize,
    /// Vertices of the mesh the cut was made on.
    meshed_vertices: usize,
    /// Small pieces of that mesh that were dropped.
    dropped_pieces: usize,
}

#[derive(Serialize)]
struct SeamFile<'a> {
    /// The blobs, in patch order.
    patches: Vec<String>,
    seams: &'a [SeamCurve],
}

pub fn run(args: &ClosedArgs) -> Result<()> {
    let scalar = blob_scalar(args.scalar)?;
    check_output(&args.out)?;
    let options = ClosedOptions {
        patches: args.patches,
        vertices: args.vertices,
        topology: args.network.options(args.seed)?,
    };
    let input = read_mesh_or_points(&args.mesh).with_context(|| {
        format!(
            "`parametric closed` takes a closed triangle mesh (OBJ or PLY) or a closed point \
             cloud (text rows of x y z, PLY or OBJ vertices); {} could not be read",
            args.mesh.display()
        )
    })?;
    let (result, cloud) = match input {
        MeshOrPoints::Mesh(mesh) => (reconstruct_closed(&mesh, &options), None),
        MeshOrPoints::Points(points) => match reconstruct_closed_points(&points, &options) {
            Ok((result, cloud)) => (Ok(result), Some(cloud)),
            Err(e) => (Err(e), None),
        },
    };
    let result =
        result.with_context(|| format!("cannot rebuild {} from patches", args.mesh.display()))?;
    // Every blob is encoded (and checked) before anything is written.
    let mut blobs = Vec::with_capacity(result.patches.len());
    for patch in &result.patches {
        let mut summary = NetworkSummary::of(&patch.fit, patch.points, 0.0);
        let step = patch.region.len().div_ceil(MAX_REGION_VERTICES);
        summary.region = patch.region.iter().step_by(step.max(1)).copied().collect();
        blobs.push(network_to_blob(&patch.fit.network, Some(&summary), scalar)?);
    }
    if let Some(dir) = &args.blobs {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the folder {}", dir.display()))?;
        let mut names = Vec::with_capacity(blobs.len());
        for (i, bytes) in blobs.iter().enumerate() {
            let name = format!("patch-{i:02}.nsb");
            neurosurf_trainer::blob::write_checked(&dir.join(&name), bytes)?;
            names.push(name);
        }
        let file = SeamFile {
            patches: names,
            seams: &result.seams,
        };
        let text = serde_json::to_string_pretty(&file).context("cannot encode the seams")?;
        write_atomic(&dir.join("seams.json"), text.as_bytes())?;
    }
    write_mesh(&args.out, &result.mesh, None)?;
    let report = ClosedReport {
        mesh: MeshReport::of(&args.out, &result.mesh),
        patches: result.patches.len(),
        seams: result
            .seams
            .iter()
            .filter(|s| s.parameters_a.len() > 1)
            .count(),
        capped_holes: result.capped_holes,
        relative_rms_error: result.distance.rms,
        relative_hausdorff: result.distance.hausdorff,
        worst_patch_error: result
            .patches
            .iter()
            .map(|p| p.fit.relative_rms_error)
            .fold(0.0, f64::max),
        seam_gap: result.seam_gap,
        max_seam_gap: result.max_seam_gap,
        gap_before_stitch: result.gap_before,
        max_displacement: result.max_displacement,
        blobs: args.blobs.as_deref(),
        from_points: cloud.map(|c| PointsReport {
            points: c.points.len() + c.duplicates,
            duplicates: c.duplicates,
            resolution: c.resolution,
            meshed_vertices: c.mesh.positions.len(),
            dropped_pieces: c.dropped_pieces,
        }),
    };
    if args.json {
        return output::json(&report);
    }
    if let Some(cloud) = &report.from_points {
        println!(
            "meshed {} points ({} duplicates dropped) on a grid of {} cells: {} vertices{}",
            cloud.points,
            cloud.duplicates,
            cloud.resolution,
            cloud.meshed_vertices,
            if cloud.dropped_pieces > 0 {
                format!(", {} stray pieces dropped", cloud.dropped_pieces)
            } else {
                String::new()
            }
        );
    }
    println!(
        "{} patches ({} holes capped first), {} seams; RMS {:.3} % of the diagonal from the \
         input both ways, at most {:.3} %; worst patch fit {:.3} %",
        report.patches,
        report.capped_holes,
        report.seams,
        100.0 * report.relative_rms_error,
        100.0 * report.relative_hausdorff,
        100.0 * report.worst_patch_error
    );
    println!(
        "the patches' networks meet at their seams within {:.3} % of the diagonal on average, \
         {:.3} % at most; the stitch closes that in the mesh",
        100.0 * report.seam_gap,
        100.0 * report.max_seam_gap
    );
    if let Some(dir) = report.blobs {
        println!(
            "wrote {} patch blobs ({}) and seams.json to {}",
            report.patches,
            scalar.name(),
            dir.display()
        );
    }
    report.mesh.print();
    Ok(())
}

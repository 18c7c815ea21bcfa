//! `neurosurf mesh`: extract a watertight triangle mesh of an implicit model or an RBF
//! baseline.

use std::path::{Path, PathBuf};

use anyhow::Result;
use serde::Serialize;

use neurosurf_trainer::io::write_mesh;
use neurosurf_trainer::quality::components;
use neurosurf_trainer::render::{ExtractedMesh, Field, MeshStats, RbfField, extract_mesh};

use super::render::{Surface, core_field};
use super::{output, progress};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob: a modular implicit model (evaluated by the core in f32) or an RBF
    /// baseline (f64 on the host).
    model: PathBuf,
    /// Grid cells along the longest side of the search boxes (1..=1024).
    #[arg(long, default_value_t = 128)]
    resolution: usize,
    /// Growth of the boxes the surface is searched in: a network's leaf normalization boxes
    /// (default 1.25), or an RBF's centres' bounding box (default 1.1), in [1, 4].
    #[arg(long)]
    inflate: Option<f64>,
    /// The mesh to write: `.obj`, `.ply` (binary) or `.stl` (binary).
    #[arg(long, short)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Summary<'a> {
    out: &'a Path,
    /// Connected pieces of the mesh (triangles sharing vertices).
    components: usize,
    #[serde(flatten)]
    stats: MeshStats,
}

pub fn run(args: &Args) -> Result<()> {
    let surface = Surface::read(&args.model)?;
    let inflate = surface.inflate(args.inflate)?;
    let bar = progress::work_bar("mesh", "blocks", args.json);
    let progress = |done: u64, total: u64| {
        bar.set_length(total);
        bar.set_position(done);
    };
    let extracted = match &surface {
        Surface::Implicit {
            bytes,
            decoded,
            box_size,
        } => extract(
            &core_field(bytes, decoded, *box_size, inflate)?,
            args,
            &progress,
        )?,
        Surface::Rbf(model) => extract(&RbfField::new(model, inflate)?, args, &progress)?,
    };
    bar.finish_and_clear();
    write_mesh(&args.out, &extracted.mesh, Some(&extracted.normals))?;
    let stats = extracted.stats;
    let components = components(&extracted.mesh);
    if args.json {
        return output::json(&Summary {
            out: &args.out,
            components,
            stats,
        });
    }
    println!(
        "wrote {} ({} vertices, {} triangles, {} component{}, watertight; grid {} cells, {} \
         of {} blocks searched, {} evaluations, {:.3} s)",
        args.out.display(),
        stats.vertices,
        stats.triangles,
        components,
        if components == 1 { "" } else { "s" },
        stats.resolution,
        stats.blocks_searched,
        stats.blocks,
        stats.evaluations,
        stats.seconds
    );
    Ok(())
}

fn extract<F: Field>(
    field: &F,
    args: &Args,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<ExtractedMesh> {
    Ok(extract_mesh(field, args.resolution, progress)?)
}

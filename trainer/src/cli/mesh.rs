//! `neurosurf mesh`: extract a watertight triangle mesh of an implicit model.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use serde::Serialize;

use neurosurf_trainer::io::write_mesh;
use neurosurf_trainer::render::{CoreField, MeshStats, Region, extract_mesh};

use super::render::load_implicit;
use super::{output, progress};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The implicit model blob.
    model: PathBuf,
    /// Grid cells along the longest side of the leaf boxes (1..=1024).
    #[arg(long, default_value_t = 128)]
    resolution: usize,
    /// Growth of the leaf normalization boxes the surface is searched in.
    #[arg(long, default_value_t = 1.25)]
    inflate: f64,
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
    #[serde(flatten)]
    stats: MeshStats,
}

pub fn run(args: &Args) -> Result<()> {
    let (bytes, decoded, box_size) = load_implicit(&args.model)?;
    if !(args.inflate >= 1.0 && args.inflate <= 4.0) {
        bail!("--inflate {} is outside [1, 4]", args.inflate);
    }
    let regions = Region::of_network(&decoded.network, box_size, args.inflate);
    let field = CoreField::new(&bytes, regions)?;
    let bar = progress::work_bar("mesh", "blocks", args.json);
    let extracted = extract_mesh(&field, args.resolution, &|done, total| {
        bar.set_length(total);
        bar.set_position(done);
    })?;
    bar.finish_and_clear();
    write_mesh(&args.out, &extracted.mesh, Some(&extracted.normals))?;
    let stats = extracted.stats;
    if args.json {
        return output::json(&Summary {
            out: &args.out,
            stats,
        });
    }
    println!(
        "wrote {} ({} vertices, {} triangles, watertight; grid {} cells, {} of {} blocks \
         searched, {} evaluations, {:.3} s)",
        args.out.display(),
        stats.vertices,
        stats.triangles,
        stats.resolution,
        stats.blocks_searched,
        stats.blocks,
        stats.evaluations,
        stats.seconds
    );
    Ok(())
}

//! `neurosurf patch compare`: the §7.1 comparison on any patch.

use std::path::PathBuf;

use anyhow::{Context, Result};

use neurosurf_trainer::io::read_mesh;
use neurosurf_trainer::parametric::{PatchCompareOptions, compare_patch};
use neurosurf_trainer::table::{Align, Table};

use super::{EmbeddingArgs, NetworkArgs, read_points};
use crate::output;

#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// Points of one open patch: text (`x y z` per line), PLY, or OBJ (its vertices).
    points: PathBuf,
    /// A mesh of the true surface (OBJ, PLY or STL): each method's mesh is measured against it.
    /// Without it, against the input points.
    #[arg(long, value_name = "MESH")]
    truth: Option<PathBuf>,
    /// Fraction of the points held out of every fit and measured against each mesh.
    #[arg(long, default_value_t = PatchCompareOptions::default().held_out)]
    held_out: f64,
    #[command(flatten)]
    embedding: EmbeddingArgs,
    #[command(flatten)]
    network: NetworkArgs,
    /// Coons grid vertices per side, shared by the network and the RBF meshes.
    #[arg(long, default_value_t = PatchCompareOptions::default().resolution)]
    resolution: usize,
    /// Centres per side of the low-density RBF.
    #[arg(long, default_value_t = PatchCompareOptions::default().rbf_grid)]
    rbf_grid: usize,
    /// Most centres of the high-density RBF: one per point up to this, then an even subsample
    /// of this many (a dense solve).
    #[arg(long, default_value_t = PatchCompareOptions::default().rbf_max_centers)]
    rbf_centers: usize,
    /// Seed of the held-out points and the network's weights.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &CompareArgs) -> Result<()> {
    let topology = args.network.options(args.seed)?;
    let points = read_points(&args.points)?;
    let truth = match &args.truth {
        Some(path) => Some(read_mesh(path)?),
        None => None,
    };
    let defaults = PatchCompareOptions::default();
    let options = PatchCompareOptions {
        held_out: args.held_out,
        seed: args.seed,
        embedding: args.embedding.options(),
        topology,
        resolution: args.resolution,
        rbf_grid: args.rbf_grid,
        rbf_max_centers: args.rbf_centers,
        ..defaults
    };
    let comparison = compare_patch(&points, truth.as_ref(), &options)
        .with_context(|| format!("cannot compare methods on {}", args.points.display()))?;
    if args.json {
        return output::json(&comparison);
    }
    println!(
        "{}: {} points, {} held out; embedded with k = {} in {:.2} s; distances as % of the \
         diagonal {:.4}, mesh → {}",
        args.points.display(),
        comparison.points,
        comparison.held_out,
        comparison.neighbors,
        comparison.embedding_seconds,
        comparison.diagonal,
        comparison.reference,
    );
    let mut table = Table::new([
        ("method", Align::Left),
        ("size", Align::Left),
        ("held-out RMS", Align::Right),
        ("held-out max", Align::Right),
        ("mesh RMS", Align::Right),
        ("mesh max", Align::Right),
        ("dihedral var.", Align::Right),
        ("vertices", Align::Right),
        ("time", Align::Right),
    ]);
    let percent = |x: f64| format!("{:.3} %", 100.0 * x);
    for r in &comparison.rows {
        table.push([
            r.method.to_string(),
            r.size.clone(),
            percent(r.held_out_rms),
            percent(r.held_out_max),
            percent(r.mesh_rms),
            percent(r.mesh_max),
            format!("{:.2e}", r.dihedral_variance),
            r.vertices.to_string(),
            format!("{:.3} s", r.seconds),
        ]);
    }
    print!("{}", table.to_text());
    Ok(())
}

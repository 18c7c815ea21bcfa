//! `neurosurf caoen teapot`: the teapot as four Cao En surfaces (paper §10.2, Fig. 7).

use std::path::{Path, PathBuf};

use anyhow::Result;
use serde::Serialize;

use neurosurf_trainer::caoen::{
    self, OuterDistance, SurfaceDistance, TEAPOT_CELL, TeapotLayout, fit_teapot,
};
use neurosurf_trainer::evaluate::Precision;
use neurosurf_trainer::io::{data_file, read_mesh, write_mesh};
use neurosurf_trainer::render::write_png;

use super::super::output::{self, blob_scalar, comma_list};
use super::render::{Camera, depth_picture};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The teapot mesh (default: `teapot.obj` in the shared data folder).
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// Key points of the body, the lid, the spout and the handle (the tubes, and the body
    /// and lid with `--layout sixfold`, take 6·rings + 2 of those asked for).
    #[arg(long, value_parser = comma_list::<usize, 4>, default_value = "32,26,20,26")]
    keys: [usize; 4],
    /// Where the body's and the lid's keys go: `sixfold` (the paper's Fig. 7: rings of six
    /// around the axis and a key at each pole) or `farthest` (farthest-first on the surface;
    /// closer on the lid by RMS, but its rim comes out wavy).
    /// The spout and the handle take rings of six along them in either layout.
    #[arg(long, value_enum, default_value = "sixfold")]
    layout: Layout,
    /// How the blobs store the networks: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    scalar: Precision,
    /// Folder for `body.nsb`, `lid.nsb`, `spout.nsb`, `handle.nsb` and `teapot.obj` (the
    /// four mapped surfaces in one mesh).
    #[arg(long)]
    out_dir: PathBuf,
    /// Also render the four surfaces (depth buffer) to this PNG.
    #[arg(long, value_name = "FILE")]
    png: Option<PathBuf>,
    #[command(flatten)]
    camera: Camera,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

/// `--layout`.
#[derive(Copy, Clone, Debug, clap::ValueEnum)]
pub enum Layout {
    Farthest,
    Sixfold,
}

#[derive(Serialize)]
struct Part {
    name: &'static str,
    blob: PathBuf,
    blob_bytes: usize,
    key_points: usize,
    /// How the part maps from the sphere: "radial", "tutte", "axial" or "tube", with
    /// ", sixfold keys" for rings of six.
    parameterization: &'static str,
    /// Vertices of the part in the mesh file.
    vertices: usize,
    /// Surface against the part's mesh, relative to the part's bounding diagonal.
    distance: SurfaceDistance,
}

#[derive(Serialize)]
struct Report<'a> {
    parts: Vec<Part>,
    key_points: usize,
    /// What shows of the four surfaces against what shows of the input mesh, relative to
    /// its diagonal: the caps and roots hidden inside the teapot are left out.
    whole: OuterDistance,
    /// Every surface, the hidden caps included, against the whole input mesh.
    all_surfaces: SurfaceDistance,
    mesh: PathBuf,
    png: Option<&'a Path>,
}

pub fn run(args: &Args) -> Result<()> {
    let scalar = blob_scalar(args.scalar)?;
    let source = match &args.mesh {
        Some(path) => path.clone(),
        None => data_file("teapot.obj")?,
    };
    let layout = match args.layout {
        Layout::Farthest => TeapotLayout::Farthest,
        Layout::Sixfold => TeapotLayout::Sixfold,
    };
    let input = read_mesh(&source)?;
    let teapot = fit_teapot(&input, args.keys, layout)?;
    let (parts, combined) = (&teapot.parts, &teapot.combined);
    std::fs::create_dir_all(&args.out_dir)?;
    let mut report = Report {
        parts: Vec::new(),
        key_points: parts.iter().map(|p| p.network.key_count()).sum(),
        whole: teapot.whole,
        all_surfaces: teapot.all_surfaces,
        mesh: args.out_dir.join("teapot.obj"),
        png: args.png.as_deref(),
    };
    for part in parts {
        let blob = caoen::to_blob(&part.network, scalar, part.name.as_bytes())?;
        let path = args.out_dir.join(format!("{}.nsb", part.name));
        neurosurf_trainer::blob::write_checked(&path, &blob)?;
        report.parts.push(Part {
            name: part.name,
            blob: path,
            blob_bytes: blob.len(),
            key_points: part.network.key_count(),
            parameterization: part.parameterization,
            vertices: part.mesh.vertex_count(),
            distance: part.distance,
        });
    }
    write_mesh(&report.mesh, combined, None)?;
    if let Some(png) = &args.png {
        let networks: Vec<_> = parts.iter().map(|p| p.network.clone()).collect();
        write_png(png, &depth_picture(&networks, &args.camera, 3)?.image)?;
    }
    if args.json {
        return output::json(&report);
    }
    println!(
        "part    keys  map                   vertices  rms      Hausdorff (of the part's diagonal)"
    );
    for p in &report.parts {
        println!(
            "{:<7} {:>4}  {:<20}  {:>8}  {:.4}   {:.4}",
            p.name,
            p.key_points,
            p.parameterization,
            p.vertices,
            p.distance.rms,
            p.distance.hausdorff
        );
    }
    let whole = report.whole.distance;
    println!(
        "whole teapot, what shows (of its diagonal): rms {:.4}; every visible input vertex \
         within {:.4} of the surfaces, which reach {:.4} from the input ({:.0} % of the \
         surfaces' samples hidden inside, at a {} cell)",
        whole.rms,
        whole.max_to_surface,
        whole.max_to_reference,
        100.0 * report.whole.hidden_surface,
        TEAPOT_CELL
    );
    println!(
        "all surfaces, hidden caps included: rms {:.4}, Hausdorff {:.4}",
        report.all_surfaces.rms, report.all_surfaces.hausdorff
    );
    println!(
        "{} key points in all; wrote the blobs and {} to {}",
        report.key_points,
        report.mesh.display(),
        args.out_dir.display()
    );
    if let Some(png) = &args.png {
        println!("wrote {}", png.display());
    }
    Ok(())
}

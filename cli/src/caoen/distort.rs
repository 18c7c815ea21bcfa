//! `neurosurf caoen distort`: a mesh moved by a 4-D hypersphere → 3-D network (paper §12.2).

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use serde::Serialize;

use neurosurf_trainer::caoen::Distortion;
use neurosurf_trainer::io::{read_mesh, write_mesh};

use super::super::output::{self, comma_list};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The mesh to distort (`.obj` or `.ply`).
    mesh: PathBuf,
    /// Centre of the distorted ball, `X,Y,Z` (default: the mesh's bounding-box centre).
    #[arg(long, value_parser = comma_list::<f64, 3>, allow_hyphen_values = true)]
    centre: Option<[f64; 3]>,
    /// Radius of the ball (default: half the bounding-box diagonal, so the ball holds the
    /// mesh). Every vertex must lie inside.
    #[arg(long)]
    radius: Option<f64>,
    /// A control `X,Y,Z,DX,DY,DZ,Q`: the point (X, Y, Z) moves by (DX, DY, DZ), the
    /// influence falls as cos^Q of the angle on S³ (Q whole, 1 … 64). Repeat for more.
    #[arg(long = "control", value_parser = comma_list::<f64, 7>, allow_hyphen_values = true, required = true)]
    controls: Vec<[f64; 7]>,
    /// Output mesh (`.obj`, `.ply` or `.stl`).
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    out: &'a Path,
    vertices: usize,
    controls: usize,
    centre: [f64; 3],
    radius: f64,
    /// Largest distance a vertex moved.
    max_displacement: f64,
}

pub fn run(args: &Args) -> Result<()> {
    let mesh = read_mesh(&args.mesh)?;
    if mesh.positions.is_empty() {
        bail!("{}: the mesh has no vertices", args.mesh.display());
    }
    let (low, high) = mesh.positions.iter().fold(
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(lo, hi), p| {
            (
                [0, 1, 2].map(|k| lo[k].min(p[k])),
                [0, 1, 2].map(|k| hi[k].max(p[k])),
            )
        },
    );
    let centre = args
        .centre
        .unwrap_or_else(|| [0, 1, 2].map(|k| 0.5 * (low[k] + high[k])));
    let radius = args.radius.unwrap_or_else(|| {
        // Half the diagonal from the centre's farther corner, a hair larger.
        1.000_001
            * (0..3)
                .map(|k| {
                    (centre[k] - low[k])
                        .abs()
                        .max((high[k] - centre[k]).abs())
                        .powi(2)
                })
                .sum::<f64>()
                .sqrt()
    });
    let mut distortion = Distortion::identity(centre, radius)?;
    for (i, c) in args.controls.iter().enumerate() {
        let q = c[6];
        if !(1.0..=64.0).contains(&q) || q.fract() != 0.0 {
            bail!("control {i}: Q must be a whole number 1 … 64, got {q}");
        }
        distortion
            .add_control([c[0], c[1], c[2]], [c[3], c[4], c[5]], q as u8)
            .map_err(|e| anyhow::anyhow!("control {i}: {e}"))?;
    }
    let moved = distortion.apply(&mesh)?;
    write_mesh(&args.out, &moved, None)?;
    let report = Report {
        out: &args.out,
        vertices: moved.vertex_count(),
        controls: args.controls.len(),
        centre,
        radius,
        max_displacement: mesh
            .positions
            .iter()
            .zip(&moved.positions)
            .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max),
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "moved {} vertices by up to {:.4} with {} controls in the ball of radius {:.4} around \
         {:?}; wrote {}",
        report.vertices,
        report.max_displacement,
        report.controls,
        report.radius,
        report.centre,
        args.out.display()
    );
    Ok(())
}

//! `neurosurf sample`: oriented control points from a built-in shape or a mesh.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::ValueEnum;
use serde::Serialize;

use neurosurf_trainer::io::{PlyEncoding, read_mesh, write_points_ply};
use neurosurf_trainer::sample::{MAX_EVEN_POINTS, Shape, Spread, sample_mesh, sample_shape};

use super::output::{self, comma_list};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// `sphere`, `ellipsoid`, `torus`, `head` (3 features: head, nose, mouth), or a mesh file
    /// (`.obj`, `.ply`) sampled area-uniformly with its face normals (see `--spread`).
    shape: String,
    /// Number of points.
    #[arg(long = "points", short = 'n')]
    count: usize,
    /// Random seed (same seed, same points).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sphere radius.
    #[arg(long, default_value_t = 1.0)]
    radius: f64,
    /// Ellipsoid semi-axes `a,b,c`.
    #[arg(long, value_parser = comma_list::<f64, 3>, default_value = "1,0.7,0.5")]
    axes: [f64; 3],
    /// Torus major radius R (ring), axis z.
    #[arg(long, default_value_t = 1.0)]
    major: f64,
    /// Torus minor radius r (tube).
    #[arg(long, default_value_t = 0.4)]
    minor: f64,
    /// How points are placed on a mesh: `even` keeps a near-constant distance between them
    /// (the best coverage for a point budget; up to 200 000 points, more are drawn at
    /// random), `random` draws each independently (clumps and gaps).
    #[arg(long, value_enum, default_value_t = SpreadArg::Even)]
    spread: SpreadArg,
    /// PLY encoding of the output.
    #[arg(long, value_enum, default_value_t = Encoding::Ascii)]
    encoding: Encoding,
    /// Output PLY file (x y z nx ny nz, and `feature` when known).
    #[arg(long, short)]
    out: PathBuf,
    /// Print a JSON summary instead of text.
    #[arg(long)]
    json: bool,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum SpreadArg {
    Even,
    Random,
}

#[derive(Copy, Clone, Debug, ValueEnum)]
enum Encoding {
    Ascii,
    Binary,
}

#[derive(Serialize)]
struct Summary<'a> {
    shape: &'a str,
    points: usize,
    features: usize,
    seed: u64,
    /// `even` or `random` for a mesh, absent for a built-in shape.
    #[serde(skip_serializing_if = "Option::is_none")]
    spread: Option<&'static str>,
    out: &'a Path,
}

pub fn run(args: &Args) -> Result<()> {
    // How the points were placed on a mesh (built-in shapes draw at random).
    let mut spread = None;
    let points = match args.shape.as_str() {
        "sphere" => sample_shape(
            &Shape::Sphere {
                radius: args.radius,
            },
            args.count,
            args.seed,
        )?,
        "ellipsoid" => sample_shape(&Shape::Ellipsoid { axes: args.axes }, args.count, args.seed)?,
        "torus" => sample_shape(
            &Shape::Torus {
                major: args.major,
                minor: args.minor,
            },
            args.count,
            args.seed,
        )?,
        "head" => sample_shape(&Shape::Head, args.count, args.seed)?,
        file if file.ends_with(".obj") || file.ends_with(".ply") => {
            let mesh = read_mesh(Path::new(file))?;
            let chosen = match args.spread {
                SpreadArg::Even if args.count <= MAX_EVEN_POINTS => Spread::Even,
                _ => Spread::Random,
            };
            spread = Some(match chosen {
                Spread::Even => "even",
                Spread::Random => "random",
            });
            sample_mesh(&mesh, args.count, args.seed, chosen)
                .with_context(|| format!("sampling {file}"))?
        }
        other => bail!(
            "unknown shape {other:?}: expected sphere, ellipsoid, torus, head, or an .obj/.ply mesh"
        ),
    };
    let encoding = match args.encoding {
        Encoding::Ascii => PlyEncoding::Ascii,
        Encoding::Binary => PlyEncoding::BinaryLittleEndian,
    };
    write_points_ply(&args.out, &points, encoding)?;
    let features = points
        .features
        .as_ref()
        .map_or(0, |f| f.iter().map(|&x| x as usize + 1).max().unwrap_or(0));
    let summary = Summary {
        shape: &args.shape,
        points: points.len(),
        features,
        seed: args.seed,
        spread,
        out: &args.out,
    };
    if args.json {
        output::json(&summary)
    } else {
        println!(
            "wrote {} points{} of {}{} to {}",
            summary.points,
            if features > 0 {
                format!(" ({features} features)")
            } else {
                String::new()
            },
            args.shape,
            spread.map_or(String::new(), |s| format!(" (spread {s})")),
            args.out.display()
        );
        Ok(())
    }
}

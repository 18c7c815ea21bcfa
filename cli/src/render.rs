//! `neurosurf render`: ray-cast an implicit model or an RBF baseline to a PNG (Carcenac §6).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::Serialize;

use neurosurf_trainer::evaluate::LoadedModel;
use neurosurf_trainer::implicit::DecodedImplicit;
use neurosurf_trainer::rbf::RbfModel;
use neurosurf_trainer::render::{
    Camera, CoreField, DEFAULT_BOX_SIZE, DEFAULT_INFLATE, DEFAULT_RBF_INFLATE, Field, Method,
    NetworkField, RbfField, Region, RenderOptions, RenderStats, View, bounds_of, render, write_png,
};

use super::{output, progress};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model blob: a modular implicit model or an RBF baseline.
    model: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 256)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 256)]
    height: u32,
    /// `azimuth,elevation[,distance]`: degrees around z (0 looks from +y), degrees above the
    /// xy plane, distance from the scene's center (default: the scene fills the image).
    #[arg(long, default_value = "35,20")]
    view: String,
    /// Vertical field of view, degrees.
    #[arg(long, default_value_t = 35.0)]
    fov: f64,
    /// Rays per pixel (a square number; the paper casts 4).
    #[arg(long, default_value_t = 4)]
    aa: u32,
    /// Cast every pixel's sub-pixel rays; by default only pixels at edges and creases get
    /// them (one ray elsewhere).
    #[arg(long)]
    full_aa: bool,
    /// Never miss a crossing: interval bounds through the module tree, in f64 (slower; not
    /// for an RBF). Without it, the paper's punctual Newton search runs on the core in f32
    /// (an RBF: on the host in f64).
    #[arg(long)]
    guaranteed: bool,
    /// Growth of the boxes the surface is searched in: a network's leaf normalization boxes
    /// (default 1.25), or an RBF's centres' bounding box (default 1.1), in [1, 4].
    #[arg(long)]
    inflate: Option<f64>,
    /// The PNG to write.
    #[arg(long, short)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Summary<'a> {
    out: &'a Path,
    evaluation: &'static str,
    #[serde(flatten)]
    stats: RenderStats,
}

/// A model `render` and `mesh` draw.
pub enum Surface {
    /// A modular implicit model: its blob, its `f64` decoding, and its normalization box side
    /// (from its training summary; default 2).
    Implicit {
        bytes: Vec<u8>,
        decoded: Box<DecodedImplicit>,
        box_size: f64,
    },
    /// The RBF baseline (evaluated in f64 on the host).
    Rbf(RbfModel),
}

/// An implicit blob in the core, in f32, inside its leaf boxes grown by `inflate`.
pub fn core_field(
    bytes: &[u8],
    decoded: &DecodedImplicit,
    box_size: f64,
    inflate: f64,
) -> Result<CoreField> {
    let regions = Region::of_network(&decoded.network, box_size, inflate);
    Ok(CoreField::new(bytes, regions)?)
}

impl Surface {
    /// Reads a model `render` and `mesh` accept.
    pub fn read(path: &Path) -> Result<Surface> {
        match LoadedModel::read(path)? {
            LoadedModel::Implicit { bytes, decoded } => {
                let box_size = decoded
                    .metadata
                    .as_ref()
                    .and_then(|m| m.summary.as_ref())
                    .map_or(DEFAULT_BOX_SIZE, |s| s.options.box_size);
                Ok(Surface::Implicit {
                    bytes,
                    decoded,
                    box_size,
                })
            }
            LoadedModel::Rbf { decoded, .. } => Ok(Surface::Rbf(*decoded)),
            _ => bail!(
                "{} is not an implicit model or an RBF (render and mesh need a field)",
                path.display()
            ),
        }
    }

    /// `--inflate`, or this kind's default, checked to lie in [1, 4].
    pub fn inflate(&self, inflate: Option<f64>) -> Result<f64> {
        let inflate = inflate.unwrap_or(match self {
            Surface::Implicit { .. } => DEFAULT_INFLATE,
            Surface::Rbf(_) => DEFAULT_RBF_INFLATE,
        });
        if !(1.0..=4.0).contains(&inflate) {
            bail!("--inflate {inflate} is outside [1, 4]");
        }
        Ok(inflate)
    }
}

/// `azimuth,elevation[,distance]`.
fn parse_view(text: &str, fov: f64) -> Result<View> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .with_context(|| format!("--view '{text}': expected azimuth,elevation[,distance]"))?;
    let (azimuth, elevation, distance) = match values[..] {
        [a, e] => (a, e, None),
        [a, e, d] => (a, e, Some(d)),
        _ => bail!("--view '{text}': expected 2 or 3 comma-separated numbers"),
    };
    if !(azimuth.is_finite() && elevation.is_finite()) {
        bail!("--view '{text}': angles must be finite");
    }
    Ok(View {
        azimuth,
        elevation,
        distance,
        fov,
    })
}

pub fn run(args: &Args) -> Result<()> {
    let surface = Surface::read(&args.model)?;
    let view = parse_view(&args.view, args.fov)?;
    let inflate = surface.inflate(args.inflate)?;
    let options = RenderOptions {
        method: if args.guaranteed {
            Method::Guaranteed
        } else {
            Method::Punctual
        },
        samples: args.aa,
        adaptive: !args.full_aa,
        ..RenderOptions::default()
    };
    let bar = progress::work_bar("render", "tiles", args.json);
    let report = |done: u64, total: u64| {
        bar.set_length(total);
        bar.set_position(done);
    };
    let (rendered, evaluation) = match &surface {
        Surface::Implicit {
            decoded, box_size, ..
        } if args.guaranteed => {
            let field = NetworkField::new(&decoded.network, *box_size, inflate)?;
            (
                draw(&field, args, &view, &options, &report)?,
                "f64 network, intervals",
            )
        }
        Surface::Implicit {
            bytes,
            decoded,
            box_size,
        } => {
            let field = core_field(bytes, decoded, *box_size, inflate)?;
            (draw(&field, args, &view, &options, &report)?, "core f32")
        }
        Surface::Rbf(_) if args.guaranteed => bail!(
            "--guaranteed needs interval bounds of the field, which the RBF baseline does not \
             have: render it without --guaranteed"
        ),
        Surface::Rbf(model) => {
            let field = RbfField::new(model, inflate)?;
            (draw(&field, args, &view, &options, &report)?, "f64 RBF")
        }
    };
    bar.finish_and_clear();
    write_png(&args.out, &rendered.image)?;
    let stats = rendered.stats;
    if args.json {
        return output::json(&Summary {
            out: &args.out,
            evaluation,
            stats,
        });
    }
    println!(
        "wrote {} ({}×{}, {} rays/pixel in {} pixels, {:?} search on the {evaluation}): {} of \
         {} rays hit, {} voxels, {:.3} s",
        args.out.display(),
        stats.width,
        stats.height,
        stats.samples,
        stats.supersampled,
        stats.method,
        stats.hits,
        stats.rays,
        stats.voxels,
        stats.seconds
    );
    Ok(())
}

fn draw<F: Field>(
    field: &F,
    args: &Args,
    view: &View,
    options: &RenderOptions,
    report: &(dyn Fn(u64, u64) + Sync),
) -> Result<neurosurf_trainer::render::Rendered> {
    let bounds = bounds_of(field.regions()).context("the model has no region to render")?;
    let camera = Camera::orbit(&bounds, view, args.width, args.height)?;
    Ok(render(field, &camera, options, report)?)
}

#[cfg(test)]
mod tests {
    use super::parse_view;

    #[test]
    fn views_parse_with_or_without_distance() {
        let v = parse_view("10, -5", 30.0).unwrap();
        assert_eq!((v.azimuth, v.elevation, v.distance), (10.0, -5.0, None));
        assert_eq!(parse_view("1,2,9", 30.0).unwrap().distance, Some(9.0));
        assert!(
            parse_view("1", 30.0)
                .unwrap_err()
                .to_string()
                .contains("2 or 3")
        );
        assert!(parse_view("a,2", 30.0).is_err());
    }
}

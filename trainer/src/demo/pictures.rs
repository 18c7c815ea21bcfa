//! Pictures of the demo's models: the §6 ray caster (punctual Newton search through the core
//! in `f32`) with search regions and a camera chosen for the shape.
//!
//! Regions: by default the renderer searches each leaf's *normalization* box, which is a cube
//! as long as the feature's longest side (isotropic scaling, [`BoxScaling`]). Around a
//! thin limb that cube is mostly empty space, where nothing constrains the blended field and
//! it can turn positive: the renderer then draws flat sheets clipped by the cube. The paper's
//! Fig. 5 boxes hug the features, so here each feature's region is the principal-axis
//! bounding box of its own control points, scaled per axis and slightly inflated — what the
//! surface is assumed to lie in, and nothing more.

use std::path::Path;

use neurosurf_core::scalar::ScalarKind;
use serde::Serialize;

use crate::error::Result;
use crate::implicit::{self, BoxScaling, ImplicitNetwork, Normalization};
use crate::points::PointSet;
use crate::rbf::RbfModel;
use crate::render::{
    Aabb, Camera, CoreField, DEFAULT_BOX_SIZE, DEFAULT_INFLATE, DEFAULT_RBF_INFLATE, Field,
    RbfField, Region, RenderOptions, RenderStats, View, render, write_png,
};

/// Growth of the per-feature boxes (their joints must overlap; the paper: "slightly").
pub const FEATURE_INFLATE: f64 = 1.1;

/// The search regions of a model trained on `points`: each feature's principal-axis box,
/// scaled per axis and inflated by `inflate`; the isotropic box for a flat feature (whose
/// per-axis box does not exist).
pub fn feature_regions(points: &PointSet, inflate: f64) -> Vec<Region> {
    let labels: Vec<u32> = points
        .features
        .clone()
        .unwrap_or_else(|| vec![0; points.len()]);
    let count = labels.iter().map(|&f| f as usize + 1).max().unwrap_or(0);
    (0..count as u32)
        .filter_map(|f| {
            let own: Vec<[f64; 3]> = points
                .positions
                .iter()
                .zip(&labels)
                .filter(|(_, l)| **l == f)
                .map(|(p, _)| *p)
                .collect();
            let what = format!("feature {f}");
            let box_of = |scaling| Normalization::fit(&own, DEFAULT_BOX_SIZE, scaling, &what);
            let normalization = box_of(BoxScaling::PerAxis)
                .or_else(|_| box_of(BoxScaling::Isotropic))
                .ok()?;
            Region::new(normalization, DEFAULT_BOX_SIZE, inflate)
        })
        .collect()
}

pub use crate::geometry::point_bounds;

/// A camera at `azimuth`, `elevation` (degrees, as [`View`]) looking at the center of
/// `bounds` from far enough that the bounding sphere's silhouette fits the image with a small
/// margin in both directions (portrait images frame tall shapes closely).
///
/// # Errors
/// As [`Camera::orbit`].
pub fn framing(
    bounds: &Aabb,
    azimuth: f64,
    elevation: f64,
    width: u32,
    height: u32,
) -> Result<Camera> {
    let fov = View::default().fov;
    let half = bounds.half();
    let radius = (half[0] * half[0] + half[1] * half[1] + half[2] * half[2]).sqrt();
    let horizontal = half[0].max(half[1]);
    let tan_v = (0.5 * fov.to_radians()).tan();
    let tan_h = tan_v * f64::from(width) / f64::from(height.max(1));
    // Seen from anywhere around z, the shape spans at most `horizontal` sideways and about
    // `half[2]` (plus the tilt) vertically; keep 8 % margin, and stay outside the sphere.
    let tilt = elevation.to_radians().sin().abs() * horizontal;
    let distance = (1.08 * (half[2] + tilt) / tan_v)
        .max(1.08 * horizontal / tan_h)
        .max(1.5 * radius)
        + horizontal;
    let view = View {
        azimuth,
        elevation,
        distance: Some(distance),
        fov,
    };
    Camera::orbit(bounds, &view, width, height)
}

/// Where and how one picture was made.
#[derive(Clone, Debug, Serialize)]
pub struct Picture {
    /// File name, relative to the report folder.
    pub file: String,
    /// What it shows.
    pub caption: String,
    /// The renderer's counts and time.
    pub stats: RenderStats,
}

/// Ray casts `field` with `camera` and `samples` rays per pixel, writes the PNG to `dir/file`.
fn field_picture(
    field: &impl Field,
    camera: &Camera,
    samples: u32,
    dir: &Path,
    file: &str,
    caption: &str,
) -> Result<Picture> {
    let options = RenderOptions {
        samples,
        ..RenderOptions::default()
    };
    let rendered = render(field, camera, &options, &|_, _| {})?;
    write_png(&dir.join(file), &rendered.image)?;
    Ok(Picture {
        file: file.to_string(),
        caption: caption.to_string(),
        stats: rendered.stats,
    })
}

/// Ray casts the RBF baseline `model` (on the host in f64, inside its centres' box grown by
/// [`DEFAULT_RBF_INFLATE`]) with `camera`, writes the PNG to `dir/file`.
///
/// # Errors
/// Render and I/O errors.
pub fn rbf_picture(
    model: &RbfModel,
    camera: &Camera,
    samples: u32,
    dir: &Path,
    file: &str,
    caption: &str,
) -> Result<Picture> {
    let field = RbfField::new(model, DEFAULT_RBF_INFLATE)?;
    field_picture(&field, camera, samples, dir, file, caption)
}

/// Ray casts `network` (stored as an f32 blob and evaluated by the core) inside `regions`
/// with `camera` and `samples` rays per pixel, writes the PNG to `dir/file`.
///
/// # Errors
/// Blob, render and I/O errors.
pub fn picture(
    network: &ImplicitNetwork,
    regions: Vec<Region>,
    camera: &Camera,
    samples: u32,
    dir: &Path,
    file: &str,
    caption: &str,
) -> Result<Picture> {
    let blob = implicit::to_blob(network, None, ScalarKind::F32)?;
    let regions = if regions.is_empty() {
        Region::of_network(network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE)
    } else {
        regions
    };
    let field = CoreField::new(&blob, regions)?;
    field_picture(&field, camera, samples, dir, file, caption)
}

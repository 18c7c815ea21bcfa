//! Ray casting (§6): one octree per image, rays walked through it front to back, a search for
//! Φ = 0 in each voxel (punctual Newton or guaranteed intervals), shading from ∇Φ, several
//! rays per pixel, image tiles in parallel (rayon).

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use image::RgbImage;
use rayon::prelude::*;
use serde::Serialize;

use super::camera::Camera;
use super::field::Field;
use super::guaranteed;
use super::interval::Interval;
use super::octree::Octree;
use super::punctual;
use super::shade::{Shading, to_srgb8};
use crate::curve::vector::{add, scale};
use crate::error::{Error, Result};

/// Side of the square image tiles rendered in parallel.
pub const TILE: u32 = 16;
/// Largest rays-per-pixel count accepted (a square number).
pub const MAX_SAMPLES: u32 = 64;

/// How a voxel is searched for the surface.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The paper's Newton search in the voxel's bounding sphere; may miss crossings.
    Punctual,
    /// Interval bounds; misses no sign change of Φ (needs a field with bounds).
    Guaranteed,
}

/// Settings of a rendering.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// The search.
    pub method: Method,
    /// Rays per pixel on a square sub-pixel grid: 1, 4 (the paper's), 9, …
    pub samples: u32,
    /// Punctual octree: voxels are split while larger than this fraction of the smallest
    /// leaf box they meet.
    pub voxel_ratio: f64,
    /// Guaranteed octree: subdivision depth of the interval-pruned voxels.
    pub bounded_depth: u32,
    /// Colours and lights.
    pub shading: Shading,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            method: Method::Punctual,
            samples: 4,
            voxel_ratio: 0.25,
            bounded_depth: 5,
            shading: Shading::default(),
        }
    }
}

/// A field, its octree, and the search: finds the first surface point along a ray.
#[derive(Debug)]
pub struct Tracer<'a, F: ?Sized> {
    field: &'a F,
    octree: Octree,
    method: Method,
    tolerance: f64,
    min_length: f64,
}

impl<'a, F: Field + ?Sized> Tracer<'a, F> {
    /// Builds the octree for `method` over `field`'s regions.
    ///
    /// Hits are refined to 10⁻⁶ of the scene's size (ray length); the guaranteed search
    /// splits segments down to 10⁻⁵ of it.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for the guaranteed method on a field without interval bounds,
    /// a field without regions, or a voxel ratio outside (0, 1].
    pub fn new(field: &'a F, method: Method, options: &RenderOptions) -> Result<Self> {
        if method == Method::Guaranteed
            && field
                .segment_bounds([0.0; 3], [1.0, 0.0, 0.0], Interval::new(0.0, 1.0))
                .is_none()
        {
            return Err(Error::invalid(
                "the guaranteed mode needs interval bounds of the field (the f64 network)",
            ));
        }
        if !(options.voxel_ratio > 0.0 && options.voxel_ratio <= 1.0) {
            return Err(Error::invalid(format!(
                "voxel ratio {} is outside (0, 1]",
                options.voxel_ratio
            )));
        }
        let octree = match method {
            Method::Punctual => Octree::regions(field.regions(), options.voxel_ratio),
            Method::Guaranteed => Octree::bounded(field, options.bounded_depth),
        }
        .ok_or_else(|| Error::invalid("the field has no region to render"))?;
        let size = super::region::bounds_of(field.regions())
            .map_or(1.0, |b| b.longest_side())
            .max(f64::MIN_POSITIVE);
        Ok(Tracer {
            field,
            octree,
            method,
            tolerance: 1e-6 * size,
            min_length: 1e-5 * size,
        })
    }

    /// Leaf voxels of the octree.
    pub fn voxel_count(&self) -> usize {
        self.octree.leaf_count()
    }

    /// The ray parameter of the first surface point along `origin + t·direction` (unit
    /// direction, t ≥ 0), or `None`.
    pub fn hit(&self, origin: [f64; 3], direction: [f64; 3]) -> Option<f64> {
        let field = self.field;
        let mut search = |voxel: &super::region::Aabb, span: [f64; 2]| match self.method {
            Method::Punctual => {
                punctual::newton_in_voxel(field, origin, direction, voxel, span, self.tolerance)
            }
            Method::Guaranteed => {
                // Only the part of the voxel inside a region is searched.
                field
                    .regions()
                    .iter()
                    .filter_map(|r| r.ray_span(origin, direction, span[0]))
                    .filter_map(|[a, b]| (a <= span[1]).then_some([a, b.min(span[1])]))
                    .filter_map(|s| {
                        guaranteed::first_root(
                            field,
                            origin,
                            direction,
                            s,
                            self.min_length,
                            self.tolerance,
                        )
                    })
                    .min_by(f64::total_cmp)
            }
        };
        self.octree.first_hit(origin, direction, &mut search)
    }
}

/// What a rendering did.
#[derive(Clone, Debug, Serialize)]
pub struct RenderStats {
    /// The search used.
    pub method: Method,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// Rays per pixel.
    pub samples: u32,
    /// Rays cast.
    pub rays: u64,
    /// Rays that hit the surface.
    pub hits: u64,
    /// Leaf voxels of the octree.
    pub voxels: usize,
    /// Wall time, seconds (octree included).
    pub seconds: f64,
}

/// An image and how it was made.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The picture.
    pub image: RgbImage,
    /// Counts and time.
    pub stats: RenderStats,
}

/// Renders `field` seen by `camera`. `progress(done, total)` is called after every tile
/// (from worker threads).
///
/// # Errors
/// [`Error::InvalidInput`] for a rays-per-pixel count that is not a square in
/// 1..=[`MAX_SAMPLES`], and as [`Tracer::new`].
pub fn render<F: Field + ?Sized>(
    field: &F,
    camera: &Camera,
    options: &RenderOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Rendered> {
    let start = Instant::now();
    let k = (f64::from(options.samples).sqrt().round()) as u32;
    if options.samples == 0 || options.samples > MAX_SAMPLES || k * k != options.samples {
        return Err(Error::invalid(format!(
            "{} rays per pixel: use a square number in 1..={MAX_SAMPLES} (1, 4, 9, …)",
            options.samples
        )));
    }
    let tracer = Tracer::new(field, options.method, options)?;
    let (width, height) = (camera.width, camera.height);
    let tiles_x = width.div_ceil(TILE);
    let tiles_y = height.div_ceil(TILE);
    let total = u64::from(tiles_x) * u64::from(tiles_y);
    let done = AtomicU64::new(0);
    let hits = AtomicU64::new(0);
    let (right, up) = (camera.right(), camera.up());
    let shading = &options.shading;
    let tiles: Vec<(u32, u32, Vec<[u8; 3]>)> = (0..total)
        .into_par_iter()
        .map(|index| {
            let tx = (index % u64::from(tiles_x)) as u32 * TILE;
            let ty = (index / u64::from(tiles_x)) as u32 * TILE;
            let mut pixels = Vec::with_capacity((TILE * TILE) as usize);
            let mut tile_hits = 0;
            for y in ty..(ty + TILE).min(height) {
                for x in tx..(tx + TILE).min(width) {
                    let mut sum = [0.0; 3];
                    for s in 0..options.samples {
                        let (sx, sy) = (f64::from(s % k) + 0.5, f64::from(s / k) + 0.5);
                        let (o, d) = camera.ray(
                            f64::from(x) + sx / f64::from(k),
                            f64::from(y) + sy / f64::from(k),
                        );
                        let colour = match tracer.hit(o, d) {
                            Some(t) => {
                                tile_hits += 1;
                                let (_, g) = field.value_gradient(add(o, scale(d, t)));
                                shading.shade(g, d, right, up)
                            }
                            None => shading.background,
                        };
                        sum = [0, 1, 2].map(|c| sum[c] + colour[c]);
                    }
                    let n = f64::from(options.samples);
                    pixels.push(sum.map(|c| to_srgb8(c / n)));
                }
            }
            hits.fetch_add(tile_hits, Ordering::Relaxed);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            (tx, ty, pixels)
        })
        .collect();
    let mut image = RgbImage::new(width, height);
    for (tx, ty, pixels) in tiles {
        let w = (tx + TILE).min(width) - tx;
        for (i, p) in pixels.into_iter().enumerate() {
            let i = i as u32;
            image.put_pixel(tx + i % w, ty + i / w, image::Rgb(p));
        }
    }
    Ok(Rendered {
        image,
        stats: RenderStats {
            method: options.method,
            width,
            height,
            samples: options.samples,
            rays: u64::from(width) * u64::from(height) * u64::from(options.samples),
            hits: hits.into_inner(),
            voxels: tracer.voxel_count(),
            seconds: start.elapsed().as_secs_f64(),
        },
    })
}

/// The ray parameter of the first hit through every pixel center (row-major), in parallel.
pub fn hit_map<F: Field + ?Sized>(tracer: &Tracer<'_, F>, camera: &Camera) -> Vec<Option<f64>> {
    let width = camera.width as usize;
    (0..width * camera.height as usize)
        .into_par_iter()
        .map(|i| {
            let (o, d) = camera.ray((i % width) as f64 + 0.5, (i / width) as f64 + 0.5);
            tracer.hit(o, d)
        })
        .collect()
}

/// Writes `image` as PNG to `path`, atomically.
///
/// # Errors
/// [`Error::Io`] when writing fails, [`Error::InvalidInput`] when encoding does.
pub fn write_png(path: &std::path::Path, image: &RgbImage) -> Result<()> {
    crate::io::write_atomic(path, &crate::plot::png_bytes(image)?)
}

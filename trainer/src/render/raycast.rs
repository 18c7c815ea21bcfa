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
use crate::error::{Error, Result};
use crate::geometry::vector::{add, dot, scale};

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
    /// Cast the sub-pixel rays only where the image changes (see [`render`]); `false` casts
    /// them through every pixel.
    pub adaptive: bool,
    /// Punctual octree: voxels are split while larger than this fraction of the smallest
    /// leaf box they meet.
    pub voxel_ratio: f64,
    /// Punctual octree: drop the voxels where samples of Φ stay away from zero
    /// ([`Octree::regions_probed`]), so rays skip empty space.
    pub probe: bool,
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
            adaptive: true,
            voxel_ratio: 0.25,
            probe: true,
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
    size: f64,
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
            Method::Punctual if options.probe => Octree::regions_probed(field, options.voxel_ratio),
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
            size,
        })
    }

    /// Leaf voxels of the octree.
    pub fn voxel_count(&self) -> usize {
        self.octree.leaf_count()
    }

    /// The ray parameter of the first surface point along `origin + t·direction` (unit
    /// direction, t ≥ 0), or `None`.
    pub fn hit(&self, origin: [f64; 3], direction: [f64; 3]) -> Option<f64> {
        self.hit_gradient(origin, direction).map(|(t, _)| t)
    }

    /// [`Tracer::hit`] with ∇Φ at the hit (from the punctual search's last Newton step, which
    /// lies within the tolerance of the hit; evaluated at the hit by the guaranteed search).
    pub fn hit_gradient(&self, origin: [f64; 3], direction: [f64; 3]) -> Option<(f64, [f64; 3])> {
        let field = self.field;
        // Only the parts of a voxel inside a region are searched, as `mesh` searches them: an
        // octree voxel also covers space beside the oriented boxes, where the field is the
        // network's extrapolation.
        let inside = move |span: [f64; 2]| {
            field
                .regions()
                .iter()
                .filter_map(move |r| r.ray_span(origin, direction, span[0]))
                .filter_map(move |[a, b]| (a <= span[1]).then_some([a, b.min(span[1])]))
        };
        match self.method {
            Method::Punctual => self.octree.first_hit(origin, direction, &mut |_, span| {
                // The regions' spans merged, nearest first: each stretch sampled once.
                let mut spans = [[0.0_f64; 2]; MAX_SPANS];
                let mut count = 0;
                for s in inside(span) {
                    if let Some(slot) = spans.get_mut(count) {
                        *slot = s;
                        count += 1;
                    }
                }
                let spans = &mut spans[..count];
                spans.sort_unstable_by(|a, b| a[0].total_cmp(&b[0]));
                let mut merged = 0;
                for i in 0..spans.len() {
                    if merged > 0 && spans[i][0] <= spans[merged - 1][1] {
                        spans[merged - 1][1] = spans[merged - 1][1].max(spans[i][1]);
                    } else {
                        spans[merged] = spans[i];
                        merged += 1;
                    }
                }
                spans[..merged].iter().find_map(|&s| {
                    punctual::newton_in_voxel(field, origin, direction, s, self.tolerance)
                })
            }),
            Method::Guaranteed => {
                let mut search = |_: &super::region::Aabb, span: [f64; 2]| {
                    inside(span)
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
                        .map(|t| (t, field.value_gradient(add(origin, scale(direction, t))).1))
                };
                self.octree.first_hit(origin, direction, &mut search)
            }
        }
    }
}

/// The most region spans a voxel's ray segment is cut into (one region per module at most,
/// and the core holds 64 modules).
const MAX_SPANS: usize = 64;

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
    /// Pixels that got every sub-pixel ray (all of them unless adaptive).
    pub supersampled: u64,
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

/// Depth difference, as a fraction of the scene's size, above which two neighbouring pixel
/// centres are on different parts of the surface (an occlusion edge).
pub const EDGE_DEPTH: f64 = 0.01;
/// Cosine of the angle between neighbouring centres' normals above which the shading is
/// smooth enough for one ray (about 8°).
pub const EDGE_COSINE: f64 = 0.99;

/// What the ray through one point of the image found.
#[derive(Copy, Clone, Debug)]
struct Sample {
    /// Ray parameter and ∇Φ of the hit.
    hit: Option<(f64, [f64; 3])>,
    /// Linear colour.
    colour: [f64; 3],
}

/// Renders `field` seen by `camera`. `progress(done, total)` is called after every tile
/// (from worker threads).
///
/// Anti-aliasing: every pixel gets `samples` rays on a square sub-pixel grid (the paper's 4).
/// With `adaptive` (the default), one ray first goes through every pixel centre, and only
/// pixels whose 3 × 3 neighbourhood changes — hit against miss, a depth jump above
/// [`EDGE_DEPTH`] of the scene, normals further apart than [`EDGE_COSINE`] — get the sub-pixel
/// rays; elsewhere the shading is smooth and the centre's colour stands for the pixel's mean.
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
    let (right, up) = (camera.right(), camera.up());
    let shading = &options.shading;
    let rays = AtomicU64::new(0);
    let hits = AtomicU64::new(0);
    let trace = |x: f64, y: f64| {
        let (o, d) = camera.ray(x, y);
        rays.fetch_add(1, Ordering::Relaxed);
        match tracer.hit_gradient(o, d) {
            Some((t, g)) => {
                hits.fetch_add(1, Ordering::Relaxed);
                Sample {
                    hit: Some((t, g)),
                    colour: shading.shade(g, d, right, up),
                }
            }
            None => Sample {
                hit: None,
                colour: shading.background,
            },
        }
    };
    let adaptive = options.adaptive && options.samples > 1;
    let centres: Vec<Sample> = if adaptive {
        (0..width as usize * height as usize)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % width as usize, i / width as usize);
                trace(x as f64 + 0.5, y as f64 + 0.5)
            })
            .collect()
    } else {
        Vec::new()
    };
    let depth_jump = EDGE_DEPTH * tracer.size;
    let smooth = |x: u32, y: u32| -> Option<[f64; 3]> {
        let at = |x: u32, y: u32| centres.get(y as usize * width as usize + x as usize);
        let centre = at(x, y)?;
        let neighbours = (y.saturating_sub(1)..=(y + 1).min(height - 1))
            .flat_map(|ny| (x.saturating_sub(1)..=(x + 1).min(width - 1)).map(move |nx| (nx, ny)));
        for (nx, ny) in neighbours {
            let other = at(nx, ny)?;
            if !similar(centre.hit, other.hit, depth_jump) {
                return None;
            }
        }
        Some(centre.colour)
    };
    let tiles_x = width.div_ceil(TILE);
    let tiles_y = height.div_ceil(TILE);
    let total = u64::from(tiles_x) * u64::from(tiles_y);
    let done = AtomicU64::new(0);
    let supersampled = AtomicU64::new(0);
    let tiles: Vec<(u32, u32, Vec<[u8; 3]>)> = (0..total)
        .into_par_iter()
        .map(|index| {
            let tx = (index % u64::from(tiles_x)) as u32 * TILE;
            let ty = (index / u64::from(tiles_x)) as u32 * TILE;
            let mut pixels = Vec::with_capacity((TILE * TILE) as usize);
            for y in ty..(ty + TILE).min(height) {
                for x in tx..(tx + TILE).min(width) {
                    let colour = smooth(x, y).unwrap_or_else(|| {
                        supersampled.fetch_add(1, Ordering::Relaxed);
                        let mut sum = [0.0; 3];
                        for s in 0..options.samples {
                            let (sx, sy) = (f64::from(s % k) + 0.5, f64::from(s / k) + 0.5);
                            let sample = trace(
                                f64::from(x) + sx / f64::from(k),
                                f64::from(y) + sy / f64::from(k),
                            );
                            sum = [0, 1, 2].map(|c| sum[c] + sample.colour[c]);
                        }
                        sum.map(|c| c / f64::from(options.samples))
                    });
                    pixels.push(colour.map(to_srgb8));
                }
            }
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
            rays: rays.into_inner(),
            hits: hits.into_inner(),
            supersampled: supersampled.into_inner(),
            voxels: tracer.voxel_count(),
            seconds: start.elapsed().as_secs_f64(),
        },
    })
}

/// Whether two neighbouring pixel centres see the same smooth part of the scene.
fn similar(a: Option<(f64, [f64; 3])>, b: Option<(f64, [f64; 3])>, depth_jump: f64) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some((ta, ga)), Some((tb, gb))) => {
            let lengths = (dot(ga, ga) * dot(gb, gb)).sqrt();
            (ta - tb).abs() <= depth_jump && dot(ga, gb) >= EDGE_COSINE * lengths
        }
        _ => false,
    }
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

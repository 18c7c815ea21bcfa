//! Punctual against guaranteed on the same scene, both checked against dense sampling: one
//! ray per pixel center, Φ sampled every `step` along the ray's spans inside the leaf boxes;
//! a pixel is a dense hit when two consecutive samples differ in sign.

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::camera::Camera;
use super::field::Field;
use super::raycast::{Method, RenderOptions, Tracer, hit_map};
use super::region::ray_spans;
use crate::error::{Error, Result};
use crate::geometry::vector::{add, scale};

/// Most samples per ray the dense reference takes.
pub const MAX_DENSE_SAMPLES: f64 = 1e6;

/// What the two searches found against the dense reference.
#[derive(Clone, Debug, Serialize)]
pub struct MethodComparison {
    /// Pixels (one ray each).
    pub pixels: usize,
    /// Dense sampling step (ray length).
    pub dense_step: f64,
    /// Pixels where dense sampling finds a sign change.
    pub dense_hits: usize,
    /// Pixels the punctual search hits.
    pub punctual_hits: usize,
    /// Dense hits the punctual search misses.
    pub punctual_missed: usize,
    /// Pixels the guaranteed search hits.
    pub guaranteed_hits: usize,
    /// Dense hits the guaranteed search misses (0 by construction).
    pub guaranteed_missed: usize,
    /// Largest |t_punctual − t_dense| over pixels both hit, where the dense hit is the
    /// first sign change refined to the step (so differences up to `dense_step` are noise).
    pub punctual_max_depth_error: f64,
    /// The same for the guaranteed search.
    pub guaranteed_max_depth_error: f64,
    /// Wall time of the punctual hit map (octree included), seconds.
    pub punctual_seconds: f64,
    /// Wall time of the guaranteed hit map, seconds.
    pub guaranteed_seconds: f64,
    /// Wall time of dense sampling, seconds.
    pub dense_seconds: f64,
}

/// Runs both searches and dense sampling with step `dense_step` on `camera`'s pixels.
///
/// # Errors
/// [`Error::InvalidInput`] for a non-positive step or one so small that a ray would take more
/// than [`MAX_DENSE_SAMPLES`]; as [`Tracer::new`] (the field needs interval bounds).
pub fn compare_methods<F: Field + ?Sized>(
    field: &F,
    camera: &Camera,
    options: &RenderOptions,
    dense_step: f64,
) -> Result<MethodComparison> {
    let size = super::region::bounds_of(field.regions()).map_or(0.0, |b| b.longest_side());
    if dense_step.is_nan() || dense_step <= 0.0 || 2.0 * size / dense_step > MAX_DENSE_SAMPLES {
        return Err(Error::invalid(format!(
            "dense step {dense_step} is not usable for a scene of size {size}"
        )));
    }
    let timed = |method: Method| -> Result<(Vec<Option<f64>>, f64)> {
        let start = Instant::now();
        let tracer = Tracer::new(field, method, options)?;
        let hits = hit_map(&tracer, camera);
        Ok((hits, start.elapsed().as_secs_f64()))
    };
    let (punctual, punctual_seconds) = timed(Method::Punctual)?;
    let (guaranteed, guaranteed_seconds) = timed(Method::Guaranteed)?;
    let start = Instant::now();
    let width = camera.width as usize;
    let dense: Vec<Option<f64>> = (0..punctual.len())
        .into_par_iter()
        .map(|i| {
            let (o, d) = camera.ray((i % width) as f64 + 0.5, (i / width) as f64 + 0.5);
            dense_hit(field, o, d, dense_step)
        })
        .collect();
    let dense_seconds = start.elapsed().as_secs_f64();
    let count = |v: &[Option<f64>]| v.iter().filter(|h| h.is_some()).count();
    let missed = |v: &[Option<f64>]| {
        v.iter()
            .zip(&dense)
            .filter(|(h, d)| d.is_some() && h.is_none())
            .count()
    };
    let depth_error = |v: &[Option<f64>]| {
        v.iter()
            .zip(&dense)
            .filter_map(|(h, d)| Some((h.as_ref()? - d.as_ref()?).abs()))
            .fold(0.0, f64::max)
    };
    Ok(MethodComparison {
        pixels: dense.len(),
        dense_step,
        dense_hits: count(&dense),
        punctual_hits: count(&punctual),
        punctual_missed: missed(&punctual),
        guaranteed_hits: count(&guaranteed),
        guaranteed_missed: missed(&guaranteed),
        punctual_max_depth_error: depth_error(&punctual),
        guaranteed_max_depth_error: depth_error(&guaranteed),
        punctual_seconds,
        guaranteed_seconds,
        dense_seconds,
    })
}

/// The first sign change of Φ sampled every `step` along the ray's spans in the regions, as
/// the midpoint of the two samples around it.
pub fn dense_hit<F: Field + ?Sized>(
    field: &F,
    origin: [f64; 3],
    direction: [f64; 3],
    step: f64,
) -> Option<f64> {
    for [a, b] in ray_spans(field.regions(), origin, direction) {
        let n = ((b - a) / step).ceil().max(1.0) as usize;
        let mut previous = (a, field.value(add(origin, scale(direction, a))));
        for i in 1..=n {
            let t = a + (b - a) * i as f64 / n as f64;
            let v = field.value(add(origin, scale(direction, t)));
            if (previous.1 < 0.0) != (v < 0.0) {
                return Some(0.5 * (previous.0 + t));
            }
            previous = (t, v);
        }
    }
    None
}

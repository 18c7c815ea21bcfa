//! The free-form tessellation of §5.3: the boundary loop resampled uniformly, embedded in a
//! uniform grid whose points outside the loop (or closer than half a step to it) are
//! discarded, and the rest triangulated by constrained Delaunay.

use super::boundary::{BoundaryOptions, boundary_loop, resample_closed};
use super::planar::{
    PlanarMesh, distance_to_polygon, inside_polygon, signed_area, triangulate_polygon,
};
use crate::error::{Error, Result};

/// A triangulated region spanning the parameter points with about `target_vertices`
/// vertices: grid step h = √(area / target_vertices), boundary resampled at the same step.
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than 16 target vertices or a boundary that cannot be
/// found or triangulated.
pub fn delaunay_grid(
    parameters: &[[f64; 2]],
    target_vertices: usize,
    options: &BoundaryOptions,
) -> Result<PlanarMesh> {
    if target_vertices < 16 {
        return Err(Error::invalid("a tessellation needs at least 16 vertices"));
    }
    let cycle = boundary_loop(parameters, options)?;
    let polygon: Vec<[f64; 2]> = cycle.iter().map(|&i| parameters[i as usize]).collect();
    fill_polygon(&polygon, target_vertices)
}

/// Resamples `polygon` and fills it with grid points (see [`delaunay_grid`]).
///
/// # Errors
/// As [`delaunay_grid`].
pub fn fill_polygon(polygon: &[[f64; 2]], target_vertices: usize) -> Result<PlanarMesh> {
    let area = signed_area(polygon).abs();
    if area.is_nan() || area <= 0.0 {
        return Err(Error::invalid("the boundary loop encloses no area"));
    }
    let h = (area / target_vertices as f64).sqrt();
    let perimeter: f64 = (0..polygon.len())
        .map(|i| {
            let (a, b) = (polygon[i], polygon[(i + 1) % polygon.len()]);
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
        })
        .sum();
    let boundary = resample_closed(polygon, ((perimeter / h).round() as usize).max(3));
    let interior = grid_inside(&boundary, h);
    triangulate_polygon(&boundary, &interior)
}

/// Grid points of step `h` inside `polygon`, at least 0.5·h from its edges.
pub fn grid_inside(polygon: &[[f64; 2]], h: f64) -> Vec<[f64; 2]> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in polygon {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let mut out = Vec::new();
    if h.is_nan() || h <= 0.0 {
        return out;
    }
    let nx = ((hi[0] - lo[0]) / h).ceil() as usize;
    let ny = ((hi[1] - lo[1]) / h).ceil() as usize;
    for j in 0..=ny {
        for i in 0..=nx {
            let p = [lo[0] + i as f64 * h, lo[1] + j as f64 * h];
            if inside_polygon(p, polygon) && distance_to_polygon(p, polygon) >= 0.5 * h {
                out.push(p);
            }
        }
    }
    out
}

//! The regular quad grid of §5.3: four anchors, four cubic Bézier boundaries, and the bilinear
//! Coons patch of Eq. 13 between them.
//!
//! 1. The anchors are the boundary-loop points farthest from the centroid in each quadrant of
//!    the two principal (PCA) directions of the parameter points.
//! 2. The loop between consecutive anchors is fitted by a cubic Bézier curve with its ends at
//!    the anchors and the two inner control points by least squares (chord-length
//!    parameters).
//! 3. Q(s, t) = (1−t)·C₀(s) + t·C₁(s) + (1−s)·D₀(t) + s·D₁(t) − the bilinear corner term,
//!    sampled on a uniform (s, t) grid; each quad is split into two triangles (diagonals
//!    mirrored across the middle, so no corner is a one-triangle ear), so the mesh has the
//!    grid's topology (vertex (i, j) at index j·columns + i).

use nalgebra::{Matrix2, SymmetricEigen, Vector2};

use super::boundary::{BoundaryOptions, boundary_loop};
use super::planar::PlanarMesh;
use crate::error::{Error, Result};

/// A cubic Bézier curve in the parameter plane.
pub type Bezier = [[f64; 2]; 4];

/// Evaluates a cubic Bézier curve at t ∈ [0, 1].
pub fn bezier_point(b: &Bezier, t: f64) -> [f64; 2] {
    let s = 1.0 - t;
    let w = [s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t];
    [0, 1].map(|a| (0..4).map(|k| w[k] * b[k][a]).sum())
}

/// Least-squares cubic Bézier through `points` with its ends fixed at the first and last.
pub fn fit_bezier(points: &[[f64; 2]]) -> Bezier {
    let (p0, p3) = (points[0], points[points.len() - 1]);
    let straight = |t: f64| [p0[0] + t * (p3[0] - p0[0]), p0[1] + t * (p3[1] - p0[1])];
    let mut b = [p0, straight(1.0 / 3.0), straight(2.0 / 3.0), p3];
    if points.len() < 4 {
        return b;
    }
    let mut chord = vec![0.0];
    for w in points.windows(2) {
        let l = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
        chord.push(chord.last().copied().unwrap_or(0.0) + l);
    }
    let total = chord.last().copied().unwrap_or(0.0);
    if total.is_nan() || total <= 0.0 {
        return b;
    }
    let mut a = Matrix2::zeros();
    let mut rhs = [Vector2::zeros(); 2];
    for (p, &c) in points.iter().zip(&chord) {
        let t = c / total;
        let s = 1.0 - t;
        let (b0, b1, b2, b3) = (s * s * s, 3.0 * s * s * t, 3.0 * s * t * t, t * t * t);
        let basis = Vector2::new(b1, b2);
        a += basis * basis.transpose();
        for k in 0..2 {
            rhs[k] += basis * (p[k] - b0 * p0[k] - b3 * p3[k]);
        }
    }
    if let Some(inv) = a.try_inverse() {
        for k in 0..2 {
            let x = inv * rhs[k];
            b[1][k] = x[0];
            b[2][k] = x[1];
        }
    }
    b
}

/// The four boundary curves C₀ (bottom, s from 0 to 1), D₁ (right, t up), C₁ (top, s from 0
/// to 1) and D₀ (left, t up).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CoonsBoundary {
    /// C₀, D₁, C₁, D₀.
    pub curves: [Bezier; 4],
    /// Indices of the four anchor points (counter-clockwise).
    pub anchors: [u32; 4],
}

/// Anchors and Bézier boundaries of the parameter points.
///
/// # Errors
/// [`Error::InvalidInput`] when the boundary loop cannot be found or two quadrants share an
/// anchor (fewer than four distinct corners).
pub fn coons_boundary(parameters: &[[f64; 2]], options: &BoundaryOptions) -> Result<CoonsBoundary> {
    let cycle = boundary_loop(parameters, options)?;
    let n = parameters.len() as f64;
    let mean = [0, 1].map(|a| parameters.iter().map(|p| p[a]).sum::<f64>() / n);
    let mut cov = Matrix2::zeros();
    for p in parameters {
        let d = Vector2::new(p[0] - mean[0], p[1] - mean[1]);
        cov += d * d.transpose();
    }
    let eig = SymmetricEigen::new(cov);
    let (i1, i2) = if eig.eigenvalues[0] >= eig.eigenvalues[1] {
        (0, 1)
    } else {
        (1, 0)
    };
    let a1: Vector2<f64> = eig.eigenvectors.column(i1).into();
    let mut a2: Vector2<f64> = eig.eigenvectors.column(i2).into();
    if a1[0] * a2[1] - a1[1] * a2[0] < 0.0 {
        a2 = -a2;
    }
    // Quadrants in counter-clockwise order: (−,−), (+,−), (+,+), (−,+).
    let mut best = [(f64::NEG_INFINITY, usize::MAX); 4];
    for (k, &v) in cycle.iter().enumerate() {
        let p = parameters[v as usize];
        let d = Vector2::new(p[0] - mean[0], p[1] - mean[1]);
        let (x, y) = (d.dot(&a1), d.dot(&a2));
        let q = match (x >= 0.0, y >= 0.0) {
            (false, false) => 0,
            (true, false) => 1,
            (true, true) => 2,
            (false, true) => 3,
        };
        let r = d.norm();
        if r > best[q].0 {
            best[q] = (r, k);
        }
    }
    if best.iter().any(|b| b.1 == usize::MAX) {
        return Err(Error::invalid(
            "the parameter boundary has no point in some PCA quadrant: no four corners",
        ));
    }
    let mut positions: Vec<usize> = best.iter().map(|b| b.1).collect();
    // The loop is counter-clockwise, so are the quadrants: rotate to start at quadrant 0 and
    // require increasing loop positions.
    let start = positions[0];
    let m = cycle.len();
    for p in positions.iter_mut() {
        *p = (*p + m - start) % m;
    }
    if !positions.windows(2).all(|w| w[0] < w[1]) {
        return Err(Error::invalid(
            "the four corner points are not in order along the boundary",
        ));
    }
    let chain = |from: usize, to: usize| -> Vec<[f64; 2]> {
        let end = if to == 0 { m } else { to };
        (from..=end)
            .map(|k| parameters[cycle[(k + start) % m] as usize])
            .collect()
    };
    let bottom = fit_bezier(&chain(positions[0], positions[1]));
    let right = fit_bezier(&chain(positions[1], positions[2]));
    let mut top = fit_bezier(&chain(positions[2], positions[3]));
    let mut left = fit_bezier(&chain(positions[3], 0));
    top.reverse();
    left.reverse();
    Ok(CoonsBoundary {
        curves: [bottom, right, top, left],
        anchors: std::array::from_fn(|q| cycle[(positions[q] + start) % m]),
    })
}

/// Q(s, t) of Eq. 13.
pub fn coons_point(boundary: &CoonsBoundary, s: f64, t: f64) -> [f64; 2] {
    let [c0, d1, c1, d0] = &boundary.curves;
    let (p00, p10, p01, p11) = (c0[0], c0[3], c1[0], c1[3]);
    let (a, b, c, d) = (
        bezier_point(c0, s),
        bezier_point(c1, s),
        bezier_point(d0, t),
        bezier_point(d1, t),
    );
    [0, 1].map(|k| {
        (1.0 - t) * a[k] + t * b[k] + (1.0 - s) * c[k] + s * d[k]
            - (1.0 - s) * (1.0 - t) * p00[k]
            - s * (1.0 - t) * p10[k]
            - (1.0 - s) * t * p01[k]
            - s * t * p11[k]
    })
}

/// The `columns × rows` Coons grid (both ≥ 2) as a planar mesh of counter-clockwise triangles.
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than 2 columns or rows.
pub fn coons_grid(boundary: &CoonsBoundary, columns: usize, rows: usize) -> Result<PlanarMesh> {
    if columns < 2 || rows < 2 || columns.saturating_mul(rows) > u32::MAX as usize / 2 {
        return Err(Error::invalid(
            "a Coons grid needs 2 or more columns and rows",
        ));
    }
    let mut vertices = Vec::with_capacity(columns * rows);
    for j in 0..rows {
        for i in 0..columns {
            let s = i as f64 / (columns - 1) as f64;
            let t = j as f64 / (rows - 1) as f64;
            vertices.push(coons_point(boundary, s, t));
        }
    }
    let mut triangles = Vec::with_capacity(2 * (columns - 1) * (rows - 1));
    for j in 0..rows - 1 {
        for i in 0..columns - 1 {
            let v = |i: usize, j: usize| (j * columns + i) as u32;
            // Diagonals mirror across the middle, so every corner vertex has two triangles
            // (a one-triangle "ear" at a corner would weld onto a neighbour's ear when
            // stitching).
            if (2 * i < columns - 1) == (2 * j < rows - 1) {
                triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            } else {
                triangles.push([v(i, j), v(i + 1, j), v(i, j + 1)]);
                triangles.push([v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
    }
    Ok(PlanarMesh {
        vertices,
        triangles,
    })
}

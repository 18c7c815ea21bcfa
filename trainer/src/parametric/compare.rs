//! The comparison of §7.1 (Fig. 13): on noisy samples of a known height field, the network
//! surface against a thin-plate-spline RBF fit (few centres — "low density" — and one centre
//! per point — "high density", interpolating) and against direct Delaunay triangulation of the
//! points in the LLE parameter plane.
//!
//! Each row reports the mean-square error at the input points (the paper's MSE: 0 for the
//! interpolating methods), the RMS vertical distance of the output mesh's vertices to the true,
//! noise-free surface, and the variance of the dihedral angles between neighbouring
//! triangles (radians², lower is smoother). The RBF baseline is a thin-plate spline
//! z = Σ wⱼ φ(|x − cⱼ|) + a + b·x + c·y, φ(r) = r² ln r (`thin_plate`; `rbf/` is a 3-D
//! implicit multiquadric and does not fit height fields). [`compare_patch`](super::compare_patch)
//! runs the same methods on any patch, without a known surface.

use std::time::Instant;

use super::embedding::embed_points;
use super::pipeline::{ReconstructOptions, Tessellation, reconstruct};
use super::planar::delaunay;
use super::samples::{SampleSurface, sample_surface};
use super::thin_plate::{Centers, ThinPlate};
use crate::error::{Error, Result};
use crate::io::Mesh;

/// One method on one point set.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ComparisonRow {
    /// The surface.
    pub surface: SampleSurface,
    /// Uniform noise as a fraction of the bounding-box diagonal.
    pub noise: f64,
    /// `network`, `rbf-low`, `rbf-high` or `delaunay`.
    pub method: &'static str,
    /// Mean squared error at the input points: squared 3-D distance to the network at the
    /// point's (u, v) for `network`, squared vertical residual for the RBF fits, 0 for
    /// `delaunay`.
    pub mse_points: f64,
    /// RMS vertical distance of the mesh vertices to the true surface.
    pub rms_truth: f64,
    /// Variance of the dihedral angles (radians²).
    pub dihedral_variance: f64,
    /// Vertices of the output mesh.
    pub vertices: usize,
    /// Wall time of the method (s).
    pub seconds: f64,
}

/// Runs the four methods on `count` samples of `surface` with `noise`.
///
/// # Errors
/// [`Error::InvalidInput`] for a surface that is not a height field or any failure of the
/// methods.
pub fn compare_methods(
    surface: SampleSurface,
    count: usize,
    noise: f64,
    seed: u64,
) -> Result<Vec<ComparisonRow>> {
    if surface.height(0.0, 0.0).is_none() {
        return Err(Error::invalid(
            "the comparison needs a height-field surface",
        ));
    }
    let sample = sample_surface(surface, count, noise, seed)?;
    let points = &sample.points;
    let truth = |p: [f64; 3]| p[2] - surface.height(p[0], p[1]).unwrap_or(p[2]);
    let row = |method, mse_points, mesh: &Mesh, seconds| ComparisonRow {
        surface,
        noise,
        method,
        mse_points,
        rms_truth: (mesh
            .positions
            .iter()
            .map(|&p| truth(p).powi(2))
            .sum::<f64>()
            / mesh.positions.len().max(1) as f64)
            .sqrt(),
        dihedral_variance: dihedral_variance(mesh),
        vertices: mesh.positions.len(),
        seconds,
    };
    let mut rows = Vec::new();
    let resolution = 30;

    let start = Instant::now();
    let options = ReconstructOptions {
        tessellation: Tessellation::Coons { resolution },
        ..ReconstructOptions::default()
    };
    let network = reconstruct(points, &options)?;
    let seconds = start.elapsed().as_secs_f64();
    rows.push(row(
        "network",
        network.fit.rms_error.powi(2),
        &network.surface.mesh,
        seconds,
    ));

    let plane: Vec<[f64; 2]> = points.iter().map(|p| [p[0], p[1]]).collect();
    let heights: Vec<[f64; 1]> = points.iter().map(|p| [p[2]]).collect();
    for (method, centers) in [
        ("rbf-low", Centers::Grid(5)),
        ("rbf-high", Centers::Points(usize::MAX)),
    ] {
        let start = Instant::now();
        let spline = ThinPlate::fit(&plane, &heights, centers)?;
        let mesh = grid_mesh(&spline, points, resolution);
        let mse = points
            .iter()
            .map(|p| (spline.value([p[0], p[1]])[0] - p[2]).powi(2))
            .sum::<f64>()
            / points.len() as f64;
        rows.push(row(method, mse, &mesh, start.elapsed().as_secs_f64()));
    }

    let start = Instant::now();
    let embedding = embed_points(points, &options.embedding)?;
    let mesh = Mesh {
        positions: points.clone(),
        triangles: delaunay(&embedding.parameters)?,
    };
    rows.push(row("delaunay", 0.0, &mesh, start.elapsed().as_secs_f64()));
    Ok(rows)
}

/// Variance of the angles between the normals of triangles sharing an edge (radians²).
pub fn dihedral_variance(mesh: &Mesh) -> f64 {
    // Folded to [0, π/2]: a triangle turned over counts as flat, not as a fold.
    let angles: Vec<f64> = crate::geometry::mesh_graph::dihedral_angles(mesh)
        .into_iter()
        .map(|a| a.min(std::f64::consts::PI - a))
        .collect();
    if angles.is_empty() {
        return 0.0;
    }
    let mean = angles.iter().sum::<f64>() / angles.len() as f64;
    angles.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / angles.len() as f64
}

/// The height field z(x, y) of a thin-plate spline on a `resolution²` grid over the points'
/// (x, y) box.
fn grid_mesh(spline: &ThinPlate<1>, points: &[[f64; 3]], resolution: usize) -> Mesh {
    let (lo, hi) = super::fit::bounds(points.iter().map(|p| p.as_slice()), 3);
    let r = resolution.max(2);
    let mut positions = Vec::with_capacity(r * r);
    for j in 0..r {
        for i in 0..r {
            let x = lo[0] + (hi[0] - lo[0]) * i as f64 / (r - 1) as f64;
            let y = lo[1] + (hi[1] - lo[1]) * j as f64 / (r - 1) as f64;
            positions.push([x, y, spline.value([x, y])[0]]);
        }
    }
    let mut triangles = Vec::new();
    for j in 0..r - 1 {
        for i in 0..r - 1 {
            let v = |i: usize, j: usize| (j * r + i) as u32;
            triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
            triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

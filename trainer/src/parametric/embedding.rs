//! Locally linear embedding to 2-D (§4): the parameterization of a point set or of a mesh
//! region.
//!
//! [`embed_points`] uses the k nearest neighbours (§4.1), [`embed_mesh`] the mesh one-rings
//! (§4.2). Both solve Eq. 1 for the weights ([`super::weights`]), form the sparse
//! M = (I − W)ᵀ(I − W) and take its 2nd and 3rd smallest eigenvectors ([`super::eigen`]),
//! scaled to the unit covariance of Eq. 4 (so u and v have mean 0 and variance 1). The
//! result is then checked for folds ([`super::folds`]) unless the options switch that off.

use super::eigen::smallest_nonconstant;
use super::folds::{FoldReport, check_flat, fold_report};
use super::neighbors::{check_points, nearest_neighbors};
use super::weights::{embedding_matrix, reconstruction_weights};
use crate::error::{Error, Result};
use crate::geometry::mesh_graph::one_rings;
use crate::io::Mesh;

/// Embedding settings.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LleOptions {
    /// Neighbours per point k (10).
    pub neighbors: usize,
    /// Gram regularization δ in C + δ·tr(C)·I (10⁻³).
    pub regularization: f64,
    /// Reject embeddings that fold or collapse (true).
    pub check_folds: bool,
}

impl Default for LleOptions {
    fn default() -> Self {
        LleOptions {
            neighbors: 10,
            regularization: 1e-3,
            check_folds: true,
        }
    }
}

/// A 2-D parameterization of a point set.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Embedding {
    /// (u, v) of every point, mean 0, unit covariance.
    pub parameters: Vec<[f64; 2]>,
    /// The eigenvalues of M that u and v belong to (λ₂, λ₃).
    pub eigenvalues: [f64; 2],
    /// Subspace iterations of the eigen solver.
    pub iterations: usize,
    /// Flip and collapse fractions of the result.
    pub folds: FoldReport,
}

/// LLE of an unstructured point set with k nearest neighbours.
///
/// # Errors
/// [`Error::InvalidInput`] for too few points for k, non-finite coordinates, duplicate points,
/// points on a line, a failed eigen solve, or (with `check_folds`) an embedding that folds.
pub fn embed_points(points: &[[f64; 3]], options: &LleOptions) -> Result<Embedding> {
    let diagonal = check_points(points, options.neighbors + 1)?;
    let neighbors = nearest_neighbors(points, options.neighbors, diagonal)?;
    embed_with_neighbors(points, &neighbors, options)
}

/// LLE of a mesh's vertices with their one-rings as neighbourhoods (§4.2). Every vertex must
/// belong to a triangle.
///
/// # Errors
/// As [`embed_points`]; also for an isolated vertex.
pub fn embed_mesh(mesh: &Mesh, options: &LleOptions) -> Result<Embedding> {
    check_points(&mesh.positions, 4)?;
    let rings = one_rings(mesh.positions.len(), &mesh.triangles);
    if let Some(i) = rings.iter().position(Vec::is_empty) {
        return Err(Error::invalid(format!(
            "vertex {i} belongs to no triangle: it has no one-ring"
        )));
    }
    embed_with_neighbors(&mesh.positions, &rings, options)
}

/// LLE with given neighbourhoods (`neighbors[i]` must not contain i).
///
/// # Errors
/// As [`embed_points`].
pub fn embed_with_neighbors(
    points: &[[f64; 3]],
    neighbors: &[Vec<usize>],
    options: &LleOptions,
) -> Result<Embedding> {
    if neighbors.len() != points.len() {
        return Err(Error::invalid("one neighbourhood per point is needed"));
    }
    if !(options.regularization > 0.0 && options.regularization.is_finite()) {
        return Err(Error::invalid("the Gram regularization must be positive"));
    }
    let weights = reconstruction_weights(points, neighbors, options.regularization)?;
    let m = embedding_matrix(neighbors, &weights);
    let eigen = smallest_nonconstant(&m, 2)?;
    let scale = (points.len() as f64).sqrt();
    let parameters: Vec<[f64; 2]> = (0..points.len())
        .map(|i| [eigen.vectors[0][i] * scale, eigen.vectors[1][i] * scale])
        .collect();
    let folds = fold_report(points, &parameters, neighbors);
    if options.check_folds {
        check_flat(&folds)?;
    }
    Ok(Embedding {
        parameters,
        eigenvalues: [eigen.values[0], eigen.values[1]],
        iterations: eigen.iterations,
        folds,
    })
}

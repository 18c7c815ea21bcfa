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
use super::unrolling::{UNEVEN_AREA_SHARE, sparse_area_share, unrolled_parameters};
use super::weights::{embedding_matrix, reconstruction_weights};
use crate::error::{Error, Result};
use crate::geometry::mesh_graph::one_rings;
use crate::io::Mesh;

/// The other k [`embed_points`] tries, in order, when the embedding folds and
/// [`LleOptions::more_neighbors`] is on: k = 10 goes on with 12, 14, 16, 20, then 8 and 6.
/// Noise and dense samples want a wider neighbourhood, thin features a narrower one.
pub const OTHER_NEIGHBORS: [isize; 6] = [2, 4, 6, 10, -2, -4];

/// Embedding settings.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LleOptions {
    /// Neighbours per point k (10).
    pub neighbors: usize,
    /// Gram regularization δ in C + δ·tr(C)·I (10⁻³).
    pub regularization: f64,
    /// Reject embeddings that fold or collapse (true).
    pub check_folds: bool,
    /// When the embedding folds at k, try k + [`OTHER_NEIGHBORS`] before refusing (true):
    /// noisy or dense samples often need a wider neighbourhood to see the surface rather
    /// than the noise. Off when the user chose k.
    #[serde(default)]
    pub more_neighbors: bool,
    /// Unroll a patch whose sampling density changes instead of taking LLE's embedding
    /// (true; see [`unrolled_parameters`] and [`sparse_area_share`]). Off, every patch gets
    /// Roweis & Saul's LLE.
    #[serde(default = "unrolled_when_uneven")]
    pub unroll_uneven: bool,
}

fn unrolled_when_uneven() -> bool {
    true
}

/// How a patch was parameterized.
#[derive(Copy, Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Parameterization {
    /// LLE's two smallest non-constant eigenvectors (§4).
    Lle,
    /// Unrolled along the patch and smoothed by the LLE matrix ([`unrolled_parameters`]):
    /// the sampling density changes, or LLE folds at every k tried.
    Unrolled,
}

impl Default for LleOptions {
    fn default() -> Self {
        LleOptions {
            neighbors: 10,
            regularization: 1e-3,
            check_folds: true,
            more_neighbors: true,
            unroll_uneven: true,
        }
    }
}

/// A 2-D parameterization of a point set.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Embedding {
    /// (u, v) of every point, mean 0, unit covariance.
    pub parameters: Vec<[f64; 2]>,
    /// The eigenvalues of M that u and v belong to (λ₂, λ₃); for an unrolled patch, the LLE
    /// cost uᵀMu / uᵀu of each coordinate.
    pub eigenvalues: [f64; 2],
    /// Subspace iterations of the eigen solver (0 for an unrolled patch).
    pub iterations: usize,
    /// Flip and collapse fractions of the result.
    pub folds: FoldReport,
    /// Neighbours per point k the embedding used (for a mesh, whose one-rings are the
    /// neighbourhoods, the option it was given).
    pub neighbors: usize,
    /// LLE's, or unrolled where the density changes.
    pub parameterization: Parameterization,
    /// The share of the patch's area sampled at more than twice its median spacing
    /// ([`sparse_area_share`]; 0 when [`LleOptions::unroll_uneven`] is off).
    pub sparse_area: f64,
}

/// LLE of an unstructured point set with k nearest neighbours; with
/// [`LleOptions::more_neighbors`], the first of k and k + [`OTHER_NEIGHBORS`] (from 4 to
/// fewer than the points) whose embedding does not fold, and when every one folds or fails,
/// the first of them whose unrolled parameterization ([`unrolled_parameters`]) does not (with
/// [`LleOptions::unroll_uneven`]).
///
/// # Errors
/// [`Error::InvalidInput`] for too few points for k, non-finite coordinates, duplicate points,
/// points on a line, a failed eigen solve, or (with `check_folds`) an embedding that folds at
/// every k tried.
pub fn embed_points(points: &[[f64; 3]], options: &LleOptions) -> Result<Embedding> {
    let diagonal = check_points(points, options.neighbors + 1)?;
    let mut tried = vec![options.neighbors];
    if options.more_neighbors && options.check_folds {
        tried.extend(
            OTHER_NEIGHBORS
                .iter()
                .filter_map(|&step| options.neighbors.checked_add_signed(step))
                .filter(|&k| k >= 4 && k < points.len()),
        );
    }
    let mut first_error = None;
    for &k in &tried {
        let neighbors = nearest_neighbors(points, k, diagonal)?;
        let options = LleOptions {
            neighbors: k,
            ..*options
        };
        match embed_with_neighbors(points, &neighbors, &options) {
            Ok(embedding) => return Ok(embedding),
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    // LLE folds or fails at every k: a patch curved too far for its local reconstructions (a
    // cap reaching round a bend) may still unroll along its path lengths.
    if options.more_neighbors && options.check_folds && options.unroll_uneven {
        for &k in &tried {
            let neighbors = nearest_neighbors(points, k, diagonal)?;
            if let Some(embedding) = unrolled_if_flat(points, &neighbors, k, options) {
                return Ok(embedding);
            }
        }
    }
    let error = first_error.unwrap_or_else(|| Error::invalid("no neighbourhood size to try"));
    if tried.len() == 1 {
        return Err(Error::invalid(format!(
            "{error} (with k = {} neighbours; more neighbours, --neighbors, often flatten noisy \
             or dense samples)",
            options.neighbors
        )));
    }
    let ks: Vec<String> = tried.iter().map(usize::to_string).collect();
    Err(Error::invalid(format!(
        "{error} (tried k = {} neighbours; another --neighbors may still help)",
        ks.join(", ")
    )))
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
    let sparse_area = if options.unroll_uneven {
        sparse_area_share(points, neighbors)
    } else {
        0.0
    };
    if sparse_area >= UNEVEN_AREA_SHARE {
        // Unrolled unless that folds or fails; then LLE's, as for an even patch.
        if let Some(embedding) = unrolled(points, neighbors, &m, options, sparse_area) {
            return Ok(embedding);
        }
    }
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
        neighbors: options.neighbors,
        parameterization: Parameterization::Lle,
        sparse_area,
    })
}

/// The unrolled parameterization ([`unrolled_parameters`]) with k = `k` neighbours, when it
/// does not fold.
fn unrolled_if_flat(
    points: &[[f64; 3]],
    neighbors: &[Vec<usize>],
    k: usize,
    options: &LleOptions,
) -> Option<Embedding> {
    let weights = reconstruction_weights(points, neighbors, options.regularization).ok()?;
    let m = embedding_matrix(neighbors, &weights);
    let options = LleOptions {
        neighbors: k,
        ..*options
    };
    unrolled(
        points,
        neighbors,
        &m,
        &options,
        sparse_area_share(points, neighbors),
    )
}

/// [`unrolled_parameters`] as an embedding, unless it fails or (with
/// [`LleOptions::check_folds`]) folds.
fn unrolled(
    points: &[[f64; 3]],
    neighbors: &[Vec<usize>],
    m: &super::sparse::SymmetricMatrix,
    options: &LleOptions,
    sparse_area: f64,
) -> Option<Embedding> {
    let (parameters, costs) = unrolled_parameters(points, neighbors, m).ok()?;
    let folds = fold_report(points, &parameters, neighbors);
    if options.check_folds && check_flat(&folds).is_err() {
        return None;
    }
    Some(Embedding {
        parameters,
        eigenvalues: costs,
        iterations: 0,
        folds,
        neighbors: options.neighbors,
        parameterization: Parameterization::Unrolled,
        sparse_area,
    })
}

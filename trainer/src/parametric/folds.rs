//! Fold detection: does the 2-D embedding flatten the patch without folding or collapsing it?
//!
//! LLE always returns two vectors; on a patch that cannot be flattened (a closed surface, a
//! self-intersecting or strongly curled sheet) they fold the sheet over itself or squash one
//! direction. For each point the local map from its 3-D tangent plane (PCA of the point and
//! its neighbours) to the (u, v) plane is fitted by least squares, J = (Σ d tᵀ)(Σ t tᵀ)⁻¹.
//! * A *flip* is a neighbour pair whose maps have opposite orientation once the two tangent
//!   frames are aligned (sign det Jᵢ · sign det Jⱼ · sign(nᵢ·nⱼ) < 0): the embedding crosses a
//!   fold line between them.
//! * A *collapse* is a point whose J has singular values in a ratio below [`COLLAPSE_RATIO`]:
//!   one surface direction vanishes in (u, v).
//!
//! A valid embedding of an open sheet measures flips ≈ 0 and collapses ≈ 0 (see the tests); the
//! embedding is rejected when more than [`MAX_FLIP_FRACTION`] of neighbour pairs flip or more
//! than [`MAX_COLLAPSE_FRACTION`] of points collapse.

use nalgebra::{Matrix2, Matrix3, SymmetricEigen, Vector2, Vector3};

use crate::error::{Error, Result};

/// Singular-value ratio of the local map below which a point counts as collapsed.
pub const COLLAPSE_RATIO: f64 = 0.02;
/// Largest tolerated fraction of flipped neighbour pairs.
pub const MAX_FLIP_FRACTION: f64 = 0.02;
/// Largest tolerated fraction of collapsed points.
pub const MAX_COLLAPSE_FRACTION: f64 = 0.05;

/// What the fold check measured.
#[derive(Copy, Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct FoldReport {
    /// Fraction of neighbour pairs whose local maps have opposite orientation.
    pub flipped_pairs: f64,
    /// Fraction of points whose local map squashes one direction.
    pub collapsed_points: f64,
}

impl FoldReport {
    /// Whether the embedding is accepted.
    pub fn is_flat(&self) -> bool {
        self.flipped_pairs <= MAX_FLIP_FRACTION && self.collapsed_points <= MAX_COLLAPSE_FRACTION
    }
}

/// Measures flips and collapses of `parameters` as an embedding of `points`.
pub fn fold_report(
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    neighbors: &[Vec<usize>],
) -> FoldReport {
    let n = points.len();
    let mut orientation = vec![0.0f64; n];
    let mut normals = vec![Vector3::zeros(); n];
    let mut collapsed = 0usize;
    for i in 0..n {
        let list = &neighbors[i];
        let origin = Vector3::from(points[i]);
        let mut mean = origin;
        for &j in list {
            mean += Vector3::from(points[j]);
        }
        mean /= (list.len() + 1) as f64;
        let mut cov = Matrix3::zeros();
        for &j in list.iter().chain(std::iter::once(&i)) {
            let d = Vector3::from(points[j]) - mean;
            cov += d * d.transpose();
        }
        let eig = SymmetricEigen::new(cov);
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let e1: Vector3<f64> = eig.eigenvectors.column(order[0]).into();
        let e2: Vector3<f64> = eig.eigenvectors.column(order[1]).into();
        normals[i] = e1.cross(&e2);
        let mut tt = Matrix2::zeros();
        let mut dt = Matrix2::zeros();
        let here = Vector2::from(parameters[i]);
        for &j in list {
            let d3 = Vector3::from(points[j]) - origin;
            let t = Vector2::new(d3.dot(&e1), d3.dot(&e2));
            let d = Vector2::from(parameters[j]) - here;
            tt += t * t.transpose();
            dt += d * t.transpose();
        }
        let Some(inverse) = tt.try_inverse() else {
            collapsed += 1;
            continue;
        };
        let jac = dt * inverse;
        let singular = jac.singular_values();
        let (big, small) = (singular[0].max(singular[1]), singular[0].min(singular[1]));
        if big.is_nan() || big <= 0.0 || small < COLLAPSE_RATIO * big {
            collapsed += 1;
        }
        orientation[i] = jac.determinant().signum();
    }
    let mut pairs = 0usize;
    let mut flipped = 0usize;
    for i in 0..n {
        for &j in &neighbors[i] {
            if j <= i && neighbors[j].contains(&i) {
                continue; // count a mutual pair once
            }
            pairs += 1;
            let aligned = normals[i].dot(&normals[j]).signum();
            if orientation[i] * orientation[j] * aligned < 0.0 {
                flipped += 1;
            }
        }
    }
    FoldReport {
        flipped_pairs: flipped as f64 / pairs.max(1) as f64,
        collapsed_points: collapsed as f64 / n.max(1) as f64,
    }
}

/// [`fold_report`], turned into an error when the embedding folds or collapses.
///
/// # Errors
/// [`Error::InvalidInput`] with the measured fractions.
pub fn check_flat(report: &FoldReport) -> Result<()> {
    if report.is_flat() {
        return Ok(());
    }
    Err(Error::invalid(format!(
        "the embedding cannot flatten this patch: {:.1} % of neighbour pairs fold over and \
         {:.1} % of points collapse (limits {:.0} % and {:.0} %); split the points into patches \
         that open out to a plane",
        100.0 * report.flipped_pairs,
        100.0 * report.collapsed_points,
        100.0 * MAX_FLIP_FRACTION,
        100.0 * MAX_COLLAPSE_FRACTION
    )))
}

//! Reconstruction weights and the embedding matrix (§4.1 step 2, §4.3 Eq. 6).
//!
//! For point i with neighbours N(i), the weights minimize |Dᵢ − Σⱼ Wᵢⱼ Dⱼ|² subject to
//! Σⱼ Wᵢⱼ = 1 (Eq. 1). With Zⱼ = Dⱼ − Dᵢ and the local Gram matrix C = ZZᵀ the solution is
//! w = C⁻¹1 / 1ᵀC⁻¹1. With more than three neighbours in 3-D, C has rank ≤ 3, so it is
//! regularized as C + δ·tr(C)·I with δ = [`super::LleOptions::regularization`] (10⁻³ by
//! default, Roweis & Saul's choice), which picks the minimum-norm weights among the
//! near-optimal ones.
//!
//! M = (I − W)ᵀ(I − W) is assembled row by row of A = I − W: each row aᵢ (1 at i, −wᵢⱼ at
//! its neighbours) adds the outer product aᵢaᵢᵀ, so M holds at most n·(k + 1)² triplets and is
//! never dense.

use nalgebra::{DMatrix, DVector};

use super::sparse::SymmetricMatrix;
use crate::error::{Error, Result};

/// Weights Wᵢⱼ for each point's neighbours (same order as `neighbors[i]`), each row summing
/// to one.
///
/// # Errors
/// [`Error::InvalidInput`] when a point has no neighbours or its neighbours all coincide with
/// it.
pub fn reconstruction_weights(
    points: &[[f64; 3]],
    neighbors: &[Vec<usize>],
    regularization: f64,
) -> Result<Vec<Vec<f64>>> {
    let mut all = Vec::with_capacity(points.len());
    for (i, list) in neighbors.iter().enumerate() {
        let m = list.len();
        if m == 0 {
            return Err(Error::invalid(format!("point {i} has no neighbours")));
        }
        let z: Vec<[f64; 3]> = list
            .iter()
            .map(|&j| std::array::from_fn(|a| points[j][a] - points[i][a]))
            .collect();
        let mut c = DMatrix::<f64>::from_fn(m, m, |r, s| {
            z[r][0] * z[s][0] + z[r][1] * z[s][1] + z[r][2] * z[s][2]
        });
        let trace = c.trace();
        if !(trace > 0.0 && trace.is_finite()) {
            return Err(Error::invalid(format!(
                "the neighbours of point {i} coincide with it"
            )));
        }
        for r in 0..m {
            c[(r, r)] += regularization * trace;
        }
        let w = match c.cholesky() {
            Some(ch) => ch.solve(&DVector::from_element(m, 1.0)),
            None => {
                return Err(Error::invalid(format!(
                    "the local Gram matrix of point {i} is singular"
                )));
            }
        };
        let sum = w.sum();
        if !(sum.abs() > 1e-300 && sum.is_finite()) {
            return Err(Error::invalid(format!(
                "the reconstruction weights of point {i} do not normalize"
            )));
        }
        all.push(w.iter().map(|v| v / sum).collect());
    }
    Ok(all)
}

/// M = (I − W)ᵀ(I − W) for the sparse W given by `neighbors` and `weights`.
pub fn embedding_matrix(neighbors: &[Vec<usize>], weights: &[Vec<f64>]) -> SymmetricMatrix {
    let n = neighbors.len();
    let mut m = SymmetricMatrix::new(n);
    let mut row: Vec<(usize, f64)> = Vec::new();
    for (i, (list, w)) in neighbors.iter().zip(weights).enumerate() {
        row.clear();
        row.push((i, 1.0));
        row.extend(list.iter().zip(w).map(|(&j, &wj)| (j, -wj)));
        for &(p, ap) in &row {
            for &(q, aq) in &row {
                m.add(p, q, ap * aq);
            }
        }
    }
    m
}

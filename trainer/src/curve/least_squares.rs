//! Linear least squares over control points, shared by the curve and surface fits.
//!
//! Each control point is an affine function of the unknowns (free control points): usually
//! one unknown, a constant for a pinned end, or 2·P₁ − P₂ for a phantom. Rows (a data point
//! or a smoothing term) are accumulated into dense normal equations (AᵀA + λ·DᵀD) x = Aᵀb
//! and solved by Cholesky. With F unknowns: O(rows · 16) to accumulate, F³/3 to factor.

use nalgebra::DMatrix;

/// A control point as `constant + Σ coefficient · unknown`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Affine {
    pub terms: Vec<(usize, f64)>,
    pub constant: [f64; 3],
}

impl Affine {
    /// Just unknown `f`.
    pub(crate) fn unknown(f: usize) -> Self {
        Affine {
            terms: vec![(f, 1.0)],
            constant: [0.0; 3],
        }
    }

    /// A fixed point.
    pub(crate) fn fixed(p: [f64; 3]) -> Self {
        Affine {
            terms: Vec::new(),
            constant: p,
        }
    }

    /// `a·self + b·other`.
    pub(crate) fn combine(&self, a: f64, other: &Affine, b: f64) -> Affine {
        let mut terms: Vec<(usize, f64)> = self.terms.iter().map(|&(f, c)| (f, a * c)).collect();
        terms.extend(other.terms.iter().map(|&(f, c)| (f, b * c)));
        Affine {
            terms,
            constant: [0, 1, 2].map(|k| a * self.constant[k] + b * other.constant[k]),
        }
    }

    /// The point for given unknowns.
    pub(crate) fn evaluate(&self, unknowns: &[[f64; 3]]) -> [f64; 3] {
        let mut p = self.constant;
        for &(f, c) in &self.terms {
            for k in 0..3 {
                p[k] += c * unknowns[f][k];
            }
        }
        p
    }
}

/// Dense normal equations for `unknowns` unknown points.
#[derive(Clone, Debug)]
pub(crate) struct NormalEquations {
    matrix: DMatrix<f64>,
    rhs: DMatrix<f64>,
    row_terms: Vec<(usize, f64)>,
}

impl NormalEquations {
    pub(crate) fn new(unknowns: usize) -> Self {
        NormalEquations {
            matrix: DMatrix::zeros(unknowns, unknowns),
            rhs: DMatrix::zeros(unknowns, 3),
            row_terms: Vec::new(),
        }
    }

    /// Adds the row `weight · (Σ cᵢ · controlᵢ − target)²`.
    pub(crate) fn add_row(&mut self, controls: &[(f64, &Affine)], target: [f64; 3], weight: f64) {
        let mut target = target;
        self.row_terms.clear();
        for &(c, affine) in controls {
            for k in 0..3 {
                target[k] -= c * affine.constant[k];
            }
            self.row_terms
                .extend(affine.terms.iter().map(|&(f, a)| (f, c * a)));
        }
        for &(f, a) in &self.row_terms {
            for &(g, b) in &self.row_terms {
                self.matrix[(f, g)] += weight * a * b;
            }
            for k in 0..3 {
                self.rhs[(f, k)] += weight * a * target[k];
            }
        }
    }

    /// Mean of the diagonal (the scale smoothing weights are relative to), 1 if empty.
    pub(crate) fn mean_diagonal(&self) -> f64 {
        let n = self.matrix.nrows();
        if n == 0 {
            return 1.0;
        }
        self.matrix.diagonal().sum() / n as f64
    }

    /// The unknowns, or `None` when the system is singular (not positive definite).
    pub(crate) fn solve(self) -> Option<Vec<[f64; 3]>> {
        if self.matrix.nrows() == 0 {
            return Some(Vec::new());
        }
        let solution = self.matrix.cholesky()?.solve(&self.rhs);
        let unknowns: Vec<[f64; 3]> = (0..solution.nrows())
            .map(|i| [solution[(i, 0)], solution[(i, 1)], solution[(i, 2)]])
            .collect();
        unknowns
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()))
            .then_some(unknowns)
    }
}

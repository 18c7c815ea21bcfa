//! Sparse symmetric positive-definite systems through `faer`: assembly from triplets (duplicates
//! summed), a supernodal Cholesky LLᵀ with faer's AMD fill-reducing ordering, and solves for
//! several right-hand sides at once. The LLE eigen solver and the stitching least squares
//! both go through here, so there is one seam to the sparse crate.

use faer::Mat;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet, linalg::solvers::Llt};

use crate::error::{Error, Result};

/// A symmetric n × n matrix assembled from (row, column, value) entries; repeated entries add.
#[derive(Clone, Debug)]
pub struct SymmetricMatrix {
    n: usize,
    entries: Vec<Triplet<usize, usize, f64>>,
}

impl SymmetricMatrix {
    /// An empty n × n matrix.
    pub fn new(n: usize) -> Self {
        SymmetricMatrix {
            n,
            entries: Vec::new(),
        }
    }

    /// Order n.
    pub fn order(&self) -> usize {
        self.n
    }

    /// Adds `value` at (i, j) only (the caller adds (j, i) too for an off-diagonal entry).
    pub fn add(&mut self, i: usize, j: usize, value: f64) {
        debug_assert!(i < self.n && j < self.n);
        self.entries.push(Triplet::new(i, j, value));
    }

    /// Sum of the diagonal entries.
    pub fn trace(&self) -> f64 {
        self.entries
            .iter()
            .filter(|t| t.row == t.col)
            .map(|t| t.val)
            .sum()
    }

    /// The compressed matrix.
    pub fn compress(&self) -> Result<CompressedMatrix> {
        let matrix =
            SparseColMat::<usize, f64>::try_new_from_triplets(self.n, self.n, &self.entries)
                .map_err(|e| Error::invalid(format!("sparse matrix assembly failed: {e:?}")))?;
        Ok(CompressedMatrix { matrix })
    }
}

/// A symmetric matrix in compressed-column form.
#[derive(Clone, Debug)]
pub struct CompressedMatrix {
    matrix: SparseColMat<usize, f64>,
}

impl CompressedMatrix {
    /// y = A·x (x, y of length n).
    pub fn multiply(&self, x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        let m = self.matrix.as_ref();
        let col_ptr = m.col_ptr();
        let rows = m.row_idx();
        let values = m.val();
        for (j, &xj) in x.iter().enumerate() {
            for p in col_ptr[j]..col_ptr[j + 1] {
                y[rows[p]] += values[p] * xj;
            }
        }
    }

    /// Stored entries.
    pub fn nonzeros(&self) -> usize {
        self.matrix.as_ref().val().len()
    }

    /// Factors A = LLᵀ (AMD ordering, supernodal).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when A is not numerically positive definite.
    pub fn cholesky(&self) -> Result<Cholesky> {
        let llt = self
            .matrix
            .sp_cholesky(faer::Side::Lower)
            .map_err(|e| Error::invalid(format!("sparse Cholesky failed: {e:?}")))?;
        Ok(Cholesky {
            llt,
            n: self.matrix.nrows(),
        })
    }
}

/// A factored sparse SPD matrix.
#[derive(Debug)]
pub struct Cholesky {
    llt: Llt<usize, f64>,
    n: usize,
}

impl Cholesky {
    /// Solves A·X = B in place for the columns of `columns` (each of length n).
    pub fn solve(&self, columns: &mut [Vec<f64>]) {
        if columns.is_empty() {
            return;
        }
        let mut rhs = Mat::<f64>::zeros(self.n, columns.len());
        for (j, c) in columns.iter().enumerate() {
            for (i, &v) in c.iter().enumerate() {
                rhs[(i, j)] = v;
            }
        }
        self.llt.solve_in_place(rhs.as_mut());
        for (j, c) in columns.iter_mut().enumerate() {
            for (i, v) in c.iter_mut().enumerate() {
                *v = rhs[(i, j)];
            }
        }
    }
}

//! Sparse symmetric positive-definite systems through `faer`: assembly from triplets (duplicates
//! summed), a supernodal Cholesky LLᵀ with faer's AMD fill-reducing ordering, and solves for
//! several right-hand sides at once. The LLE eigen solver and the stitching least squares
//! both go through here, so there is one seam to the sparse crate.

use faer::Mat;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, SymbolicSparseColMat, Triplet, linalg::solvers::Llt};

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
    ///
    /// The entries are bucketed by column (a counting sort); in each column repeated rows are
    /// summed in a dense accumulator, in the order the entries were given, and only the
    /// distinct rows are sorted: linear in the entries plus a small sort per column. faer's
    /// general triplet assembly sorted all entries at once (a third of the embedding's time at
    /// 36 000 points); sorting each column's entries before merging them took 40–54 ms on the
    /// 10 000-point matrix of `lle_matrix_timing`, this 29–30 ms (the same sums bit for bit).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an entry outside the n × n matrix.
    pub fn compress(&self) -> Result<CompressedMatrix> {
        let n = self.n;
        if let Some(t) = self.entries.iter().find(|t| t.row >= n || t.col >= n) {
            return Err(Error::invalid(format!(
                "sparse entry ({}, {}) lies outside the {n} × {n} matrix",
                t.row, t.col
            )));
        }
        let mut start = vec![0usize; n + 1];
        for t in &self.entries {
            start[t.col + 1] += 1;
        }
        for j in 0..n {
            start[j + 1] += start[j];
        }
        let mut next = start.clone();
        let mut bucket = vec![(0usize, 0.0f64); self.entries.len()];
        for t in &self.entries {
            bucket[next[t.col]] = (t.row, t.val);
            next[t.col] += 1;
        }
        let mut col_ptr = Vec::with_capacity(n + 1);
        col_ptr.push(0usize);
        let mut row_idx = Vec::with_capacity(self.entries.len());
        let mut values: Vec<f64> = Vec::with_capacity(self.entries.len());
        // One column at a time: repeated rows are summed in a dense accumulator in the order
        // they were given, then the distinct rows are sorted.
        let mut sums = vec![0.0f64; n];
        let mut seen_in = vec![usize::MAX; n];
        let mut rows: Vec<usize> = Vec::new();
        for j in 0..n {
            rows.clear();
            for &(row, value) in &bucket[start[j]..start[j + 1]] {
                if seen_in[row] == j {
                    sums[row] += value;
                } else {
                    seen_in[row] = j;
                    sums[row] = value;
                    rows.push(row);
                }
            }
            rows.sort_unstable();
            row_idx.extend_from_slice(&rows);
            values.extend(rows.iter().map(|&row| sums[row]));
            col_ptr.push(row_idx.len());
        }
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Ok(CompressedMatrix {
            matrix: SparseColMat::new(symbolic, values),
        })
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

    /// A + σI, when every diagonal entry is stored (`None` otherwise).
    pub fn with_diagonal_added(&self, sigma: f64) -> Option<CompressedMatrix> {
        let mut shifted = self.matrix.clone();
        let (symbolic, values) = shifted.parts_mut();
        let (col_ptr, rows) = (symbolic.col_ptr(), symbolic.row_idx());
        for j in 0..symbolic.ncols() {
            let column = &rows[col_ptr[j]..col_ptr[j + 1]];
            let at = column.binary_search(&j).ok()?;
            values[col_ptr[j] + at] += sigma;
        }
        Some(CompressedMatrix { matrix: shifted })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compression_adds_repeated_entries_and_shifts_the_diagonal() {
        let mut m = SymmetricMatrix::new(3);
        for (i, j, v) in [
            (2, 2, 1.0),
            (0, 0, 2.0),
            (1, 0, -1.0),
            (0, 1, -1.0),
            (0, 0, 3.0),
        ] {
            m.add(i, j, v);
        }
        m.add(1, 1, 4.0);
        m.add(2, 1, 0.5);
        m.add(1, 2, 0.5);
        let c = m.compress().unwrap();
        assert_eq!(c.nonzeros(), 7);
        let mut y = [0.0; 3];
        c.multiply(&[1.0, 10.0, 100.0], &mut y);
        assert_eq!(y, [5.0 - 10.0, -1.0 + 40.0 + 50.0, 5.0 + 100.0]);
        let shifted = c.with_diagonal_added(0.25).unwrap();
        shifted.multiply(&[1.0, 0.0, 0.0], &mut y);
        assert_eq!(y, [5.25, -1.0, 0.0]);
        let mut no_diagonal = SymmetricMatrix::new(2);
        no_diagonal.add(0, 1, 1.0);
        no_diagonal.add(1, 0, 1.0);
        assert!(
            no_diagonal
                .compress()
                .unwrap()
                .with_diagonal_added(1.0)
                .is_none()
        );
    }
}

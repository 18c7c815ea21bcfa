//! The RBF's symmetric saddle-point system, solved by the null-space method.
//!
//! With m centres, kernel matrix A (m×m, Aᵢⱼ = φ(|cᵢ − cⱼ|)) and polynomial matrix P (m×4,
//! rows [cᵢ − c̄, 1] in centroid-relative coordinates) the system is
//!
//! ```text
//! M [w; p] = [A P; Pᵀ 0] [w; p] = [d; e]
//! ```
//!
//! M is symmetric indefinite. Instead of LU with partial pivoting on M (2m³/3 flops, no use
//! of the structure) this factors P = Q [R; 0] with four Householder reflectors and writes
//! w = Q u. The trailing block B₂₂ of B = QᵀAQ is Q₂ᵀAQ₂, A restricted to the null space of
//! Pᵀ, where the multiquadric (and its c = 0 limit, the biharmonic r) is *conditionally
//! negative definite* (Micchelli 1986): for distinct centres −B₂₂ is symmetric positive
//! definite. So one Cholesky factorization of −B₂₂ (m³/3 flops, half the LU's, backward
//! stable without pivoting) solves M, and its failure is a reliable "numerically singular"
//! signal (coincident centres).
//!
//! Everything happens in one m×m column-major buffer: the kernel matrix is assembled into it,
//! the reflectors are applied to it in place (O(m²) each, columns in parallel), and faer's
//! blocked Cholesky factors its trailing block in place on every core of the current rayon
//! pool. Peak memory is 8m² bytes.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{MatMut, MatRef, Par};
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Below this |Rₖₖ| relative to the norm of P's column k, the centres are taken as coplanar
/// (or collinear): the linear term is then not determined.
const RANK_TOLERANCE: f64 = 1e-9;

/// A factored saddle-point matrix M; applies M⁻¹ to any right-hand side in O(m²).
#[derive(Debug)]
pub(super) struct SaddleSolver {
    m: usize,
    /// H₁ … H₄, with Q = H₁H₂H₃H₄.
    reflectors: Vec<Reflector>,
    /// The 4×4 upper triangle R of P = Q [R; 0]; `r[i][j]`, j ≥ i.
    r: [[f64; 4]; 4],
    /// The first four rows of B = QᵀAQ, row-major (4 × m).
    top: Vec<f64>,
    /// The m×m buffer, column-major; the lower triangle of its trailing (m − 4)² block is
    /// the Cholesky factor L of −B₂₂.
    data: Vec<f64>,
    /// ‖M‖₁ (maximum absolute column sum), as assembled.
    norm1: f64,
    par: Par,
}

/// faer's parallelism for the current rayon pool (sequential in a one-thread pool).
fn parallelism() -> Par {
    match rayon::current_num_threads() {
        0 | 1 => Par::Seq,
        n => Par::rayon(n),
    }
}

impl SaddleSolver {
    /// Factors M from the kernel matrix `a` (m×m column-major, symmetric, consumed) and the
    /// polynomial rows `p` (one `[x, y, z, 1]` per centre).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the centres are coplanar (P rank-deficient) or −B₂₂ is
    /// not numerically positive definite (coincident or nearly coincident centres).
    pub(super) fn new(mut data: Vec<f64>, p: &[[f64; 4]]) -> Result<Self> {
        let m = p.len();
        assert!(m > 4 && data.len() == m * m, "an m×m kernel matrix, m > 4");
        let norm1 = saddle_norm1(&data, p);
        let (reflectors, r) = householder_qr(p)?;
        for reflector in &reflectors {
            reflect_both_sides(&mut data, reflector);
        }
        let mut top = vec![0.0; 4 * m];
        for j in 0..m {
            for k in 0..4 {
                top[k * m + j] = data[j * m + k];
            }
        }
        // −B₂₂, lower triangle only (all the factorization reads).
        data.par_chunks_mut(m)
            .enumerate()
            .skip(4)
            .for_each(|(j, column)| {
                for v in &mut column[j..] {
                    *v = -*v;
                }
            });
        let par = parallelism();
        let n = m - 4;
        let mut memory =
            MemBuffer::new(cholesky_in_place_scratch::<f64>(n, par, Default::default()));
        cholesky_in_place(
            MatMut::from_column_major_slice_with_stride_mut(&mut data[4 * m + 4..], n, n, m),
            Default::default(),
            par,
            MemStack::new(&mut memory),
            Default::default(),
        )
        .map_err(|_| {
            Error::invalid(
                "the RBF system is numerically singular (its reduced kernel matrix is not \
                 definite): some control points or off-surface points nearly coincide",
            )
        })?;
        Ok(SaddleSolver {
            m,
            reflectors,
            r,
            top,
            data,
            norm1,
            par,
        })
    }

    /// ‖M‖₁ of the assembled matrix.
    pub(super) fn norm1(&self) -> f64 {
        self.norm1
    }

    /// The Cholesky factor L of −B₂₂ (lower triangle; the strict upper one is not L's).
    fn factor(&self) -> MatRef<'_, f64> {
        let (m, n) = (self.m, self.m - 4);
        MatRef::from_column_major_slice_with_stride(&self.data[4 * m + 4..], n, n, m)
    }

    /// Solves M [w; p] = [d; e]: returns w (length m) and p.
    pub(super) fn solve(&self, d: &[f64], e: [f64; 4]) -> (Vec<f64>, [f64; 4]) {
        let m = self.m;
        debug_assert_eq!(d.len(), m);
        let mut g = d.to_vec();
        for reflector in &self.reflectors {
            reflector.apply(&mut g);
        }
        // Rᵀ u₁ = e (forward substitution).
        let r = &self.r;
        let mut u1 = [0.0; 4];
        for k in 0..4 {
            let mut s = e[k];
            for j in 0..k {
                s -= r[j][k] * u1[j];
            }
            u1[k] = s / r[k][k];
        }
        // −B₂₂ u₂ = −(g₂ − B₂₁ u₁), with −B₂₂ = L Lᵀ.
        let mut u: Vec<f64> = u1.to_vec();
        u.extend((0..m - 4).map(|i| {
            let mut s = -g[4 + i];
            for k in 0..4 {
                s += self.top[k * m + 4 + i] * u1[k];
            }
            s
        }));
        {
            let mut rhs = MatMut::from_column_major_slice_mut(&mut u[4..], m - 4, 1);
            let factor = self.factor();
            solve_lower_triangular_in_place(factor, rhs.as_mut(), self.par);
            solve_upper_triangular_in_place(factor.transpose(), rhs, self.par);
        }
        // R p = g₁ − B₁₁ u₁ − B₁₂ u₂ (back substitution).
        let mut t = [0.0; 4];
        for k in 0..4 {
            let row = &self.top[k * m..(k + 1) * m];
            t[k] = g[k] - row.iter().zip(&u).map(|(b, x)| b * x).sum::<f64>();
        }
        let mut poly = [0.0; 4];
        for k in (0..4).rev() {
            let mut s = t[k];
            for j in k + 1..4 {
                s -= r[k][j] * poly[j];
            }
            poly[k] = s / r[k][k];
        }
        for reflector in self.reflectors.iter().rev() {
            reflector.apply(&mut u);
        }
        (u, poly)
    }

    /// Applies M⁻¹ to a stacked vector [d; e] of length m + 4.
    pub(super) fn solve_stacked(&self, rhs: &[f64]) -> Vec<f64> {
        let m = self.m;
        let e = [rhs[m], rhs[m + 1], rhs[m + 2], rhs[m + 3]];
        let (mut w, p) = self.solve(&rhs[..m], e);
        w.extend_from_slice(&p);
        w
    }
}

/// A Householder reflector H = I − τvvᵀ.
#[derive(Debug)]
struct Reflector {
    /// v, length m, zero above its column index.
    v: Vec<f64>,
    /// τ = 2/(vᵀv).
    tau: f64,
}

impl Reflector {
    /// x ← H x.
    fn apply(&self, x: &mut [f64]) {
        let s = self.tau * x.iter().zip(&self.v).map(|(a, b)| a * b).sum::<f64>();
        for (xi, vi) in x.iter_mut().zip(&self.v) {
            *xi -= s * vi;
        }
    }
}

/// ‖M‖₁ for M = [A P; Pᵀ 0] (A symmetric, so column sums are row sums), columns in parallel.
fn saddle_norm1(a: &[f64], p: &[[f64; 4]]) -> f64 {
    let m = p.len();
    let kernel = a
        .par_chunks(m)
        .zip(p.par_iter())
        .map(|(column, row)| {
            column.iter().map(|v| v.abs()).sum::<f64>() + row.iter().map(|v| v.abs()).sum::<f64>()
        })
        .reduce(|| 0.0, f64::max);
    (0..4)
        .map(|k| p.iter().map(|row| row[k].abs()).sum::<f64>())
        .fold(kernel, f64::max)
}

/// Householder QR of the m×4 matrix with rows `p`: the reflectors and R.
fn householder_qr(p: &[[f64; 4]]) -> Result<(Vec<Reflector>, [[f64; 4]; 4])> {
    let m = p.len();
    let mut columns: Vec<Vec<f64>> = (0..4)
        .map(|k| p.iter().map(|row| row[k]).collect())
        .collect();
    let original: Vec<f64> = columns.iter().map(|c| norm2(c)).collect();
    let mut reflectors = Vec::with_capacity(4);
    let mut r = [[0.0; 4]; 4];
    for k in 0..4 {
        let norm = norm2(&columns[k][k..]);
        if norm.is_nan() || norm <= RANK_TOLERANCE * original[k] {
            return Err(Error::invalid(
                "all RBF centres (control points and their off-surface points) are coplanar \
                 or collinear, so the linear term a·x + b is not determined",
            ));
        }
        let x0 = columns[k][k];
        let alpha = if x0 >= 0.0 { -norm } else { norm };
        let mut v = vec![0.0; m];
        v[k..].copy_from_slice(&columns[k][k..]);
        v[k] -= alpha;
        let tau = 2.0 / v[k..].iter().map(|x| x * x).sum::<f64>();
        let reflector = Reflector { v, tau };
        for column in columns.iter_mut().skip(k) {
            reflector.apply(column);
        }
        for j in k..4 {
            r[k][j] = columns[j][k];
        }
        reflectors.push(reflector);
    }
    Ok((reflectors, r))
}

/// A ← H A H for symmetric A (m×m, column-major) and H = I − τvvᵀ, as the symmetric rank-2
/// update A − v qᵀ − q vᵀ with q = τAv − (τ²/2)(vᵀAv) v; columns in parallel.
fn reflect_both_sides(a: &mut [f64], reflector: &Reflector) {
    let (v, tau) = (reflector.v.as_slice(), reflector.tau);
    let m = v.len();
    // (Av)ᵢ = Σⱼ Aᵢⱼvⱼ = (column i)·v, A being symmetric.
    let mut q: Vec<f64> = a
        .par_chunks(m)
        .map(|column| tau * column.iter().zip(v).map(|(x, y)| x * y).sum::<f64>())
        .collect();
    let half = 0.5 * tau * v.iter().zip(&q).map(|(x, y)| x * y).sum::<f64>();
    for (qi, vi) in q.iter_mut().zip(v) {
        *qi -= half * vi;
    }
    a.par_chunks_mut(m).enumerate().for_each(|(j, column)| {
        let (vj, qj) = (v[j], q[j]);
        for ((x, vi), qi) in column.iter_mut().zip(v).zip(&q) {
            *x -= vi * qj + qi * vj;
        }
    });
}

fn norm2(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

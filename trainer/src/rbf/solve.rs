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
//! Pᵀ, where the multiquadric is *conditionally negative definite* (Micchelli 1986): for
//! distinct centres −B₂₂ is symmetric positive definite. So one Cholesky factorization of
//! −B₂₂ (m³/3 flops, half the LU's, backward stable without pivoting) solves M, and its
//! failure is a reliable "numerically singular" signal (coincident centres). The reflectors
//! cost O(m²).

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

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
    /// Cholesky factor of −B₂₂.
    cholesky: Cholesky<f64, Dyn>,
    /// ‖M‖₁ (maximum absolute column sum), as assembled.
    norm1: f64,
}

impl SaddleSolver {
    /// Factors M from the kernel matrix `a` (symmetric, consumed) and the polynomial rows
    /// `p` (one `[x, y, z, 1]` per centre).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the centres are coplanar (P rank-deficient) or −B₂₂ is
    /// not numerically positive definite (coincident or nearly coincident centres).
    pub(super) fn new(mut a: DMatrix<f64>, p: &[[f64; 4]]) -> Result<Self> {
        let m = p.len();
        debug_assert!(a.nrows() == m && a.ncols() == m && m > 4);
        let norm1 = saddle_norm1(&a, p);
        let (reflectors, r) = householder_qr(p)?;
        for reflector in &reflectors {
            reflect_both_sides(&mut a, reflector);
        }
        let mut top = vec![0.0; 4 * m];
        for k in 0..4 {
            for j in 0..m {
                top[k * m + j] = a[(k, j)];
            }
        }
        let mut reduced = a.remove_rows(0, 4).remove_columns(0, 4);
        reduced.neg_mut();
        let cholesky = Cholesky::new(reduced).ok_or_else(|| {
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
            cholesky,
            norm1,
        })
    }

    /// ‖M‖₁ of the assembled matrix.
    pub(super) fn norm1(&self) -> f64 {
        self.norm1
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
        // −B₂₂ u₂ = −(g₂ − B₂₁ u₁).
        let mut rhs = DVector::from_fn(m - 4, |i, _| {
            let mut s = -g[4 + i];
            for k in 0..4 {
                s += self.top[k * m + 4 + i] * u1[k];
            }
            s
        });
        self.cholesky.solve_mut(&mut rhs);
        let mut u = Vec::with_capacity(m);
        u.extend_from_slice(&u1);
        u.extend(rhs.iter());
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

/// ‖M‖₁ for M = [A P; Pᵀ 0] (A symmetric, so column sums are row sums).
fn saddle_norm1(a: &DMatrix<f64>, p: &[[f64; 4]]) -> f64 {
    let mut norm: f64 = 0.0;
    for (j, row) in p.iter().enumerate() {
        let column: f64 = a.column(j).iter().map(|v| v.abs()).sum::<f64>()
            + row.iter().map(|v| v.abs()).sum::<f64>();
        norm = norm.max(column);
    }
    for k in 0..4 {
        norm = norm.max(p.iter().map(|row| row[k].abs()).sum());
    }
    norm
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

/// A ← H A H for symmetric A and H = I − τvvᵀ, as the symmetric rank-2 update
/// A − v qᵀ − q vᵀ with q = τAv − (τ²/2)(vᵀAv) v.
fn reflect_both_sides(a: &mut DMatrix<f64>, reflector: &Reflector) {
    let (v, tau) = (reflector.v.as_slice(), reflector.tau);
    let m = v.len();
    let mut q = vec![0.0; m];
    for (j, &vj) in v.iter().enumerate() {
        if vj != 0.0 {
            for (qi, aij) in q.iter_mut().zip(a.column(j).iter()) {
                *qi += tau * vj * aij;
            }
        }
    }
    let half = 0.5 * tau * v.iter().zip(&q).map(|(x, y)| x * y).sum::<f64>();
    for (qi, vi) in q.iter_mut().zip(v) {
        *qi -= half * vi;
    }
    let data = a.as_mut_slice();
    for j in 0..m {
        let (vj, qj) = (v[j], q[j]);
        let column = &mut data[j * m..(j + 1) * m];
        for i in 0..m {
            column[i] -= v[i] * qj + q[i] * vj;
        }
    }
}

fn norm2(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

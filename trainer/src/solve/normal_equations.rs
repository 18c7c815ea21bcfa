//! The normal equations of a least-squares step: JᵀJ and Jᵀe accumulated a block of rows at a
//! time (SYRK tiles, in f64 or f32, AVX2 + FMA when the CPU has them), and the damped system
//! (A + μI)Δ = b solved by a blocked Cholesky factorization.
//!
//! This file is long (about 730 lines, 300 of them tests) because each kernel has a portable
//! and an AVX2 + FMA build that must agree, and the tests that check they do sit beside them.

#[cfg(test)]
use nalgebra::{DMatrix, DVector};

use super::kept_rows::KeptRows;
use super::lanes::{cpu_has_fma, madd};

/// The LM system (A + μI)Δ = b for one A and b and a sequence of μ.
///
/// A's upper triangle is kept row-major n × n, padded from p to a multiple of 4 with an
/// identity block (which leaves the step unchanged); each [`Self::solve`] copies it, adds μ and
/// factors the copy with the blocked Cholesky below (AVX2/FMA when the CPU has them).
#[derive(Clone, Debug)]
pub struct DampedSystem {
    p: usize,
    n: usize,
    lhs: Vec<f64>,
    system: Vec<f64>,
    rhs: Vec<f64>,
    step: Vec<f64>,
    /// Right-hand side of [`Self::solve_again`] (padded to `n`).
    second_rhs: Vec<f64>,
    /// Whether `system` holds the factor of the last solve.
    factored: bool,
    fma: bool,
}

impl DampedSystem {
    /// A zero system of `p` unknowns.
    pub fn new(p: usize) -> Self {
        let n = p.div_ceil(4) * 4;
        let mut lhs = vec![0.0; n * n];
        for i in p..n {
            lhs[i * n + i] = 1.0;
        }
        DampedSystem {
            p,
            n,
            lhs,
            system: vec![0.0; n * n],
            rhs: vec![0.0; n],
            step: vec![0.0; n],
            second_rhs: vec![0.0; n],
            factored: false,
            fma: cpu_has_fma(),
        }
    }

    /// Row `i` of A from the diagonal on: entry k is A[i][i + k] (`p − i` entries).
    pub fn lhs_row_mut(&mut self, i: usize) -> &mut [f64] {
        let n = self.n;
        &mut self.lhs[i * n + i..i * n + self.p]
    }

    /// b (`p` entries).
    pub fn rhs_mut(&mut self) -> &mut [f64] {
        &mut self.rhs[..self.p]
    }

    /// Δ for damping `mu`, or `None` when A + μI is not positive definite.
    pub fn solve(&mut self, mu: f64) -> Option<&[f64]> {
        let (p, n) = (self.p, self.n);
        for i in 0..n {
            let row = i * n + i..(i + 1) * n;
            self.system[row.clone()].copy_from_slice(&self.lhs[row]);
            if i < p {
                self.system[i * n + i] += mu;
            }
        }
        self.factored = false;
        if !cholesky(&mut self.system, n, self.fma) {
            return None;
        }
        cholesky_solve(&self.system, n, &self.rhs, &mut self.step);
        self.factored = true;
        Some(&self.step[..p])
    }

    /// (A + μI)⁻¹·`rhs` (`p` entries) with the factor of the last successful [`Self::solve`]
    /// (whose step it overwrites); `None` before any.
    pub fn solve_again(&mut self, rhs: &[f64]) -> Option<&[f64]> {
        if !self.factored {
            return None;
        }
        let (p, n) = (self.p, self.n);
        self.second_rhs[..p].copy_from_slice(&rhs[..p]);
        cholesky_solve(&self.system, n, &self.second_rhs, &mut self.step);
        Some(&self.step[..p])
    }
}

/// Rows of J multiplied at once (32 rows × 136 parameters: about a 32 KiB L1 cache; 16 and 64
/// measured slower or no faster).
const BLOCK_ROWS: usize = 32;

/// Rows multiplied at once by [`NormalEquations::single_precision`]: the SYRK reads 64 rows
/// of f32 from the room 32 rows of f64 take, and each tile's f32 sums are widened and added to
/// the f64 sums once per block.
const SINGLE_BLOCK_ROWS: usize = 64;

/// Accumulates JᵀJ and Jᵀe from J's rows, a block at a time (a SYRK on the upper triangle).
///
/// Rows are stored with a stride rounded up to a multiple of 4 and zero padding, so the product
/// runs in register tiles of two AVX2 registers' width: 4 × 8 in f64, 4 × 16 for
/// [`Self::single_precision`]. With AVX2 and FMA (detected at run time) a tile is eight fused
/// multiply–adds per row (measured at about 60 % of the core's peak in f64).
#[derive(Clone, Debug)]
pub struct NormalEquations {
    p: usize,
    stride: usize,
    /// Σ JᵀJ, row-major with `stride`; upper triangle (diagonal tiles spill a little below it).
    gram: Vec<f64>,
    /// Σ Jᵀe.
    gradient: Vec<f64>,
    /// Pending rows (`block_rows` × `stride`), their residuals and the residuals' indices.
    block: Vec<f64>,
    block_residuals: Vec<f64>,
    block_index: Vec<u32>,
    /// Index of the next row's residual ([`Self::set_cursor`]).
    cursor: usize,
    /// Every row in f32, when asked for ([`Self::keeping_rows`]).
    kept: Option<KeptRows>,
    block_rows: usize,
    /// The pending rows rounded to f32, for [`Self::single_precision`] sums.
    single: Option<Vec<f32>>,
    pending: usize,
    fma: bool,
}

impl NormalEquations {
    /// Empty sums for `p` parameters.
    pub fn new(p: usize) -> Self {
        Self::with_block(p, BLOCK_ROWS, None)
    }

    /// Empty sums for `p` parameters whose JᵀJ is multiplied in f32: each block of 64 rows is
    /// rounded to f32, its tile products summed in f32 (eight lanes per AVX2 register instead
    /// of four, so about twice as fast) and added to the f64 sums. Jᵀe stays in f64 from the
    /// f64 rows. Each entry of JᵀJ then carries an error of at most about (64 + 2) · 2⁻²⁴ ≈
    /// 4·10⁻⁶ of Σ|Jᵢ||Jⱼ| (the rounding of both factors and of 64 sums per block): enough for
    /// the search direction of an LM step, whose acceptance is still decided by the f64 error.
    /// A block with an entry beyond 10¹⁸, whose f32 products could overflow, is multiplied in
    /// f64.
    pub fn single_precision(p: usize) -> Self {
        let stride = p.div_ceil(4) * 4;
        Self::with_block(
            p,
            SINGLE_BLOCK_ROWS,
            Some(vec![0.0; SINGLE_BLOCK_ROWS * stride]),
        )
    }

    fn with_block(p: usize, block_rows: usize, single: Option<Vec<f32>>) -> Self {
        let stride = p.div_ceil(4) * 4;
        NormalEquations {
            p,
            stride,
            gram: vec![0.0; stride * stride],
            gradient: vec![0.0; stride],
            block: vec![0.0; block_rows * stride],
            block_residuals: vec![0.0; block_rows],
            block_index: vec![0; block_rows],
            cursor: 0,
            kept: None,
            block_rows,
            single,
            pending: 0,
            fma: cpu_has_fma(),
        }
    }

    /// These sums, also keeping every row in f32 with its residual's index
    /// ([`Self::kept_rows`]): J·v and Jᵀq then cost a pass over the kept rows. The rows are
    /// rounded once and the f32 products of [`Self::single_precision`] read them where they
    /// are kept.
    pub fn keeping_rows(mut self) -> Self {
        self.kept = Some(KeptRows::new(self.stride));
        self
    }

    /// The rows since [`Self::clear`], once [`Self::finish`]ed, when they are kept.
    pub fn kept_rows(&self) -> Option<&KeptRows> {
        self.kept.as_ref()
    }

    /// The index of the next row's residual; rows handed out by [`Self::rows_mut`] follow
    /// it (0 after [`Self::clear`]). Only [`Self::kept_rows`] reads it.
    pub fn set_cursor(&mut self, residual: usize) {
        self.cursor = residual;
    }

    /// Most rows [`Self::rows_mut`] hands out at once (32, or 64 for
    /// [`Self::single_precision`]).
    pub fn max_rows(&self) -> usize {
        self.block_rows
    }

    /// Number of parameters.
    pub fn parameter_count(&self) -> usize {
        self.p
    }

    /// Row stride of the blocks [`Self::rows_mut`] returns (≥ parameters).
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Zeroes the sums.
    pub fn clear(&mut self) {
        self.gram.fill(0.0);
        self.gradient.fill(0.0);
        self.pending = 0;
        self.cursor = 0;
        if let Some(kept) = &mut self.kept {
            kept.clear();
        }
    }

    /// Takes J's next `count` rows (at most [`Self::max_rows`]) and their residuals, to be
    /// filled: the rows row-major with [`Self::stride`], of which only the first
    /// [`Self::parameter_count`] entries are read (all of them must be written).
    pub fn rows_mut(&mut self, count: usize) -> (&mut [f64], &mut [f64]) {
        let max = self.block_rows;
        assert!(count <= max, "at most {max} rows at once");
        if self.pending + count > max {
            self.flush();
        }
        let start = self.pending;
        self.pending += count;
        for (k, index) in self.block_index[start..start + count]
            .iter_mut()
            .enumerate()
        {
            *index = (self.cursor + k) as u32;
        }
        self.cursor += count;
        (
            &mut self.block[start * self.stride..(start + count) * self.stride],
            &mut self.block_residuals[start..start + count],
        )
    }

    /// Adds a whole row-major J (N_s × parameters) and its residuals.
    pub fn add_jacobian(&mut self, jacobian: &[f64], residuals: &[f64]) {
        let p = self.p;
        let max = self.block_rows;
        for (rows, e) in jacobian.chunks(max * p).zip(residuals.chunks(max)) {
            let stride = self.stride;
            let (block, block_e) = self.rows_mut(e.len());
            block_e.copy_from_slice(e);
            for (dst, src) in block.chunks_exact_mut(stride).zip(rows.chunks_exact(p)) {
                dst[..p].copy_from_slice(src);
            }
        }
    }

    /// Multiplies the pending rows in.
    pub fn finish(&mut self) {
        self.flush();
    }

    /// Empty sums of the same size and precision.
    pub fn empty_like(&self) -> Self {
        let single = self.single.as_ref().map(|s| vec![0.0; s.len()]);
        let mut empty = Self::with_block(self.p, self.block_rows, single);
        if self.kept.is_some() {
            empty.kept = Some(KeptRows::new(self.stride));
        }
        empty
    }

    /// Adds another accumulator's finished sums to these (finished) sums.
    pub fn add(&mut self, other: &NormalEquations) {
        debug_assert!(self.pending == 0 && other.pending == 0 && self.p == other.p);
        for (a, b) in self.gram.iter_mut().zip(&other.gram) {
            *a += b;
        }
        for (a, b) in self.gradient.iter_mut().zip(&other.gradient) {
            *a += b;
        }
        if let Some(kept) = &mut self.kept {
            match &other.kept {
                Some(theirs) => kept.extend(theirs),
                None => kept.mark_incomplete(),
            }
        }
    }

    /// Σ JᵀJ at (i, j), either order.
    pub fn gram(&self, i: usize, j: usize) -> f64 {
        debug_assert!(i < self.p && j < self.p);
        self.gram[i.min(j) * self.stride + i.max(j)]
    }

    /// Σ Jᵀe at i.
    pub fn gradient(&self, i: usize) -> f64 {
        self.gradient[i]
    }

    fn flush(&mut self) {
        let rows = self.pending;
        if rows == 0 {
            return;
        }
        self.pending = 0;
        let (p, stride) = (self.p, self.stride);
        let block = &mut self.block[..rows * stride];
        for row in block.chunks_exact_mut(stride) {
            row[p..].fill(0.0);
        }
        let residuals = &self.block_residuals[..rows];
        let fma = self.fma;
        let single_sums = self.single.is_some();
        // The f32 rows: where they are kept, else in the block's own buffer.
        let narrowed = match self.kept.as_mut() {
            Some(kept) => Some(kept.push(&self.block_index[..rows])),
            None => self.single.as_mut().map(|s| &mut s[..rows * stride]),
        };
        let mut in_range = true;
        match narrowed {
            Some(single) => {
                in_range = narrow(fma, single, block);
                if single_sums && in_range {
                    gram_update(fma, &mut self.gram, stride, single);
                } else {
                    gram_update(fma, &mut self.gram, stride, block);
                }
            }
            None => gram_update(fma, &mut self.gram, stride, block),
        }
        if !in_range && let Some(kept) = &mut self.kept {
            kept.mark_incomplete();
        }
        gradient_update(self.fma, &mut self.gradient, stride, block, residuals);
    }
}

/// An element the SYRK tiles multiply: f64, or f32 for [`NormalEquations::single_precision`].
trait TileElement:
    Copy + Default + std::ops::Mul<Output = Self> + std::ops::Add<Output = Self>
{
    /// Whether a full tile is 16 columns wide (f32: two 8-lane registers) instead of 8.
    const WIDE: bool;
    /// a·b + c, fused when `FMA`.
    fn madd<const FMA: bool>(a: Self, b: Self, c: Self) -> Self;
    /// The value as f64 (exact).
    fn widen(self) -> f64;
}

impl TileElement for f64 {
    const WIDE: bool = false;
    #[inline(always)]
    fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
        madd::<FMA>(a, b, c)
    }
    #[inline(always)]
    fn widen(self) -> f64 {
        self
    }
}

impl TileElement for f32 {
    const WIDE: bool = true;
    #[inline(always)]
    fn madd<const FMA: bool>(a: f32, b: f32, c: f32) -> f32 {
        if FMA { a.mul_add(b, c) } else { a * b + c }
    }
    #[inline(always)]
    fn widen(self) -> f64 {
        f64::from(self)
    }
}

/// `out[i][j] ±= Σ_rows row[i]·row[j]` for the 4 × N tile at (i0, j0), summed in `T` and added
/// in f64; `out` starts at row `row0`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn syrk_tile<T: TileElement, const FMA: bool, const N: usize, const SUBTRACT: bool>(
    out: &mut [f64],
    row0: usize,
    stride: usize,
    block: &[T],
    i0: usize,
    j0: usize,
) {
    let mut acc = [[T::default(); N]; 4];
    for row in block.chunks_exact(stride) {
        let a: &[T; 4] = row[i0..i0 + 4].try_into().unwrap();
        let b: &[T; N] = row[j0..j0 + N].try_into().unwrap();
        for ii in 0..4 {
            for jj in 0..N {
                acc[ii][jj] = T::madd::<FMA>(a[ii], b[jj], acc[ii][jj]);
            }
        }
    }
    for ii in 0..4 {
        let dst: &mut [f64; N] = (&mut out[(i0 + ii - row0) * stride + j0..][..N])
            .try_into()
            .unwrap();
        for jj in 0..N {
            if SUBTRACT {
                dst[jj] -= acc[ii][jj].widen();
            } else {
                dst[jj] += acc[ii][jj].widen();
            }
        }
    }
}

/// out ±= blockᵀ·block on the upper triangle of rows and columns `from..stride` (`out` starts
/// at row `from`; `stride` and `from` multiples of 4).
///
/// Tiles of two registers' width: 4 × 8 in f64, 4 × 16 in f32. That is eight accumulators,
/// two row loads and four broadcasts per row, which keeps every accumulator in a register
/// (4 × 12 f64 spills one and runs at half the speed).
#[inline(always)]
fn syrk_upper<T: TileElement, const FMA: bool, const SUBTRACT: bool>(
    out: &mut [f64],
    from: usize,
    stride: usize,
    block: &[T],
) {
    for i0 in (from..stride).step_by(4) {
        let mut j0 = i0;
        if T::WIDE {
            while j0 + 16 <= stride {
                syrk_tile::<T, FMA, 16, SUBTRACT>(out, from, stride, block, i0, j0);
                j0 += 16;
            }
        }
        while j0 + 8 <= stride {
            syrk_tile::<T, FMA, 8, SUBTRACT>(out, from, stride, block, i0, j0);
            j0 += 8;
        }
        if stride - j0 == 4 {
            syrk_tile::<T, FMA, 4, SUBTRACT>(out, from, stride, block, i0, j0);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn gram_update_fma<T: TileElement>(gram: &mut [f64], stride: usize, block: &[T]) {
    syrk_upper::<T, true, false>(gram, 0, stride, block);
}

/// gram += blockᵀ·block on the upper triangle.
fn gram_update<T: TileElement>(fma: bool, gram: &mut [f64], stride: usize, block: &[T]) {
    #[cfg(target_arch = "x86_64")]
    if fma {
        // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
        unsafe { gram_update_fma(gram, stride, block) };
        return;
    }
    let _ = fma;
    syrk_upper::<T, false, false>(gram, 0, stride, block);
}

/// Rounds `block` to f32 into `single`; false when an entry's magnitude is 10¹⁸ or more (or
/// NaN), whose f32 products could overflow: |x| < 10¹⁸ keeps every product and 64-row sum far
/// below f32::MAX (3.4·10³⁸).
///
/// One pass without an early exit, so that it vectorizes: the short-circuit check it replaces
/// (`all`, then a second pass to convert) ran one compare and branch per entry and took 12 % of
/// the bunny's 10 000-point fit.
#[inline(always)]
fn narrow_impl(single: &mut [f32], block: &[f64]) -> bool {
    let mut in_range = true;
    for (s, &x) in single.iter_mut().zip(block) {
        *s = x as f32;
        in_range &= x.abs() < 1e18;
    }
    in_range
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn narrow_fma(single: &mut [f32], block: &[f64]) -> bool {
    narrow_impl(single, block)
}

/// [`narrow_impl`], in AVX2 when the CPU has it.
fn narrow(fma: bool, single: &mut [f32], block: &[f64]) -> bool {
    #[cfg(target_arch = "x86_64")]
    if fma {
        // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
        return unsafe { narrow_fma(single, block) };
    }
    let _ = fma;
    narrow_impl(single, block)
}

/// gradient += blockᵀ·e.
#[inline(always)]
fn gradient_update_impl<const FMA: bool>(
    gradient: &mut [f64],
    stride: usize,
    block: &[f64],
    residuals: &[f64],
) {
    for (row, &e) in block.chunks_exact(stride).zip(residuals) {
        for (g, &x) in gradient.iter_mut().zip(row) {
            *g = madd::<FMA>(x, e, *g);
        }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn gradient_update_fma(gradient: &mut [f64], stride: usize, block: &[f64], residuals: &[f64]) {
    gradient_update_impl::<true>(gradient, stride, block, residuals);
}

/// gradient += blockᵀ·e.
fn gradient_update(
    fma: bool,
    gradient: &mut [f64],
    stride: usize,
    block: &[f64],
    residuals: &[f64],
) {
    #[cfg(target_arch = "x86_64")]
    if fma {
        // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
        unsafe { gradient_update_fma(gradient, stride, block, residuals) };
        return;
    }
    let _ = fma;
    gradient_update_impl::<false>(gradient, stride, block, residuals);
}

/// Rows factored per panel of the Cholesky factorization; the trailing rows are then updated
/// by the whole panel at once, with the JᵀJ tiles.
const CHOLESKY_PANEL: usize = 8;

/// Cholesky factorization in place: the upper triangle of `a` (row-major n × n, n a multiple
/// of 4) becomes U with A = UᵀU (U = Lᵀ). Right-looking by panels of [`CHOLESKY_PANEL`] rows.
/// False when A is not positive definite (a pivot ≤ 0 or NaN), as nalgebra's `Cholesky::new`
/// reports it.
#[inline(always)]
fn cholesky_impl<const FMA: bool>(a: &mut [f64], n: usize) -> bool {
    assert!(n.is_multiple_of(4) && a.len() == n * n);
    let mut k0 = 0;
    while k0 < n {
        let k1 = (k0 + CHOLESKY_PANEL).min(n);
        // Factor the panel rows k0..k1 (their columns ≥ k0 are up to date).
        for k in k0..k1 {
            let (done, rest) = a.split_at_mut((k + 1) * n);
            let row_k = &mut done[k * n + k..];
            let pivot = row_k[0];
            if pivot.is_nan() || pivot <= 0.0 {
                return false;
            }
            let diag = pivot.sqrt();
            row_k[0] = diag;
            for x in &mut row_k[1..] {
                *x /= diag;
            }
            for i in k + 1..k1 {
                let coef = -row_k[i - k];
                let row_i = &mut rest[(i - k - 1) * n + i..(i - k) * n];
                for (x, &u) in row_i.iter_mut().zip(&row_k[i - k..]) {
                    *x = madd::<FMA>(coef, u, *x);
                }
            }
        }
        // Trailing rows k1..n: A₂₂ −= U₁₂ᵀU₁₂.
        let (done, rest) = a.split_at_mut(k1 * n);
        syrk_upper::<f64, FMA, true>(rest, k1, n, &done[k0 * n..]);
        k0 = k1;
    }
    true
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn cholesky_fma(a: &mut [f64], p: usize) -> bool {
    cholesky_impl::<true>(a, p)
}

fn cholesky(a: &mut [f64], p: usize, fma: bool) -> bool {
    #[cfg(target_arch = "x86_64")]
    if fma {
        // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
        return unsafe { cholesky_fma(a, p) };
    }
    let _ = fma;
    cholesky_impl::<false>(a, p)
}

/// Solves UᵀUx = b with the factor from [`cholesky`] (p × p).
fn cholesky_solve(u: &[f64], p: usize, b: &[f64], x: &mut [f64]) {
    // Uᵀy = b, a column of Uᵀ (a row of U) at a time.
    x.copy_from_slice(b);
    for k in 0..p {
        let row = &u[k * p + k..(k + 1) * p];
        x[k] /= row[0];
        let yk = x[k];
        for (y, &a) in x[k + 1..].iter_mut().zip(&row[1..]) {
            *y -= a * yk;
        }
    }
    // Ux = y.
    for k in (0..p).rev() {
        let row = &u[k * p + k..(k + 1) * p];
        let sum = dot(&row[1..], &x[k + 1..]);
        x[k] = (x[k] - sum) / row[0];
    }
}

/// `Σ a[i]·b[i]` over equal lengths, with four partial sums (independent chains).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (a4, a_tail) = a.as_chunks::<4>();
    let (b4, b_tail) = b.as_chunks::<4>();
    let mut acc = [0.0; 4];
    for (x, y) in a4.iter().zip(b4) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let tail: f64 = a_tail.iter().zip(b_tail).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// JᵀJ/N_s and Jᵀe/N_s for a row-major J, through [`NormalEquations`] (for tests and probes).
#[cfg(test)]
pub(crate) fn normal_equations(
    jacobian: &[f64],
    residuals: &[f64],
    ns: usize,
    p: usize,
) -> (DMatrix<f64>, DVector<f64>) {
    let mut sums = NormalEquations::new(p);
    sums.add_jacobian(&jacobian[..ns * p], &residuals[..ns]);
    sums.finish();
    let scale = 1.0 / ns.max(1) as f64;
    let normal = DMatrix::from_fn(p, p, |i, j| sums.gram(i, j) * scale);
    let gradient = DVector::from_fn(p, |i, _| sums.gradient(i) * scale);
    (normal, gradient)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_jacobian(ns: usize, p: usize) -> (Vec<f64>, Vec<f64>) {
        let j = (0..ns * p)
            .map(|i| ((i * 7919) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let e = (0..ns).map(|i| (i % 5) as f64 - 2.0).collect();
        (j, e)
    }

    #[test]
    fn blocked_normal_equations_equal_the_plain_product() {
        for (ns, p) in [(7, 3), (40, 13), (64, 136), (5, 1), (100, 271), (33, 12)] {
            let (j, e) = sample_jacobian(ns, p);
            let (normal, gradient) = normal_equations(&j, &e, ns, p);
            let jm = DMatrix::from_row_slice(ns, p, &j);
            let expected = jm.transpose() * &jm / ns as f64;
            let expected_g = jm.transpose() * DVector::from_column_slice(&e) / ns as f64;
            assert!((normal - expected).amax() < 1e-12, "{ns}x{p}");
            assert!((gradient - expected_g).amax() < 1e-12, "{ns}x{p}");
        }
    }

    #[test]
    fn portable_and_fma_kernels_agree() {
        let (ns, p) = (40, 30);
        let (j, e) = sample_jacobian(ns, p);
        let mut sums = [NormalEquations::new(p), NormalEquations::new(p)];
        sums[0].fma = false;
        for s in &mut sums {
            s.add_jacobian(&j, &e);
            s.finish();
        }
        for i in 0..p {
            for k in i..p {
                assert!((sums[0].gram(i, k) - sums[1].gram(i, k)).abs() < 1e-11);
            }
        }
    }

    #[test]
    fn single_precision_sums_are_within_their_stated_error() {
        // 150 rows: two full f32 blocks and a partial one. p = 30 and 45 (strides 32 and 48)
        // take the 16- and 8-wide tiles, p = 43 (stride 44) the 16-, 8- and 4-wide ones.
        for p in [30, 43, 45] {
            let ns = 150;
            let (j, e) = sample_jacobian(ns, p);
            let mut exact = NormalEquations::new(p);
            let mut single = [
                NormalEquations::single_precision(p),
                NormalEquations::single_precision(p),
            ];
            single[0].fma = false;
            exact.add_jacobian(&j, &e);
            exact.finish();
            for s in &mut single {
                s.add_jacobian(&j, &e);
                s.finish();
            }
            for i in 0..p {
                for k in i..p {
                    let magnitude: f64 = (0..ns).map(|r| (j[r * p + i] * j[r * p + k]).abs()).sum();
                    let bound = 66.0 * 2f64.powi(-24) * magnitude;
                    for s in &single {
                        assert!(
                            (s.gram(i, k) - exact.gram(i, k)).abs() <= bound,
                            "{p}: {i},{k}"
                        );
                    }
                }
                // Jᵀe is summed in f64 from the f64 rows: the same bits.
                assert_eq!(single[1].gradient(i), exact.gradient(i));
            }
        }
    }

    #[test]
    fn single_precision_falls_back_to_f64_for_huge_rows() {
        let (p, ns) = (5, 3);
        let j: Vec<f64> = (0..ns * p).map(|i| 1e20 * (i as f64 + 1.0)).collect();
        let e = vec![1.0; ns];
        let mut single = NormalEquations::single_precision(p);
        single.add_jacobian(&j, &e);
        single.finish();
        let mut exact = NormalEquations::new(p);
        exact.add_jacobian(&j, &e);
        exact.finish();
        for i in 0..p {
            for k in i..p {
                assert!(single.gram(i, k).is_finite());
                assert_eq!(single.gram(i, k), exact.gram(i, k));
            }
        }
    }

    #[test]
    fn narrowing_rounds_every_entry_and_flags_huge_or_nan_ones() {
        let block: Vec<f64> = (0..37).map(|i| (i as f64 - 18.0) * 1.1e16).collect();
        for fma in [false, cpu_has_fma()] {
            let mut single = vec![0.0_f32; block.len()];
            assert!(narrow(fma, &mut single, &block));
            assert!(single.iter().zip(&block).all(|(&s, &x)| s == x as f32));
            for bad in [1e18, -1e18, f64::NAN, f64::INFINITY] {
                let mut with_bad = block.clone();
                with_bad[29] = bad;
                assert!(!narrow(fma, &mut single, &with_bad), "{bad} passed");
            }
        }
    }

    #[test]
    fn cholesky_solves_like_nalgebra() {
        for p in [1, 2, 7, 8, 9, 17, 40, 136] {
            let (j, _) = sample_jacobian(2 * p + 3, p);
            let jm = DMatrix::from_row_slice(2 * p + 3, p, &j);
            let a = jm.transpose() * &jm + DMatrix::identity(p, p) * 0.1;
            let b = DVector::from_fn(p, |i, _| (i as f64 * 0.37).sin());
            let expected = nalgebra::Cholesky::new(a.clone()).unwrap().solve(&b);
            let n = p.div_ceil(4) * 4;
            for fma in [false, cpu_has_fma()] {
                let mut l: Vec<f64> = (0..n * n)
                    .map(|k| {
                        let (i, j) = (k / n, k % n);
                        if i < p && j < p {
                            a[(i, j)]
                        } else {
                            f64::from(u8::from(i == j))
                        }
                    })
                    .collect();
                assert!(cholesky(&mut l, n, fma));
                let mut x = vec![0.0; n];
                let mut rhs = vec![0.0; n];
                rhs[..p].copy_from_slice(b.as_slice());
                cholesky_solve(&l, n, &rhs, &mut x);
                for i in 0..p {
                    assert!((x[i] - expected[i]).abs() < 1e-9 * (1.0 + expected[i].abs()));
                }
            }
        }
    }

    #[test]
    fn cholesky_rejects_indefinite_and_nan() {
        let identity = |n: usize| -> Vec<f64> {
            (0..n * n)
                .map(|k| f64::from(u8::from(k % (n + 1) == 0)))
                .collect()
        };
        for fma in [false, cpu_has_fma()] {
            let mut a = identity(4);
            a[1] = 2.0;
            assert!(!cholesky(&mut a, 4, fma));
            let mut a = identity(12);
            a[10 * 13] = f64::NAN;
            assert!(!cholesky(&mut a, 12, fma));
            let mut a = identity(4);
            a[0] = 0.0;
            assert!(!cholesky(&mut a, 4, fma));
        }
    }
}

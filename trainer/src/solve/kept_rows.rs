//! J's rows kept in f32 through one accumulation of the normal equations, each with the index
//! of its residual, so that products with J and Jᵀ cost one pass over memory instead of a new
//! Jacobian: the geodesic acceleration of [`super::lm`] needs Jᵀq for a q that depends on
//! J·v.

use super::lanes::cpu_has_fma;

/// J's rows rounded to f32 (row-major, zero-padded to `stride`) and their residuals' indices.
///
/// The buffers grow to the largest accumulation seen and are then reused: clearing keeps
/// their memory.
#[derive(Clone, Debug)]
pub struct KeptRows {
    stride: usize,
    rows: Vec<f32>,
    index: Vec<u32>,
    len: usize,
    /// False when a row could not be rounded to f32 (an entry of 10¹⁸ or more, or NaN).
    complete: bool,
    fma: bool,
}

impl KeptRows {
    /// No rows, `stride` entries per row.
    pub fn new(stride: usize) -> Self {
        KeptRows {
            stride,
            rows: Vec::new(),
            index: Vec::new(),
            len: 0,
            complete: true,
            fma: cpu_has_fma(),
        }
    }

    /// Forgets the rows (keeping the memory).
    pub fn clear(&mut self) {
        self.len = 0;
        self.complete = true;
    }

    /// Number of rows kept.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no row is kept.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether every row handed over since [`Self::clear`] was kept.
    pub fn is_complete(&self) -> bool {
        self.complete
    }

    /// Marks the accumulation as missing a row.
    pub(super) fn mark_incomplete(&mut self) {
        self.complete = false;
    }

    /// Room for `index.len()` more rows, whose residuals have these indices; the caller
    /// writes the rows into the returned slice (`index.len()` × stride).
    pub(super) fn push(&mut self, index: &[u32]) -> &mut [f32] {
        let (start, end) = (self.len, self.len + index.len());
        if self.index.len() < end {
            self.index.resize(end, 0);
            self.rows.resize(end * self.stride, 0.0);
        }
        self.index[start..end].copy_from_slice(index);
        self.len = end;
        &mut self.rows[start * self.stride..end * self.stride]
    }

    /// Appends another accumulation's rows.
    pub(super) fn extend(&mut self, other: &KeptRows) {
        debug_assert_eq!(self.stride, other.stride);
        let rows = other.len;
        let dst = self.push(&other.index[..rows]);
        dst.copy_from_slice(&other.rows[..rows * other.stride]);
        self.complete &= other.complete;
    }

    /// out = Σ_r q_r·J_r over the kept rows, where q_r = `weight(i, J_r·v)` for the row's
    /// residual index i: Jᵀq for a q that depends on the directional derivative J·v (`v` and
    /// `out` have at least the rows' parameter count of entries, `out` is overwritten).
    ///
    /// Products are formed in f64 from the f32 rows.
    pub fn transpose_along(&self, v: &[f64], weight: impl Fn(usize, f64) -> f64, out: &mut [f64]) {
        #[cfg(target_arch = "x86_64")]
        if self.fma {
            // SAFETY: `fma` comes from `cpu_has_fma`: this CPU has AVX2 and FMA.
            unsafe { self.transpose_along_fma(v, &weight, out) };
            return;
        }
        self.transpose_along_impl(v, &weight, out);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn transpose_along_fma(&self, v: &[f64], weight: &dyn Fn(usize, f64) -> f64, out: &mut [f64]) {
        self.transpose_along_impl(v, weight, out);
    }

    #[inline(always)]
    fn transpose_along_impl(&self, v: &[f64], weight: &dyn Fn(usize, f64) -> f64, out: &mut [f64]) {
        let (stride, p) = (self.stride, v.len().min(out.len()).min(self.stride));
        // J_r·v in f64, four rows at a time (four independent sums): q_r is the small
        // difference of it and a finite difference. v is zero-padded to the stride.
        let mut padded = vec![0.0; stride];
        padded[..p].copy_from_slice(&v[..p]);
        let rows = &self.rows[..self.len * stride];
        let v4 = padded.as_chunks::<4>().0;
        let row = |r: usize| &rows[r * stride..(r + 1) * stride];
        // Σ q_r·J_r in f32 (eight lanes per register): the rows are f32 already, and the
        // product feeds a correction, not the step itself. Each group of four rows is added
        // while it is in cache from its dot products.
        let mut sum = vec![0.0f32; stride];
        for r0 in (0..self.len).step_by(4) {
            // A short last group repeats its last row (and adds it once).
            let last = self.len - 1;
            let quad = [0, 1, 2, 3].map(|k| row((r0 + k).min(last)).as_chunks::<4>().0);
            let along = dot_quad(quad, v4);
            for (k, &along) in along.iter().enumerate().take(self.len - r0) {
                let q = weight(self.index[r0 + k] as usize, along) as f32;
                for (o, &j) in sum.iter_mut().zip(row(r0 + k)) {
                    *o += q * j;
                }
            }
        }
        for (o, &s) in out[..p].iter_mut().zip(&sum) {
            *o = f64::from(s);
        }
        out[p..].fill(0.0);
    }
}

/// The dot products of four f32 rows with one f64 vector, each summed in four f64 lanes
/// (AVX2: one register per row; portable: the same sums in the same order).
#[inline(always)]
fn dot_quad(rows: [&[[f32; 4]]; 4], v: &[[f64; 4]]) -> [f64; 4] {
    #[cfg(target_arch = "x86_64")]
    if cfg!(target_feature = "avx2") || std::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present (checked above); every load reads a whole [_; 4].
        return unsafe { dot_quad_avx2(rows, v) };
    }
    dot_quad_portable(rows, v)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn dot_quad_avx2(rows: [&[[f32; 4]]; 4], v: &[[f64; 4]]) -> [f64; 4] {
    use std::arch::x86_64::*;
    let n = v.len().min(rows.iter().map(|r| r.len()).min().unwrap_or(0));
    let mut acc = [_mm256_setzero_pd(); 4];
    for k in 0..n {
        // SAFETY: k < n ≤ every length; [f64; 4] and [f32; 4] are 32 and 16 bytes.
        let x = unsafe { _mm256_loadu_pd(v[k].as_ptr()) };
        for (a, row) in acc.iter_mut().zip(&rows) {
            let j = unsafe { _mm256_cvtps_pd(_mm_loadu_ps(row[k].as_ptr())) };
            *a = _mm256_add_pd(*a, _mm256_mul_pd(j, x));
        }
    }
    acc.map(|a| {
        let mut lanes = [0.0; 4];
        // SAFETY: four f64 lanes into [f64; 4].
        unsafe { _mm256_storeu_pd(lanes.as_mut_ptr(), a) };
        (lanes[0] + lanes[1]) + (lanes[2] + lanes[3])
    })
}

#[inline(always)]
fn dot_quad_portable(rows: [&[[f32; 4]]; 4], v: &[[f64; 4]]) -> [f64; 4] {
    let (mut a0, mut a1, mut a2, mut a3) = ([0.0f64; 4], [0.0f64; 4], [0.0f64; 4], [0.0f64; 4]);
    let [r0, r1, r2, r3] = rows;
    let columns = v.iter().zip(r0).zip(r1).zip(r2).zip(r3);
    for ((((x, j0), j1), j2), j3) in columns {
        for l in 0..4 {
            a0[l] += f64::from(j0[l]) * x[l];
            a1[l] += f64::from(j1[l]) * x[l];
            a2[l] += f64::from(j2[l]) * x[l];
            a3[l] += f64::from(j3[l]) * x[l];
        }
    }
    [a0, a1, a2, a3].map(|a| (a[0] + a[1]) + (a[2] + a[3]))
}

#[cfg(test)]
mod tests {
    use super::KeptRows;

    #[test]
    fn transpose_along_is_j_transpose_times_a_function_of_j_v() {
        // Three rows of three parameters (stride 4), residual indices 5, 0, 9.
        let mut kept = KeptRows::new(4);
        let rows: [[f32; 4]; 3] = [
            [1.0, 2.0, 0.5, 0.0],
            [-1.0, 0.0, 3.0, 0.0],
            [2.0, -2.0, 1.0, 0.0],
        ];
        let dst = kept.push(&[5, 0, 9]);
        for (d, r) in dst.chunks_exact_mut(4).zip(&rows) {
            d.copy_from_slice(r);
        }
        let v = [0.5, -1.0, 2.0];
        let mut out = [0.0; 3];
        // q_r = 10·i + J_r·v.
        kept.transpose_along(&v, |i, jv| 10.0 * i as f64 + jv, &mut out);
        let mut expected = [0.0; 3];
        for (r, i) in rows.iter().zip([5.0, 0.0, 9.0]) {
            let jv: f64 = (0..3).map(|k| f64::from(r[k]) * v[k]).sum();
            for k in 0..3 {
                expected[k] += (10.0 * i + jv) * f64::from(r[k]);
            }
        }
        for k in 0..3 {
            assert!(
                (out[k] - expected[k]).abs() < 1e-12,
                "{out:?} vs {expected:?}"
            );
        }
        // Appending another accumulation keeps both sets; clearing forgets them.
        let mut more = KeptRows::new(4);
        more.extend(&kept);
        more.extend(&kept);
        assert_eq!(more.len(), 6);
        more.clear();
        assert!(more.is_empty() && more.is_complete());
    }
}

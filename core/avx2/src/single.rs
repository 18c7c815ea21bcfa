//! One point's width-9 layers with the neurons side by side: neurons 0 to 7 in one register,
//! neuron 8 beside it, each neuron's sum in the portable loop's order. Where the lane kernels
//! of `lanes.rs` put eight points in a register, these serve a single point, whose layers
//! would otherwise run one scalar neuron after another.

#![allow(unsafe_code)]

use core::arch::x86_64::{
    __m256, _mm_cvtss_f32, _mm256_add_ps, _mm256_castps256_ps128, _mm256_loadu_ps, _mm256_mul_ps,
    _mm256_set1_ps, _mm256_setr_ps, _mm256_setzero_ps, _mm256_storeu_ps, _mm256_sub_ps,
};

use crate::lanes::{activate, available};
use crate::{Activation, Slope};

/// The neurons of the layers these kernels serve: Carcenac's N = 9.
pub const WIDTH: usize = 9;

/// The forward layer of one point with nine neurons: `out[j]` = a(`biases[j]` + Σᵢ
/// `weights[j][i]`·`x[i]`), each sum in input order, a the [`Activation`]. `None` when AVX2 is
/// missing.
#[inline]
pub fn layer<const IN: usize>(
    weights: &[[f32; IN]; WIDTH],
    biases: &[f32; WIDTH],
    x: &[f32; IN],
    activation: &Activation,
) -> Option<[f32; WIDTH]> {
    if !available() {
        return None;
    }
    // SAFETY: AVX2 is available (checked above).
    Some(unsafe { layer_avx2(weights, biases, x, activation) })
}

/// The transposed layer of one point onto nine of its inputs, `first..first + 9` (all of a
/// width-9 layer's, or one child's part of a node's layer a′): `out[c]` = Σⱼ
/// `weights[j][first + c]`·`g[j]`, each sum from +0 over the rows in order, and with `slope`
/// times (offset − square·(a·a)), a = `slope.0[c]`. `None` when AVX2 is missing or the
/// columns do not lie within a row.
#[inline]
pub fn transposed<const COUNT: usize, const ROWS: usize>(
    weights: &[[f32; COUNT]; ROWS],
    first: usize,
    g: &[f32; ROWS],
    slope: Option<(&[f32; WIDTH], &Slope)>,
) -> Option<[f32; WIDTH]> {
    if first.checked_add(WIDTH)? > COUNT || !available() {
        return None;
    }
    // SAFETY: AVX2 is available (checked above).
    Some(unsafe { transposed_avx2(weights, first, g, slope) })
}

#[target_feature(enable = "avx2")]
fn layer_avx2<const IN: usize>(
    weights: &[[f32; IN]; WIDTH],
    biases: &[f32; WIDTH],
    x: &[f32; IN],
    activation: &Activation,
) -> [f32; WIDTH] {
    let [.., last_row] = weights;
    let [.., last_bias] = *biases;
    // Neuron j's weight for input i lies at j·IN + i of the flattened matrix.
    let flat = weights.as_flattened();
    let mut sum = load8(head(biases));
    let mut last = last_bias;
    for (i, (&xi, &w)) in x.iter().zip(last_row).enumerate() {
        let weight = |j: usize| flat.get(j * IN + i).copied().unwrap_or(0.0);
        let column = _mm256_setr_ps(
            weight(0),
            weight(1),
            weight(2),
            weight(3),
            weight(4),
            weight(5),
            weight(6),
            weight(7),
        );
        sum = _mm256_add_ps(sum, _mm256_mul_ps(column, _mm256_set1_ps(xi)));
        last += w * xi;
    }
    let mut first = [0.0; 8];
    store8(&mut first, activate(sum, activation));
    let last = _mm_cvtss_f32(_mm256_castps256_ps128(activate(
        _mm256_set1_ps(last),
        activation,
    )));
    join(first, last)
}

#[target_feature(enable = "avx2")]
fn transposed_avx2<const COUNT: usize, const ROWS: usize>(
    weights: &[[f32; COUNT]; ROWS],
    first: usize,
    g: &[f32; ROWS],
    slope: Option<(&[f32; WIDTH], &Slope)>,
) -> [f32; WIDTH] {
    let mut sum = _mm256_setzero_ps();
    let mut last = 0.0_f32;
    for (row, &gj) in weights.iter().zip(g) {
        // Within the row: `transposed` checked the columns.
        let row = row
            .get(first..)
            .and_then(<[f32]>::first_chunk::<WIDTH>)
            .unwrap_or(&[0.0; WIDTH]);
        let [.., w8] = *row;
        sum = _mm256_add_ps(sum, _mm256_mul_ps(load8(head(row)), _mm256_set1_ps(gj)));
        last += w8 * gj;
    }
    if let Some((a, slope)) = slope {
        let [.., a8] = *a;
        let a = load8(head(a));
        let factor = _mm256_sub_ps(
            _mm256_set1_ps(slope.offset),
            _mm256_mul_ps(_mm256_set1_ps(slope.square), _mm256_mul_ps(a, a)),
        );
        sum = _mm256_mul_ps(sum, factor);
        last *= slope.offset - slope.square * (a8 * a8);
    }
    let mut first = [0.0; 8];
    store8(&mut first, sum);
    join(first, last)
}

/// A nine-neuron layer from neurons 0 to 7 and neuron 8.
#[inline(always)]
fn join([a, b, c, d, e, f, g, h]: [f32; 8], last: f32) -> [f32; WIDTH] {
    [a, b, c, d, e, f, g, h, last]
}

/// Neurons 0 to 7 of a nine-neuron layer.
#[inline(always)]
fn head(x: &[f32; WIDTH]) -> &[f32; 8] {
    x.first_chunk().unwrap_or(&[0.0; 8])
}

#[inline(always)]
fn load8(x: &[f32; 8]) -> __m256 {
    // SAFETY: `x` is eight readable `f32`; the load has no alignment requirement.
    unsafe { _mm256_loadu_ps(x.as_ptr()) }
}

#[inline(always)]
fn store8(out: &mut [f32; 8], v: __m256) {
    // SAFETY: `out` is eight writable `f32`; the store has no alignment requirement.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) }
}

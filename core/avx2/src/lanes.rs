//! The AVX2 kernels and their run-time selection: the crate's only unsafe code.

#![allow(unsafe_code)]

use core::arch::x86_64::{
    __m256, _CMP_NLT_UQ, _CMP_UNORD_Q, _mm256_add_epi32, _mm256_add_ps, _mm256_and_ps,
    _mm256_blendv_ps, _mm256_castps_si256, _mm256_castsi256_ps, _mm256_cmp_ps, _mm256_div_ps,
    _mm256_loadu_ps, _mm256_mul_ps, _mm256_or_ps, _mm256_set1_ps, _mm256_setzero_ps,
    _mm256_slli_epi32, _mm256_storeu_ps, _mm256_sub_ps,
};

use crate::{Activation, Lanes, Slope, WIDE_GROUPS};

cpufeatures::new!(avx2, "avx2");

/// Whether the processor running has AVX2 (detected once, then one atomic load).
#[inline]
pub fn available() -> bool {
    avx2::get()
}

/// The forward layer: `out[j]` = a(`biases[j]` + Σᵢ `weights[j][i]`·xᵢ) for every row j, x the
/// concatenation of `inputs[0]`, `inputs[1]` and `inputs[2]`, each sum in input order, a the
/// [`Activation`]. Each neuron (input or output) is `groups` lane groups side by side: neuron
/// k of a part is its entries `k·groups..(k + 1)·groups`, `groups · 8` points in all. Returns
/// `false` without writing when AVX2 is missing or the slices do not fit (every part a whole
/// number of neurons, `weights` `biases.len()` rows of one weight per input, `out` at least
/// `biases.len()` neurons).
pub fn forward(
    weights: &[f32],
    biases: &[f32],
    inputs: [&[Lanes]; 3],
    groups: usize,
    activation: &Activation,
    out: &mut [Lanes],
) -> bool {
    if groups == 0 || inputs.iter().any(|part| part.len() % groups != 0) {
        return false;
    }
    let count = inputs.iter().map(|part| part.len()).sum::<usize>() / groups;
    let rows = biases.len();
    if count == 0
        || Some(weights.len()) != rows.checked_mul(count)
        || rows
            .checked_mul(groups)
            .is_none_or(|needed| out.len() < needed)
    {
        return false;
    }
    if !available() {
        return false;
    }
    // SAFETY: AVX2 is available (checked above).
    unsafe { forward_avx2(weights, (count, groups), biases, inputs, activation, out) };
    true
}

/// The transposed layer: `out[c]` = Σⱼ `weights[j][first + c]`·`g[j]` for c below `columns`,
/// each sum from +0 over the rows in order, each neuron `groups` lane groups side by side (see
/// [`forward`]). Returns `false` without writing when AVX2 is missing or the slices do not
/// fit (`g` a whole number of neurons, `weights` one row of `count` weights per neuron of `g`,
/// `first + columns` ≤ `count`, `out` at least `columns` neurons).
pub fn transposed(
    weights: &[f32],
    count: usize,
    (first, columns): (usize, usize),
    (g, groups): (&[Lanes], usize),
    out: &mut [Lanes],
) -> bool {
    if !fits_transposed(weights, count, (first, columns), (g, groups), out.len()) || !available() {
        return false;
    }
    // SAFETY: AVX2 is available (checked above).
    unsafe { transposed_avx2(weights, count, (first, columns), (g, groups), None, out) };
    true
}

/// [`transposed`] with the chain rule on each sum: `out[c]` = (Σⱼ `weights[j][first + c]`·`g[j]`)
/// · (offset − square·(a·a)), a = `outputs[c]` (`outputs` at least `columns` neurons).
pub fn transposed_slope(
    weights: &[f32],
    count: usize,
    (first, columns): (usize, usize),
    (g, groups): (&[Lanes], usize),
    (outputs, slope): (&[Lanes], &Slope),
    out: &mut [Lanes],
) -> bool {
    if !fits_transposed(weights, count, (first, columns), (g, groups), out.len())
        || columns
            .checked_mul(groups)
            .is_none_or(|needed| outputs.len() < needed)
        || !available()
    {
        return false;
    }
    // SAFETY: AVX2 is available (checked above).
    unsafe {
        transposed_avx2(
            weights,
            count,
            (first, columns),
            (g, groups),
            Some((outputs, slope)),
            out,
        )
    };
    true
}

/// Whether `g` is a whole number of neurons of `groups` lane groups, `weights` holds one row of
/// `count` weights per neuron, the columns lie within a row and `out` entries hold them: the
/// shape every transposed kernel needs.
pub(crate) fn fits_transposed<W, G>(
    weights: &[W],
    count: usize,
    (first, columns): (usize, usize),
    (g, groups): (&[G], usize),
    out: usize,
) -> bool {
    groups > 0
        && g.len() % groups == 0
        && Some(weights.len()) == (g.len() / groups).checked_mul(count)
        && first.checked_add(columns).is_some_and(|end| end <= count)
        && columns
            .checked_mul(groups)
            .is_some_and(|needed| out >= needed)
        && columns > 0
}

#[inline(always)]
fn load(x: &Lanes) -> __m256 {
    // SAFETY: `x` is eight readable `f32`; the load has no alignment requirement.
    unsafe { _mm256_loadu_ps(x.as_ptr()) }
}

#[inline(always)]
fn store(out: &mut Lanes, v: __m256) {
    // SAFETY: `out` is eight writable `f32`; the store has no alignment requirement.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), v) }
}

#[target_feature(enable = "avx2")]
fn forward_avx2(
    weights: &[f32],
    (count, groups): (usize, usize),
    biases: &[f32],
    inputs: [&[Lanes]; 3],
    activation: &Activation,
    out: &mut [Lanes],
) {
    // Carcenac's N = 9: a leaf's layers (9 × 3, 9 × 9, 1 × 9) and a node's first (9 × 21),
    // every bound known when compiled, for one lane group or the wide ones.
    let parts = inputs.map(|part| part.len() / groups);
    let done = match (biases.len(), parts, groups) {
        (9, [3, 0, 0], 1) => {
            forward_fixed::<9, 3, 0, 0, 1>(weights, biases, inputs, activation, out)
        }
        (9, [9, 0, 0], 1) => {
            forward_fixed::<9, 9, 0, 0, 1>(weights, biases, inputs, activation, out)
        }
        (1, [9, 0, 0], 1) => {
            forward_fixed::<1, 9, 0, 0, 1>(weights, biases, inputs, activation, out)
        }
        (9, [9, 9, 3], 1) => {
            forward_fixed::<9, 9, 9, 3, 1>(weights, biases, inputs, activation, out)
        }
        (9, [3, 0, 0], WIDE_GROUPS) => {
            forward_fixed::<9, 3, 0, 0, WIDE_GROUPS>(weights, biases, inputs, activation, out)
        }
        (9, [9, 0, 0], WIDE_GROUPS) => {
            forward_fixed::<9, 9, 0, 0, WIDE_GROUPS>(weights, biases, inputs, activation, out)
        }
        (1, [9, 0, 0], WIDE_GROUPS) => {
            forward_fixed::<1, 9, 0, 0, WIDE_GROUPS>(weights, biases, inputs, activation, out)
        }
        (9, [9, 9, 3], WIDE_GROUPS) => {
            forward_fixed::<9, 9, 9, 3, WIDE_GROUPS>(weights, biases, inputs, activation, out)
        }
        _ => false,
    };
    if done {
        return;
    }
    for group in 0..groups {
        let mut row = 0;
        while row < biases.len() {
            let at = (count, row, groups, group);
            row += match biases.len() - row {
                1 => forward_rows::<1>(weights, at, biases, inputs, activation, out),
                2 => forward_rows::<2>(weights, at, biases, inputs, activation, out),
                3..WIDE => forward_rows::<3>(weights, at, biases, inputs, activation, out),
                _ => forward_rows::<WIDE>(weights, at, biases, inputs, activation, out),
            };
        }
    }
}

/// [`forward_avx2`] for `ROWS` rows, input parts of `I0`, `I1` and `I2` neurons and `G` lane
/// groups per neuron; false (nothing written) when the slices are not of that shape. Row by
/// row, the `G` groups' sums side by side share each weight and hide each other's latency.
#[target_feature(enable = "avx2")]
#[inline]
fn forward_fixed<
    const ROWS: usize,
    const I0: usize,
    const I1: usize,
    const I2: usize,
    const G: usize,
>(
    weights: &[f32],
    biases: &[f32],
    [x0, x1, x2]: [&[Lanes]; 3],
    activation: &Activation,
    out: &mut [Lanes],
) -> bool {
    let count = I0 + I1 + I2;
    let (Some(biases), Some(out), Some(x0), Some(x1), Some(x2)) = (
        biases.first_chunk::<ROWS>(),
        out.as_chunks_mut::<G>().0.first_chunk_mut::<ROWS>(),
        x0.as_chunks::<G>().0.first_chunk::<I0>(),
        x1.as_chunks::<G>().0.first_chunk::<I1>(),
        x2.as_chunks::<G>().0.first_chunk::<I2>(),
    ) else {
        return false;
    };
    if weights.len() != ROWS * count {
        return false;
    }
    for ((out, &bias), row) in out.iter_mut().zip(biases).zip(weights.chunks_exact(count)) {
        let Some((w0, rest)) = row.split_first_chunk::<I0>() else {
            return false;
        };
        let Some((w1, rest)) = rest.split_first_chunk::<I1>() else {
            return false;
        };
        let Some(w2) = rest.first_chunk::<I2>() else {
            return false;
        };
        let mut sums = [_mm256_set1_ps(bias); G];
        for (&w, x) in w0.iter().zip(x0) {
            multiply_add_groups(&mut sums, w, x);
        }
        for (&w, x) in w1.iter().zip(x1) {
            multiply_add_groups(&mut sums, w, x);
        }
        for (&w, x) in w2.iter().zip(x2) {
            multiply_add_groups(&mut sums, w, x);
        }
        for (out, &sum) in out.iter_mut().zip(&sums) {
            store(out, sum);
        }
    }
    // The activations after all sums: independent of each other, they overlap in the core.
    for out in out.as_flattened_mut() {
        store(out, activate(load(out), activation));
    }
    true
}

/// `sums[g] += w·x[g]` for each lane group g.
#[target_feature(enable = "avx2")]
#[inline]
fn multiply_add_groups<const G: usize>(sums: &mut [__m256; G], w: f32, x: &[Lanes; G]) {
    let w = _mm256_set1_ps(w);
    for (sum, x) in sums.iter_mut().zip(x) {
        *sum = _mm256_add_ps(*sum, _mm256_mul_ps(w, load(x)));
    }
}

/// Rows (or columns) of a wide block: nine independent sums (Carcenac's N = 9) keep both
/// vector adders busy; with the input and a weight they take 11 of the 16 registers.
const WIDE: usize = 9;

/// Rows `row..row + B` of [`forward_avx2`] for lane group `group` of `groups`, their sums side
/// by side; returns `B`.
#[target_feature(enable = "avx2")]
#[inline]
fn forward_rows<const B: usize>(
    weights: &[f32],
    (count, row, groups, group): (usize, usize, usize, usize),
    biases: &[f32],
    inputs: [&[Lanes]; 3],
    activation: &Activation,
    out: &mut [Lanes],
) -> usize {
    let (Some(biases), Some(weights)) = (
        biases.get(row..).and_then(<[f32]>::first_chunk::<B>),
        weights.get(row * count..),
    ) else {
        return B;
    };
    // No closures here: they would be compiled without AVX2.
    let mut acc = [_mm256_setzero_ps(); B];
    for (acc, &bias) in acc.iter_mut().zip(biases) {
        *acc = _mm256_set1_ps(bias);
    }
    let mut offset = 0;
    for part in inputs {
        let neurons = part.len() / groups;
        let at = (count, offset);
        match neurons {
            0 => {}
            3 => accumulate::<B, 3>(&mut acc, weights, at, (part, groups, group)),
            9 => accumulate::<B, 9>(&mut acc, weights, at, (part, groups, group)),
            _ => accumulate_any::<B>(&mut acc, weights, at, (part, groups, group)),
        }
        offset += neurons;
    }
    for (b, &acc) in acc.iter().enumerate() {
        if let Some(out) = out.get_mut((row + b) * groups + group) {
            store(out, activate(acc, activation));
        }
    }
    B
}

/// Lane group `group` of every neuron of a part whose neurons are `groups` lane groups each.
type Strided<'a> = (&'a [Lanes], usize, usize);

/// `acc[b] += Σₖ w[b][offset + k]·x[k]` in order of k, for `IN` inputs known when compiled
/// (the loop unrolls); `w[b]` is row b of `weights` (`count` per row).
#[target_feature(enable = "avx2")]
#[inline]
fn accumulate<const B: usize, const IN: usize>(
    acc: &mut [__m256; B],
    weights: &[f32],
    (count, offset): (usize, usize),
    x: Strided<'_>,
) {
    let mut rows = [&[0.0; IN]; B];
    for (b, row) in rows.iter_mut().enumerate() {
        match weights
            .get(b * count + offset..)
            .and_then(<[f32]>::first_chunk::<IN>)
        {
            Some(weights) => *row = weights,
            None => return,
        }
    }
    multiply_accumulate(acc, &rows, x);
}

/// [`accumulate`] for any number of inputs.
#[target_feature(enable = "avx2")]
#[inline]
fn accumulate_any<const B: usize>(
    acc: &mut [__m256; B],
    weights: &[f32],
    (count, offset): (usize, usize),
    x: Strided<'_>,
) {
    let n = x.0.len() / x.1;
    // Each row's weights for these inputs: exactly `n` of them.
    let mut rows: [&[f32]; B] = [&[]; B];
    for (b, row) in rows.iter_mut().enumerate() {
        let start = b * count + offset;
        match weights.get(start..start + n) {
            Some(weights) => *row = weights,
            None => return,
        }
    }
    multiply_accumulate(acc, &rows, x);
}

/// `acc[b] += Σₖ rows[b][k]·x[k]` in order of k (every row at least as long as `x`).
#[target_feature(enable = "avx2")]
#[inline]
fn multiply_accumulate<const B: usize, R: AsRef<[f32]>>(
    acc: &mut [__m256; B],
    rows: &[R; B],
    (x, groups, group): Strided<'_>,
) {
    for (k, x) in x.iter().skip(group).step_by(groups).enumerate() {
        let x = load(x);
        for (acc, row) in acc.iter_mut().zip(rows) {
            let w = row.as_ref().get(k).copied().unwrap_or(0.0);
            *acc = _mm256_add_ps(*acc, _mm256_mul_ps(_mm256_set1_ps(w), x));
        }
    }
}

/// The core's branch-free `f32` activation on eight lanes, operation for operation.
#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn activate(h: __m256, constants: &Activation) -> __m256 {
    let saturation = _mm256_set1_ps(constants.saturation);
    let rounder = _mm256_set1_ps(constants.rounder);
    let one = _mm256_set1_ps(1.0);
    let u = _mm256_mul_ps(h, _mm256_set1_ps(constants.u_per_h));
    let magnitude = _mm256_and_ps(u, _mm256_castsi256_ps(splat_bits(0x7fff_ffff)));
    // "Not below" the saturation point, NaN included.
    let saturated = _mm256_cmp_ps::<_CMP_NLT_UQ>(magnitude, saturation);
    let u = _mm256_blendv_ps(u, saturation, saturated);
    let rounded = _mm256_add_ps(u, rounder);
    let r = _mm256_sub_ps(u, _mm256_sub_ps(rounded, rounder));
    let [lower @ .., highest] = constants.polynomial;
    let mut acc = _mm256_set1_ps(highest);
    for &c in lower.iter().rev() {
        acc = _mm256_add_ps(_mm256_set1_ps(c), _mm256_mul_ps(r, acc));
    }
    let p = _mm256_add_ps(one, _mm256_mul_ps(r, acc));
    let e = _mm256_castsi256_ps(_mm256_add_epi32(
        _mm256_castps_si256(p),
        _mm256_slli_epi32::<23>(_mm256_castps_si256(rounded)),
    ));
    let below = _mm256_mul_ps(
        _mm256_div_ps(_mm256_sub_ps(e, one), _mm256_add_ps(e, one)),
        _mm256_set1_ps(constants.amplitude),
    );
    // ±A with the sign of H, or H itself when it is NaN.
    let sign = _mm256_and_ps(h, _mm256_castsi256_ps(splat_bits(0x8000_0000_u32 as i32)));
    let limit = _mm256_or_ps(_mm256_set1_ps(constants.amplitude), sign);
    let limit = _mm256_blendv_ps(limit, h, _mm256_cmp_ps::<_CMP_UNORD_Q>(h, h));
    _mm256_blendv_ps(below, limit, saturated)
}

#[target_feature(enable = "avx2")]
#[inline]
pub(crate) fn splat_bits(bits: i32) -> core::arch::x86_64::__m256i {
    core::arch::x86_64::_mm256_set1_epi32(bits)
}

#[target_feature(enable = "avx2")]
fn transposed_avx2(
    weights: &[f32],
    count: usize,
    (first, columns): (usize, usize),
    (g, groups): (&[Lanes], usize),
    slope: Option<(&[Lanes], &Slope)>,
    out: &mut [Lanes],
) {
    // Carcenac's N = 9: the output layer and layer b of every module, a leaf's layer a, and a
    // node's layer a′ towards each child and its own position, every bound known when compiled,
    // for one lane group or the wide ones.
    macro_rules! fixed {
        ($rows:literal, $count:literal, $first:literal, $columns:literal) => {
            match groups {
                1 => transposed_fixed::<$rows, $count, $first, $columns, 1>(weights, g, slope, out),
                WIDE_GROUPS => transposed_fixed::<$rows, $count, $first, $columns, WIDE_GROUPS>(
                    weights, g, slope, out,
                ),
                _ => false,
            }
        };
    }
    let done = match (g.len() / groups, count, first, columns) {
        (1, 9, 0, 9) => fixed!(1, 9, 0, 9),
        (9, 9, 0, 9) => fixed!(9, 9, 0, 9),
        (9, 3, 0, 3) => fixed!(9, 3, 0, 3),
        (9, 21, 0, 9) => fixed!(9, 21, 0, 9),
        (9, 21, 9, 9) => fixed!(9, 21, 9, 9),
        (9, 21, 18, 3) => fixed!(9, 21, 18, 3),
        _ => false,
    };
    if done {
        return;
    }
    for group in 0..groups {
        let mut done = 0;
        while done < columns {
            let at = (first, done, groups, group);
            done += match columns - done {
                1 => transposed_columns::<1>(weights, count, at, g, slope, out),
                2 => transposed_columns::<2>(weights, count, at, g, slope, out),
                3..WIDE => transposed_columns::<3>(weights, count, at, g, slope, out),
                _ => transposed_columns::<WIDE>(weights, count, at, g, slope, out),
            };
        }
    }
}

/// [`transposed_avx2`] for `ROWS` rows of `COUNT` weights, the columns `FIRST..FIRST +
/// COLUMNS` and `G` lane groups per neuron; false (nothing written) when the slices are not of
/// that shape.
#[target_feature(enable = "avx2")]
#[inline]
fn transposed_fixed<
    const ROWS: usize,
    const COUNT: usize,
    const FIRST: usize,
    const COLUMNS: usize,
    const G: usize,
>(
    weights: &[f32],
    g: &[Lanes],
    slope: Option<(&[Lanes], &Slope)>,
    out: &mut [Lanes],
) -> bool {
    let (rows, _) = weights.as_chunks::<COUNT>();
    let (Some(rows), Some(g), Some(out)) = (
        rows.first_chunk::<ROWS>(),
        g.as_chunks::<G>().0.first_chunk::<ROWS>(),
        out.as_chunks_mut::<G>().0.first_chunk_mut::<COLUMNS>(),
    ) else {
        return false;
    };
    if weights.len() != ROWS * COUNT {
        return false;
    }
    // No closures here: they would be compiled without AVX2.
    let outputs = match slope {
        Some((a, s)) => match a.as_chunks::<G>().0.first_chunk::<COLUMNS>() {
            Some(a) => Some((a, s)),
            None => return false,
        },
        None => None,
    };
    let mut weights = [[0.0; COLUMNS]; ROWS];
    for (weights, row) in weights.iter_mut().zip(rows) {
        match row.get(FIRST..).and_then(<[f32]>::first_chunk::<COLUMNS>) {
            Some(w) => *weights = *w,
            None => return false,
        }
    }
    for group in 0..G {
        let mut acc = [_mm256_setzero_ps(); COLUMNS];
        for (w, g) in weights.iter().zip(g) {
            let Some(g) = g.get(group) else {
                return false;
            };
            let g = load(g);
            for (acc, &w) in acc.iter_mut().zip(w) {
                *acc = _mm256_add_ps(*acc, _mm256_mul_ps(_mm256_set1_ps(w), g));
            }
        }
        match outputs {
            Some((a, slope)) => {
                for ((out, &acc), a) in out.iter_mut().zip(&acc).zip(a) {
                    if let (Some(out), Some(a)) = (out.get_mut(group), a.get(group)) {
                        finish_column(acc, Some((a, slope)), out);
                    }
                }
            }
            None => {
                for (out, &acc) in out.iter_mut().zip(&acc) {
                    if let Some(out) = out.get_mut(group) {
                        store(out, acc);
                    }
                }
            }
        }
    }
    true
}

/// Writes the column sum `acc` to `out`, times (offset − square·(a·a)) when `slope` gives the
/// output `a`.
#[target_feature(enable = "avx2")]
#[inline]
fn finish_column(acc: __m256, slope: Option<(&Lanes, &Slope)>, out: &mut Lanes) {
    match slope {
        Some((a, slope)) => {
            let a = load(a);
            let factor = _mm256_sub_ps(
                _mm256_set1_ps(slope.offset),
                _mm256_mul_ps(_mm256_set1_ps(slope.square), _mm256_mul_ps(a, a)),
            );
            store(out, _mm256_mul_ps(acc, factor));
        }
        None => store(out, acc),
    }
}

/// Columns `first + done..first + done + B` of [`transposed_avx2`] for lane group `group` of
/// `groups` into `out`, their sums side by side; returns `B`.
#[target_feature(enable = "avx2")]
#[inline]
fn transposed_columns<const B: usize>(
    weights: &[f32],
    count: usize,
    (first, done, groups, group): (usize, usize, usize, usize),
    g: &[Lanes],
    slope: Option<(&[Lanes], &Slope)>,
    out: &mut [Lanes],
) -> usize {
    let column = first + done;
    let mut acc = [_mm256_setzero_ps(); B];
    let g = g.iter().skip(group).step_by(groups);
    for (row, g) in weights.chunks_exact(count).zip(g) {
        let Some(w) = row.get(column..).and_then(<[f32]>::first_chunk::<B>) else {
            return B;
        };
        let g = load(g);
        for (acc, &w) in acc.iter_mut().zip(w) {
            *acc = _mm256_add_ps(*acc, _mm256_mul_ps(_mm256_set1_ps(w), g));
        }
    }
    for (b, &acc) in acc.iter().enumerate() {
        let at = (done + b) * groups + group;
        let a = slope.and_then(|(a, s)| Some((a.get(at)?, s)));
        if let Some(out) = out.get_mut(at) {
            finish_column(acc, a, out);
        }
    }
    B
}

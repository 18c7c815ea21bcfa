//! Every target kernel against the portable loop it replaces, on edge cases and seeded random
//! inputs: what the simulator runs on the Cortex-M4F (`firmware-sim`'s kernel check), so that a
//! broken kernel is named, not only seen as a wrong Φ somewhere in a model.
//!
//! The reference here is each kernel's contract written out with the scalar's operations (the
//! same `to_acc`, `mac`, `from_acc`, `activation_from_acc` and `times_slope` the portable loops
//! in `dense.rs` use). On a machine without kernels every check is skipped and the count is 0.

use super::Kernels;
use crate::implicit::Activation;
use crate::scalar::{Q16, Scalar};

/// A kernel whose result differs from the portable loop's.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KernelMismatch {
    /// The kernel, as `<operation> <OUT>x<IN>` (`layer 9x9`, `transposed 9x3`, …).
    pub kernel: &'static str,
    /// The case that failed: 0 to 4 are the edge cases (zeros, the largest values of both
    /// signs, the smallest steps of both signs), the others seeded random inputs.
    pub case: u32,
}

/// Runs every kernel of the machine compiled for on `cases` inputs (the edge cases first, then
/// inputs drawn from `seed`) and compares each with its portable loop. Returns how many kernel
/// calls were checked (0 where there are no kernels).
///
/// # Errors
/// The first kernel and case whose bits differ.
pub fn check_kernels(seed: u32, cases: u32) -> Result<u32, KernelMismatch> {
    let mut random = Xorshift(seed | 1);
    let mut checked = 0;
    for case in 0..cases {
        let mut draw = |scale: i32| Q16::from_bits(input(case, scale, &mut random));
        checked += layer::<9, 9>("layer 9x9", case, &mut draw)?;
        checked += layer::<3, 9>("layer 9x3", case, &mut draw)?;
        checked += layer::<9, 1>("layer 1x9", case, &mut draw)?;
        checked += transposed::<3, 9>("transposed 9x3", case, &mut draw)?;
        checked += times_slope("times_slope 9", case, &mut draw)?;
        checked += transposed_slope::<9, 9>("transposed_slope 9x9", case, &mut draw)?;
        checked += transposed_slope::<9, 1>("transposed_slope 1x9", case, &mut draw)?;
    }
    if <f32 as Kernels>::TARGET_KERNELS {
        checked += f32_kernels::check(seed, cases)?;
    }
    if <f32 as Kernels>::LANE_KERNELS {
        checked += lane_kernels::check::<f32>(seed, cases)?;
    }
    if <Q16 as Kernels>::LANE_KERNELS {
        checked += lane_kernels::check::<Q16>(seed, cases)?;
    }
    Ok(checked)
}

/// Bits of one input: the edge case's value, or a random one of magnitude below `scale` in
/// Q16.16 units (at most the ±1 024 a blob's parameter may hold).
fn input(case: u32, scale: i32, random: &mut Xorshift) -> i32 {
    let limit = scale.saturating_mul(1 << 16);
    match case {
        0 => 0,
        1 => limit,
        2 => -limit,
        3 => 1,
        4 => -1,
        5 => random.below(2 * limit) - limit,
        _ => (random.below(2 * limit) - limit) >> random.below(12),
    }
}

type Draw<'a> = dyn FnMut(i32) -> Q16 + 'a;

fn matrix<const IN: usize, const OUT: usize>(draw: &mut Draw<'_>, scale: i32) -> [[Q16; IN]; OUT] {
    core::array::from_fn(|_| core::array::from_fn(|_| draw(scale)))
}

fn vector<const N: usize>(draw: &mut Draw<'_>, scale: i32) -> [Q16; N] {
    core::array::from_fn(|_| draw(scale))
}

/// Activations lie within ±1.7159: the backward kernels' `a` stays in that range.
const ACTIVATION_BITS: i32 = 112_453;

fn activations<const N: usize>(draw: &mut Draw<'_>) -> [Q16; N] {
    core::array::from_fn(|_| {
        let a = draw(2).to_bits();
        Q16::from_bits(a.clamp(-ACTIVATION_BITS, ACTIVATION_BITS))
    })
}

fn compare<T: PartialEq>(
    kernel: &'static str,
    case: u32,
    got: Option<T>,
    want: T,
) -> Result<u32, KernelMismatch> {
    match got {
        None => Ok(0),
        Some(got) if got == want => Ok(1),
        Some(_) => Err(KernelMismatch { kernel, case }),
    }
}

fn layer<const IN: usize, const OUT: usize>(
    kernel: &'static str,
    case: u32,
    draw: &mut Draw<'_>,
) -> Result<u32, KernelMismatch> {
    let (w, b, x) = (
        matrix::<IN, OUT>(draw, 8),
        vector::<OUT>(draw, 8),
        vector::<IN>(draw, 2),
    );
    let mut want = [Q16::ZERO; OUT];
    for ((out, row), bias) in want.iter_mut().zip(&w).zip(&b) {
        let acc = row
            .iter()
            .zip(&x)
            .fold(bias.to_acc(), |acc, (&wi, &xi)| Q16::mac(acc, wi, xi));
        *out = Q16::activation_from_acc(acc);
    }
    compare(
        kernel,
        case,
        <Q16 as Kernels>::layer_kernel(&w, &b, &x),
        want,
    )
}

fn transposed<const IN: usize, const OUT: usize>(
    kernel: &'static str,
    case: u32,
    draw: &mut Draw<'_>,
) -> Result<u32, KernelMismatch> {
    let (w, g) = (matrix::<IN, OUT>(draw, 8), vector::<OUT>(draw, 16));
    let want = column_sums(&w, &g);
    compare(
        kernel,
        case,
        <Q16 as Kernels>::transposed_kernel(&w, &g),
        want,
    )
}

fn times_slope(
    kernel: &'static str,
    case: u32,
    draw: &mut Draw<'_>,
) -> Result<u32, KernelMismatch> {
    let (delta, a) = (vector::<9>(draw, 64), activations::<9>(draw));
    let want = through_slope(delta, &a);
    let mut got = delta;
    let ran = <Q16 as Kernels>::times_slope_kernel(&mut got, &a);
    compare(kernel, case, ran.then_some(got), want)
}

fn transposed_slope<const IN: usize, const OUT: usize>(
    kernel: &'static str,
    case: u32,
    draw: &mut Draw<'_>,
) -> Result<u32, KernelMismatch> {
    let (w, mut g, a) = (
        matrix::<IN, OUT>(draw, 8),
        vector::<OUT>(draw, 16),
        activations::<IN>(draw),
    );
    if OUT == 1 {
        // One row is the output layer's: its g is the output's slope, within ±1.1442; the
        // kernel takes −2 ≤ g < 2.
        g = g.map(|v| Q16::from_bits(v.to_bits().clamp(-(2 << 16), (2 << 16) - 1)));
    }
    let want = through_slope(column_sums(&w, &g), &a);
    compare(
        kernel,
        case,
        <Q16 as Kernels>::transposed_slope_kernel(&w, &g, &a),
        want,
    )
}

/// `Wᵀ·g`: each output `from_acc` of zero accumulating `mac` over the rows in order.
fn column_sums<const IN: usize, const OUT: usize>(
    w: &[[Q16; IN]; OUT],
    g: &[Q16; OUT],
) -> [Q16; IN] {
    let mut sums = [Q16::ZERO.to_acc(); IN];
    for (row, &gj) in w.iter().zip(g) {
        for (sum, &wji) in sums.iter_mut().zip(row) {
            *sum = Q16::mac(*sum, wji, gj);
        }
    }
    sums.map(Q16::from_acc)
}

/// `δᵢ · a′(aᵢ)` for every neuron: the chain rule through the activation.
fn through_slope<const N: usize>(mut delta: [Q16; N], a: &[Q16; N]) -> [Q16; N] {
    for (d, &ai) in delta.iter_mut().zip(a) {
        *d = Q16::times_slope(*d, ai);
    }
    delta
}

/// Marsaglia's xorshift32: the same inputs on host and target from the same seed.
struct Xorshift(u32);

impl Xorshift {
    fn next(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    /// A value in `0..bound` (`bound` > 0; 0 otherwise).
    fn below(&mut self, bound: i32) -> i32 {
        let bound = bound.max(1) as u32;
        (self.next() % bound) as i32
    }
}

/// The `f32` single-point kernels (x86-64 with AVX2) against their contracts, bit for bit, on
/// the inputs of the `f32` lane kernels' check: zeros of both signs, saturation, infinities,
/// NaN and subnormals, then seeded random values.
mod f32_kernels {
    use super::lane_kernels::Sample;
    use super::{KernelMismatch, Kernels, Xorshift};
    use crate::implicit::Activation;
    use crate::scalar::Scalar;

    /// Every `f32` single-point kernel of the layer shapes the models use (N = 9: a leaf's
    /// 9×3, 9×9 and 1×9 layers and their transposes, a node's 9×21 layer and the parts of its
    /// transpose) on `cases` inputs; how many kernel calls ran and matched.
    #[inline(never)]
    pub(super) fn check(seed: u32, cases: u32) -> Result<u32, KernelMismatch> {
        let mut random = Xorshift(seed | 1);
        let mut checked = 0;
        for case in 0..cases {
            let mut draw = |scale: f32| f32::value(case, scale, &mut random);
            checked += layer::<9, 9>("f32 layer 9x9", case, &mut draw)?;
            checked += layer::<3, 9>("f32 layer 9x3", case, &mut draw)?;
            checked += layer::<9, 1>("f32 layer 1x9", case, &mut draw)?;
            let all = (0, false);
            checked += transposed::<9, 9, 9>("f32 transposed 9x9", case, all, &mut draw)?;
            checked += transposed::<3, 9, 3>("f32 transposed 9x3", case, all, &mut draw)?;
            let slope = (0, true);
            checked += transposed::<9, 9, 9>("f32 transposed_slope 9x9", case, slope, &mut draw)?;
            checked += transposed::<9, 1, 9>("f32 transposed_slope 1x9", case, slope, &mut draw)?;
            // A node's layer a′ (2N + 3 inputs) and the chain rule onto each child's part.
            checked += layer::<21, 9>("f32 layer 9x21", case, &mut draw)?;
            for first in [0, 9, 12] {
                let part = (first, true);
                let name = "f32 transposed_slope part 9x21";
                checked += transposed::<21, 9, 9>(name, case, part, &mut draw)?;
            }
        }
        Ok(checked)
    }

    fn same<const N: usize>(got: Option<[f32; N]>, want: &[f32; N]) -> Option<bool> {
        Some(got?.iter().zip(want).all(|(&a, &b)| f32::same(a, b)))
    }

    fn verdict(kernel: &'static str, case: u32, same: Option<bool>) -> Result<u32, KernelMismatch> {
        match same {
            None => Ok(0),
            Some(true) => Ok(1),
            Some(false) => Err(KernelMismatch { kernel, case }),
        }
    }

    fn layer<const IN: usize, const OUT: usize>(
        kernel: &'static str,
        case: u32,
        draw: &mut dyn FnMut(f32) -> f32,
    ) -> Result<u32, KernelMismatch> {
        let w: [[f32; IN]; OUT] = core::array::from_fn(|_| core::array::from_fn(|_| draw(4.0)));
        let b: [f32; OUT] = core::array::from_fn(|_| draw(4.0));
        let x: [f32; IN] = core::array::from_fn(|_| draw(2.0));
        let mut want = [0.0; OUT];
        for ((out, row), bias) in want.iter_mut().zip(&w).zip(&b) {
            let acc = row
                .iter()
                .zip(&x)
                .fold(bias.to_acc(), |acc, (&wi, &xi)| f32::mac(acc, wi, xi));
            *out = f32::activation_from_acc(acc);
        }
        let got = <f32 as Kernels>::layer_kernel(&w, &b, &x);
        verdict(kernel, case, same(got, &want))
    }

    /// Columns `first..first + COLUMNS` of a transpose with rows of `COUNT` weights, with
    /// the chain rule when `slope`: all columns through `transposed_kernel` or
    /// `transposed_slope_kernel`, a part of them through `transposed_part_kernel`.
    fn transposed<const COUNT: usize, const OUT: usize, const COLUMNS: usize>(
        kernel: &'static str,
        case: u32,
        (first, slope): (usize, bool),
        draw: &mut dyn FnMut(f32) -> f32,
    ) -> Result<u32, KernelMismatch> {
        let w: [[f32; COUNT]; OUT] = core::array::from_fn(|_| core::array::from_fn(|_| draw(4.0)));
        let g: [f32; OUT] = core::array::from_fn(|_| draw(8.0));
        // Activations lie within ±1.7159.
        let a: [f32; COLUMNS] = core::array::from_fn(|_| draw(1.7159));
        let mut want = [f32::ZERO.to_acc(); COLUMNS];
        for (row, &gj) in w.iter().zip(&g) {
            for (sum, &wi) in want.iter_mut().zip(row.iter().skip(first)) {
                *sum = f32::mac(*sum, wi, gj);
            }
        }
        for (out, &ai) in want.iter_mut().zip(&a) {
            *out = f32::from_acc(*out);
            if slope {
                *out = f32::times_slope(*out, ai);
            }
        }
        let got = if first == 0 && COLUMNS == COUNT {
            let all: Option<&[f32; COUNT]> = a.as_slice().try_into().ok();
            let got = match (slope, all) {
                (true, Some(a)) => <f32 as Kernels>::transposed_slope_kernel(&w, &g, a),
                (true, None) => None,
                (false, _) => <f32 as Kernels>::transposed_kernel(&w, &g),
            };
            got.and_then(|got| got.as_slice().try_into().ok())
        } else {
            <f32 as Kernels>::transposed_part_kernel(&w, first, &g, slope.then_some(&a))
        };
        verdict(kernel, case, same(got, &want))
    }
}

/// The lane kernels (x86-64 with AVX2: `f32` and Q16.16) against their contracts, bit for bit,
/// on layer shapes of every kind the models use (a leaf's 3 inputs, N = 9, a node's 9 + 9 + 3,
/// run-time widths, one row) and on inputs that reach every path: for `f32` zeros of both
/// signs, saturation, infinities, NaN and subnormals; for Q16.16 the extremes of `i32`, where
/// sums saturate and the activation table ends; then seeded random values.
mod lane_kernels {
    use super::{KernelMismatch, Kernels, Xorshift};
    use crate::arch::Lanes;
    use crate::scalar::{Q16, Scalar};

    /// A scalar whose lane kernels are checked: its inputs and its equality.
    pub(super) trait Sample: Scalar + Kernels {
        /// The kernels' names in a [`KernelMismatch`]: forward, transposed, transposed_slope.
        const NAMES: [&'static str; 3];
        /// One input of the case (see [`check`]), of magnitude below `scale` when random.
        fn value(case: u32, scale: f32, random: &mut Xorshift) -> Self;
        /// Whether the kernel's result stands for the contract's.
        fn same(a: Self, b: Self) -> bool;
    }

    impl Sample for f32 {
        const NAMES: [&'static str; 3] = [
            "f32 forward lanes",
            "f32 transposed lanes",
            "f32 transposed_slope lanes",
        ];
        /// Case 0 zeros of both signs, 1 and 2 huge values of either sign, 3 the smallest
        /// subnormals, 4 infinities and NaN among ordinary values; then random values, every
        /// other case scaled down by up to 2¹².
        fn value(case: u32, scale: f32, random: &mut Xorshift) -> f32 {
            let bits = random.next();
            let unit = (bits >> 8) as f32 / (1 << 24) as f32 * 2.0 - 1.0;
            match case {
                0 => f32::from_bits(bits & 0x8000_0000),
                1 => 1.0e30,
                2 => -3.0e38,
                3 => f32::from_bits((bits & 0x8000_0000) | 1),
                4 => match bits & 3 {
                    0 => f32::INFINITY,
                    1 => f32::NEG_INFINITY,
                    2 => f32::NAN,
                    _ => unit * scale,
                },
                _ if case.is_multiple_of(2) => unit * scale / (1 << (bits % 13)) as f32,
                _ => unit * scale,
            }
        }
        /// Equal bits, or both NaN: which NaN payload an operation with two NaN operands
        /// returns depends on the operand order the compiler chose for a commutative product,
        /// in the portable loop as much as in a kernel.
        fn same(a: f32, b: f32) -> bool {
            a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
        }
    }

    impl Sample for Q16 {
        const NAMES: [&'static str; 3] = [
            "q16.16 forward lanes",
            "q16.16 transposed lanes",
            "q16.16 transposed_slope lanes",
        ];
        /// Case 0 zeros, 1 and 2 the largest values of either sign (sums saturate, the
        /// activation leaves its table), 3 one step of either sign, 4 any `i32`; then random
        /// values: every third of any magnitude, the others below `scale`, half of those
        /// scaled down by up to 2¹².
        fn value(case: u32, scale: f32, random: &mut Xorshift) -> Q16 {
            let bits = random.next();
            let unit = (bits >> 8) as f32 / (1 << 24) as f32 * 2.0 - 1.0;
            let random_bits = (unit * scale * 65536.0) as i32;
            Q16::from_bits(match case {
                0 => 0,
                1 => i32::MAX,
                2 => i32::MIN,
                3 => {
                    if bits & 1 == 0 {
                        1
                    } else {
                        -1
                    }
                }
                4 => bits as i32,
                // Any magnitude: sums near every power of two, the saturation bound included.
                _ if case.is_multiple_of(3) => (random.next() as i32) >> (bits % 24),
                _ if case.is_multiple_of(2) => random_bits >> (bits % 13),
                _ => random_bits,
            })
        }
        fn same(a: Q16, b: Q16) -> bool {
            a == b
        }
    }

    /// Rows and inputs of the largest layer checked.
    const ROWS: usize = 16;
    const INPUTS: usize = 35;

    /// Lane groups per neuron checked: one, and the wide kernels' (`f32` only; Q16.16
    /// declines them).
    const GROUPS: [usize; 2] = [1, 4];
    const MAX_GROUPS: usize = 4;

    /// (rows, the three input parts' lengths) of the forward layers checked.
    const FORWARD: [(usize, [usize; 3]); 8] = [
        (9, [3, 0, 0]),
        (9, [9, 0, 0]),
        (1, [9, 0, 0]),
        (9, [9, 9, 3]),
        (4, [4, 4, 3]),
        (5, [7, 0, 0]),
        (16, [16, 16, 3]),
        (2, [1, 0, 0]),
    ];

    /// (rows, inputs per row, first column, columns) of the transposed layers checked.
    const TRANSPOSED: [(usize, usize, usize, usize); 8] = [
        (9, 9, 0, 9),
        (9, 3, 0, 3),
        (1, 9, 0, 9),
        (9, 21, 0, 9),
        (9, 21, 9, 9),
        (9, 21, 18, 3),
        (16, 35, 16, 16),
        (5, 7, 2, 4),
    ];

    /// Every lane kernel of `S` on `cases` inputs (edge cases 0 to 4, then random ones drawn
    /// from `seed`); how many kernel calls ran and matched.
    #[inline(never)]
    pub(super) fn check<S: Sample>(seed: u32, cases: u32) -> Result<u32, KernelMismatch> {
        let mut random = Xorshift(seed | 1);
        let mut checked = 0;
        let [forward_name, transposed_name, slope_name] = S::NAMES;
        for case in 0..cases {
            let mut draw = |scale: f32| S::value(case, scale, &mut random);
            for groups in GROUPS {
                for (rows, parts) in FORWARD {
                    checked += forward(forward_name, case, (rows, parts, groups), &mut draw)?;
                }
                for shape in TRANSPOSED {
                    let shape = (shape, groups);
                    checked += transposed(transposed_name, case, shape, false, &mut draw)?;
                    checked += transposed(slope_name, case, shape, true, &mut draw)?;
                }
            }
        }
        Ok(checked)
    }

    fn lanes<S: Sample>(draw: &mut dyn FnMut(f32) -> S, scale: f32) -> Lanes<S> {
        core::array::from_fn(|_| draw(scale))
    }

    fn same<S: Sample>(a: &[Lanes<S>], b: &[Lanes<S>]) -> bool {
        a.iter()
            .flatten()
            .zip(b.iter().flatten())
            .all(|(&x, &y)| S::same(x, y))
    }

    /// The neuron of a part of `groups` lane groups per neuron: entry `k·groups + group`.
    fn neuron<S: Sample>(
        part: &[Lanes<S>],
        (k, groups, group): (usize, usize, usize),
        lane: usize,
    ) -> S {
        part.get(k * groups + group)
            .and_then(|lanes| lanes.get(lane))
            .copied()
            .unwrap_or(S::ZERO)
    }

    fn forward<S: Sample>(
        kernel: &'static str,
        case: u32,
        (rows, parts, groups): (usize, [usize; 3], usize),
        draw: &mut dyn FnMut(f32) -> S,
    ) -> Result<u32, KernelMismatch> {
        let count: usize = parts.iter().sum();
        let weights: [S; ROWS * INPUTS] = core::array::from_fn(|_| draw(4.0));
        let biases: [S; ROWS] = core::array::from_fn(|_| draw(4.0));
        let x: [Lanes<S>; INPUTS * MAX_GROUPS] = core::array::from_fn(|_| lanes(draw, 2.0));
        let mut want = [[S::ZERO; 8]; ROWS * MAX_GROUPS];
        let mut got = [[S::ZERO; 8]; ROWS * MAX_GROUPS];
        let (Some(w), Some(b), Some(x), Some(want), Some(got)) = (
            weights.get(..rows * count),
            biases.get(..rows),
            x.get(..count * groups),
            want.get_mut(..rows * groups),
            got.get_mut(..rows * groups),
        ) else {
            return Ok(0);
        };
        let (x0, rest) = x.split_at_checked(parts[0] * groups).unwrap_or((x, &[]));
        let (x1, x2) = rest
            .split_at_checked(parts[1] * groups)
            .unwrap_or((rest, &[]));
        for (j, (row, &bias)) in w.chunks_exact(count).zip(b).enumerate() {
            for group in 0..groups {
                let Some(out) = want.get_mut(j * groups + group) else {
                    return Ok(0);
                };
                for (lane, out) in out.iter_mut().enumerate() {
                    let inputs = (0..parts[0]).map(|k| neuron(x0, (k, groups, group), lane));
                    let inputs = inputs
                        .chain((0..parts[1]).map(|k| neuron(x1, (k, groups, group), lane)))
                        .chain((0..parts[2]).map(|k| neuron(x2, (k, groups, group), lane)));
                    let acc = row
                        .iter()
                        .zip(inputs)
                        .fold(bias.to_acc(), |acc, (&w, x)| S::mac(acc, w, x));
                    *out = S::activation_from_acc(acc);
                }
            }
        }
        if !S::forward_lanes_kernel(w, b, [x0, x1, x2], groups, got) {
            return Ok(0);
        }
        if same(got, want) {
            Ok(1)
        } else {
            Err(KernelMismatch { kernel, case })
        }
    }

    fn transposed<S: Sample>(
        kernel: &'static str,
        case: u32,
        ((rows, count, first, columns), groups): ((usize, usize, usize, usize), usize),
        slope: bool,
        draw: &mut dyn FnMut(f32) -> S,
    ) -> Result<u32, KernelMismatch> {
        let weights: [S; ROWS * INPUTS] = core::array::from_fn(|_| draw(4.0));
        let g: [Lanes<S>; ROWS * MAX_GROUPS] = core::array::from_fn(|_| lanes(draw, 8.0));
        // Activations lie within ±1.7159.
        let a: [Lanes<S>; INPUTS * MAX_GROUPS] = core::array::from_fn(|_| lanes(draw, 1.7159));
        let mut want = [[S::ZERO; 8]; INPUTS * MAX_GROUPS];
        let mut got = [[S::ZERO; 8]; INPUTS * MAX_GROUPS];
        let (Some(w), Some(g), Some(a), Some(want), Some(got)) = (
            weights.get(..rows * count),
            g.get(..rows * groups),
            a.get(..columns * groups),
            want.get_mut(..columns * groups),
            got.get_mut(..columns * groups),
        ) else {
            return Ok(0);
        };
        for c in 0..columns {
            for group in 0..groups {
                let Some(out) = want.get_mut(c * groups + group) else {
                    return Ok(0);
                };
                for (lane, out) in out.iter_mut().enumerate() {
                    let acc = w.chunks_exact(count).enumerate().fold(
                        S::ZERO.to_acc(),
                        |acc, (j, row)| {
                            let w = row.get(first + c).copied().unwrap_or(S::ZERO);
                            S::mac(acc, w, neuron(g, (j, groups, group), lane))
                        },
                    );
                    *out = S::from_acc(acc);
                    if slope {
                        *out = S::times_slope(*out, neuron(a, (c, groups, group), lane));
                    }
                }
            }
        }
        let ran = if slope {
            S::transposed_slope_lanes_kernel(w, count, (first, columns), (g, groups), a, got)
        } else {
            S::transposed_lanes_kernel(w, count, (first, columns), (g, groups), got)
        };
        if !ran {
            return Ok(0);
        }
        if same(got, want) {
            Ok(1)
        } else {
            Err(KernelMismatch { kernel, case })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the host only the lane kernels and the `f32` single-point kernels can run (x86-64
    /// with AVX2): every one of them matches its contract, and nothing is checked where they cannot run. The Q16.16 chain rule
    /// declines lanes outside its fast range (the edge cases), for the portable loop to take.
    #[test]
    fn the_host_kernels_match_their_contracts() {
        let runs = <f32 as Kernels>::LANE_KERNELS && neurosurf_avx2::available();
        // Every shape, for one lane group and for the wide ones.
        let expected = if runs { 64 * 2 * (8 + 2 * 8) } else { 0 };
        assert_eq!(lane_kernels::check::<f32>(1, 64), Ok(expected));
        // One point's width-9 layers: the 9×9, 9×3 and 9×21 forward layers, the 9×9
        // transpose, both chain-rule transposes and three nine-column parts of a node's (the
        // 1×9 layer and the 9×3 transpose stay portable).
        let single = <f32 as Kernels>::TARGET_KERNELS && neurosurf_avx2::available();
        let expected = if single { 64 * 9 } else { 0 };
        assert_eq!(f32_kernels::check(1, 64), Ok(expected));
        let checked = lane_kernels::check::<Q16>(1, 64).expect("Q16.16 lane kernels");
        if runs {
            // Every forward and plain transposed call, and the chain rule on most random cases.
            assert!(checked >= 64 * (8 + 8) + 30 * 8, "{checked} checked");
        } else {
            assert_eq!(checked, 0);
        }
        assert!(check_kernels(7, 16).is_ok());
    }

    /// The inputs cover both signs and both ends of their range.
    #[test]
    fn the_inputs_reach_both_ends() {
        let mut random = Xorshift(7);
        let values: [i32; 64] = core::array::from_fn(|c| input(c as u32, 8, &mut random));
        assert!(values.contains(&(8 << 16)) && values.contains(&-(8 << 16)));
        assert!(values.iter().any(|&v| v > 0 && v < 1 << 16));
        assert!(values.iter().any(|&v| v < 0 && v > -(1 << 16)));
    }
}

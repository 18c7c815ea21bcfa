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

#[cfg(test)]
mod tests {
    use super::*;

    /// On the host there are no kernels: nothing is checked and nothing fails.
    #[test]
    fn the_host_has_no_kernels_to_check() {
        assert_eq!(check_kernels(1, 20), Ok(0));
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

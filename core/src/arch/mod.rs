//! The one seam between the portable core and target-specific speed-ups, in the manner of
//! libm's `math/arch/`: the layer loops ask a scalar's [`Kernels`] whether a kernel covers a
//! shape, and the answer comes from the one module chosen below — the Cortex-M4F assembly of
//! `neurosurf-m4f` (`m4f.rs`), or none at all (`portable.rs`). Every kernel computes exactly
//! the bits of the loop it replaces, so the choice changes speed, never a result.
//!
//! [`Kernels`] is a supertrait of [`crate::scalar::Scalar`] that users cannot name: it is not
//! part of the public API.

use crate::scalar::Q16;

pub mod kernel_check;

/// Chooses the kernels' module: the target conditions, written once.
macro_rules! select_target {
    ($m4f:item $x86_64:item $portable:item) => {
        #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
        $m4f
        #[cfg(target_arch = "x86_64")]
        $x86_64
        #[cfg(not(any(
            all(target_arch = "arm", target_abi = "eabihf", target_os = "none"),
            target_arch = "x86_64"
        )))]
        $portable
    };
}

// "Use the portable loop" for every kernel: what a target module has no kernel for, it takes
// from here.
#[allow(dead_code)]
mod portable;

select_target! {
    #[path = "m4f.rs"]
    mod target;
    #[path = "x86_64.rs"]
    mod target;
    use portable as target;
}

/// One neuron of a lane group: [`crate::implicit::LANES`] points.
pub(crate) type Lanes<S = f32> = [S; crate::implicit::LANES];

/// Target kernels and lane counts of a scalar. Each `*_kernel` returns `None` (or `false`)
/// for "use the portable loop"; what it returns otherwise is exactly that loop's bits.
pub trait Kernels: Sized + Copy {
    /// Whether this scalar has kernels on the machine compiled for, for some shapes; the layer
    /// loops only ask when it does.
    const TARGET_KERNELS: bool;
    /// How many points of a field batch go through the layers together, in structure-of-arrays
    /// lanes: 1 or [`crate::implicit::LANES`], whichever is cheaper per point on the machine
    /// compiled for (other values mean [`crate::implicit::LANES`]). Never changes a result:
    /// every lane computes exactly what a single point does.
    const LANE_GROUP: usize;
    /// `LANE_GROUP` for field-and-gradient batches at a width compiled as a constant
    /// ([`crate::implicit::SPECIALIZED_WIDTHS`]), whose backward pass keeps four layers per
    /// module alive. At other widths `LANE_GROUP` applies: loops with run-time bounds amortize
    /// their set-up over the lanes.
    const GRADIENT_LANE_GROUP: usize;
    /// `LANE_GROUP` for field batches at the width the target kernels are written for, N = 9
    /// (`crate::dense::KERNEL_WIDTH`).
    const KERNEL_WIDTH_LANE_GROUP: usize = Self::LANE_GROUP;

    /// A whole forward layer (W row-major, one row per output): output j is
    /// `activation_from_acc` of the bias accumulating `mac` over the inputs in order.
    /// (Q16.16 on a Cortex-M4F: the width-9 layers, whose rounding and table lookup the kernel
    /// does too.)
    #[inline(always)]
    fn layer_kernel<const IN: usize, const OUT: usize>(
        w: &[[Self; IN]; OUT],
        b: &[Self; OUT],
        x: &[Self; IN],
    ) -> Option<[Self; OUT]> {
        let _ = (w, b, x);
        None
    }
    /// `Wᵀ·g`: each output `from_acc` of `ZERO.to_acc()` accumulating `mac` over the rows in
    /// order. (Q16.16 on a Cortex-M4F: the 9×3 transpose.)
    #[inline(always)]
    fn transposed_kernel<const IN: usize, const OUT: usize>(
        w: &[[Self; IN]; OUT],
        g: &[Self; OUT],
    ) -> Option<[Self; IN]> {
        let _ = (w, g);
        None
    }
    /// `times_slope` on every pair `(delta[i], a[i])`; `false`, with `delta` unchanged, means
    /// "use the portable loop". (Q16.16 on a Cortex-M4F: N = 9.)
    #[inline(always)]
    fn times_slope_kernel<const N: usize>(delta: &mut [Self; N], a: &[Self; N]) -> bool {
        let _ = (delta, a);
        false
    }
    /// `transposed_kernel` followed by `times_slope` on each output with `a[i]`. (Q16.16 on a
    /// Cortex-M4F: the 9×9 and 1×9 transposes of the backward pass, the chain rule on the
    /// column sums while they are in registers.)
    #[inline(always)]
    fn transposed_slope_kernel<const IN: usize, const OUT: usize>(
        w: &[[Self; IN]; OUT],
        g: &[Self; OUT],
        a: &[Self; IN],
    ) -> Option<[Self; IN]> {
        let _ = (w, g, a);
        None
    }

    /// Whether this scalar's single-point kernels also take a node's layer a′ at N = 9 (its
    /// 2N + 3 inputs in three parts, offered to `layer_kernel` joined) and the transposes onto
    /// each child's part of it (`transposed_part_kernel`); the layer loops only offer them when
    /// it does.
    const NODE_KERNELS: bool = false;
    /// `transposed_slope_kernel` onto the columns `first..first + COLUMNS` of rows of `COUNT`
    /// weights: with `a`, each output times the activation's slope at `a[c]`; `None` means
    /// "use the portable loop". (`f32` on x86-64 with AVX2: nine columns of a node's a′.)
    #[inline(always)]
    fn transposed_part_kernel<const COUNT: usize, const OUT: usize, const COLUMNS: usize>(
        w: &[[Self; COUNT]; OUT],
        first: usize,
        g: &[Self; OUT],
        a: Option<&[Self; COLUMNS]>,
    ) -> Option<[Self; COLUMNS]> {
        let _ = (w, first, g, a);
        None
    }

    /// Whether this scalar has kernels for whole lane groups ([`crate::implicit::LANES`]
    /// points in structure-of-arrays form, or several such groups per neuron) on the machine
    /// compiled for; the layer loops only ask when it does.
    const LANE_KERNELS: bool = false;

    /// A forward layer for `groups` lane groups (W row-major, one row of the concatenated
    /// `inputs` per output; each neuron `groups` lane groups side by side): output j is
    /// `activation_from_acc` of the bias accumulating `mac` over the inputs in order, lane by
    /// lane; `false`, with `out` unwritten, means "use the portable loop". (`f32` and Q16.16
    /// on x86-64 with AVX2; Q16.16 for one group only.)
    #[inline(always)]
    fn forward_lanes_kernel(
        weights: &[Self],
        biases: &[Self],
        inputs: [&[Lanes<Self>]; 3],
        groups: usize,
        out: &mut [Lanes<Self>],
    ) -> bool {
        let _ = (weights, biases, inputs, groups, out);
        false
    }
    /// Columns `first..first + columns` of `Wᵀ·g` for `g.1` lane groups per neuron (W has
    /// `count` columns, one row per neuron of `g.0`): each output `from_acc` of
    /// `ZERO.to_acc()` accumulating `mac` over the rows in order; `false`, with `out`
    /// unwritten, means "use the portable loop".
    #[inline(always)]
    fn transposed_lanes_kernel(
        weights: &[Self],
        count: usize,
        columns: (usize, usize),
        g: (&[Lanes<Self>], usize),
        out: &mut [Lanes<Self>],
    ) -> bool {
        let _ = (weights, count, columns, g, out);
        false
    }
    /// `transposed_lanes_kernel` followed by `times_slope` on output c with `outputs[c]`;
    /// `false`, with `out` unspecified, means "use the portable loop" (Q16.16 declines lanes
    /// outside the chain rule's fast range after it has written some of `out`).
    #[inline(always)]
    fn transposed_slope_lanes_kernel(
        weights: &[Self],
        count: usize,
        columns: (usize, usize),
        g: (&[Lanes<Self>], usize),
        outputs: &[Lanes<Self>],
        out: &mut [Lanes<Self>],
    ) -> bool {
        let _ = (weights, count, columns, g, outputs, out);
        false
    }
}

/// No single-point kernels on the Cortex-M4F, where the portable loops cost fewer estimated
/// cycles than assembly layer products (`docs/performance/kernels.md`); on x86-64 with AVX2,
/// one point's width-9 layers with the neurons side by side (`neurosurf-avx2`).
impl Kernels for f32 {
    const TARGET_KERNELS: bool = target::F32_TARGET_KERNELS;
    /// Eight `f32` accumulators (and their inputs) fit the FPU's 32 registers.
    const LANE_GROUP: usize = 8;
    /// On 64-bit hosts the lanes vectorize: 32 on x86-64 (four groups of eight per neuron,
    /// see `x86_64.rs`), eight elsewhere. One on 32-bit targets: on the Cortex-M4F
    /// the backward pass's eight-lane layers (288 bytes each) are zeroed and copied in memory,
    /// and with N = 9 compiled in, point by point costs fewer estimated cycles (measured: 2 675
    /// vs 2 863 per point for the N = 9 leaf, 15 710 vs 17 510 for the three-leaf head) and
    /// less than half the stack. (At run-time widths eight lanes stay cheaper: width 16, 4356
    /// vs 6397 instructions.)
    const GRADIENT_LANE_GROUP: usize = if cfg!(target_pointer_width = "64") {
        target::F32_HOST_LANES
    } else {
        1
    };
    /// As `GRADIENT_LANE_GROUP` on 64-bit hosts; one on 32-bit targets: on the Cortex-M4F eight lanes of the N = 9
    /// head cost more estimated cycles per point than one (11 084 against 10 780; the leaf
    /// alone is even, 1 859 against 1 862) and 5 KiB more stack.
    const KERNEL_WIDTH_LANE_GROUP: usize = Self::GRADIENT_LANE_GROUP;
    /// On x86-64: the AVX2 layers of `neurosurf-avx2`, when the processor has AVX2.
    const LANE_KERNELS: bool = target::F32_LANE_KERNELS;

    #[inline(always)]
    fn forward_lanes_kernel(
        weights: &[f32],
        biases: &[f32],
        inputs: [&[Lanes]; 3],
        groups: usize,
        out: &mut [Lanes],
    ) -> bool {
        target::f32_forward_lanes(weights, biases, inputs, groups, out)
    }
    #[inline(always)]
    fn transposed_lanes_kernel(
        weights: &[f32],
        count: usize,
        columns: (usize, usize),
        g: (&[Lanes], usize),
        out: &mut [Lanes],
    ) -> bool {
        target::f32_transposed_lanes(weights, count, columns, g, out)
    }
    #[inline(always)]
    fn transposed_slope_lanes_kernel(
        weights: &[f32],
        count: usize,
        columns: (usize, usize),
        g: (&[Lanes], usize),
        outputs: &[Lanes],
        out: &mut [Lanes],
    ) -> bool {
        target::f32_transposed_slope_lanes(weights, count, columns, g, outputs, out)
    }

    const NODE_KERNELS: bool = target::F32_TARGET_KERNELS;
    #[inline(always)]
    fn transposed_part_kernel<const COUNT: usize, const OUT: usize, const COLUMNS: usize>(
        w: &[[f32; COUNT]; OUT],
        first: usize,
        g: &[f32; OUT],
        a: Option<&[f32; COLUMNS]>,
    ) -> Option<[f32; COLUMNS]> {
        target::f32_transposed(w, first, g, a)
    }
    #[inline(always)]
    fn layer_kernel<const IN: usize, const OUT: usize>(
        w: &[[f32; IN]; OUT],
        b: &[f32; OUT],
        x: &[f32; IN],
    ) -> Option<[f32; OUT]> {
        target::f32_layer(w, b, x)
    }
    #[inline(always)]
    fn transposed_kernel<const IN: usize, const OUT: usize>(
        w: &[[f32; IN]; OUT],
        g: &[f32; OUT],
    ) -> Option<[f32; IN]> {
        target::f32_transposed(w, 0, g, None)
    }
    #[inline(always)]
    fn transposed_slope_kernel<const IN: usize, const OUT: usize>(
        w: &[[f32; IN]; OUT],
        g: &[f32; OUT],
        a: &[f32; IN],
    ) -> Option<[f32; IN]> {
        target::f32_transposed(w, 0, g, Some(a))
    }
}

impl Kernels for Q16 {
    const TARGET_KERNELS: bool = neurosurf_m4f::AVAILABLE;
    /// One on 32-bit targets: a 64-bit accumulator takes two of the Cortex-M4's 13 general
    /// registers, so even two lanes spill (measured for the N = 9 leaf's field and gradient: 2
    /// lanes cost 6 % more per point than one, 8 lanes 21 % more). Eight on 64-bit hosts, where
    /// an accumulator is one register and the lanes vectorize.
    const LANE_GROUP: usize = if cfg!(target_pointer_width = "64") {
        8
    } else {
        1
    };
    /// As `LANE_GROUP`.
    const GRADIENT_LANE_GROUP: usize = Self::LANE_GROUP;
    /// On x86-64: the AVX2 lanes of `neurosurf-avx2`, when the processor has AVX2.
    const LANE_KERNELS: bool = target::Q16_LANE_KERNELS;

    #[inline(always)]
    fn forward_lanes_kernel(
        weights: &[Q16],
        biases: &[Q16],
        inputs: [&[Lanes<Q16>]; 3],
        groups: usize,
        out: &mut [Lanes<Q16>],
    ) -> bool {
        groups == 1 && target::q16_forward_lanes(weights, biases, inputs, out)
    }
    #[inline(always)]
    fn transposed_lanes_kernel(
        weights: &[Q16],
        count: usize,
        columns: (usize, usize),
        (g, groups): (&[Lanes<Q16>], usize),
        out: &mut [Lanes<Q16>],
    ) -> bool {
        groups == 1 && target::q16_transposed_lanes(weights, count, columns, g, None, out)
    }
    #[inline(always)]
    fn transposed_slope_lanes_kernel(
        weights: &[Q16],
        count: usize,
        columns: (usize, usize),
        (g, groups): (&[Lanes<Q16>], usize),
        outputs: &[Lanes<Q16>],
        out: &mut [Lanes<Q16>],
    ) -> bool {
        groups == 1 && target::q16_transposed_lanes(weights, count, columns, g, Some(outputs), out)
    }

    #[inline(always)]
    fn layer_kernel<const IN: usize, const OUT: usize>(
        w: &[[Q16; IN]; OUT],
        b: &[Q16; OUT],
        x: &[Q16; IN],
    ) -> Option<[Q16; OUT]> {
        target::q16_layer(w, b, x, &crate::scalar::activation_table::SEGMENTS)
    }
    #[inline(always)]
    fn transposed_kernel<const IN: usize, const OUT: usize>(
        w: &[[Q16; IN]; OUT],
        g: &[Q16; OUT],
    ) -> Option<[Q16; IN]> {
        target::q16_transposed(w, g)
    }
    #[inline(always)]
    fn times_slope_kernel<const N: usize>(delta: &mut [Q16; N], a: &[Q16; N]) -> bool {
        use crate::scalar::q16::{SLOPE_OFFSET, SLOPE_SQUARE, finish_times_slope};
        let Some(slow) = target::q16_times_slope(delta, a, SLOPE_OFFSET, SLOPE_SQUARE) else {
            return false;
        };
        finish_times_slope(delta, a, slow);
        true
    }
    #[inline(always)]
    fn transposed_slope_kernel<const IN: usize, const OUT: usize>(
        w: &[[Q16; IN]; OUT],
        g: &[Q16; OUT],
        a: &[Q16; IN],
    ) -> Option<[Q16; IN]> {
        use crate::scalar::q16::{SLOPE_OFFSET, SLOPE_SQUARE, finish_times_slope};
        let (mut delta, slow) = target::q16_transposed_slope(w, g, a, SLOPE_OFFSET, SLOPE_SQUARE)?;
        finish_times_slope(&mut delta, a, slow);
        Some(delta)
    }
}

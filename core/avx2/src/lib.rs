//! # neurosurf-avx2
//!
//! The layers of `neurosurf-core`'s implicit modules for eight points at once (in `f32` also
//! for four such lane groups per neuron, 32 points, so that each weight serves four
//! independent sums), written with
//! x86-64 AVX2 intrinsics and chosen at run time, in `f32` (`lanes.rs`: the forward layer with
//! its activation, the transposed layer, the transposed layer fused with the chain rule through
//! the activation) and in Q16.16 (`fixed_lanes.rs`: the same three, with exact 64-bit sums and
//! the core's activation table); and one point's width-9 `f32` layers with its nine neurons
//! side by side (`single.rs`: the forward layer, and the transposed layer onto nine inputs,
//! with or without the chain rule). On a processor without AVX2, and on every other target, each
//! function returns `false` and the core runs its portable loops; on other targets the crate is
//! empty but for [`AVAILABLE`] and [`available`].
//!
//! **Same bits as the portable loops.** Every lane computes exactly the operations of the
//! core's portable code, in the same order: in `f32` the IEEE-754 operations, none fused (AVX2
//! has no fused multiply–add; FMA is a separate feature this crate never enables); in Q16.16
//! the exact products and wrapping 64-bit sums, the round-half-up and saturation of `from_acc`,
//! the table lookup of the activation, and the chain rule's rounded high words (lanes outside
//! its fast range make the kernel decline). The core's kernel check
//! (`neurosurf_core::kernel_check`) compares each function with its contract, and the
//! simulator tests compare the host's batches with the Cortex-M4F's portable results bit for
//! bit.
//!
//! **Safety.** The unsafe code is in the three kernel modules: the calls into functions compiled
//! with `#[target_feature(enable = "avx2")]`, made only after run-time detection has found
//! AVX2; unaligned loads and stores of eight-lane arrays through references, so the lengths
//! read and written are fixed by the types; and the Q16.16 table's gathers, whose indices are
//! clamped to the table's checked length. Every slice index is checked before the unsafe code
//! runs: a function whose slices do not fit its shape returns `false` (or `None`).
//!
//! Layouts are the core's: `weights` is row-major, one row of `inputs` weights per output
//! neuron; a point set is structure-of-arrays, one eight-lane array per neuron or input, lane
//! `k` being point `k`.
#![no_std]
#![deny(unsafe_code)]
#![warn(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

/// Points per lane group: one 256-bit register of `f32`.
pub const LANES: usize = 8;

/// Lane groups per neuron that the width-9 kernels are also compiled for: each neuron 32
/// points, four groups of eight side by side.
pub const WIDE_GROUPS: usize = 4;

/// One neuron (or input) of eight points.
pub type Lanes = [f32; LANES];

/// The activation a(H) = A·(2^u − 1)/(2^u + 1), u = H·`u_per_h`, exactly as the core computes
/// it in `f32` (`scalar/activation_f32.rs`, the branch-free form): the core passes its
/// constants, so that they are written once.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Activation {
    /// u per unit of H.
    pub u_per_h: f32,
    /// |u| from which ±A is returned (a NaN H returns itself).
    pub saturation: f32,
    /// 1.5·2²³: `u + rounder` holds u rounded to an integer in its low mantissa bits.
    pub rounder: f32,
    /// 2^r ≈ 1 + r·(c₁ + r·(c₂ + … + r·c₆)), c₁ first.
    pub polynomial: [f32; 6],
    /// A.
    pub amplitude: f32,
}

/// The chain rule through the activation: δ·(offset − square·(a·a)), a the neuron's output.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Slope {
    /// a′ at a = 0.
    pub offset: f32,
    /// The factor of a².
    pub square: f32,
}

#[cfg(target_arch = "x86_64")]
mod fixed_lanes;
#[cfg(target_arch = "x86_64")]
mod lanes;
#[cfg(target_arch = "x86_64")]
pub mod single;

#[cfg(target_arch = "x86_64")]
pub use fixed_lanes::{FixedLanes, FixedSlope, FixedTable, fixed_forward, fixed_transposed};

#[cfg(target_arch = "x86_64")]
pub use lanes::{available, forward, transposed, transposed_slope};

/// Whether the processor running has AVX2: never, off x86-64.
#[cfg(not(target_arch = "x86_64"))]
pub fn available() -> bool {
    false
}

/// Whether this target has the kernels at all (x86-64); [`available`] then says whether the
/// processor running has AVX2.
pub const AVAILABLE: bool = cfg!(target_arch = "x86_64");

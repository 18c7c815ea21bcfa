//! # neurosurf-m4f
//!
//! The Q16.16 layers of `neurosurf-core`'s width-9 implicit modules, written for the
//! Cortex-M4F's integer multiply–accumulate in inline assembly: the forward layers, the
//! transposes with the chain rule, and the chain rule alone. On every other target this crate is
//! empty and the core runs its portable loops.
//!
//! Only kernels that beat the portable loops by at least 10 % in the simulator's estimated
//! cycles (the Cortex-M4 TRM's timings, `docs/target.md`) are here
//! (`docs/performance/kernels.md`). `f32` has none: its portable loop is three instructions per
//! multiply–accumulate (`vldr` 2 cycles + `vmul` 1 + `vadd` 1), and a `vldmia` + non-fused
//! `vmla` kernel is not cheaper per product (`vmla` 3 + a ninth of `vldmia`'s 1 + 9) while it
//! has to save the FPU registers it uses (Rust 1.96 refuses FPU register operands on this
//! target), so such kernels were 7–25 % slower. The input normalization (nine products) has
//! none either: it saved at most 1.5 %.
//!
//! **Same bits as the portable loops.** Every function computes exactly what the core's
//! portable code does for its shape: the simulator tests compare the target's results with the
//! host's portable ones (`tests/tests/simulator.rs`) and require them equal bit for bit.
//!
//! **Safety.** Each function takes references to fixed-size arrays, so the lengths the assembly
//! reads are fixed by the types. The assembly reads through those pointers and writes exactly
//! the result buffer it then returns (a `MaybeUninit` every element of which it stores). The
//! blocks declare every general register they change, save r6, r7 and r11 (which Rust does not
//! let them declare on every ARM target) on the stack for their duration when they use them
//! (`q16_layer_9x9` also keeps its biases and pre-activations in 72 bytes below them, the fused
//! 9×9 transpose its constants and mask in 16, sp staying 8-byte aligned), and change the APSR
//! flags; `q16_times_slope_9` updates its `&mut` array in place. That is the whole unsafe
//! surface, in one module.
//!
//! The kernels are compiled for bare-metal hard-float ARM (`target_arch = "arm"`,
//! `target_abi = "eabihf"`, `target_os = "none"`: the Cortex-M4F/M7 targets); their
//! instruction counts are the M4F's.
//!
//! The kernels (`fixed_layers.rs`, `I16F16` in and out; `W` is row-major, one row per output
//! neuron, as in the core's parameter layout): every product an `smull` / `smlal` into
//! a 64-bit accumulator (exact: the same sum as the portable `i64` loop), every sum rounded like
//! the core's `Scalar::from_acc` (add 2¹⁵, shift by 16, saturate, the saturation out of line)
//! or, before an activation, clamped to ±10, where the table has saturated.
//!
//! - The forward layers (`q16_layer_9x9`, `q16_layer_9x3`, `q16_layer_1x9`) are exactly the
//!   core's `activation_from_acc` per output. The 9×9 holds the nine inputs in r0–r8 and reads
//!   two weights per `ldm`, each row starting from its bias as a pre-rounded Q32.32 pair; the
//!   activation reads the table's (value, rise) segment by H's signed integer part, 7
//!   instructions a neuron (see the core's `activation_table.rs` for why that gives the
//!   symmetric interpolation's bits). The 9×3 activates each row as it is summed; the 1×9 (the
//!   output neuron) reuses each input's register for a later weight once its product is done.
//! - The backward pass fuses each transpose with the chain rule δ·a′ on its sums
//!   (`q16_transposed_slope_9x9`, `q16_transposed_slope_1x9`, the core's
//!   `Kernels::transposed_slope_kernel`): the 9×9 reads two columns at once, one `ldrd` of two
//!   weights per row with g₀…g₄ and then g₅…g₈ in registers, and tests the slope's fast range
//!   (−2 ≤ a < 2, −2¹³ ≤ t < 2¹³) on the accumulator's high word, so that path needs no saturation
//!   test. A neuron outside it keeps its rounded sum and comes back in a mask, which the core
//!   finishes on its portable saturating path. `q16_transposed_9x3` (back through a leaf's
//!   first layer) reads columns 0 and 1 the same way.
//! - `q16_times_slope_9` is the chain rule alone on nine neurons, for node modules, whose
//!   transposes have no kernel: the slope from the neuron's output and the product, each a
//!   rounded high word (`smmulr`), 14 instructions a neuron with the constants in registers.
//!
//! Instructions per call on the torus leaf (the simulator's profile, field + gradient):
//!
//! | function | computes | multiply–accumulates | instructions |
//! |---|---|---:|---:|
//! | `q16_layer_9x9` | a(b + W·x), W 9×9 | 81 | 318 |
//! | `q16_transposed_slope_9x9` | times_slope(round(Wᵀ·g), a), W 9×9 | 81 (+ 27 products) | 309 |
//! | `q16_layer_9x3` | a(b + W·x), W 9×3 | 27 | 198 |
//! | `q16_transposed_slope_1x9` | times_slope(round(wᵀ·g), a), w 1×9 | 9 (+ 27 products) | 140 |
//! | `q16_transposed_9x3` | round(Wᵀ·g), W 9×3 | 27 | 85 |
//! | `q16_layer_1x9` | a(b + w·x), w 1×9 | 9 | 42 |
//! | `q16_times_slope_9` | δᵢ ← round(δᵢ·a′(aᵢ)), 9 neurons (node modules) | (27 products) | 127 (from the source) |
//!
//! The simulator tests hold the Q16.16 kernels to the host's bits too, including a model built
//! so that every column of its transposes saturates, at both ends, and every pre-activation
//! is clamped; two models built so that the chain rule's δ leaves the fast range without
//! saturating, so that its fallback changes the result — a leaf (the fused 9×9 transpose) and
//! a node module's children (`q16_times_slope_9`).
#![no_std]
#![deny(unsafe_code)]
#![deny(missing_docs)]

#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
mod fixed_layers;

#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
pub use fixed_layers::{
    ActivationTable, q16_layer_1x9, q16_layer_9x3, q16_layer_9x9, q16_times_slope_9,
    q16_transposed_9x3, q16_transposed_slope_1x9, q16_transposed_slope_9x9,
};

/// Whether this build has the kernels (bare-metal hard-float ARM: the Cortex-M4F/M7 targets).
pub const AVAILABLE: bool = cfg!(all(
    target_arch = "arm",
    target_abi = "eabihf",
    target_os = "none"
));

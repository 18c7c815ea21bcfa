//! # neurosurf-m4f
//!
//! The dense-layer products of `neurosurf-core`'s width-9 implicit modules, written for the
//! Cortex-M4F's single-precision FPU (FPv4-SP) in inline assembly, and the Q16.16 layers,
//! transposes with the chain rule, and input normalization for its integer multiply–accumulate. On every other target this crate is
//! empty and the core runs its portable loops.
//!
//! Why assembly: the portable loop compiles to three instructions per multiply–accumulate on the
//! M4F (`vldr` of the weight, `vmul`, `vadd`), because LLVM neither merges the weight loads into
//! `vldm` nor, for this core, emits `vmla`. Here a row of nine weights is one `vldmia` and each
//! product one `vmla.f32`: with the loads, stores and the register save, about 1.2 instructions
//! per multiply–accumulate. By the simulator's cycle estimate (the Cortex-M4 TRM's
//! timings, `docs/target.md`) that is not a win: a multiply–accumulate costs about the same
//! either way (`vldr` 2 + `vmul` 1 + `vadd` 1 against `vmla` 3 + a ninth of `vldmia`'s 1 + 9),
//! and every kernel also saves and restores up to 28 FPU registers (`vpush`/`vpop`, 1 + n cycles
//! each), so the f32 kernels cost more estimated cycles than the portable loops
//! (`docs/performance/kernels.md`); that save goes away once the firmware's compiler accepts FPU
//! register operands (see `layers.rs`).
//!
//! **Same bits as the portable loops.** `vmla.f32` is the *non-fused* multiply–accumulate:
//! `d = d + round(n·m)` with two roundings, exactly `acc + w * x` in Rust (`vfma`, the fused
//! one, would not be). Every function sums in the order the core's portable kernels do: a
//! forward row starts at its bias and adds inputs 0, 1, …; a transposed column starts at +0.0 and
//! adds rows 0, 1, …. The simulator tests compare the target's results with the host's portable
//! ones (`tests/tests/simulator.rs`) and require them equal bit for bit.
//!
//! **Safety.** Each function takes references to fixed-size arrays, so the lengths the assembly
//! reads are fixed by the types. The assembly reads through those pointers, writes exactly the
//! result buffer it then returns (a `MaybeUninit` every element of which it stores), pushes and
//! pops 88–112 bytes of stack, restores every FPU register it uses, and changes only the FPSCR's
//! sticky exception flags (so no block claims `preserves_flags`). The Q16.16 blocks declare every
//! general register they change, save r6, r7 and r11 (which Rust does not let them declare on
//! every ARM target) on the stack for their duration when they use them (`q16_layer_9x9` also
//! keeps its biases and pre-activations in 72 bytes below them, the fused 9×9 transpose its
//! constants and mask in 16, sp staying 8-byte aligned), and change the APSR flags;
//! `q16_times_slope_9` updates its `&mut` array in place. That is the whole unsafe surface,
//! in two modules.
//!
//! The kernels are compiled for bare-metal hard-float ARM (`target_arch = "arm"`,
//! `target_abi = "eabihf"`, `target_os = "none"`: the Cortex-M4F/M7 targets); their bits are
//! those of any VFP (every VFP `vmla` is non-fused), their instruction counts are the M4F's.
//!
//! Shapes (`W` is row-major, one row per output neuron, as in the core's parameter layout;
//! instructions counted from the source, the register save included):
//!
//! | function | computes | multiply–accumulates | instructions |
//! |---|---|---:|---:|
//! | `affine_9x9` | `b + W·x`, W 9×9 | 81 | 95 |
//! | `affine_9x3` | `b + W·x`, W 9×3 | 27 | 41 |
//! | `affine_1x9` | `b + w·x`, w 1×9 | 9 | 15 |
//! | `transposed_9x9` | `Wᵀ·g`, W 9×9 | 81 | 95 |
//! | `transposed_9x3` | `Wᵀ·g`, W 9×3 | 27 | 41 |
//! | `transposed_1x9` | `wᵀ·g`, w 1×9 | 9 | 15 |
//!
//! **Q16.16** (`fixed_layers.rs`, `I16F16` in and out): every product an `smull` / `smlal` into
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
//! - `q16_normalize` is a leaf's input normalization x′ = A·(x − c) (`qsub`, three rows).
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
//! | `q16_normalize` | round(A·(x − c)) | 9 | 46 |
//! | `q16_layer_1x9` | a(b + w·x), w 1×9 | 9 | 42 |
//! | `q16_times_slope_9` | δᵢ ← round(δᵢ·a′(aᵢ)), 9 neurons (node modules) | (27 products) | 127 (from the source) |
//!
//! The simulator tests hold the Q16.16 kernels to the host's bits too, including a model built
//! so that every column of its transposes saturates, at both ends, and every pre-activation
//! is clamped; two models built so that the chain rule's δ leaves the fast range without
//! saturating, so that its fallback changes the result — a leaf (the fused 9×9 transpose) and
//! a node module's children (`q16_times_slope_9`); and a model whose normalized input
//! saturates where it shows in Φ (row 0; rows 1 and 2 share its code).
#![no_std]
#![deny(unsafe_code)]
#![deny(missing_docs)]

#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
mod fixed_layers;
#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
mod layers;

#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
pub use fixed_layers::{
    ActivationTable, q16_layer_1x9, q16_layer_9x3, q16_layer_9x9, q16_normalize, q16_times_slope_9,
    q16_transposed_9x3, q16_transposed_slope_1x9, q16_transposed_slope_9x9,
};
#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
pub use layers::{
    affine_1x9, affine_9x3, affine_9x9, transposed_1x9, transposed_9x3, transposed_9x9,
};

/// Whether this build has the kernels (bare-metal hard-float ARM: the Cortex-M4F/M7 targets).
pub const AVAILABLE: bool = cfg!(all(
    target_arch = "arm",
    target_abi = "eabihf",
    target_os = "none"
));

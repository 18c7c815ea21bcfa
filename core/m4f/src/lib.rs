//! # neurosurf-m4f
//!
//! The dense-layer products of `neurosurf-core`'s width-9 implicit modules, written for the
//! Cortex-M4F's single-precision FPU (FPv4-SP) in inline assembly, and the Q16.16 hidden layers,
//! transposes and chain rule for its integer multiply–accumulate. On every other target this crate is
//! empty and the core runs its portable loops.
//!
//! Why assembly: the portable loop compiles to three instructions per multiply–accumulate on the
//! M4F (`vldr` of the weight, `vmul`, `vadd`), because LLVM neither merges the weight loads into
//! `vldm` nor, for this core, emits `vmla`. Here a row of nine weights is one `vldmia` and each
//! product one `vmla.f32`: with the loads, stores and the register save, about 1.2 instructions
//! per multiply–accumulate. What is measured (by the simulator) is instructions; cycles are
//! not. By the Cortex-M4 TRM's figures a multiply–accumulate costs about the same either way
//! (`vldr` 2 + `vmul` 1 + `vadd` 1 against `vmla` 3 + a ninth of `vldmia`'s 1 + 9), but every
//! kernel also saves and restores up to 28 FPU registers (`vpush`/`vpop`, 1 + n cycles each), so
//! the cycle count is probably somewhat *worse*; that save goes away once the firmware's compiler
//! accepts FPU register operands (see `layers.rs`).
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
//! every ARM target) with lr on the stack for their duration (the layer kernels also keep their
//! nine pre-activations in 40 bytes below them, sp staying 8-byte aligned), and change the APSR
//! flags; `q16_times_slope_9` updates its `&mut` array in place and uses no stack. That is the
//! whole unsafe surface, in two modules.
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
//! **Q16.16** (`fixed_layers.rs`, `I16F16` in and out): the three transposes, rounded like the
//! core's `Scalar::from_acc` (add 2¹⁵, shift by 16, saturate), which is what the core's
//! backward pass does with each of them. The nine values of g sit in r0–r8, so each product is
//! one `ldr` of the weight at a constant offset and one `smull` / `smlal` into a 64-bit
//! accumulator (exact: the same sum as the portable `i64` loop), and a column's rounding is six
//! instructions with its saturation out of line. The two hidden forward layers are whole
//! kernels (`q16_layer_9x9`, `q16_layer_9x3`): the inputs in r0–r8, each row its bias, the
//! weights two at a time by `ldm` (three for the 3-input rows) and an `smlal` per product, the
//! rounding and a clamp to ±10 (where the table has saturated) onto the stack; then each
//! neuron's table interpolation with the constants in registers, 14 instructions — exactly the
//! core's `activation_from_acc`.
//!
//! | function | computes | multiply–accumulates | instructions |
//! |---|---|---:|---:|
//! | `q16_transposed_9x9` | `round(Wᵀ·g)`, W 9×9 | 81 | 239 |
//! | `q16_transposed_9x3` | `round(Wᵀ·g)`, W 9×3 | 27 | 83 |
//! | `q16_transposed_1x9` | `round(wᵀ·g)`, w 1×9 (−2 ≤ g < 2: one `smmulr` each) | 9 | 44 |
//! | `q16_times_slope_9` | δᵢ ← round(δᵢ·a′(aᵢ)), 9 neurons | (27 products) | 127 |
//! | `q16_layer_9x9` | a(b + W·x), W 9×9 | 81 | 361 |
//! | `q16_layer_9x3` | a(b + W·x), W 9×3 | 27 | 271 |
//!
//! `q16_times_slope_9` is the core's `Scalar::times_slope` for Q16.16 on nine neurons: the
//! slope from the neuron's output and the product, each a rounded high word (`smmulr`), 14
//! instructions a neuron with the constants in registers. It covers the fast range
//! (−2 ≤ a < 2, −2¹³ ≤ δ < 2¹³, one combined test) and returns a mask of the neurons outside
//! it, which the core finishes on its portable saturating path.
//!
//! The simulator tests hold the Q16.16 kernels to the host's bits too, including a model built
//! so that every column of its 9×9 and 9×3 transposes saturates, at both ends (the 1×9
//! transpose multiplies by one g and cannot saturate within the loader's parameter bound), and
//! a model built so that the chain rule's δ leaves the slope kernel's fast range without
//! saturating, so its fallback changes the result.
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

//! # neurosurf-m4f
//!
//! The dense-layer products of `neurosurf-core`'s width-9 implicit modules, written for the
//! Cortex-M4F's single-precision FPU (FPv4-SP) in inline assembly. On every other target this
//! crate is empty and the core runs its portable loops.
//!
//! Why assembly: the portable loop compiles to three instructions per multiply–accumulate on the
//! M4F (`vldr` of the weight, `vmul`, `vadd`), because LLVM neither merges the weight loads into
//! `vldm` nor, for this core, emits `vmla`. Here a row of nine weights is one `vldmia` and each
//! product one `vmla.f32`, about 1.1 instructions per multiply–accumulate. (The M4's TRM gives
//! `vmla` 3 cycles where a `vmul`–`vadd` pair with its `vldr` takes about as many, so the cycle
//! count does not get worse; the instruction count, which the simulator measures, halves.)
//!
//! **Same bits as the portable loops.** `vmla.f32` is the *non-fused* multiply–accumulate:
//! `d = d + round(n·m)` with two roundings, exactly `acc + w * x` in Rust (`vfma`, the fused
//! one, would not be). Every function sums in the order the core's portable kernels do: a
//! forward row starts at its bias and adds inputs 0, 1, …; a transposed column starts at +0.0 and
//! adds rows 0, 1, …. The simulator tests compare the target's results with the host's portable
//! ones (`tests/tests/simulator.rs`) and find them equal bit for bit.
//!
//! **Safety.** Each function takes references to fixed-size arrays, so the lengths the assembly
//! reads are guaranteed by the types; the assembly writes no memory (results come back in
//! registers) and touches no flags or stack. That is the whole unsafe surface.
//!
//! Shapes (`W` is row-major, one row per output neuron, as in the core's parameter layout):
//!
//! | function | computes | multiply–accumulates | instructions |
//! |---|---|---:|---:|
//! | `affine_9x9` | `b + W·x`, W 9×9 | 81 | 91 |
//! | `affine_9x3` | `b + W·x`, W 9×3 | 27 | 37 |
//! | `affine_1x9` | `b + w·x`, w 1×9 | 9 | 10 |
//! | `transposed_9x9` | `Wᵀ·g`, W 9×9 | 81 | 91 |
//! | `transposed_9x3` | `Wᵀ·g`, W 9×3 | 27 | 37 |
//! | `transposed_1x9` | `wᵀ·g`, w 1×9 | 9 | 11 |
#![no_std]
#![deny(unsafe_code)]
#![deny(missing_docs)]

#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
mod layers;

#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
pub use layers::{
    affine_1x9, affine_9x3, affine_9x9, transposed_1x9, transposed_9x3, transposed_9x9,
};

/// Whether this build has the kernels (a Cortex-M4F-class hard-float ARM target).
pub const AVAILABLE: bool = cfg!(all(target_arch = "arm", target_abi = "eabihf"));

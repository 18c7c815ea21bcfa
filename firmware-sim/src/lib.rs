//! Runs `neurosurf-core` on a simulated Cortex-M4F.
//!
//! Placeholder until the simulator lands (issue 3): the crate exists so the workspace has its
//! final shape. It exposes the target description the simulator will be built for.

/// The simulated machine: QEMU's `mps2-an386` board, a Cortex-M4 with FPU.
pub const TARGET_MACHINE: &str = "mps2-an386";
/// The Rust target the firmware is built for.
pub const TARGET_TRIPLE: &str = "thumbv7em-none-eabihf";

//! Runs `neurosurf-core` on a simulated Cortex-M4F and measures it there.
//!
//! The firmware in `firmware-sim/firmware/` is the unmodified core compiled for
//! `thumbv7em-none-eabihf` (Debian's Rust with `-Zbuild-std=core`) and linked for a common
//! M4F budget (1 MiB flash, 192 KiB RAM). This crate is its host side:
//!
//! - [`Toolchain`]: finds the Debian toolchain and the unpacked QEMU (under the ignored
//!   `.tools/`), or names what is missing and `firmware-sim/scripts/setup.sh`, which installs
//!   it idempotently;
//! - [`Firmware`]: builds the firmware once (cargo caches it in `target/firmware`) and reads
//!   its ELF: marker addresses, flash and static RAM;
//! - [`Simulator`]: one QEMU run per [`Job`] — writes the blob and the points, launches
//!   `qemu-system-arm -M mps2-an386` under a time limit, decodes the defmt log with
//!   `defmt-decoder`, and returns the raw result words with the instruction count of every
//!   evaluation (a TCG plugin, [`plugin`]);
//! - [`build_elf`] and [`run_program`]: the same build and QEMU run for any firmware crate that
//!   needs no request, such as the example in `examples/cortex-m/`, returning its defmt log.
//!
//! ```no_run
//! use neurosurf_firmware_sim::{Job, Simulator};
//! use neurosurf_core::scalar::ScalarKind;
//! # fn main() -> Result<(), neurosurf_firmware_sim::SimError> {
//! let simulator = Simulator::prepare()?;
//! let blob = std::fs::read("torus-q16.16.nsb").unwrap();
//! let run = simulator.run(&Job::field_gradient(&blob, ScalarKind::Q16_16, &[[0.5, 0.0, 0.1]]))?;
//! println!("{:?} in {} instructions per point", run.samples()[0], run.instructions_per_point());
//! # Ok(()) }
//! ```

mod error;
mod firmware;
mod log;
pub mod plugin;
mod qemu;
mod simulator;
mod toolchain;

pub use error::SimError;
pub use firmware::{Firmware, Footprint, build_elf};
pub use neurosurf_sim_protocol::{Mode, Op, Status};
pub use qemu::run_program;
pub use simulator::{Job, Run, Simulator};
pub use toolchain::Toolchain;

/// The simulated machine: QEMU's `mps2-an386` board, a Cortex-M4 with FPU.
pub const TARGET_MACHINE: &str = "mps2-an386";
/// The Rust target the firmware is built for.
pub const TARGET_TRIPLE: &str = "thumbv7em-none-eabihf";

/// The repository root (this crate's parent folder): where the firmware sources, the setup
/// script and the ignored `.tools/` and `target/` folders are.
pub fn repository_root() -> std::path::PathBuf {
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().unwrap_or(manifest).to_path_buf()
}

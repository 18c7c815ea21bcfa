//! Builds the simulator's firmware exactly as the tests do (the same flags and target folder,
//! so they reuse it), and prints its footprint: `scripts/test.sh` runs this first, so a core
//! that does not build for `thumbv7em-none-eabihf` shows before any test starts.
//!
//! Run: `cargo run -p neurosurf-firmware-sim --example build_firmware`.

use std::process::ExitCode;

use neurosurf_firmware_sim::{Firmware, Toolchain, repository_root};

fn main() -> ExitCode {
    let root = repository_root();
    match Toolchain::find(&root).and_then(|toolchain| Firmware::build(&toolchain, &root)) {
        Ok(firmware) => {
            let f = firmware.footprint;
            println!(
                "{}: flash {} of {} bytes, static RAM {} of {} bytes",
                firmware.elf.display(),
                f.flash_bytes,
                f.flash_budget,
                f.static_ram_bytes,
                f.ram_budget
            );
            ExitCode::SUCCESS
        }
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::FAILURE
        }
    }
}

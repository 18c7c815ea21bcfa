//! The Cortex-M toolchain: Debian's Rust 1.96 with its library sources (so `-Zbuild-std=core`
//! works without rustup), `ld.lld`, and `qemu-system-arm` unpacked under `.tools/qemu`.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::SimError;

/// Paths of the tools the simulator needs.
#[derive(Clone, Debug)]
pub struct Toolchain {
    /// Debian's `cargo` (not rustup's, which ignores `build-std` on stable).
    pub cargo: PathBuf,
    /// Debian's `rustc`, whose sysroot has the `core` sources.
    pub rustc: PathBuf,
    /// The linker named in the firmware's `.cargo/config.toml`.
    pub linker: PathBuf,
    /// `qemu-system-arm`.
    pub qemu: PathBuf,
    /// A C compiler for the instruction-counting plugin.
    pub cc: PathBuf,
}

const RUST_SOURCES: &str = "/usr/lib/rustlib/src/rust/library/core";

impl Toolchain {
    /// The expected locations under repository `root` (QEMU may be overridden with the
    /// `NEUROSURF_QEMU` environment variable).
    pub fn expected(root: &Path) -> Self {
        let qemu = std::env::var_os("NEUROSURF_QEMU")
            .map(PathBuf::from)
            .unwrap_or_else(|| root.join(".tools/qemu/usr/bin/qemu-system-arm"));
        Toolchain {
            cargo: PathBuf::from("/usr/bin/cargo"),
            rustc: PathBuf::from("/usr/bin/rustc"),
            linker: PathBuf::from("/usr/lib/llvm-22/bin/ld.lld"),
            qemu,
            cc: PathBuf::from("gcc"),
        }
    }

    /// What is missing, if anything.
    pub fn missing(&self) -> Vec<String> {
        let mut missing = Vec::new();
        for path in [&self.cargo, &self.rustc, &self.linker, &self.qemu] {
            if !path.exists() {
                missing.push(path.display().to_string());
            }
        }
        if !Path::new(RUST_SOURCES).exists() {
            missing.push(format!("{RUST_SOURCES} (rust-web-src)"));
        }
        missing
    }

    /// The toolchain, installing what is missing with `firmware-sim/scripts/setup.sh` (apt
    /// and an unpacked QEMU; safe to repeat).
    ///
    /// # Errors
    /// [`SimError::Setup`] when something is still missing after the script ran.
    pub fn ensure(root: &Path) -> Result<Self, SimError> {
        let toolchain = Self::expected(root);
        if toolchain.missing().is_empty() {
            return Ok(toolchain);
        }
        let script = root.join("firmware-sim/scripts/setup.sh");
        let output = Command::new("bash")
            .arg(&script)
            .output()
            .map_err(|e| SimError::Setup(format!("cannot run {}: {e}", script.display())))?;
        let still_missing = toolchain.missing();
        if !output.status.success() || !still_missing.is_empty() {
            return Err(SimError::Setup(format!(
                "{} failed ({}); missing: {}\n{}{}",
                script.display(),
                output.status,
                still_missing.join(", "),
                String::from_utf8_lossy(&output.stdout),
                String::from_utf8_lossy(&output.stderr)
            )));
        }
        Ok(toolchain)
    }
}

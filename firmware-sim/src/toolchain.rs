//! The Cortex-M toolchain: Debian's Rust 1.96 with its library sources (so `-Zbuild-std=core`
//! works without rustup), `ld.lld`, and `qemu-system-arm` unpacked under `.tools/qemu`.

use std::path::{Path, PathBuf};

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

    /// The toolchain, when every part of it is installed. Nothing is installed from here:
    /// `firmware-sim/scripts/setup.sh` does that (apt and an unpacked QEMU; safe to repeat),
    /// and the test command `scripts/test.sh` runs it first.
    ///
    /// # Errors
    /// [`SimError::Setup`] naming what is missing and the command that installs it.
    pub fn find(root: &Path) -> Result<Self, SimError> {
        Self::expected(root).checked(root)
    }

    /// This toolchain when nothing is missing, else the error [`Toolchain::find`] gives.
    fn checked(self, root: &Path) -> Result<Self, SimError> {
        let missing = self.missing();
        if missing.is_empty() {
            return Ok(self);
        }
        Err(SimError::Setup(format!(
            "the simulated Cortex-M4F needs {}; install it with `{}` (or run the whole test \
             command, `scripts/test.sh`, which does)",
            missing.join(", "),
            root.join("firmware-sim/scripts/setup.sh").display()
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_tool_is_named_with_the_command_that_installs_it() {
        let root = Path::new("/nonexistent/neurosurf");
        let mut toolchain = Toolchain::expected(root);
        toolchain.qemu = root.join(".tools/qemu/usr/bin/qemu-system-arm");
        let Err(SimError::Setup(message)) = toolchain.checked(root) else {
            panic!("a toolchain without QEMU was accepted");
        };
        assert!(message.contains("qemu-system-arm"), "{message}");
        assert!(
            message.contains("firmware-sim/scripts/setup.sh"),
            "{message}"
        );
    }
}

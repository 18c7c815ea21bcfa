//! Building the firmware and reading its ELF.

use std::path::{Path, PathBuf};
use std::process::Command;

use neurosurf_sim_protocol::{REGION_START_SYMBOL, REGION_STOP_SYMBOL};
use object::{Object, ObjectSection, ObjectSymbol, SectionFlags};

use crate::{SimError, TARGET_TRIPLE, Toolchain};

/// Where RAM starts on the target (Cortex-M SRAM region).
const RAM_ORIGIN: u64 = 0x2000_0000;

/// Memory the firmware occupies, against the budget it is linked for.
#[derive(Copy, Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Footprint {
    /// Bytes of flash: vector table, code, read-only data and `.data` initializers.
    pub flash_bytes: u64,
    /// Flash the firmware is linked for (`memory.x`).
    pub flash_budget: u64,
    /// Bytes of statically allocated RAM (`.data`, `.bss`, `.uninit`).
    pub static_ram_bytes: u64,
    /// RAM the firmware is linked for (`memory.x`); the stack gets what statics leave.
    pub ram_budget: u64,
}

/// A `--remap-path-prefix` flag as a TOML string, mapping `from` to `to`.
fn remap(from: &Path, to: &str) -> String {
    toml_string(&format!("--remap-path-prefix={}={to}", from.display()))
}

/// `text` as a TOML basic string.
fn toml_string(text: &str) -> String {
    format!("\"{}\"", text.replace('\\', "\\\\").replace('"', "\\\""))
}

/// Cargo's home (its registry sources are compiled into the firmware).
fn cargo_home() -> Option<PathBuf> {
    std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|home| Path::new(&home).join(".cargo")))
}

/// The built firmware: its ELF and what the runner needs from it.
#[derive(Clone, Debug)]
pub struct Firmware {
    /// The ELF QEMU loads.
    pub elf: PathBuf,
    /// Entry address of the region-start marker.
    pub region_start: u64,
    /// Entry address of the region-stop marker.
    pub region_stop: u64,
    /// Memory use.
    pub footprint: Footprint,
    /// The whole ELF (the defmt decoder needs its tables).
    pub(crate) bytes: std::sync::Arc<Vec<u8>>,
}

impl Firmware {
    /// Builds the simulator's firmware under repository `root` (see [`build_elf`]; cargo caches
    /// it in `target/firmware`) and reads the result.
    ///
    /// # Errors
    /// [`SimError::Build`] with the compiler output; [`SimError::Elf`] when the result lacks
    /// the markers.
    pub fn build(toolchain: &Toolchain, root: &Path) -> Result<Self, SimError> {
        Self::build_with(toolchain, root, "target/firmware", &[])
    }

    /// As [`Firmware::build`], with the core's Cortex-M4F kernels named in `portable` turned
    /// off (`--cfg neurosurf_portable="<kernel>"`, see the core's `src/arch/m4f.rs`): the
    /// portable loops they replace run instead, with the same results. Built in
    /// `target/firmware-portable`, which each call with other kernels rebuilds.
    ///
    /// # Errors
    /// As [`Firmware::build`].
    pub fn build_portable(
        toolchain: &Toolchain,
        root: &Path,
        portable: &[&str],
    ) -> Result<Self, SimError> {
        let flags: Vec<String> = portable
            .iter()
            .map(|kernel| format!("--cfg=neurosurf_portable=\"{kernel}\""))
            .collect();
        Self::build_with(toolchain, root, "target/firmware-portable", &flags)
    }

    /// Builds the firmware into `target_dir` (relative to `root`) with extra rustc `flags`.
    fn build_with(
        toolchain: &Toolchain,
        root: &Path,
        target_dir: &str,
        flags: &[String],
    ) -> Result<Self, SimError> {
        let source = root.join("firmware-sim/firmware");
        let target_dir = root.join(target_dir);
        let elf = build_elf_flags(
            toolchain,
            root,
            &source,
            &target_dir,
            "neurosurf-firmware",
            flags,
        )?;
        let memory = std::fs::read_to_string(source.join("memory.x"))
            .map_err(SimError::io(source.join("memory.x")))?;
        Self::read(&elf, &memory)
    }

    /// Reads a built firmware ELF, with the `memory.x` it was linked with.
    ///
    /// # Errors
    /// [`SimError::Io`], [`SimError::Elf`].
    pub fn read(elf: &Path, memory_x: &str) -> Result<Self, SimError> {
        let bytes = std::fs::read(elf).map_err(SimError::io(elf))?;
        let bad = |reason: String| SimError::Elf {
            path: elf.to_path_buf(),
            reason,
        };
        let file = object::File::parse(&*bytes).map_err(|e| bad(e.to_string()))?;
        let symbol = |name: &str| {
            file.symbols()
                .find(|s| s.name() == Ok(name))
                .map(|s| s.address() & !1)
                .ok_or_else(|| bad(format!("no symbol {name}")))
        };
        let (region_start, region_stop) =
            (symbol(REGION_START_SYMBOL)?, symbol(REGION_STOP_SYMBOL)?);
        let (mut flash_bytes, mut static_ram_bytes) = (0, 0);
        for section in file.sections() {
            let SectionFlags::Elf { sh_flags } = section.flags() else {
                continue;
            };
            const SHF_ALLOC: u64 = 0x2;
            if sh_flags & SHF_ALLOC == 0 {
                continue;
            }
            let in_ram = section.address() >= RAM_ORIGIN;
            let has_bytes = section.file_range().is_some();
            if in_ram {
                static_ram_bytes += section.size();
            }
            if !in_ram || has_bytes {
                // .data lives in RAM but its initializers are loaded from flash.
                flash_bytes += section.size();
            }
        }
        Ok(Firmware {
            elf: elf.to_path_buf(),
            region_start,
            region_stop,
            footprint: Footprint {
                flash_bytes,
                flash_budget: memory_length(memory_x, "FLASH")
                    .ok_or_else(|| bad("memory.x has no FLASH length".into()))?,
                static_ram_bytes,
                ram_budget: memory_length(memory_x, "RAM")
                    .ok_or_else(|| bad("memory.x has no RAM length".into()))?,
            },
            bytes: std::sync::Arc::new(bytes),
        })
    }
}

/// Builds the firmware crate in `source` (a cargo workspace of its own whose
/// `.cargo/config.toml` names the target, the linker and `build-std`) in release with the
/// Debian toolchain into `target_dir`, and returns the ELF of its binary `binary`. A no-op when
/// nothing changed. The repository `root` and cargo's home are remapped out of the image
/// (to `/neurosurf` and `/cargo`), so it does not depend on where they are.
///
/// # Errors
/// [`SimError::Build`] with the compiler output.
pub fn build_elf(
    toolchain: &Toolchain,
    root: &Path,
    source: &Path,
    target_dir: &Path,
    binary: &str,
) -> Result<PathBuf, SimError> {
    build_elf_flags(toolchain, root, source, target_dir, binary, &[])
}

/// [`build_elf`] with extra rustc `flags`.
fn build_elf_flags(
    toolchain: &Toolchain,
    root: &Path,
    source: &Path,
    target_dir: &Path,
    binary: &str,
    flags: &[String],
) -> Result<PathBuf, SimError> {
    let mut command = Command::new(&toolchain.cargo);
    command
        .args(["build", "--release", "--quiet"])
        .current_dir(source);
    // The host build's environment (rustup's toolchain, the test harness's CARGO_* and
    // flags) must not leak into the Debian toolchain's cross build.
    for (key, _) in std::env::vars_os() {
        let key = key.to_string_lossy();
        let leaks = (key.starts_with("CARGO") && key != "CARGO_HOME")
            || key.starts_with("RUSTUP")
            || key.starts_with("RUSTC")
            || key.starts_with("RUSTFLAGS")
            || key.starts_with("RUSTDOC");
        if leaks {
            command.env_remove(key.as_ref());
        }
    }
    // Paths end up in the image (panic locations of dependencies); without remapping, the
    // flash size and the committed instruction table would depend on where the repository
    // and cargo's registry happen to live.
    let mut remaps = vec![remap(root, "/neurosurf")];
    if let Some(home) = cargo_home() {
        remaps.push(remap(&home, "/cargo"));
    }
    remaps.extend(flags.iter().map(|flag| toml_string(flag)));
    command.arg("--config").arg(format!(
        "target.{TARGET_TRIPLE}.rustflags=[{}]",
        remaps.join(", ")
    ));
    command
        .env("RUSTC", &toolchain.rustc)
        .env("RUSTC_BOOTSTRAP", "1")
        .env("CARGO_TARGET_DIR", target_dir);
    let output = command.output().map_err(|e| SimError::Build {
        what: "the firmware",
        output: format!("cannot run {}: {e}", toolchain.cargo.display()),
    })?;
    if !output.status.success() {
        return Err(SimError::Build {
            what: "the firmware",
            output: String::from_utf8_lossy(&output.stderr).into_owned(),
        });
    }
    Ok(target_dir.join(TARGET_TRIPLE).join("release").join(binary))
}

/// The `LENGTH` of `region` in a `memory.x` (`1M`, `192K` or plain bytes).
fn memory_length(memory_x: &str, region: &str) -> Option<u64> {
    let line = memory_x
        .lines()
        .find(|line| line.split_whitespace().next() == Some(region))?;
    let value = line
        .split("LENGTH")
        .nth(1)?
        .trim_start_matches([' ', '='])
        .trim();
    let value = value.trim_end_matches(|c: char| c == ',' || c.is_whitespace());
    let (digits, unit) = value.split_at(
        value
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(value.len()),
    );
    let scale = match unit.trim() {
        "" => 1,
        "K" | "k" => 1024,
        "M" | "m" => 1024 * 1024,
        _ => return None,
    };
    digits.parse::<u64>().ok().map(|n| n * scale)
}

#[cfg(test)]
mod tests {
    use super::memory_length;

    #[test]
    fn memory_x_lengths_parse() {
        let text = "MEMORY\n{\n  FLASH : ORIGIN = 0x00000000, LENGTH = 1M\n  RAM   : ORIGIN = 0x20000000, LENGTH = 192K\n}\n";
        assert_eq!(memory_length(text, "FLASH"), Some(1 << 20));
        assert_eq!(memory_length(text, "RAM"), Some(192 * 1024));
        assert_eq!(memory_length(text, "CCM"), None);
    }
}

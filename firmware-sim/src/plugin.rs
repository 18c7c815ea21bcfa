//! The instruction-counting QEMU plugin (`firmware-sim/plugin/insn_count.c`), built with the
//! system C compiler into `target/firmware/` the first time it is needed.
//!
//! Debian's QEMU 7.2 accepts `-plugin` but ships neither plugins nor `qemu-plugin.h`; the
//! plugin declares the handful of API functions it uses. It prints one line per timed region:
//! `neurosurf-region <index> <instructions>` ([`parse_regions`]).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::{SimError, Toolchain};

/// Builds the plugin unless an up-to-date build exists; returns the shared library.
///
/// # Errors
/// [`SimError::Build`] with the compiler's output.
pub fn build(toolchain: &Toolchain, root: &Path) -> Result<PathBuf, SimError> {
    let source = root.join("firmware-sim/plugin/insn_count.c");
    let out_dir = root.join("target/firmware");
    let library = out_dir.join("insn_count.so");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if let (Some(lib), Some(src)) = (modified(&library), modified(&source))
        && lib >= src
    {
        return Ok(library);
    }
    std::fs::create_dir_all(&out_dir).map_err(SimError::io(&out_dir))?;
    // Concurrent test processes may build at once: compile to a private name, then rename.
    let partial = out_dir.join(format!("insn_count.so.{}.tmp", std::process::id()));
    let output = Command::new(&toolchain.cc)
        .args(["-O2", "-shared", "-fPIC", "-Wall", "-Wextra", "-o"])
        .arg(&partial)
        .arg(&source)
        .output()
        .map_err(|e| SimError::Build {
            what: "the instruction-counting plugin",
            output: format!("cannot run {}: {e}", toolchain.cc.display()),
        })?;
    if !output.status.success() {
        return Err(SimError::Build {
            what: "the instruction-counting plugin",
            output: String::from_utf8_lossy(&output.stderr).into_owned(),
        });
    }
    std::fs::rename(&partial, &library).map_err(SimError::io(&library))?;
    Ok(library)
}

/// The instruction counts of the plugin's region lines, in order.
///
/// # Errors
/// [`SimError::Protocol`] for a region line that does not parse or is out of order.
pub fn parse_regions(log: &str) -> Result<Vec<u64>, SimError> {
    let mut counts = Vec::new();
    for line in log.lines() {
        let Some(rest) = line.strip_prefix("neurosurf-region ") else {
            continue;
        };
        let mut fields = rest.split_whitespace().map(str::parse::<u64>);
        match (fields.next(), fields.next(), fields.next()) {
            (Some(Ok(index)), Some(Ok(count)), None) if index == counts.len() as u64 => {
                counts.push(count);
            }
            _ => return Err(SimError::Protocol(format!("bad plugin line {line:?}"))),
        }
    }
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::parse_regions;

    #[test]
    fn region_lines_parse_in_order_and_garbage_is_refused() {
        let log = "other\nneurosurf-region 0 9\nneurosurf-region 1 393587\n";
        assert_eq!(parse_regions(log).unwrap(), vec![9, 393_587]);
        assert!(parse_regions("neurosurf-region 1 5\n").is_err());
        assert!(parse_regions("neurosurf-region 0 x\n").is_err());
    }
}

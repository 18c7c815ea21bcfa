//! The instruction-counting QEMU plugin (`firmware-sim/plugin/insn_count.c`, with the
//! Cortex-M4 cycle table in `firmware-sim/plugin/m4_cycles.h`), built with the system C
//! compiler into `target/firmware/` the first time it is needed.
//!
//! Debian's QEMU 7.2 accepts `-plugin` but ships neither plugins nor `qemu-plugin.h`; the
//! plugin declares the handful of API functions it uses. It prints one line per timed region:
//! `neurosurf-region <index> <instructions> <estimated cycles>` ([`parse_regions`]).
//!
//! The cycles are an estimate: every executed instruction priced by the Cortex-M4 Technical
//! Reference Manual's timing tables (processor and FPU), plus a pipeline refill after every
//! taken branch, on zero-wait-state memory. QEMU models no timing; `m4_cycles.h` lists the
//! choices made where the manual gives a range.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::{SimError, Toolchain};

/// Builds the plugin unless an up-to-date build exists; returns the shared library.
///
/// # Errors
/// [`SimError::Build`] with the compiler's output.
pub fn build(toolchain: &Toolchain, root: &Path) -> Result<PathBuf, SimError> {
    let source = root.join("firmware-sim/plugin/insn_count.c");
    let table = root.join(CYCLE_TABLE);
    let out_dir = root.join("target/firmware");
    let library = out_dir.join("insn_count.so");
    let modified = |p: &Path| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    if let (Some(lib), Some(src), Some(tab)) =
        (modified(&library), modified(&source), modified(&table))
        && lib >= src
        && lib >= tab
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

/// The cycle table, relative to the repository root (a header of the plugin's).
const CYCLE_TABLE: &str = "firmware-sim/plugin/m4_cycles.h";

/// What the plugin measured in one timed region.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct RegionCount {
    /// Guest instructions executed.
    pub instructions: u64,
    /// Their estimated Cortex-M4 cycles (see the module documentation).
    pub cycles: u64,
}

/// The counts of the plugin's region lines, in order.
///
/// # Errors
/// [`SimError::Protocol`] for a region line that does not parse or is out of order.
pub fn parse_regions(log: &str) -> Result<Vec<RegionCount>, SimError> {
    let mut counts = Vec::new();
    for line in log.lines() {
        let Some(rest) = line.strip_prefix("neurosurf-region ") else {
            continue;
        };
        let mut fields = rest.split_whitespace().map(str::parse::<u64>);
        match (fields.next(), fields.next(), fields.next(), fields.next()) {
            (Some(Ok(index)), Some(Ok(instructions)), Some(Ok(cycles)), None)
                if index == counts.len() as u64 =>
            {
                counts.push(RegionCount {
                    instructions,
                    cycles,
                });
            }
            _ => return Err(SimError::Protocol(format!("bad plugin line {line:?}"))),
        }
    }
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::{CYCLE_TABLE, RegionCount, parse_regions};
    use crate::{Toolchain, repository_root};
    use std::process::Command;

    #[test]
    fn region_lines_parse_in_order_and_garbage_is_refused() {
        let log = "other\nneurosurf-region 0 9 14\nneurosurf-region 1 393587 501234\n";
        let count = |instructions, cycles| RegionCount {
            instructions,
            cycles,
        };
        assert_eq!(
            parse_regions(log).unwrap(),
            vec![count(9, 14), count(393_587, 501_234)]
        );
        assert!(parse_regions("neurosurf-region 1 5 5\n").is_err());
        assert!(parse_regions("neurosurf-region 0 x 5\n").is_err());
        assert!(parse_regions("neurosurf-region 0 5\n").is_err());
    }

    /// Encodings (first halfword, second halfword or none) with their disassembly, as
    /// `llvm-mc -triple=thumbv7em -mattr=+vfp4d16sp` writes them, and the cycles the TRM's
    /// tables give them (a taken branch's refill is added by the plugin, not here).
    const PRICES: &[(u16, Option<u16>, &str, u32)] = &[
        (0x1888, None, "adds r0, r1, r2", 1),
        (0x4348, None, "muls r0, r1, r0", 1),
        (0x6808, None, "ldr r0, [r1]", 2),
        (0x9001, None, "str r0, [sp, #4]", 2),
        (0x4801, None, "ldr r0, [pc, #4]", 2),
        (0xb5f0, None, "push {r4, r5, r6, r7, lr}", 6),
        (0xbd10, None, "pop {r4, pc}", 3),
        (0xc90c, None, "ldm r1!, {r2, r3}", 3),
        (0xd0fe, None, "beq .", 1),
        (0xe7fe, None, "b .", 1),
        (0x4770, None, "bx lr", 1),
        (0xbf08, None, "it eq", 1),
        (0xfb01, Some(0xf002), "mul r0, r1, r2", 1),
        (0xfb01, Some(0x3002), "mla r0, r1, r2, r3", 1),
        (0xfb81, Some(0x0102), "smull r0, r1, r1, r2", 1),
        (0xfbc2, Some(0x0103), "smlal r0, r1, r2, r3", 1),
        (0xfb91, Some(0xf0f2), "sdiv r0, r1, r2", 7),
        (0xfbb1, Some(0xf0f2), "udiv r0, r1, r2", 7),
        (0xf8d1, Some(0x0004), "ldr.w r0, [r1, #4]", 2),
        (0xf841, Some(0x0b04), "str r0, [r1], #4", 2),
        (0xe9d1, Some(0x2300), "ldrd r2, r3, [r1]", 3),
        (0xe8d0, Some(0xf001), "tbb [r0, r1]", 2),
        (0xe92d, Some(0x4ff0), "push.w {r4-r11, lr}", 10),
        (0xe8bd, Some(0x8ff0), "pop.w {r4-r11, pc}", 10),
        (0xf241, Some(0x2234), "movw r2, #0x1234", 1),
        (0xea4f, Some(0x0041), "lsl.w r0, r1, #1", 1),
        (0xf000, Some(0xb800), "b.w", 1),
        (0xf000, Some(0xf800), "bl", 1),
        (0xee30, Some(0x0a01), "vadd.f32 s0, s0, s2", 1),
        (0xee20, Some(0x0a01), "vmul.f32 s0, s0, s2", 1),
        (0xee00, Some(0x0a01), "vmla.f32 s0, s0, s2", 3),
        (0xeea0, Some(0x0a01), "vfma.f32 s0, s0, s2", 3),
        (0xee80, Some(0x0a01), "vdiv.f32 s0, s0, s2", 14),
        (0xeeb1, Some(0x0ac1), "vsqrt.f32 s0, s2", 14),
        (0xeeb1, Some(0x0a41), "vneg.f32 s0, s2", 1),
        (0xeeb8, Some(0x0ac0), "vcvt.f32.s32 s0, s0", 1),
        (0xeeb4, Some(0x0a41), "vcmp.f32 s0, s2", 1),
        (0xeef1, Some(0xfa10), "vmrs APSR_nzcv, fpscr", 1),
        (0xee00, Some(0x0a10), "vmov s0, r0", 1),
        (0xee10, Some(0x0a10), "vmov r0, s0", 1),
        (0xec41, Some(0x0b10), "vmov d0, r0, r1", 2),
        (0xed91, Some(0x0a01), "vldr s0, [r1, #4]", 2),
        (0xed81, Some(0x0b00), "vstr d0, [r1]", 3),
        (0xecb0, Some(0x9a09), "vldmia r0!, {s18-s26}", 10),
        (0xed2d, Some(0x8a10), "vpush {s16-s31}", 17),
        (0xecbd, Some(0x8b08), "vpop {d8-d11}", 9),
    ];

    /// Prices every encoding of [`PRICES`] with the plugin's own table (`m4_cycles.h`,
    /// compiled into a small program with the compiler that builds the plugin).
    #[test]
    fn the_cycle_table_prices_known_encodings_as_the_trm_does() {
        let root = repository_root();
        let dir = tempfile::tempdir().unwrap();
        let source = dir.path().join("price.c");
        let program = dir.path().join("price");
        std::fs::write(
            &source,
            format!(
                "#include <stdio.h>\n#include <stdlib.h>\n#include \"{}\"\n\
                 int main(int argc, char **argv) {{\n\
                 for (int i = 1; i + 1 < argc; i += 2) {{\n\
                 unsigned long hw1 = strtoul(argv[i], 0, 16), hw2 = strtoul(argv[i + 1], 0, 16);\n\
                 printf(\"%u\\n\", m4_cycles((uint16_t)hw1, (uint16_t)hw2, \
                 hw2 > 0xffff ? 2 : 4));\n\
                 }}\n\
                 return 0;\n}}\n",
                root.join(CYCLE_TABLE).display()
            ),
        )
        .unwrap();
        let cc = Toolchain::expected(&root).cc;
        let built = Command::new(&cc)
            .args(["-O2", "-Wall", "-Wextra", "-Werror", "-o"])
            .arg(&program)
            .arg(&source)
            .output()
            .expect("the C compiler runs");
        assert!(
            built.status.success(),
            "{}",
            String::from_utf8_lossy(&built.stderr)
        );
        // A 16-bit encoding is passed with an out-of-range second halfword.
        let args = PRICES.iter().flat_map(|&(hw1, hw2, _, _)| {
            [
                format!("{hw1:x}"),
                hw2.map_or("10000".into(), |h| format!("{h:x}")),
            ]
        });
        let output = Command::new(&program).args(args).output().unwrap();
        let prices: Vec<u32> = String::from_utf8(output.stdout)
            .unwrap()
            .lines()
            .map(|l| l.parse().unwrap())
            .collect();
        assert_eq!(prices.len(), PRICES.len());
        for (&(_, _, text, expected), &got) in PRICES.iter().zip(&prices) {
            assert_eq!(got, expected, "{text}");
        }
    }
}

//! `sim-bench --check`: does a committed `docs/performance/target.md` match a fresh run?
//!
//! Instruction counts, MACs, stack and flash are exact on every machine, so they must match to
//! the last digit. The cycle estimates are made from the same executed instructions, but they
//! depend on where the code lies: cargo hashes the absolute path of a path dependency outside
//! the firmware's workspace (the core) into its symbol names (cargo issue 13586), rustc orders
//! generic instantiations by symbol name, and so a checkout at another path places the same
//! code at other addresses, which QEMU cuts into other translation blocks. Measured between two
//! checkout paths: the same instruction counts, estimates up to 0.5 % apart (a few refills per
//! evaluation). Cells of the estimated-cycles column may therefore differ by
//! [`CYCLE_TOLERANCE`]; a change of the core or the firmware moves instruction counts, which
//! stay exact.

/// The header of the column whose cells may differ within [`CYCLE_TOLERANCE`].
const CYCLES_HEADER: &str = "est. cycles/eval";

/// The largest relative difference of two estimated-cycles cells that still match (2 %, four
/// times the largest placement effect measured).
pub(super) const CYCLE_TOLERANCE: f64 = 2e-2;

/// `Ok` when `fresh` matches `committed`, else the first line that differs, both ways.
pub(super) fn compare(committed: &str, fresh: &str) -> Result<(), String> {
    let (old_lines, new_lines): (Vec<&str>, Vec<&str>) =
        (committed.lines().collect(), fresh.lines().collect());
    let mut cycles_column = None;
    for (old, new) in old_lines.iter().zip(&new_lines) {
        let cells = |line: &str| -> Vec<String> {
            line.trim()
                .trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        };
        let (old_cells, new_cells) = (cells(old), cells(new));
        if old.starts_with('|') && old_cells.iter().any(|c| c == CYCLES_HEADER) {
            cycles_column = old_cells.iter().position(|c| c == CYCLES_HEADER);
        } else if !old.starts_with('|') {
            cycles_column = None;
        }
        if old == new {
            continue;
        }
        let cells_match = old_cells.len() == new_cells.len()
            && old_cells
                .iter()
                .zip(&new_cells)
                .enumerate()
                .all(|(i, (a, b))| a == b || (Some(i) == cycles_column && close(a, b)));
        if !cells_match {
            return Err(format!("\n  committed: {old}\n  this run:  {new}"));
        }
    }
    if old_lines.len() != new_lines.len() {
        return Err("\n  (one is a prefix of the other)".into());
    }
    Ok(())
}

/// Two numbers within [`CYCLE_TOLERANCE`] of each other.
fn close(a: &str, b: &str) -> bool {
    match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(a), Ok(b)) => (a - b).abs() <= CYCLE_TOLERANCE * a.abs().max(b.abs()),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: &str = "Intro.\n\n| model | instr/eval | est. cycles/eval | stack B |\n\
                         |---|---:|---:|---:|\n| torus | 734.9 | 1186.3 | 11880 |\n\nEnd.\n";

    #[test]
    fn an_identical_table_matches() {
        assert_eq!(compare(TABLE, TABLE), Ok(()));
    }

    #[test]
    fn estimated_cycles_may_move_within_the_tolerance_only() {
        assert_eq!(compare(TABLE, &TABLE.replace("1186.3", "1192.2")), Ok(()));
        let error = compare(TABLE, &TABLE.replace("1186.3", "1215.0")).unwrap_err();
        assert!(error.contains("1215.0"), "{error}");
    }

    #[test]
    fn instructions_stack_and_text_are_exact() {
        for (old, new) in [("734.9", "735.0"), ("11880", "11881"), ("End.", "End!")] {
            let error = compare(TABLE, &TABLE.replace(old, new)).unwrap_err();
            assert!(error.contains(new), "{error}");
        }
        assert!(compare(TABLE, &format!("{TABLE}more\n")).is_err());
        assert!(compare(&format!("{TABLE}more\n"), TABLE).is_err());
    }

    #[test]
    fn the_tolerance_applies_to_the_cycles_column_of_its_own_table_only() {
        // Same number in a table without that column: exact.
        let other = "| model | instr/eval |\n|---|---:|\n| torus | 1186.3 |\n";
        assert!(compare(other, &other.replace("1186.3", "1186.2")).is_err());
    }
}

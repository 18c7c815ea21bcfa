//! `neurosurf-core` must build without `std`: no crate in its dependency graph (proc-macros,
//! which run on the host, excepted) may enable a `std` or `alloc` feature, and the crate itself
//! declares `#![no_std]` and never names `std` or `alloc`. Checked with `cargo tree`, for the
//! default features and for every optional feature.

use std::path::Path;
use std::process::Command;

fn workspace() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ is inside the workspace")
}

/// `name version [features]` lines of core's normal, non-proc-macro dependency graph.
fn graph(features: &str) -> Vec<String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut command = Command::new(cargo);
    command
        .current_dir(workspace())
        .args(["tree", "-p", "neurosurf-core", "-e", "normal,no-proc-macro"])
        .args(["--prefix", "none", "--format", "{p} [{f}]"]);
    if !features.is_empty() {
        command.args(["--features", features]);
    }
    let out = command.output().expect("cargo tree runs");
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .expect("utf-8")
        .lines()
        .map(str::to_owned)
        .collect()
}

#[test]
fn no_crate_in_the_core_graph_enables_std_or_alloc() {
    for features in ["", "defmt", "serde", "defmt,serde"] {
        let lines = graph(features);
        assert!(
            lines.iter().any(|l| l.starts_with("neurosurf-core ")),
            "unexpected cargo tree output: {lines:?}"
        );
        for line in &lines {
            let enabled = line
                .rsplit_once('[')
                .map_or("", |(_, f)| f.trim_end_matches(']'));
            for feature in enabled.split(',') {
                assert!(
                    !matches!(feature, "std" | "alloc" | "use_std" | "use-std"),
                    "with features [{features}], `{line}` enables {feature}"
                );
            }
        }
    }
}

/// The core forbids `unsafe`; the one crate of ours it relies on for it, `neurosurf-m4f` (the
/// Cortex-M4F assembly kernels), denies it, and only its kernel module lowers that lint. The
/// compiler enforces the `deny`; this test finds every attribute that could lift it (`allow`,
/// `expect`, `warn` naming `unsafe_code`, also inside `cfg_attr`) in every file of the crate.
#[test]
fn unsafe_code_lives_only_in_the_m4f_kernel_module() {
    let src = workspace().join("core/m4f/src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("core/m4f/src/lib.rs");
    assert!(lib.contains("#![no_std]"));
    assert!(lib.contains("#![deny(unsafe_code)]"));
    let lifts = |code: &str| {
        ["allow", "expect", "warn"].iter().any(|level| {
            code.match_indices(level).any(|(at, _)| {
                let rest = code.get(at + level.len()..).unwrap_or("").trim_start();
                rest.starts_with('(')
                    && rest
                        .split(')')
                        .next()
                        .is_some_and(|args| args.contains("unsafe_code"))
            })
        })
    };
    let mut lifted = Vec::new();
    for path in files_below(src) {
        let bytes = std::fs::read(&path).expect("readable file");
        let text = String::from_utf8_lossy(&bytes);
        if text
            .lines()
            .any(|line| lifts(line.split("//").next().unwrap_or("")))
        {
            lifted.push(path.file_name().expect("file name").to_owned());
        }
    }
    lifted.sort();
    assert_eq!(
        lifted,
        ["fixed_layers.rs"],
        "unsafe_code lifted outside the kernel module"
    );
}

#[test]
fn core_sources_declare_no_std_and_never_name_std_or_alloc() {
    let src = workspace().join("core/src");
    let lib = std::fs::read_to_string(src.join("lib.rs")).expect("core/src/lib.rs");
    assert!(lib.contains("#![no_std]"));
    assert!(lib.contains("#![forbid(unsafe_code)]"));
    let mut files = 0;
    for path in files_below(src) {
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        files += 1;
        let text = std::fs::read_to_string(&path).expect("readable file");
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for banned in ["std::", "alloc::", "extern crate std", "extern crate alloc"] {
                let hit = code.match_indices(banned).any(|(i, _)| {
                    // `core::` paths that end in `std` (none today) would be fine; only
                    // a path segment that starts the identifier counts.
                    i == 0
                        || !code.as_bytes()[i - 1].is_ascii_alphanumeric()
                            && code.as_bytes()[i - 1] != b'_'
                            && code.as_bytes()[i - 1] != b':'
                });
                assert!(!hit, "{}:{}: names {banned}: {line}", path.display(), n + 1);
            }
        }
    }
    assert!(files > 5, "only {files} source files found");
}

/// Every file in `dir` and its subfolders.
fn files_below(dir: std::path::PathBuf) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("readable dir") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                stack.push(path);
            } else {
                files.push(path);
            }
        }
    }
    files
}

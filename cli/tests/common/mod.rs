//! Running the `neurosurf` binary from tests.

// Each test file uses a subset of these helpers.
#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs `neurosurf` with `args`.
pub fn neurosurf(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_neurosurf"))
        .args(args)
        .output()
        .expect("the binary runs")
}

/// Runs a command that must succeed and returns its stdout.
pub fn ok(args: &[&str]) -> String {
    let out = neurosurf(args);
    assert!(
        out.status.success(),
        "neurosurf {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 output")
}

/// Runs a command that must fail and returns its stderr.
pub fn fails(args: &[&str]) -> String {
    let out = neurosurf(args);
    assert!(
        !out.status.success(),
        "neurosurf {args:?} should have failed"
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Samples `count` points of the wavy test surface (`parametric sample wavy`) into `path`.
pub fn wavy_points(path: &std::path::Path, count: usize) {
    let count = count.to_string();
    ok(&[
        "parametric",
        "sample",
        "wavy",
        "--points",
        &count,
        "--out",
        path.to_str().expect("utf-8 path"),
    ]);
}

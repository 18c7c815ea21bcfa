//! The commands that run models on the simulated Cortex-M4F, run as a user would: `sim` prints
//! exactly what `eval` prints, `compare` reports the fixed-versus-float errors and the
//! target's bit-exactness, `sim-bench` measures the cost — and bad requests fail clearly.
//!
//! The simulator's toolchain comes from `firmware-sim/scripts/setup.sh` (the test command
//! `scripts/test.sh` runs it first); a run takes about 0.1 s.

mod common;

use common::{fails, neurosurf, ok};
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions};
use neurosurf_trainer::rbf::{self, RbfOptions};
use neurosurf_trainer::sample::{Shape, sample_shape};

const TORUS: Shape = Shape::Torus {
    major: 1.0,
    minor: 0.4,
};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A torus trained once per test binary, stored as f32.
fn torus_blob() -> &'static [u8] {
    static BLOB: OnceLock<Vec<u8>> = OnceLock::new();
    BLOB.get_or_init(|| {
        let points = sample_shape(&TORUS, 96, 4).unwrap();
        let trained = implicit::fit(
            points,
            &FitRequest::default(),
            &ImplicitOptions::default(),
            &|_| {},
        )
        .unwrap();
        implicit::to_blob(&trained.network, Some(&trained.summary), ScalarKind::F32).unwrap()
    })
}

/// The torus blob written into `dir`.
fn torus_file(dir: &Path) -> PathBuf {
    let path = dir.join("torus.nsb");
    fs::write(&path, torus_blob()).unwrap();
    path
}

/// Query points: held-out surface points, the hole, and far-field points where activations
/// saturate.
fn query_file(dir: &Path) -> PathBuf {
    let mut text = String::from("# surface, hole, far field\n");
    for p in sample_shape(&TORUS, 40, 99).unwrap().positions {
        text.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
    }
    text.push_str("0 0 0\n1.4 0 0\n6 -5 4\n-30 2 0.5\n0.123456789 -0.987654321 0.3\n");
    let path = dir.join("q.txt");
    fs::write(&path, text).unwrap();
    path
}

#[test]
fn sim_prints_exactly_what_eval_prints() {
    let dir = tempfile::tempdir().unwrap();
    let model = torus_file(dir.path());
    let queries = query_file(dir.path());
    for scalar in ["q16.16", "f32"] {
        let common = [s(&model), "--points", s(&queries), "--scalar", scalar];
        let host = ok(&[&["eval"], &common[..]].concat());
        assert_eq!(host.lines().count(), 46, "{host}");
        for mode in ["batch", "single"] {
            let target = ok(&[&["sim"], &common[..], &["--mode", mode]].concat());
            assert!(
                host == target,
                "{scalar}, {mode}: sim differs from eval\n--- eval\n{host}\n--- sim\n{target}"
            );
        }
    }
}

#[test]
fn sim_json_reports_the_cost_of_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let model = torus_file(dir.path());
    let queries = query_file(dir.path());
    let out = ok(&[
        "sim",
        s(&model),
        "--points",
        s(&queries),
        "--scalar",
        "q16.16",
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(json["scalar"], "q16.16");
    assert_eq!(json["mode"], "batch");
    assert_eq!(json["points"], 45);
    // One leaf of width 9: 252 multiply–accumulates per field+gradient (reverse mode).
    assert_eq!(json["mac_count"], 252);
    let instructions = json["instructions_per_point"].as_f64().unwrap();
    assert!(instructions >= 252.0, "{out}");
    assert!(json["instructions_per_mac"].as_f64().unwrap() >= 1.0);
    for key in [
        "stack_bytes",
        "flash_bytes",
        "static_ram_bytes",
        "ram_budget",
        "flash_budget",
    ] {
        assert!(json[key].as_u64().unwrap() > 0, "{key}: {out}");
    }
    let log = json["log"].as_array().unwrap();
    assert!(
        log.iter()
            .any(|l| l.as_str().unwrap().contains("evaluated 45 points")),
        "{out}"
    );
}

#[test]
fn sim_refuses_f64_corrupt_blobs_and_host_only_models() {
    let dir = tempfile::tempdir().unwrap();
    let model = torus_file(dir.path());
    let queries = query_file(dir.path());
    let sim = |model: &Path, scalar: &str| {
        fails(&["sim", s(model), "--points", s(&queries), "--scalar", scalar])
    };
    let err = sim(&model, "f64");
    assert!(
        err.contains("no f64") && err.contains("f32 or q16.16"),
        "{err}"
    );

    // A flipped byte: the target's core finds the bad checksum and says so.
    let mut bytes = torus_blob().to_vec();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x40;
    let corrupt = dir.path().join("corrupt.nsb");
    fs::write(&corrupt, &bytes).unwrap();
    let err = sim(&corrupt, "q16.16");
    assert!(
        err.contains("corrupt.nsb") && err.contains("target rejected") && err.contains("CRC"),
        "{err}"
    );
    let junk = dir.path().join("junk.nsb");
    fs::write(&junk, b"not a model").unwrap();
    let err = sim(&junk, "f32");
    assert!(err.contains("junk.nsb") && err.contains("magic"), "{err}");

    let points = sample_shape(&TORUS, 40, 2).unwrap();
    let (model, _) = rbf::fit(&points, &RbfOptions::default()).unwrap();
    let rbf_path = dir.path().join("rbf.nsb");
    fs::write(&rbf_path, model.to_blob().unwrap()).unwrap();
    let err = sim(&rbf_path, "f32");
    assert!(
        err.contains("rbf.nsb") && err.contains("host-only"),
        "{err}"
    );
    let err = fails(&["compare", s(&rbf_path)]);
    assert!(err.contains("host-only"), "{err}");
}

fn row<'a>(report: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["row"] == name)
        .unwrap_or_else(|| panic!("no row {name}: {report}"))
}

#[test]
fn compare_reports_fixed_against_float_on_the_models_surface() {
    let dir = tempfile::tempdir().unwrap();
    let model = torus_file(dir.path());
    let out = ok(&["compare", s(&model), "--json"]);
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["point_source"], "surface", "{out}");
    assert!(report["points"].as_u64().unwrap() >= 50, "{out}");
    let names: Vec<&str> = report["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["row"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        ["f32 host", "f32 target", "q16.16 host", "q16.16 target"]
    );
    let q16 = row(&report, "q16.16 target");
    assert_eq!(q16["bit_exact"], true, "{out}");
    assert_eq!(q16["max_ulp"], 0, "{out}");
    for name in ["q16.16 host", "q16.16 target"] {
        let median = row(&report, name)["normal_median_degrees"]
            .as_f64()
            .unwrap();
        assert!(median < 0.5, "{name}: median normal angle {median}°");
    }
    let f32_target = row(&report, "f32 target");
    assert!(f32_target["max_ulp"].as_u64().unwrap() <= 2, "{out}");
    // f32 is closer to f64 than Q16.16 is.
    let field = |name: &str| row(&report, name)["field_rms"].as_f64().unwrap();
    assert!(field("f32 host") < field("q16.16 host"), "{out}");
    assert_eq!(
        row(&report, "f32 host")["bit_exact"],
        serde_json::Value::Null
    );
    // Same model, same points: the report is deterministic.
    assert_eq!(ok(&["compare", s(&model), "--json"]), out);
}

#[test]
fn compare_writes_a_markdown_table_for_given_points() {
    let dir = tempfile::tempdir().unwrap();
    let model = torus_file(dir.path());
    let queries = query_file(dir.path());
    let markdown = dir.path().join("report.md");
    let text = ok(&[
        "compare",
        s(&model),
        "--points",
        s(&queries),
        "--markdown",
        s(&markdown),
    ]);
    assert!(
        text.contains("45 points from") && text.contains("q16.16 target"),
        "{text}"
    );
    let md = fs::read_to_string(&markdown).unwrap();
    let table: Vec<&str> = md.lines().filter(|l| l.starts_with('|')).collect();
    assert_eq!(table.len(), 6, "{md}");
    assert!(table[0].starts_with("| evaluation |"), "{md}");
    assert!(table[1].starts_with("| :--- | ---: |"), "{md}");
    assert!(table[5].starts_with("| q16.16 target |"), "{md}");
    // An unwritable destination is an error naming it.
    let err = fails(&[
        "compare",
        s(&model),
        "--markdown",
        "/nonexistent-dir/report.md",
    ]);
    assert!(err.contains("/nonexistent-dir/report.md"), "{err}");
}

#[test]
fn sim_bench_costs_at_least_one_instruction_per_mac() {
    let dir = tempfile::tempdir().unwrap();
    let model = torus_file(dir.path());
    let out = ok(&["sim-bench", s(&model), "--json"]);
    let bench: serde_json::Value = serde_json::from_str(&out).unwrap();
    let rows = bench["rows"].as_array().unwrap();
    // (torus, head, the head with its sign guards, cubic and quintic spiral curves, wavy
    // surface network, four Cao En networks, the extra blob) × (f32, q16.16) × (value,
    // value+derivative) × (single, batch)
    assert_eq!(rows.len(), 88, "{out}");
    for r in rows {
        let instructions = r["instructions_per_eval"].as_f64().unwrap();
        let macs = r["macs"].as_u64().unwrap() as f64;
        assert!(macs > 0.0 && instructions >= macs, "{r}");
        // Every instruction costs at least one estimated cycle.
        assert!(
            r["cycles_per_eval"].as_f64().unwrap() >= instructions,
            "{r}"
        );
        assert!(r["stack_bytes"].as_u64().unwrap() > 0, "{r}");
        assert_eq!(r["points"], 64, "{r}");
    }
    let head_gradient = rows
        .iter()
        .find(|r| r["model"].as_str().unwrap().starts_with("head") && r["op"] == "field+gradient")
        .unwrap();
    // 3 leaves × 252 + 2 nodes × 576 (a node reads 2N + 3 inputs and has its own normalization).
    assert_eq!(head_gradient["macs"], 1908, "{head_gradient}");
    let curve = rows
        .iter()
        .find(|r| r["model"].as_str().unwrap().starts_with("spiral curve"))
        .unwrap();
    assert_eq!(curve["op"], "position", "{curve}");
    assert_eq!(bench["ratios"].as_array().unwrap().len(), 44, "{out}");
    // Local support: with 104 keys, compact blending skips the groups out of reach and costs
    // well under half of exponential blending, which touches every key (the normalized compact
    // network even has n more MACs).
    let cao_en = |blending: &str, op: &str| {
        rows.iter()
            .find(|r| {
                let model = r["model"].as_str().unwrap();
                model.starts_with("Cao En sphere, 104 keys")
                    && model.contains(blending)
                    && r["op"] == op
                    && r["scalar"] == "f32"
                    && r["mode"] == "single"
            })
            .unwrap_or_else(|| panic!("no 104-key {blending} {op} row: {out}"))
    };
    for op in ["position", "position+direction"] {
        let (compact, exponential) = (cao_en("compact", op), cao_en("exponential", op));
        assert!(compact["macs"].as_u64() > exponential["macs"].as_u64());
        let ratio = compact["instructions_per_eval"].as_f64().unwrap()
            / exponential["instructions_per_eval"].as_f64().unwrap();
        assert!(
            ratio < 0.5,
            "compact / exponential {ratio}: {compact} {exponential}"
        );
    }
    let footprint = &bench["footprint"];
    assert!(
        footprint["flash_bytes"].as_u64().unwrap() < footprint["flash_budget"].as_u64().unwrap()
    );
}

/// `docs/performance/target.md` is what `sim-bench` measures now: instruction counts and stack
/// on the target are exact (cycle estimates within 0.1 %), so any difference is a change of
/// the core or the firmware, to be regenerated and committed with it.
#[test]
fn the_committed_target_table_matches_a_fresh_run() {
    let table = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/performance/target.md");
    let out = neurosurf(&["sim-bench", "--markdown", s(&table), "--check"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

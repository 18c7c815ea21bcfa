//! The `neurosurf` command line, run as a user would: sample → train → eval → info, and every
//! kind of bad input answered with a clear error and no damaged output.

mod common;

use common::{fails, ok};
use std::fs;
use std::path::{Path, PathBuf};

/// An OBJ of the torus with radii `major`, `minor` (axis z), `u` × `v` quads split in two.
fn torus_obj(major: f64, minor: f64, u: usize, v: usize) -> String {
    let mut text = String::new();
    for i in 0..u {
        let a = std::f64::consts::TAU * i as f64 / u as f64;
        for j in 0..v {
            let b = std::f64::consts::TAU * j as f64 / v as f64;
            let r = major + minor * b.cos();
            text += &format!("v {} {} {}\n", r * a.cos(), r * a.sin(), minor * b.sin());
        }
    }
    let index = |i: usize, j: usize| (i % u) * v + (j % v) + 1;
    for i in 0..u {
        for j in 0..v {
            let (p, q, r, t) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            text += &format!("f {p} {q} {r}\nf {p} {r} {t}\n");
        }
    }
    text
}

fn path(dir: &Path, name: &str) -> PathBuf {
    dir.join(name)
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn sample_train_eval_info_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let points = path(dir.path(), "torus.ply");
    let model = path(dir.path(), "torus.nsb");
    ok(&[
        "sample",
        "torus",
        "--points",
        "96",
        "--seed",
        "4",
        "--out",
        s(&points),
    ]);
    let summary = ok(&[
        "implicit",
        "fit",
        "--points",
        s(&points),
        "--out",
        s(&model),
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert!(json["outcome"].is_string(), "{summary}");
    assert_eq!(
        json["converged"],
        json["outcome"] == "converged",
        "{summary}"
    );
    assert!(json["iterations"].as_u64().unwrap() > 0);

    // The same points, options and seed give the same bytes, on one thread or two.
    let again = path(dir.path(), "again.nsb");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_neurosurf"))
        .args([
            "implicit",
            "fit",
            "--points",
            s(&points),
            "--out",
            s(&again),
            "-q",
        ])
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .unwrap()
        .status;
    assert!(status.success());
    assert_eq!(fs::read(&again).unwrap(), fs::read(&model).unwrap());

    let queries = path(dir.path(), "q.txt");
    fs::write(&queries, "# a comment\n1.4 0 0\n0.6 0 0 1 0 0\n\n0 0 0\n").unwrap();
    for scalar in ["f64", "f32", "q16.16"] {
        let csv = ok(&[
            "eval",
            s(&model),
            "--points",
            s(&queries),
            "--scalar",
            scalar,
        ]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "x,y,z,phi,gx,gy,gz");
        assert_eq!(lines.len(), 4, "{csv}");
        let phi = |line: &str| line.split(',').nth(3).unwrap().parse::<f64>().unwrap();
        // On the outer equator Φ ≈ 0, and the torus' hole (the origin) is outside.
        assert!(phi(lines[1]).abs() < 0.1, "{scalar}: {csv}");
        assert!(phi(lines[3]) < -0.5, "{scalar}: {csv}");
        // ∇Φ points inward at (1.4, 0, 0): gx < 0.
        let gx: f64 = lines[1].split(',').nth(4).unwrap().parse().unwrap();
        assert!(gx < -1.0, "{scalar}: {csv}");
    }
    // Against the true torus, both ways, in f64, f32 and Q16.16.
    let truth = path(dir.path(), "truth.obj");
    fs::write(&truth, torus_obj(1.0, 0.4, 96, 48)).unwrap();
    let report = ok(&["compare", s(&model), "--truth", s(&truth), "--json"]);
    let report: serde_json::Value = serde_json::from_str(&report).unwrap();
    let measures = report["truth"].as_array().unwrap();
    assert_eq!(measures.len(), 3, "{report}");
    for m in measures {
        let m = &m[1];
        assert!(
            m["truth_to_model"]["median_percent"].as_f64().unwrap() < 0.2,
            "{m}"
        );
        assert!(
            m["model_to_truth"]["median_percent"].as_f64().unwrap() < 0.2,
            "{m}"
        );
        assert_eq!(m["stray"]["sign_changes"], 0, "{m}");
        assert_eq!(m["mesh"]["components"], 1, "{m}");
    }

    let info = ok(&["info", s(&model), "--json"]);
    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(info["kind"], "implicit");
    assert_eq!(info["parameters"], 148);
}

#[test]
fn head_trains_with_its_three_features_and_warm_starts() {
    let dir = tempfile::tempdir().unwrap();
    let points = path(dir.path(), "head.ply");
    let model = path(dir.path(), "head.nsb");
    let again = path(dir.path(), "again.nsb");
    ok(&["sample", "head", "--points", "99", "--out", s(&points)]);
    let first = ok(&[
        "implicit",
        "fit",
        "--points",
        s(&points),
        "--tree",
        "((0,1),2)",
        "--out",
        s(&model),
        "--json",
    ]);
    let first: serde_json::Value = serde_json::from_str(&first).unwrap();
    assert_eq!(first["training"]["modules"].as_array().unwrap().len(), 5);
    // The same points from the trained model: almost nothing left to learn.
    let second = ok(&[
        "implicit",
        "fit",
        "--points",
        s(&points),
        "--init",
        s(&model),
        "--out",
        s(&again),
        "--json",
    ]);
    let second: serde_json::Value = serde_json::from_str(&second).unwrap();
    let saved = second["iterations_saved"].as_i64().unwrap();
    assert!(saved > 0, "warm start saved nothing: {second}");
    assert!(second["iterations"].as_u64().unwrap() < first["iterations"].as_u64().unwrap());
}

#[test]
fn a_mesh_is_sampled_evenly_unless_random_is_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let bunny = neurosurf_trainer::io::data_file("stanford-bunny.obj").unwrap();
    // The closest pair among the points of an ascii PLY file (x y z first on each line).
    let closest = |ply: &std::path::Path| {
        let text = fs::read_to_string(ply).unwrap();
        let points: Vec<[f64; 3]> = text
            .lines()
            .skip_while(|l| *l != "end_header")
            .skip(1)
            .map(|l| {
                let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        assert_eq!(points.len(), 600);
        let mut best = f64::INFINITY;
        for (i, p) in points.iter().enumerate() {
            for q in &points[i + 1..] {
                best = best.min((0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt());
            }
        }
        best
    };
    let mut gaps = Vec::new();
    for spread in ["even", "random"] {
        let points = path(dir.path(), &format!("{spread}.ply"));
        let out = ok(&[
            "sample",
            bunny.to_str().unwrap(),
            "--points",
            "600",
            "--spread",
            spread,
            "--out",
            s(&points),
            "--json",
        ]);
        let json: serde_json::Value = serde_json::from_str(&out).unwrap();
        assert_eq!(json["spread"], spread, "{json}");
        gaps.push(closest(&points));
    }
    // Even points keep their distance; independent draws clump.
    assert!(gaps[0] > 4.0 * gaps[1], "closest pairs {gaps:?}");
    // Past the limit of even spreading, points are drawn at random, and the report says so.
    let many = ok(&[
        "sample",
        bunny.to_str().unwrap(),
        "--points",
        "200001",
        "--encoding",
        "binary",
        "--out",
        s(&path(dir.path(), "many.ply")),
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_str(&many).unwrap();
    assert_eq!(json["spread"], "random", "{json}");
    let built_in = ok(&[
        "sample",
        "torus",
        "-n",
        "50",
        "--out",
        s(&path(dir.path(), "t.ply")),
        "--json",
    ]);
    assert!(!built_in.contains("spread"), "{built_in}");
}

#[test]
fn automatic_features_split_an_unlabelled_shape() {
    let dir = tempfile::tempdir().unwrap();
    let points = path(dir.path(), "e.ply");
    let model = path(dir.path(), "e.nsb");
    ok(&[
        "sample",
        "ellipsoid",
        "--points",
        "160",
        "--axes",
        "1.2,0.8,0.5",
        "--out",
        s(&points),
    ]);
    let text = fs::read_to_string(&points).unwrap();
    let max_z = text
        .lines()
        .skip_while(|l| *l != "end_header")
        .skip(1)
        .filter_map(|l| l.split_whitespace().nth(2)?.parse::<f64>().ok())
        .fold(0.0_f64, |m, z| m.max(z.abs()));
    assert!(
        max_z <= 0.5 + 1e-9 && max_z > 0.4,
        "the c semi-axis is 0.5: {max_z}"
    );
    let short = fails(&[
        "sample",
        "ellipsoid",
        "-n",
        "10",
        "--axes",
        "1,2",
        "--out",
        s(&points),
    ]);
    assert!(short.contains("expected 3"), "{short}");
    let out = ok(&[
        "implicit",
        "fit",
        "--points",
        s(&points),
        "--features",
        "2",
        "--out",
        s(&model),
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(json["training"]["tree"], "(0,1)");
    assert!(json["outcome"].is_string(), "{json}");

    // More features than the core holds: refused before any training, naming the way out;
    // the blob already written is kept.
    let before = fs::read(&model).unwrap();
    let err = fails(&[
        "implicit",
        "fit",
        "--points",
        s(&points),
        "--features",
        "24",
        "--out",
        s(&model),
    ]);
    assert!(err.contains("the core holds at most"), "{err}");
    assert!(
        err.contains("--features") && err.contains("--width"),
        "{err}"
    );
    assert_eq!(fs::read(&model).unwrap(), before);
    // An absurd option value is named.
    let err = fails(&[
        "implicit",
        "fit",
        "--points",
        s(&points),
        "--offset",
        "5",
        "--out",
        s(&model),
    ]);
    assert!(err.contains("option offset"), "{err}");
    assert_eq!(fs::read(&model).unwrap(), before);
}

#[test]
fn bad_inputs_get_clear_errors_and_leave_outputs_alone() {
    let dir = tempfile::tempdir().unwrap();
    let model = path(dir.path(), "m.nsb");
    fs::write(&model, b"precious").unwrap();
    let train = |points: &Path| {
        fails(&[
            "implicit",
            "fit",
            "--points",
            s(points),
            "--out",
            s(&model),
            "--quiet",
        ])
    };
    let ply = |name: &str, body: &str| {
        let p = path(dir.path(), name);
        let header = "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nend_header\n";
        let n = body.lines().count();
        fs::write(&p, header.replace("{n}", &n.to_string()) + body).unwrap();
        p
    };
    // Malformed PLY.
    let garbage = path(dir.path(), "garbage.ply");
    fs::write(
        &garbage,
        "ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n",
    )
    .unwrap();
    let err = train(&garbage);
    assert!(err.contains("garbage.ply"), "{err}");
    // NaN coordinates: an ascii `nan` is not a PLY number; a binary NaN reads and is rejected.
    let err = train(&ply(
        "nan.ply",
        "0 0 0 0 0 1\nnan 0 1 0 0 1\n1 1 0 0 0 1\n1 0 1 0 0 1\n0 1 1 1 0 0\n",
    ));
    assert!(err.contains("nan.ply") && err.contains("line"), "{err}");
    let mut cloud = neurosurf_trainer::sample::sample_shape(
        &neurosurf_trainer::sample::Shape::Sphere { radius: 1.0 },
        20,
        1,
    )
    .unwrap();
    cloud.positions[7][1] = f64::NAN;
    let binary_nan = path(dir.path(), "nan-binary.ply");
    neurosurf_trainer::io::write_points_ply(
        &binary_nan,
        &cloud,
        neurosurf_trainer::io::PlyEncoding::BinaryLittleEndian,
    )
    .unwrap();
    let err = train(&binary_nan);
    assert!(
        err.contains("point 7") && err.contains("non-finite"),
        "{err}"
    );
    // Zero-length normal.
    let err = train(&ply(
        "zero.ply",
        "0 0 0 0 0 0\n1 0 0 1 0 0\n0 1 0 0 1 0\n0 0 1 0 0 1\n1 1 1 1 0 0\n",
    ));
    assert!(err.contains("zero-length normal"), "{err}");
    // Fewer points than a module can fit.
    let err = train(&ply("few.ply", "0 0 0 0 0 1\n1 0 0 1 0 0\n0 1 0 0 1 0\n"));
    assert!(err.contains("at least"), "{err}");
    // Points in a plane enclose no volume: no implicit surface to learn.
    let flat = ply(
        "flat.ply",
        "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n1 1 0 0 0 1\n0.5 0.2 0 0 0 1\n0.1 0.9 0 0 0 1\n",
    );
    let err = train(&flat);
    assert!(err.contains("lie in a plane"), "{err}");
    // Collinear points have no box at all.
    let err = train(&ply(
        "line.ply",
        "0 0 0 0 0 1\n1 0 0 0 0 1\n2 0 0 0 0 1\n3 0 0 0 0 1\n4 0 0 0 0 1\n",
    ));
    assert!(err.contains("collinear"), "{err}");
    // A tree naming a feature the points do not have (an empty feature).
    let head = path(dir.path(), "head.ply");
    ok(&["sample", "head", "--points", "99", "--out", s(&head)]);
    let err = fails(&[
        "implicit",
        "fit",
        "--points",
        s(&head),
        "--tree",
        "((0,1),(2,3))",
        "--out",
        s(&model),
    ]);
    assert!(err.contains('3'), "{err}");
    // An unreadable --init.
    let junk = path(dir.path(), "junk.nsb");
    fs::write(&junk, b"NSRF but not really").unwrap();
    let err = fails(&[
        "implicit",
        "fit",
        "--points",
        s(&head),
        "--init",
        s(&junk),
        "--out",
        s(&model),
    ]);
    assert!(err.contains("junk.nsb"), "{err}");
    let err = fails(&[
        "implicit",
        "fit",
        "--points",
        s(&head),
        "--init",
        "/nonexistent/m0.nsb",
        "--out",
        s(&model),
    ]);
    assert!(err.contains("m0.nsb"), "{err}");
    // Nothing above touched the existing output.
    assert_eq!(fs::read(&model).unwrap(), b"precious");
    // A corrupt blob for eval and info.
    let err = fails(&["info", s(&junk)]);
    assert!(err.contains("junk.nsb"), "{err}");
}

/// `neurosurf info` on a model with nodes, built without training: every module, node
/// included, stores its normalization (blob format 2), so the head ((0,1),2) at N = 9 has
/// 3 × 148 + 2 × 310 = 1 064 parameters, and a node's a′ reads 2N + 3 = 21 inputs: field
/// 3 × 126 + 2 × 288 = 954 MACs, field + gradient twice that. A version-1 blob (nodes without
/// normalization) is refused with the core's version error.
#[test]
fn info_counts_the_nodes_normalization_and_position_inputs() {
    use neurosurf_core::scalar::ScalarKind;
    use neurosurf_trainer::implicit::{ImplicitNetwork, Normalization, TreeSpec, to_blob};

    let dir = tempfile::tempdir().unwrap();
    let tree: TreeSpec = "((0,1),2)".parse().unwrap();
    let mut network = ImplicitNetwork::new(9, &tree).unwrap();
    for module in 0..network.module_count() {
        network.set_normalization(
            module,
            &Normalization {
                center: [0.1 * module as f64, 0.0, -0.2],
                matrix: [[1.0, 0.1, 0.0], [0.0, 0.9, 0.2], [0.1, 0.0, 1.1]],
            },
        );
        for (k, p) in network.trained_params_mut(module).iter_mut().enumerate() {
            *p = ((k * 7 + module) % 11) as f64 / 20.0 - 0.25;
        }
    }
    let model = path(dir.path(), "head.nsb");
    fs::write(&model, to_blob(&network, None, ScalarKind::Q16_16).unwrap()).unwrap();
    let info = ok(&["info", s(&model), "--json"]);
    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(info["kind"], "implicit", "{info}");
    assert_eq!(info["parameters"], 1064, "{info}");
    assert_eq!(info["modules"], 5, "{info}");
    assert_eq!(info["leaves"], 3, "{info}");
    assert_eq!(info["macs"], serde_json::json!([954, 1908]), "{info}");
    let text = ok(&["info", s(&model)]);
    assert!(text.contains("parameters   1064"), "{text}");
    assert!(
        text.contains("MACs         954 per value, 1908 with the derivative"),
        "{text}"
    );

    // The same file with the header of format version 1 (and a consistent CRC).
    let mut old = fs::read(&model).unwrap();
    old[4..6].copy_from_slice(&1_u16.to_le_bytes());
    let body = old.len() - 4;
    let crc = neurosurf_core::blob::crc32(&old[..body]);
    old[body..].copy_from_slice(&crc.to_le_bytes());
    let old_model = path(dir.path(), "old.nsb");
    fs::write(&old_model, &old).unwrap();
    let err = fails(&["info", s(&old_model)]);
    assert!(
        err.contains("blob format version 1 is not supported (this core reads versions 3..=4)"),
        "{err}"
    );
}

#[test]
fn the_old_command_names_still_work() {
    // One name per paper (`implicit`, `parametric`), the old verbs kept as aliases.
    for args in [
        ["train", "implicit", "--help"],
        ["train", "rbf", "--help"],
        ["patch", "fit", "--help"],
    ] {
        let help = ok(&args);
        assert!(help.contains("Usage"), "{args:?}: {help}");
    }
}

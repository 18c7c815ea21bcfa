//! The RBF baseline from the command line, as a user would run it: sample → `implicit rbf` →
//! `info`, `eval`, `render` and `mesh` of the RBF blob, and the errors for what an RBF cannot do.

mod common;

use common::{fails, ok};
use std::fs;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn an_rbf_blob_trains_renders_and_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("torus.ply");
    let model = dir.path().join("torus-rbf.nsb");
    ok(&[
        "sample",
        "torus",
        "--points",
        "160",
        "--seed",
        "3",
        "--out",
        s(&points),
    ]);
    let summary = ok(&[
        "implicit",
        "rbf",
        "--points",
        s(&points),
        "--out",
        s(&model),
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let report = &json["report"];
    assert_eq!(report["points"], 160, "{summary}");
    assert_eq!(report["unknowns"], 484, "{summary}");
    assert_eq!(report["kernel"], "multiquadric", "{summary}");
    // c = 0.0078·D: about Carcenac's c² = 10⁻³ on this torus (D ≈ 4).
    let c2 = report["c2"].as_f64().unwrap();
    assert!(c2 > 0.95e-3 && c2 < 1e-3, "{summary}");
    assert!(report["max_residual"].as_f64().unwrap() < 1e-9, "{summary}");

    let info = ok(&["info", s(&model), "--json"]);
    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(info["kind"], "rbf");
    assert_eq!(info["centers"], 480);

    // f64 evaluation: the outer equator is on the surface, the hole outside, the tube inside.
    let queries = dir.path().join("q.txt");
    fs::write(&queries, "1.4 0 0\n0 0 0\n1 0 0\n").unwrap();
    let csv = ok(&[
        "eval",
        s(&model),
        "--points",
        s(&queries),
        "--scalar",
        "f64",
    ]);
    let phi: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(3).unwrap().parse().unwrap())
        .collect();
    assert!(
        phi[0].abs() < 0.01 && phi[1] < -0.5 && phi[2] > 0.5,
        "{csv}"
    );

    let png = dir.path().join("torus.png");
    let rendered = ok(&[
        "render",
        s(&model),
        "--width",
        "48",
        "--height",
        "40",
        "--aa",
        "1",
        "--out",
        s(&png),
        "--json",
    ]);
    let rendered: serde_json::Value = serde_json::from_str(&rendered).unwrap();
    assert_eq!(rendered["evaluation"], "f64 RBF", "{rendered}");
    let hits = rendered["hits"].as_u64().unwrap();
    let rays = rendered["rays"].as_u64().unwrap();
    // The torus fills a good part of the default view, and not all of it.
    assert!(hits > rays / 5 && hits < rays, "{rendered}");
    let image = image::open(&png).unwrap();
    assert_eq!((image.width(), image.height()), (48, 40));

    let mesh = dir.path().join("torus.obj");
    let meshed = ok(&[
        "mesh",
        s(&model),
        "--resolution",
        "32",
        "--out",
        s(&mesh),
        "--json",
    ]);
    let meshed: serde_json::Value = serde_json::from_str(&meshed).unwrap();
    assert!(meshed["triangles"].as_u64().unwrap() > 500, "{meshed}");
    let text = fs::read_to_string(&mesh).unwrap();
    let vertices: Vec<[f64; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(vertices.len() as u64, meshed["vertices"].as_u64().unwrap());
    // Every vertex lies near the true torus (R = 1, r = 0.4): within a grid cell (~0.1).
    for v in &vertices {
        let ring = (v[0].hypot(v[1]) - 1.0).hypot(v[2]);
        assert!((ring - 0.4).abs() < 0.05, "{v:?}: {ring}");
    }

    // A grown box searches farther; an RBF has no interval bounds.
    ok(&[
        "mesh",
        s(&model),
        "--resolution",
        "16",
        "--inflate",
        "1.5",
        "--out",
        s(&mesh),
    ]);
    let e = fails(&["render", s(&model), "--guaranteed", "--out", s(&png)]);
    assert!(e.contains("interval bounds"), "{e}");
    let e = fails(&["mesh", s(&model), "--inflate", "0.9", "--out", s(&mesh)]);
    assert!(e.contains("--inflate 0.9 is outside [1, 4]"), "{e}");
}

#[test]
fn the_biharmonic_kernel_and_relative_settings_from_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("sphere.ply");
    let model = dir.path().join("sphere-rbf.nsb");
    ok(&[
        "sample",
        "sphere",
        "--points",
        "60",
        "--seed",
        "2",
        "--out",
        s(&points),
    ]);
    let summary = ok(&[
        "implicit",
        "rbf",
        "--points",
        s(&points),
        "--out",
        s(&model),
        "--kernel",
        "biharmonic",
        "--epsilon-relative",
        "0.02",
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let report = &json["report"];
    assert_eq!(report["kernel"], "biharmonic", "{summary}");
    assert_eq!(report["c2"], 0.0, "{summary}");
    let (epsilon, diagonal) = (
        report["epsilon"].as_f64().unwrap(),
        report["diagonal"].as_f64().unwrap(),
    );
    assert!((epsilon - 0.02 * diagonal).abs() < 1e-12, "{summary}");
    let text = ok(&[
        "implicit",
        "rbf",
        "--points",
        s(&points),
        "--out",
        s(&model),
    ]);
    assert!(text.contains("multiquadric RBF on 60 points"), "{text}");
    let e = fails(&[
        "implicit",
        "rbf",
        "--points",
        s(&points),
        "--out",
        s(&model),
        "--epsilon-relative",
        "0.7",
    ]);
    assert!(e.contains("below 0.5"), "{e}");
}

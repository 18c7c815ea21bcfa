//! `neurosurf curve …` run as a user would: sample scattered points, fit a curve and a
//! surface, plot them, evaluate the blobs on the host (f64, f32, Q16.16) and on the simulated
//! Cortex-M4F — which must print exactly what the host prints — and compare fixed against
//! float. Bad point sets fail with a message naming the problem.

mod common;

use common::{fails, ok, wavy_points};
use std::fs;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Parameters t: the ends, the interior, and out-of-range values the core clamps.
fn t_file(dir: &Path) -> PathBuf {
    let mut text = String::from("# t\n");
    for i in 0..=40 {
        text.push_str(&format!("{}\n", f64::from(i) / 40.0));
    }
    text.push_str("-0.5\n1.5\n0.123456789\n");
    let path = dir.join("t.txt");
    fs::write(&path, text).unwrap();
    path
}

/// Scattered points on a wavy sheet over [−1, 1]², shuffled by construction.
fn sheet_file(dir: &Path) -> PathBuf {
    let mut text = String::new();
    let mut state = 12345_u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    for _ in 0..300 {
        let (x, y) = (next(), next());
        text.push_str(&format!(
            "{x} {y} {}\n",
            0.3 * (2.0 * x).sin() * (1.5 * y).cos()
        ));
    }
    let path = dir.join("sheet.txt");
    fs::write(&path, text).unwrap();
    path
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

#[test]
fn a_fitted_curve_evaluates_identically_on_the_host_and_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("spiral.txt");
    ok(&[
        "curve",
        "sample",
        "spiral",
        "-n",
        "120",
        "--seed",
        "5",
        "--out",
        s(&points),
    ]);
    let model = dir.path().join("spiral.nsb");
    let plot = dir.path().join("spiral.png");
    let fit = json(&ok(&[
        "curve",
        "fit",
        s(&points),
        "--out",
        s(&model),
        "--plot",
        s(&plot),
        "--scalar",
        "q16.16",
        "--json",
    ]));
    assert_eq!(fit["points"], 120);
    assert_eq!(fit["closed"], false);
    assert_eq!(fit["stored_as"], "q16.16");
    assert!(fit["rms_residual"].as_f64().unwrap() < 0.01, "{fit}");
    let image = image::open(&plot).unwrap();
    assert_eq!((image.width(), image.height()), (800, 800));

    let info = ok(&["info", s(&model)]);
    assert!(
        info.contains("curve model") && info.contains("open"),
        "{info}"
    );

    let t = t_file(dir.path());
    let f64_rows = ok(&["eval", s(&model), "--points", s(&t)]);
    assert!(f64_rows.starts_with("t,x,y,z,tx,ty,tz\n"), "{f64_rows}");
    assert_eq!(f64_rows.lines().count(), 45);
    host_equals_target(&model, &t);
    let cost = json(&ok(&[
        "sim",
        s(&model),
        "--points",
        s(&t),
        "--scalar",
        "f32",
        "--json",
    ]));
    assert_eq!(cost["op"], "position+direction");
    assert!(cost["instructions_per_point"].as_f64().unwrap() > cost["mac_count"].as_f64().unwrap());

    let report = json(&ok(&["compare", s(&model), "--json"]));
    assert_eq!(report["kind"], "curve");
    assert_eq!(report["points"], 1001);
    for row in report["rows"].as_array().unwrap() {
        if row["on"] == "target" {
            assert_eq!(row["bit_exact"], true, "{row}");
        }
        // Q16.16 control points of a curve in [−1, 1]²: positions within 2·10⁻⁴.
        assert!(row["field_max"].as_f64().unwrap() < 2e-4, "{row}");
    }
}

#[test]
fn interpolation_passes_through_the_points_and_plots_without_them() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("ellipse.txt");
    ok(&[
        "curve",
        "sample",
        "ellipse",
        "-n",
        "40",
        "--out",
        s(&points),
    ]);
    let model = dir.path().join("ellipse.nsb");
    let fit = json(&ok(&[
        "curve",
        "fit",
        s(&points),
        "--closed",
        "--interpolate",
        "--out",
        s(&model),
        "--json",
    ]));
    assert_eq!(fit["method"], "interpolation");
    assert_eq!(fit["closed"], true);
    assert_eq!(fit["control_points"], 40);
    assert!(fit["max_residual"].as_f64().unwrap() < 1e-9, "{fit}");
    let svg = dir.path().join("ellipse.svg");
    ok(&[
        "curve",
        "plot",
        s(&model),
        "--control-polygon",
        "--out",
        s(&svg),
    ]);
    let text = fs::read_to_string(&svg).unwrap();
    assert!(text.contains("stroke-dasharray") && text.contains("<polyline"));
}

#[test]
fn a_tube_is_fitted_closed_around_and_evaluates_identically_on_the_target() {
    let dir = tempfile::tempdir().unwrap();
    // 1 500 points on an open cylinder of radius 1 and height 3, scattered by a golden-ratio
    // sequence.
    let mut text = String::new();
    for k in 0..1_500 {
        let angle = std::f64::consts::TAU * (k as f64 * 0.618_033_988_749_895).fract();
        let height = 3.0 * (k as f64 * 0.754_877_666_246_693).fract();
        text.push_str(&format!("{} {} {height}\n", angle.cos(), angle.sin()));
    }
    let points = dir.path().join("tube.txt");
    fs::write(&points, text).unwrap();
    let model = dir.path().join("tube.nsb");
    let fit = json(&ok(&[
        "curve",
        "surface",
        s(&points),
        "--tube",
        "--out",
        s(&model),
        "--json",
    ]));
    assert_eq!(fit["tube"], true, "{fit}");
    assert!(fit["rms_residual"].as_f64().unwrap() < 0.01, "{fit}");
    let info = ok(&["info", s(&model)]);
    assert!(info.contains("closed"), "{info}");
    let uv = dir.path().join("uv.txt");
    fs::write(&uv, "0 0\n0.5 0.5\n1 1\n0.999 0.25\n").unwrap();
    for scalar in ["q16.16", "f32"] {
        let common = [s(&model), "--points", s(&uv), "--scalar", scalar];
        let host = ok(&[&["eval"], &common[..]].concat());
        let target = ok(&[&["sim"], &common[..]].concat());
        assert!(host == target, "{scalar}\n{host}\n---\n{target}");
    }
    // Without --tube the two edges are found, and the tube fits far better than one patch.
    let found = json(&ok(&[
        "curve",
        "surface",
        s(&points),
        "--out",
        s(&model),
        "--json",
    ]));
    assert_eq!(found["tube"], true, "{found}");
    let check = &found["tube_check"];
    let (tube, patch) = (check["tube_rms"].as_f64(), check["patch_rms"].as_f64());
    assert!(tube.unwrap() * 1.5 < patch.unwrap(), "{found}");
    let text = ok(&["curve", "surface", s(&points), "--out", s(&model)]);
    assert!(
        text.contains("a tube") && text.contains("as one patch"),
        "{text}"
    );
    // --patch keeps it one patch.
    let forced = json(&ok(&[
        "curve",
        "surface",
        s(&points),
        "--patch",
        "--out",
        s(&model),
        "--json",
    ]));
    assert_eq!(forced["tube"], false, "{forced}");
    assert!(forced["tube_check"].is_null(), "{forced}");
    // A sheet has no two edges: named, and no blob written; by default it is one patch.
    let sheet = sheet_file(dir.path());
    let out = dir.path().join("sheet.nsb");
    let error = fails(&["curve", "surface", s(&sheet), "--tube", "--out", s(&out)]);
    assert!(error.contains("not a tube"), "{error}");
    assert!(!out.exists());
    let patch = json(&ok(&[
        "curve",
        "surface",
        s(&sheet),
        "--out",
        s(&out),
        "--json",
    ]));
    assert_eq!(patch["tube"], false, "{patch}");
}

#[test]
fn a_fitted_surface_evaluates_identically_on_the_host_and_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let points = sheet_file(dir.path());
    let model = dir.path().join("sheet.nsb");
    let mesh = dir.path().join("sheet.obj");
    let fit = json(&ok(&[
        "curve",
        "surface",
        s(&points),
        "--out",
        s(&model),
        "--mesh",
        s(&mesh),
        "--resolution",
        "16",
        "--json",
    ]));
    // A square patch: a square map and control grid.
    let aspect = fit["aspect"].as_f64().unwrap();
    assert!((1.0..1.3).contains(&aspect), "{fit}");
    assert_eq!(fit["control"], serde_json::json!([8, 8]));
    assert!(fit["rms_residual"].as_f64().unwrap() < 0.01, "{fit}");
    let obj = fs::read_to_string(&mesh).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 17 * 17);

    let uv = dir.path().join("uv.txt");
    fs::write(&uv, "0 0\n0.5 0.5\n1 1\n0.25 0.75\n-1 2\n").unwrap();
    let rows = ok(&["eval", s(&model), "--points", s(&uv)]);
    assert!(rows.starts_with("u,v,x,y,z,nx,ny,nz\n"), "{rows}");
    for scalar in ["q16.16", "f32"] {
        let common = [s(&model), "--points", s(&uv), "--scalar", scalar];
        let host = ok(&[&["eval"], &common[..]].concat());
        let target = ok(&[&["sim"], &common[..]].concat());
        assert!(host == target, "{scalar}\n{host}\n---\n{target}");
    }
    let report = json(&ok(&["compare", s(&model), "--json"]));
    assert_eq!(report["points"], 33 * 33);
    for row in report["rows"].as_array().unwrap() {
        assert!(
            row["normal_median_degrees"].as_f64().unwrap() < 0.1,
            "{row}"
        );
        if row["on"] == "target" {
            assert_eq!(row["bit_exact"], true, "{row}");
        }
    }
    // A surface is not a curve: wrong arity and wrong command are refused clearly.
    let t = dir.path().join("t.txt");
    fs::write(&t, "0.5\n").unwrap();
    assert!(fails(&["eval", s(&model), "--points", s(&t)]).contains("2 numbers (u v)"));
    let svg = dir.path().join("x.svg");
    assert!(fails(&["curve", "plot", s(&model), "--out", s(&svg)]).contains("draws curves"));
}

#[test]
fn bad_point_sets_fail_with_a_message_naming_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.nsb");
    let case = |name: &str, text: &str| {
        let path = dir.path().join(name);
        fs::write(&path, text).unwrap();
        fails(&["curve", "fit", s(&path), "--out", s(&out)])
    };
    let few = case("few.txt", "0 0\n1 0\n1 1\n");
    assert!(few.contains("at least 4"), "{few}");
    let nan = case("nan.txt", "0 0\n1 0\n1 NaN\n0 1\n2 2\n");
    assert!(nan.contains("line 3") && nan.contains("NaN"), "{nan}");
    let duplicate = case("dup.txt", "0 0\n1 0\n1 1\n1 0\n0 1\n");
    assert!(duplicate.contains("duplicate"), "{duplicate}");
    let mixed = case("mixed.txt", "0 0\n1 0 0\n");
    assert!(mixed.contains("first point has 2"), "{mixed}");
    assert!(!out.exists(), "nothing is written for a failed fit");
    let flat = dir.path().join("flat.txt");
    fs::write(&flat, "0 0\n1 0\n1 1\n0 1\n0.5 0.5\n").unwrap();
    let surface = fails(&["curve", "surface", s(&flat), "--out", s(&out)]);
    assert!(surface.contains("3-D points"), "{surface}");
}

#[test]
fn curves_beyond_the_core_are_refused_before_training_and_large_sets_fit_by_default() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("big.txt");
    ok(&[
        "curve",
        "sample",
        "ellipse",
        "-n",
        "2700",
        "--seed",
        "3",
        "--out",
        s(&points),
    ]);
    let model = dir.path().join("big.nsb");
    let through = fails(&[
        "curve",
        "fit",
        s(&points),
        "--closed",
        "--interpolate",
        "--out",
        s(&model),
    ]);
    assert!(
        through.contains("--interpolate") && through.contains("512"),
        "{through}"
    );
    let many = fails(&[
        "curve",
        "fit",
        s(&points),
        "--closed",
        "--control",
        "513",
        "--out",
        s(&model),
    ]);
    assert!(
        many.contains("--control 513") && many.contains("512"),
        "{many}"
    );
    assert!(!model.exists());
    // The default K = n/5 = 540 is capped at what the core holds.
    let fit = json(&ok(&[
        "curve",
        "fit",
        s(&points),
        "--closed",
        "--out",
        s(&model),
        "--json",
    ]));
    assert_eq!(fit["control_points"], 512, "{fit}");
    assert!(model.exists());
}

#[test]
fn spline_surfaces_beyond_the_core_are_refused_before_training() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("wavy.txt");
    wavy_points(&points, 200);
    let out = dir.path().join("s.nsb");
    let error = fails(&[
        "curve",
        "surface",
        s(&points),
        "--control",
        "33,32",
        "--out",
        s(&out),
    ]);
    assert!(
        error.contains("--control 33,32") && error.contains("1056") && error.contains("1024"),
        "{error}"
    );
    assert!(!out.exists());
    // 32 × 32 is exactly what the core holds.
    ok(&[
        "curve",
        "surface",
        s(&points),
        "--control",
        "32,32",
        "--out",
        s(&out),
    ]);
    assert!(out.exists());
}

/// The fit says whether the chain's tests matter (the order's long steps), and warns when a
/// closed curve is fitted open or an open one closed.
#[test]
fn the_fit_reports_the_order_and_a_wrong_topology() {
    let dir = tempfile::tempdir().unwrap();
    let fit = |curve: &str, closed: bool| {
        let points = dir.path().join(format!("{curve}.txt"));
        ok(&[
            "curve",
            "sample",
            curve,
            "-n",
            "300",
            "--seed",
            "3",
            "--out",
            s(&points),
        ]);
        let out = dir.path().join("c.nsb");
        let mut args = vec!["curve", "fit", s(&points), "--out", s(&out)];
        if closed {
            args.push("--closed");
        }
        ok(&args)
    };
    let right = fit("ellipse", true);
    assert!(right.contains("order: no step longer than"), "{right}");
    assert!(!right.contains("warning"), "{right}");
    let open_ellipse = fit("ellipse", false);
    assert!(
        open_ellipse.contains("the curve looks closed; fit it with --closed"),
        "{open_ellipse}"
    );
    let closed_spiral = fit("spiral", true);
    assert!(
        closed_spiral.contains("fit it without --closed"),
        "{closed_spiral}"
    );
    let right = fit("spiral", false);
    assert!(!right.contains("warning"), "{right}");
}

/// de Boor's algorithm for a cubic B-spline at t in its domain.
fn de_boor(knots: &[f64], control: &[Vec<f64>], t: f64) -> Vec<f64> {
    any_degree_de_boor(knots, control, 3, t)
}

/// The knots and control points of the one `SPLINE` entity of an ASCII DXF file, read from
/// its group codes (40: a knot; 10, 20, 30: a control point's x, y, z).
fn dxf_spline(text: &str) -> (Vec<f64>, Vec<Vec<f64>>) {
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let (mut knots, mut control) = (Vec::new(), Vec::<Vec<f64>>::new());
    let mut inside = false;
    for pair in lines.chunks(2) {
        let (code, value) = (pair[0], pair.get(1).copied().unwrap_or(""));
        if code == "0" {
            inside = value == "SPLINE";
            continue;
        }
        if !inside {
            continue;
        }
        match code {
            "40" => knots.push(value.parse().unwrap()),
            "10" => control.push(vec![value.parse().unwrap()]),
            "20" | "30" => control.last_mut().unwrap().push(value.parse().unwrap()),
            _ => {}
        }
    }
    (knots, control)
}

/// The knots and control points of the first IGES entity 126 in `text`.
fn iges_curve(text: &str) -> (Vec<f64>, Vec<Vec<f64>>) {
    let data: String = text
        .lines()
        .filter(|l| l.len() == 80 && l.as_bytes()[72] == b'P')
        .map(|l| &l[..64])
        .collect();
    let p: Vec<f64> = data
        .split(';')
        .next()
        .unwrap()
        .split(',')
        .map(|t| t.trim().parse().unwrap())
        .collect();
    assert_eq!(p[0], 126.0);
    let (k, m) = (p[1] as usize, p[2] as usize);
    let knots = p[7..7 + k + m + 2].to_vec();
    let at = 7 + k + m + 2 + k + 1;
    let control = (0..=k)
        .map(|i| p[at + 3 * i..at + 3 * i + 3].to_vec())
        .collect();
    (knots, control)
}

/// The exported knots and control points (JSON, DXF and IGES, by de Boor's algorithm) and
/// the SVG path's cubic Béziers reproduce `eval` to 10⁻⁶ of the curve's size.
#[test]
fn exports_reproduce_eval() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("peanut.txt");
    ok(&[
        "curve",
        "sample",
        "peanut",
        "-n",
        "120",
        "--out",
        s(&points),
    ]);
    for closed in [true, false] {
        let blob = dir.path().join("c.nsb");
        let mut fit = vec!["curve", "fit", s(&points), "--out", s(&blob)];
        if closed {
            fit.push("--closed");
        }
        ok(&fit);
        let (json_path, svg_path) = (dir.path().join("c.json"), dir.path().join("c.svg"));
        let (dxf_path, iges_path) = (dir.path().join("c.dxf"), dir.path().join("c.igs"));
        ok(&[
            "curve",
            "export",
            s(&blob),
            "--json",
            s(&json_path),
            "--svg",
            s(&svg_path),
            "--dxf",
            s(&dxf_path),
            "--iges",
            s(&iges_path),
        ]);
        let (iges_knots, iges_control) = iges_curve(&fs::read_to_string(&iges_path).unwrap());
        let (dxf_knots, dxf_control) = dxf_spline(&fs::read_to_string(&dxf_path).unwrap());
        assert_eq!(dxf_knots.len(), dxf_control.len() + 4);
        assert_eq!(dxf_knots[..4], [0.0; 4], "clamped");
        let t_path = t_file(dir.path());
        let csv = ok(&["eval", s(&blob), "--points", s(&t_path), "--scalar", "f64"]);
        let rows: Vec<Vec<f64>> = csv
            .lines()
            .filter_map(|l| l.split(',').map(|v| v.parse().ok()).collect())
            .collect();
        let exported = json(&fs::read_to_string(&json_path).unwrap());
        let numbers = |v: &serde_json::Value| -> Vec<f64> {
            v.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        };
        let knots = numbers(&exported["knots"]);
        let control: Vec<Vec<f64>> = exported["control_points"]
            .as_array()
            .unwrap()
            .iter()
            .map(numbers)
            .collect();
        // The Béziers: after "M x,y", groups of three points per segment.
        let svg = fs::read_to_string(&svg_path).unwrap();
        let d = svg
            .split(" d=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        let flat: Vec<[f64; 2]> = d
            .split_whitespace()
            .filter(|w| w.contains(','))
            .map(|w| {
                let (x, y) = w.split_once(',').unwrap();
                [x.parse().unwrap(), y.parse().unwrap()]
            })
            .collect();
        let segments = (flat.len() - 1) / 3;
        assert!(rows.len() > 40);
        for row in &rows {
            let t = row[0].clamp(0.0, 1.0);
            let want = [row[1], row[2]];
            // de Boor on the exported knots.
            let p = de_boor(&knots, &control, t);
            let from_dxf = de_boor(&dxf_knots, &dxf_control, t);
            let from_iges = de_boor(&iges_knots, &iges_control, t);
            // The Bézier segment holding t.
            let st = t * segments as f64;
            let i = (st.floor() as usize).min(segments - 1);
            let (u, v) = (st - i as f64, 1.0 - (st - i as f64));
            let b = &flat[3 * i..3 * i + 4];
            let w = [v * v * v, 3.0 * u * v * v, 3.0 * u * u * v, u * u * u];
            for c in 0..2 {
                let bezier: f64 = (0..4).map(|j| w[j] * b[j][c]).sum();
                assert!(
                    (p[c] - want[c]).abs() < 1e-6,
                    "de Boor at {t}: {p:?} {want:?}"
                );
                assert!(
                    (from_dxf[c] - want[c]).abs() < 1e-6,
                    "DXF at {t}: {from_dxf:?} {want:?}"
                );
                assert!(
                    (from_iges[c] - want[c]).abs() < 1e-6,
                    "IGES at {t}: {from_iges:?} {want:?}"
                );
                assert!(
                    (bezier - want[c]).abs() < 1e-6,
                    "Bézier at {t}: {bezier} {want:?}"
                );
            }
        }
    }
}

/// `--smoothing` reaches the fit (a stiffer curve leaves larger residuals), and absurd
/// values are refused before training.
#[test]
fn smoothing_is_an_option() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("e.txt");
    ok(&[
        "curve",
        "sample",
        "ellipse",
        "-n",
        "200",
        "--noise",
        "3",
        "--out",
        s(&points),
    ]);
    let out = dir.path().join("e.nsb");
    let rms = |lambda: &str| {
        let report = json(&ok(&[
            "curve",
            "fit",
            s(&points),
            "--closed",
            "--out",
            s(&out),
            "--smoothing",
            lambda,
            "--json",
        ]));
        report["rms_residual"].as_f64().unwrap()
    };
    assert!(rms("10") > 1.5 * rms("0"));
    for bad in ["nan", "1e9", "inf"] {
        let error = fails(&[
            "curve",
            "fit",
            s(&points),
            "--out",
            s(&out),
            "--smoothing",
            bad,
        ]);
        assert!(error.contains("--smoothing"), "{error}");
    }
}

/// `--tolerance` picks the control count (its fit meets it), and a tolerance that is not a
/// positive distance, or one with `--control`, is refused before training.
#[test]
fn tolerance_is_an_option() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("e.txt");
    let out = dir.path().join("e.nsb");
    ok(&[
        "curve",
        "sample",
        "ellipse",
        "-n",
        "300",
        "--out",
        s(&points),
    ]);
    let (points, out) = (s(&points), s(&out));
    let fit = |extra: &[&'static str]| -> Vec<&str> {
        let mut args = vec!["curve", "fit", points, "--out", out];
        args.extend_from_slice(extra);
        args
    };
    let report = json(&ok(&fit(&["--closed", "--tolerance", "0.01", "--json"])));
    assert!(report["max_residual"].as_f64().unwrap() <= 0.01, "{report}");
    assert!(report["control_points"].as_u64().unwrap() < 60, "{report}");
    for bad in [
        &["--tolerance", "0"][..],
        &["--tolerance", "nan"],
        &["--tolerance", "1", "--control", "9"],
    ] {
        let error = fails(&fit(bad));
        assert!(error.contains("--tolerance"), "{error}");
    }
}

/// Two circles far apart are two groups and get a curve each, in two blobs, with a far
/// point left out; `--join-groups` fits one curve and warns. One circle is one group.
#[test]
fn separate_groups_get_a_curve_each_and_stray_points_are_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let circle = |cx: f64, n: usize| -> String {
        (0..n)
            .map(|i| {
                let a = std::f64::consts::TAU * (i as f64 + 0.4 * (i % 3) as f64) / n as f64;
                format!("{} {}\n", cx + a.cos(), a.sin())
            })
            .collect()
    };
    let (one, two) = (dir.path().join("one.txt"), dir.path().join("two.txt"));
    fs::write(&one, circle(0.0, 150)).unwrap();
    fs::write(&two, circle(0.0, 150) + &circle(3.0, 100) + "9 9\n").unwrap();
    let (out, second) = (dir.path().join("c.nsb"), dir.path().join("c-2.nsb"));
    let fit = |points: &Path| {
        json(&ok(&[
            "curve",
            "fit",
            s(points),
            "--closed",
            "--out",
            s(&out),
            "--json",
        ]))
    };
    let report = fit(&one);
    assert_eq!(report["groups"], serde_json::json!([150]), "{report}");
    assert_eq!(report["stray_points"], 0);
    assert_eq!(report["more_curves"], serde_json::json!([]));
    assert!(!second.exists());
    let report = fit(&two);
    assert_eq!(report["groups"], serde_json::json!([150, 100]), "{report}");
    assert_eq!(report["stray_points"], 1);
    assert_eq!(report["points"], 150, "{report}");
    assert_eq!(report["more_curves"][0]["points"], 100, "{report}");
    assert_eq!(report["more_curves"][0]["out"], s(&second), "{report}");
    // Each curve stays on its own circle: no bridge, nothing pulled to the stray point.
    for (blob, cx) in [(&out, 0.0), (&second, 3.0)] {
        let queries = dir.path().join("t.txt");
        let t: String = (0..=200)
            .map(|i| format!("{}\n", f64::from(i) / 200.0))
            .collect();
        fs::write(&queries, t).unwrap();
        let csv = ok(&["eval", s(blob), "--points", s(&queries)]);
        for line in csv.lines().filter(|l| !l.starts_with('t')) {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            let r = (v[1] - cx).hypot(v[2]);
            assert!((r - 1.0).abs() < 0.02, "{blob:?}: {line}");
        }
    }
    let text = ok(&["curve", "fit", s(&two), "--closed", "--out", s(&out)]);
    assert!(
        text.contains("group 2: 100 points")
            && text.contains("1 stray point far from the others left out"),
        "{text}"
    );
    assert!(!text.contains("warning: group"), "{text}");
    // An open arc beside a circle, both fitted --closed: the arc's ring is told.
    let mixed = dir.path().join("mixed.txt");
    let arc: String = (0..80)
        .map(|i| {
            let x = -1.0 + f64::from(i) / 40.0;
            format!("{x} {}\n", 4.0 + 0.3 * (2.0 * x).sin())
        })
        .collect();
    fs::write(&mixed, circle(0.0, 150) + &arc).unwrap();
    let text = ok(&["curve", "fit", s(&mixed), "--closed", "--out", s(&out)]);
    assert!(
        text.contains("warning: group 2: a step of the ring") && text.contains("without --closed"),
        "{text}"
    );
    let joined = ok(&[
        "curve",
        "fit",
        s(&two),
        "--closed",
        "--join-groups",
        "--out",
        s(&out),
    ]);
    assert!(
        joined.contains("2 separate groups") && joined.contains("one curve bridges them"),
        "{joined}"
    );
}

/// `curve fit --degree`: quadratic and quintic curves run through the same blob, `eval` and
/// the simulated target print the same rows in both scalars, the exports carry the degree
/// (DXF clamped with p + 1 equal end knots, reproducing `eval`), an SVG path exists for the
/// quadratic and is refused for the quintic, and bad degrees are refused before anything is
/// written. `curve surface --degree 4` likewise runs the same on the host and the target.
#[test]
fn curves_of_degree_two_to_five_run_on_the_host_and_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("peanut.txt");
    ok(&[
        "curve",
        "sample",
        "peanut",
        "-n",
        "150",
        "--seed",
        "9",
        "--out",
        s(&points),
    ]);
    let t_path = t_file(dir.path());
    for degree in ["2", "5"] {
        let blob = dir.path().join(format!("p{degree}.nsb"));
        let fit = json(&ok(&[
            "curve",
            "fit",
            s(&points),
            "--closed",
            "--degree",
            degree,
            "--out",
            s(&blob),
            "--json",
        ]));
        assert_eq!(fit["degree"].to_string(), degree, "{fit}");
        assert!(fit["rms_residual"].as_f64().unwrap() < 0.01, "{fit}");
        let info = ok(&["info", s(&blob)]);
        assert!(info.contains(&format!("degree {degree}")), "{info}");
        host_equals_target(&blob, &t_path);
        let (json_path, dxf_path) = (dir.path().join("e.json"), dir.path().join("e.dxf"));
        ok(&[
            "curve",
            "export",
            s(&blob),
            "--json",
            s(&json_path),
            "--dxf",
            s(&dxf_path),
        ]);
        let exported = json(&fs::read_to_string(&json_path).unwrap());
        assert_eq!(exported["degree"].to_string(), degree);
        let p: usize = degree.parse().unwrap();
        let (knots, control) = dxf_spline(&fs::read_to_string(&dxf_path).unwrap());
        assert_eq!(knots.len(), control.len() + p + 1);
        assert!(knots[..=p].iter().all(|&k| k == 0.0), "clamped: {knots:?}");
        let csv = ok(&["eval", s(&blob), "--points", s(&t_path), "--scalar", "f64"]);
        for row in csv.lines().skip(1) {
            let row: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
            let at = any_degree_de_boor(&knots, &control, p, row[0].clamp(0.0, 1.0));
            assert!(
                (at[0] - row[1]).abs() < 1e-6 && (at[1] - row[2]).abs() < 1e-6,
                "{row:?}"
            );
        }
        let svg = dir.path().join(format!("e{degree}.svg"));
        if p == 2 {
            ok(&["curve", "export", s(&blob), "--svg", s(&svg)]);
        } else {
            let error = fails(&["curve", "export", s(&blob), "--svg", s(&svg)]);
            assert!(
                error.contains("degree 5") && error.contains("--dxf"),
                "{error}"
            );
            assert!(!svg.exists());
        }
    }
    // A surface of degree 4 in both directions: the same rows on the host and the target.
    let sheet = sheet_file(dir.path());
    let patch = dir.path().join("patch4.nsb");
    let fit = json(&ok(&[
        "curve",
        "surface",
        s(&sheet),
        "--degree",
        "4",
        "--out",
        s(&patch),
        "--json",
    ]));
    assert_eq!(fit["degrees"], serde_json::json!([4, 4]), "{fit}");
    assert!(fit["rms_residual"].as_f64().unwrap() < 0.01, "{fit}");
    let info = ok(&["info", s(&patch)]);
    assert!(info.contains("degree 4 × 4"), "{info}");
    let uv = dir.path().join("uv.txt");
    fs::write(&uv, "0 0\n0.5 0.5\n1 1\n0.25 0.75\n0.9 0.1\n").unwrap();
    host_equals_target(&patch, &uv);
    // Bad degrees, and too few control points for one, are refused before the chain
    // trains, each naming what to change; nothing is written.
    let blob = dir.path().join("bad.nsb");
    let (sheet, points, out) = (s(&sheet), s(&points), s(&blob));
    let refusals: [(&[&str], &[&str]); 4] = [
        (&["surface", sheet, "--degree", "1"], &["degree 1"]),
        (
            &["fit", points, "--degree", "6"],
            &["degree 6", "--degree 2..=5"],
        ),
        (
            &["fit", points, "--degree", "2", "--interpolate"],
            &["--interpolate", "cubic"],
        ),
        (
            &["fit", points, "--degree", "5", "--control", "5", "--closed"],
            &["--control 5", "--control 6"],
        ),
    ];
    for (args, wanted) in refusals {
        let error = fails(&[&["curve"], args, &["--out", out]].concat());
        assert!(
            wanted.iter().all(|w| error.contains(w)),
            "{args:?}: {error}"
        );
    }
    assert!(!blob.exists());
}

/// `eval` of `model` at `points` prints exactly what the simulated target prints, in both
/// scalars and both modes.
fn host_equals_target(model: &Path, points: &Path) {
    for scalar in ["q16.16", "f32"] {
        let common = [s(model), "--points", s(points), "--scalar", scalar];
        let host = ok(&[&["eval"], &common[..]].concat());
        for mode in ["batch", "single"] {
            let target = ok(&[&["sim"], &common[..], &["--mode", mode]].concat());
            assert!(host == target, "{} {scalar} {mode}", model.display());
        }
    }
}

/// De Boor's algorithm for degree `p` (the span found by search over the domain).
fn any_degree_de_boor(knots: &[f64], control: &[Vec<f64>], p: usize, t: f64) -> Vec<f64> {
    let last = control.len() - 1;
    let k = (p..=last).rev().find(|&k| knots[k] <= t).unwrap_or(p);
    let mut d: Vec<Vec<f64>> = (0..=p).map(|j| control[j + k - p].clone()).collect();
    for r in 1..=p {
        for j in (r..=p).rev() {
            let i = j + k - p;
            let alpha = (t - knots[i]) / (knots[i + p + 1 - r] - knots[i]);
            d[j] = d[j - 1]
                .iter()
                .zip(&d[j])
                .map(|(a, b)| (1.0 - alpha) * a + alpha * b)
                .collect();
        }
    }
    d[p].clone()
}

#[test]
fn an_interpolating_surface_passes_through_every_point() {
    let dir = tempfile::tempdir().unwrap();
    let points = sheet_file(dir.path());
    let model = dir.path().join("through.nsb");
    let fit = json(&ok(&[
        "curve",
        "surface",
        s(&points),
        "--interpolate",
        "--out",
        s(&model),
        "--json",
    ]));
    let report = &fit["interpolation"];
    assert_eq!(report["exact"], true, "{fit}");
    assert!(fit["max_residual"].as_f64().unwrap() < 1e-8, "{fit}");
    let control = fit["control"].as_array().unwrap();
    let count = control[0].as_u64().unwrap() * control[1].as_u64().unwrap();
    assert!((600..=1024).contains(&count), "{fit}");
    // The core loads it and evaluates it on the target as on the host.
    let uv = dir.path().join("uv.txt");
    fs::write(&uv, "0 0\n0.5 0.5\n0.25 0.75\n").unwrap();
    host_equals_target(&model, &uv);
    let text = ok(&[
        "curve",
        "surface",
        s(&points),
        "--interpolate",
        "--out",
        s(&model),
    ]);
    assert!(text.contains("through every point"), "{text}");
    // More points than the core's control points allow: refused before training, no blob.
    let mut many = fs::read_to_string(&points).unwrap();
    for line in fs::read_to_string(&points).unwrap().lines() {
        let p: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
        many.push_str(&format!("{} {} {}\n", p[0] + 2.5, p[1], p[2]));
    }
    let many_path = dir.path().join("many.txt");
    fs::write(&many_path, many).unwrap();
    let out = dir.path().join("many.nsb");
    let error = fails(&[
        "curve",
        "surface",
        s(&many_path),
        "--interpolate",
        "--out",
        s(&out),
    ]);
    assert!(error.contains("at most 512 points"), "{error}");
    assert!(!out.exists());
}

//! `neurosurf caoen …` run as a user would: fit a Cao En network to targets (on the sphere)
//! or to key/target pairs (on the torus), mesh it, and evaluate the blob on the host and on
//! the simulated Cortex-M4F — which must print exactly what the host prints.

mod common;

use common::{fails, ok};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_3};
use std::fs;
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

/// 26 targets on a bent ellipsoid, one per direction of the cube's corners, edges and faces.
fn targets_file(dir: &Path) -> PathBuf {
    let mut text = String::from("# x y z of each target\n");
    for i in -1_i32..=1 {
        for j in -1_i32..=1 {
            for k in -1_i32..=1 {
                if (i, j, k) == (0, 0, 0) {
                    continue;
                }
                let n = f64::from(i * i + j * j + k * k).sqrt();
                let (x, y, z) = (f64::from(i) / n, f64::from(j) / n, f64::from(k) / n);
                text.push_str(&format!(
                    "{} {} {}\n",
                    1.3 * x,
                    0.8 * y + 0.25 * x * x,
                    0.6 * z
                ));
            }
        }
    }
    let path = dir.join("targets.txt");
    fs::write(&path, text).unwrap();
    path
}

/// Source points on the sphere (unit vectors, 3 per line).
fn sphere_points(dir: &Path) -> PathBuf {
    let mut text = String::new();
    for i in 0..30 {
        let (a, z) = (f64::from(i) * 2.4, 1.0 - f64::from(2 * i + 1) / 30.0);
        let r = (1.0 - z * z).sqrt();
        text.push_str(&format!("{} {} {z}\n", r * a.cos(), r * a.sin()));
    }
    let path = dir.join("sources.txt");
    fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_fitted_sphere_network_passes_through_its_targets_and_runs_on_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let targets = targets_file(dir.path());
    let model = dir.path().join("bean.nsb");
    let mesh = dir.path().join("bean.obj");
    let report = json(&ok(&[
        "caoen",
        "fit",
        s(&targets),
        "--out",
        s(&model),
        "--mesh",
        s(&mesh),
        "--scalar",
        "q16.16",
        "--json",
    ]));
    assert_eq!(report["key_points"], 26);
    assert!(report["rms_at_keys"].as_f64().unwrap() < 1e-6, "{report}");
    // By default: the rational form, q chosen by leave-one-out, and the surface between the
    // keys reported on dense samples.
    assert_eq!(report["normalized"], true, "{report}");
    assert_eq!(report["sharpness_from"], "leave-one-out", "{report}");
    let range = report["sharpness_range"].as_array().unwrap();
    for q in range.iter().map(|q| q.as_f64().unwrap()) {
        assert!((1.0..=64.0).contains(&q) && q.fract() == 0.0, "{report}");
    }
    assert!(report["leave_one_out"].as_f64().unwrap() > 0.0, "{report}");
    let between = &report["between_keys"];
    assert!(
        between["farthest_from_targets"].as_f64().unwrap()
            < between["target_gap"].as_f64().unwrap(),
        "{report}"
    );
    let obj = fs::read_to_string(&mesh).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 2562);

    let info = ok(&["info", s(&model)]);
    assert!(
        info.contains("cao-en model") && info.contains("26 key points"),
        "{info}"
    );
    let sources = sphere_points(dir.path());
    let rows = ok(&["eval", s(&model), "--points", s(&sources)]);
    assert!(rows.starts_with("s1,s2,s3,x,y,z,nx,ny,nz\n"), "{rows}");
    for scalar in ["q16.16", "f32"] {
        let common = [s(&model), "--points", s(&sources), "--scalar", scalar];
        let host = ok(&[&["eval"], &common[..]].concat());
        for mode in ["batch", "single"] {
            let target = ok(&[&["sim"], &common[..], &["--mode", mode]].concat());
            assert!(host == target, "{scalar} {mode}\n{host}\n---\n{target}");
        }
    }
    let compare = json(&ok(&["compare", s(&model), "--json"]));
    assert_eq!(compare["kind"], "cao-en");
    for row in compare["rows"].as_array().unwrap() {
        assert!(
            row["normal_median_degrees"].as_f64().unwrap() < 0.05,
            "{row}"
        );
        if row["on"] == "target" {
            assert_eq!(row["bit_exact"], true, "{row}");
        }
    }
}

#[test]
fn a_torus_network_from_key_and_target_pairs_meshes_its_grid() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = String::new();
    for i in 0..6 {
        for j in 0..4 {
            let (a, b) = (f64::from(i) * FRAC_PI_3, f64::from(j) * FRAC_PI_2);
            let r = 1.0 + 0.4 * b.cos();
            text.push_str(&format!(
                "{} {} {} {} {} {} {}\n",
                a.cos(),
                a.sin(),
                b.cos(),
                b.sin(),
                r * a.cos(),
                r * a.sin(),
                0.4 * b.sin()
            ));
        }
    }
    let pairs = dir.path().join("torus.txt");
    fs::write(&pairs, text).unwrap();
    let model = dir.path().join("torus.nsb");
    let report = json(&ok(&[
        "caoen",
        "fit",
        s(&pairs),
        "--domain",
        "torus",
        "--blending",
        "exponential",
        "--out",
        s(&model),
        "--json",
    ]));
    assert_eq!(report["source_dimension"], 4);
    assert!(report["rms_at_keys"].as_f64().unwrap() < 1e-6, "{report}");
    let mesh = dir.path().join("torus.ply");
    let out = ok(&[
        "caoen",
        "mesh",
        s(&model),
        "--grid",
        "24,12",
        "--out",
        s(&mesh),
    ]);
    assert!(
        out.contains("288 vertices") && out.contains("576 triangles"),
        "{out}"
    );
}

#[test]
fn bad_key_point_files_fail_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.nsb");
    let case = |name: &str, text: &str, extra: &[&str]| {
        let path = dir.path().join(name);
        fs::write(&path, text).unwrap();
        fails(&[&["caoen", "fit", s(&path), "--out", s(&out)], extra].concat())
    };
    assert!(case("empty.txt", "# nothing\n", &[]).contains("no key points"));
    let mixed = case("mixed.txt", "1 0 0\n0 1 0 1\n", &[]);
    assert!(mixed.contains("row 2"), "{mixed}");
    let centre = case("centre.txt", "1 0 0\n-1 0 0\n0 0 0\n", &[]);
    assert!(centre.contains("centroid"), "{centre}");
    let same = case(
        "same.txt",
        "1 0 0\n1 0 0\n0 1 0\n0 0 1\n-1 0 0\n0 -1 0\n",
        &[],
    );
    assert!(same.contains("rows 1 and 2"), "{same}");
    let short = case("short.txt", "1 0 0 0\n0 1 0 0\n", &["--domain", "torus"]);
    assert!(short.contains("4 source coordinates"), "{short}");
    assert!(!out.exists());
}

#[test]
fn shading_folds_into_the_network_and_meshes_carry_texture_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let targets = targets_file(dir.path());
    let model = dir.path().join("bean.nsb");
    let paper = ["--plain", "--sharpness", "4"];
    ok(&[
        &["caoen", "fit", s(&targets), "--out", s(&model)],
        &paper[..],
    ]
    .concat());
    let lit = dir.path().join("lit.nsb");
    let report = json(&ok(&[
        "caoen",
        "shade",
        s(&model),
        "--light",
        "0,0,1",
        "--light=-1,0.5,0.2",
        "--out",
        s(&lit),
        "--scalar",
        "q16.16",
        "--json",
    ]));
    assert_eq!(report["target_dimension"], 5, "{report}");
    assert!(
        report["max_error_at_keys"].as_f64().unwrap() < 1e-9,
        "{report}"
    );
    // 26 keys (power, q = 4): the shading between them is coarse, measured RMS 0.23 (max 1.24,
    // where the bean's own normal turns fastest); the tests of `caoen::texture` bound the
    // 104-key case at 0.01.
    assert!(
        report["rms_error_between"].as_f64().unwrap() < 0.3,
        "{report}"
    );
    // Five outputs, the same on the host and the simulated target.
    let sources = sphere_points(dir.path());
    let common = [s(&lit), "--points", s(&sources), "--scalar", "q16.16"];
    let host = ok(&[&["eval"], &common[..]].concat());
    assert!(host.lines().count() == 31, "{host}");
    let target = ok(&[&["sim"], &common[..]].concat());
    assert!(host == target, "{host}\n---\n{target}");

    let mesh = dir.path().join("lit.obj");
    let report = json(&ok(&[
        "caoen",
        "mesh",
        s(&lit),
        "--subdivisions",
        "2",
        "--texture",
        "--out",
        s(&mesh),
        "--json",
    ]));
    assert_eq!(report["vertices"], 162);
    let obj = fs::read_to_string(&mesh).unwrap();
    let vt = obj.lines().filter(|l| l.starts_with("vt ")).count();
    assert_eq!(report["texture_coordinates"].as_u64().unwrap() as usize, vt);
    assert!(
        vt > 162,
        "seam and pole corners get their own entries: {vt}"
    );
    let face = obj.lines().find(|l| l.starts_with("f ")).unwrap();
    assert_eq!(
        face.split_whitespace().nth(1).unwrap().split('/').count(),
        3
    );

    let ply = dir.path().join("lit.ply");
    let error = fails(&["caoen", "mesh", s(&lit), "--texture", "--out", s(&ply)]);
    assert!(error.contains("OBJ files only"), "{error}");
    let error = fails(&[
        "caoen",
        "shade",
        s(&model),
        "--light",
        "0,0,0",
        "--out",
        s(&lit),
    ]);
    assert!(error.contains("no direction"), "{error}");
}

#[test]
fn key_counts_beyond_the_core_are_refused_before_fitting() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("k.nsb");
    // n key points spread over a sphere (a golden-angle spiral).
    let sphere = |n: u32| -> String {
        (0..n)
            .map(|i| {
                let t = f64::from(i) * 2.399_963;
                let z = 1.0 - 2.0 * (f64::from(i) + 0.5) / f64::from(n);
                let r = (1.0 - z * z).sqrt();
                format!("{} {} {}\n", r * t.cos(), r * t.sin(), z)
            })
            .collect()
    };
    // 256 key points: exactly what the core holds, written and loaded back.
    let keys = dir.path().join("keys.txt");
    fs::write(&keys, sphere(256)).unwrap();
    let fit = ok(&["caoen", "fit", s(&keys), "--out", s(&out), "--json"]);
    assert!(fit.contains("256"), "{fit}");
    ok(&["info", s(&out)]);
    fs::remove_file(&out).unwrap();
    // 257: one past.
    fs::write(&keys, sphere(257)).unwrap();
    let error = fails(&["caoen", "fit", s(&keys), "--out", s(&out)]);
    assert!(
        error.contains("257 key points") && error.contains("256"),
        "{error}"
    );
    let spot = format!("{}/../data/spot.obj", env!("CARGO_MANIFEST_DIR"));
    let error = fails(&[
        "caoen",
        "fit-mesh",
        &spot,
        "--keys",
        "300",
        "--out",
        s(&out),
    ]);
    assert!(
        error.contains("--keys") && error.contains("300") && error.contains("256"),
        "{error}"
    );
    let picture = dir.path().join("p.png");
    ok(&[
        "caoen",
        "image",
        "sample",
        "--size",
        "16,16",
        "--out",
        s(&picture),
    ]);
    let error = fails(&[
        "caoen",
        "image",
        "compress",
        s(&picture),
        "--bytes",
        "20",
        "--out",
        s(&out),
    ]);
    assert!(
        error.contains("--bytes") && error.contains("at least"),
        "{error}"
    );
    assert!(!out.exists());
}

/// The Stanford bunny as shipped (unused vertices, five holes at the base) is mapped onto the
/// sphere and fitted: the holes are capped by the command, the map does not fold (the
/// command fails otherwise), and the surface lies within 0.6 % of the diagonal of the scan
/// (two-sided RMS over the surface and the scan).
#[test]
fn fit_mesh_takes_the_scanned_bunny_with_its_holes() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bunny.nsb");
    let bunny = format!("{}/../data/stanford-bunny.obj", env!("CARGO_MANIFEST_DIR"));
    let report = json(&ok(&[
        "caoen",
        "fit-mesh",
        &bunny,
        "--keys",
        "256",
        "--out",
        s(&out),
        "--json",
    ]));
    assert_eq!(report["closing"]["holes"].as_array().unwrap().len(), 5);
    assert_eq!(report["closing"]["unused_vertices"], 1113);
    let rms = report["distance"]["rms"].as_f64().unwrap();
    let hausdorff = report["distance"]["hausdorff"].as_f64().unwrap();
    assert!(rms <= 0.006 && hausdorff < 0.05, "{report}");
    assert!(
        report["area_distortion"].as_f64().unwrap() < 4.0,
        "{report}"
    );
    // The blob loads and meshes.
    let mesh = dir.path().join("bunny.obj");
    ok(&["caoen", "mesh", s(&out), "--out", s(&mesh)]);
    // A torus is another genus: refused, naming it.
    let torus = dir.path().join("torus.obj");
    let mut text = String::new();
    let (around, across) = (24, 12);
    for i in 0..around {
        for j in 0..across {
            let (a, b) = (
                std::f64::consts::TAU * i as f64 / around as f64,
                std::f64::consts::TAU * j as f64 / across as f64,
            );
            let r = 1.0 + 0.35 * b.cos();
            text += &format!("v {} {} {}\n", r * a.cos(), r * a.sin(), 0.35 * b.sin());
        }
    }
    for i in 0..around {
        for j in 0..across {
            let v = |i: usize, j: usize| (i % around) * across + (j % across) + 1;
            let (p, q, r, t) = (v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1));
            text += &format!("f {p} {q} {t}\nf {p} {t} {r}\n");
        }
    }
    fs::write(&torus, text).unwrap();
    let error = fails(&["caoen", "fit-mesh", s(&torus), "--out", s(&out)]);
    assert!(error.contains("genus 1"), "{error}");
}

/// The paper's derived networks from the command line: the approximate normals (angle error
/// reported) and the perspective view (screen error reported), each a blob that the host and
/// the simulated target evaluate alike in both scalars.
#[test]
fn normal_and_perspective_networks_are_blobs_the_target_evaluates() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("bean.nsb");
    ok(&[
        "caoen",
        "fit",
        s(&targets_file(dir.path())),
        "--out",
        s(&model),
    ]);
    let sources = sphere_points(dir.path());
    let normals = dir.path().join("normals.nsb");
    let report = json(&ok(&[
        "caoen",
        "normals",
        s(&model),
        "--out",
        s(&normals),
        "--json",
    ]));
    assert_eq!(report["key_points"], 26);
    let (mean, max) = (
        report["mean_error_degrees"].as_f64().unwrap(),
        report["max_error_degrees"].as_f64().unwrap(),
    );
    assert!(mean > 0.0 && mean <= max && max < 45.0, "{report}");
    let near = dir.path().join("near.nsb");
    let far = dir.path().join("far.nsb");
    let mut relative = Vec::new();
    for (eye, out) in [("0.5,0.8,3", &near), ("1.5,2.4,9", &far)] {
        let report = json(&ok(&[
            "caoen",
            "perspective",
            s(&model),
            "--eye",
            eye,
            "--focal",
            "2",
            "--out",
            s(out),
            "--json",
        ]));
        assert!(
            report["max_error_at_keys"].as_f64().unwrap() < 1e-6,
            "{report}"
        );
        relative.push(
            report["max_screen_error"].as_f64().unwrap()
                / report["screen_extent"].as_f64().unwrap(),
        );
    }
    println!(
        "perspective screen error / picture: near {:.2e}, far {:.2e}",
        relative[0], relative[1]
    );
    assert!(
        relative[1] < relative[0] && relative[0] < 0.05,
        "{relative:?}"
    );
    for blob in [&normals, &near] {
        for scalar in ["f32", "q16.16"] {
            let common = [s(blob), "--points", s(&sources), "--scalar", scalar];
            let host = ok(&[&["eval"], &common[..]].concat());
            let target = ok(&[&["sim"], &common[..]].concat());
            assert!(host == target, "{scalar}\n{host}\n---\n{target}");
        }
    }
    let e = fails(&[
        "caoen",
        "perspective",
        s(&model),
        "--eye",
        "0,0,0.1",
        "--out",
        s(&dir.path().join("inside.nsb")),
    ]);
    assert!(e.contains("in front of the eye"), "{e}");
    assert!(!dir.path().join("inside.nsb").exists());
    let e = fails(&[
        "caoen",
        "perspective",
        s(&model),
        "--eye",
        "0,0,0",
        "--out",
        s(&dir.path().join("nowhere.nsb")),
    ]);
    assert!(e.contains("--look-at"), "{e}");
}

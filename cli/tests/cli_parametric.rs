//! `neurosurf parametric …` run as a user would: sample points on a known surface, embed them, fit
//! a surface network, tessellate it both ways, evaluate the blob on the host and on the
//! simulated Cortex-M4F (which must print exactly what the host prints), stitch two patches
//! and fill a hole. Bad point sets fail with a message naming the problem and write nothing.

mod common;

use common::{fails, ok, wavy_points};
use std::fs;
use std::path::Path;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

#[test]
fn points_to_network_to_meshes_and_the_target_agrees() {
    let dir = tempfile::tempdir().unwrap();
    let (points, uv, blob) = (
        dir.path().join("wavy.txt"),
        dir.path().join("uv.txt"),
        dir.path().join("wavy.nsb"),
    );
    ok(&[
        "parametric",
        "sample",
        "wavy",
        "--points",
        "300",
        "--seed",
        "4",
        "--out",
        s(&points),
    ]);
    let embedded = json(&ok(&[
        "parametric",
        "embed",
        s(&points),
        "--out",
        s(&uv),
        "--json",
    ]));
    assert_eq!(embedded["points"], 300);
    assert_eq!(fs::read_to_string(&uv).unwrap().lines().count(), 300);
    let fit = json(&ok(&[
        "parametric",
        "fit",
        s(&points),
        "--parameters",
        s(&uv),
        "--max-neurons",
        "6",
        "--scalar",
        "q16.16",
        "--out",
        s(&blob),
        "--json",
    ]));
    assert_eq!(fit["stored_as"], "q16.16");
    assert!(fit["relative_rms_error"].as_f64().unwrap() < 0.01, "{fit}");
    let layers = fit["hidden_layers"].as_array().unwrap();
    assert!(!layers.is_empty() && layers.len() <= 2, "{fit}");
    // The blob records the points fitted: a coarse network's first fit may leave out a few
    // where its own error changes fastest (at most 2 %).
    let off_fit = fit["off_fit"].as_u64().unwrap();
    assert!(fit["outliers"] == 0 && off_fit <= 6, "{fit}");
    let info = ok(&["info", s(&blob)]);
    assert!(
        info.contains("surface-network") && info.contains(&format!("{} points", 300 - off_fit)),
        "{info}"
    );

    for (method, out, resolution) in [("coons", "grid.obj", "20"), ("delaunay", "tri.ply", "20")] {
        let mesh = dir.path().join(out);
        let report = json(&ok(&[
            "parametric",
            "tessellate",
            s(&blob),
            "--parameters",
            s(&uv),
            "--method",
            method,
            "--resolution",
            resolution,
            "--out",
            s(&mesh),
            "--json",
        ]));
        assert_eq!(report["non_manifold_edges"], 0, "{method}");
        assert!(
            report["boundary_edges"].as_u64().unwrap() > 20,
            "{method}: an open patch"
        );
        let vertices = report["vertices"].as_u64().unwrap();
        if method == "coons" {
            assert_eq!(
                (vertices, report["triangles"].as_u64().unwrap()),
                (400, 2 * 19 * 19)
            );
        } else {
            assert!((250..600).contains(&vertices), "{report}");
        }
        assert!(fs::metadata(&mesh).unwrap().len() > 1000);
    }
    // Without parameters: the trained (u, v) box.
    let boxed = dir.path().join("box.obj");
    let report = json(&ok(&[
        "parametric",
        "tessellate",
        s(&blob),
        "--resolution",
        "8",
        "--out",
        s(&boxed),
        "--json",
    ]));
    assert_eq!(report["vertices"], 64);

    // `u v` queries: the target prints exactly what the host's core prints.
    let queries = dir.path().join("q.txt");
    fs::write(&queries, "0 0\n0.5 -0.25\n-1 1\n1.5 0.3\n").unwrap();
    let host = ok(&[
        "eval",
        s(&blob),
        "--points",
        s(&queries),
        "--scalar",
        "q16.16",
    ]);
    assert!(host.starts_with("u,v,x,y,z,nx,ny,nz"), "{host}");
    assert_eq!(host.lines().count(), 5);
    let target = ok(&[
        "sim",
        s(&blob),
        "--points",
        s(&queries),
        "--scalar",
        "q16.16",
    ]);
    assert_eq!(host, target);
}

#[test]
fn stitched_patches_are_watertight_and_a_punched_fandisk_is_filled() {
    let dir = tempfile::tempdir().unwrap();
    let (points, blob, top) = (
        dir.path().join("plane.txt"),
        dir.path().join("plane.nsb"),
        dir.path().join("top.obj"),
    );
    ok(&[
        "parametric",
        "sample",
        "plane",
        "--points",
        "200",
        "--out",
        s(&points),
    ]);
    ok(&[
        "parametric",
        "fit",
        s(&points),
        "--max-neurons",
        "3",
        "--out",
        s(&blob),
    ]);
    ok(&[
        "parametric",
        "tessellate",
        s(&blob),
        "--resolution",
        "12",
        "--out",
        s(&top),
    ]);
    // The same patch lifted by `dz`.
    let lifted = |dz: f64, name: &str| {
        let text: String = fs::read_to_string(&top)
            .unwrap()
            .lines()
            .map(|line| match line.strip_prefix("v ") {
                Some(rest) => {
                    let c: Vec<f64> = rest
                        .split_whitespace()
                        .map(|x| x.parse().unwrap())
                        .collect();
                    format!("v {} {} {}\n", c[0], c[1], c[2] + dz)
                }
                None => format!("{line}\n"),
            })
            .collect();
        let path = dir.path().join(name);
        fs::write(&path, text).unwrap();
        path
    };
    // 1.5 above (more than half the patch's size): the loops do not meet, no seam.
    let far = lifted(1.5, "far.obj");
    let e = fails(&[
        "parametric",
        "stitch",
        s(&top),
        s(&far),
        "--out",
        s(&dir.path().join("dragged.ply")),
    ]);
    assert!(e.contains("do not meet"), "{e}");
    assert!(!dir.path().join("dragged.ply").exists());
    // 0.05 above: stitched to the first, a closed pillow.
    let bottom = lifted(0.05, "bottom.obj");
    let stitched = dir.path().join("pillow.ply");
    let report = json(&ok(&[
        "parametric",
        "stitch",
        s(&top),
        s(&bottom),
        "--out",
        s(&stitched),
        "--json",
    ]));
    assert_eq!(report["watertight"], true, "{report}");
    assert_eq!(report["gap_after"], 0.0);
    assert!((report["gap_before"].as_f64().unwrap() - 0.05).abs() < 1e-6);
    let e = fails(&[
        "parametric",
        "stitch",
        s(&top),
        s(&bottom),
        s(&top),
        "--out",
        s(&stitched),
    ]);
    assert!(e.contains("--seam"), "{e}");

    let Ok(fandisk) = neurosurf_trainer::io::data_file("fandisk.obj") else {
        eprintln!("fandisk.obj not found: skipped");
        return;
    };
    let filled = dir.path().join("filled.obj");
    let punched = |punch: &str, more: &[&str]| {
        let args = [
            &["parametric", "fill-hole", s(&fandisk), "--punch", punch][..],
            more,
            &["--out", s(&filled), "--json"],
        ]
        .concat();
        json(&ok(&args))
    };
    let report = punched("1000,3", &[]);
    assert_eq!(
        (report["holes"].as_u64(), report["watertight"].as_bool()),
        (Some(1), Some(true))
    );
    assert!(report["new_vertices"].as_u64().unwrap() > 5, "{report}");
    // Sharp creases run through the region: the network's surface is kept.
    assert_eq!(report["faired"], 0, "{report}");
    // The punched triangles' inner vertices are gone from the output, not left unused.
    assert!(
        report["removed_unused_vertices"].as_u64().unwrap() > 0,
        "{report}"
    );
    assert_eq!(unused_obj_vertices(&filled), 0);
    let e = fails(&["parametric", "fill-hole", s(&fandisk), "--out", s(&filled)]);
    assert!(e.contains("has no holes"), "{e}");
    // A hole across fandisk's crease: LLE folds its region, Tutte's embedding fills it.
    let report = punched("1444,3", &[]);
    assert_eq!(report["tutte_embeddings"], 1, "{report}");
    assert_eq!(report["watertight"], true, "{report}");
    // A smooth surface: the fill is faired, unless --no-fairing keeps the network's.
    let spot = neurosurf_trainer::io::data_file("spot.obj").unwrap();
    for (more, faired) in [(&[][..], 1), (&["--no-fairing"][..], 0)] {
        let args = [
            &["parametric", "fill-hole", s(&spot), "--punch", "100,3"][..],
            more,
            &["--out", s(&filled), "--json"],
        ]
        .concat();
        let report = json(&ok(&args));
        assert_eq!(
            (report["faired"].as_u64(), report["watertight"].as_bool()),
            (Some(faired), Some(true)),
            "{report}"
        );
    }

    // A real scan: the bunny's 5 holes. One outline crosses itself in LLE's plane and is
    // filled through Tutte's embedding; a hole left open would be named with its reason.
    let bunny = neurosurf_trainer::io::data_file("stanford-bunny.obj").unwrap();
    let report = json(&ok(&[
        "parametric",
        "fill-hole",
        s(&bunny),
        "--out",
        s(&filled),
        "--json",
    ]));
    assert_eq!(report["holes"], 5, "{report}");
    assert_eq!(report["filled"], 5, "{report}");
    for open in report["unfilled"].as_array().unwrap() {
        assert!(!open["reason"].as_str().unwrap().is_empty(), "{report}");
    }
    assert_eq!(unused_obj_vertices(&filled), 0);
}

/// Vertices of an OBJ file that no face uses.
fn unused_obj_vertices(path: &Path) -> usize {
    let text = fs::read_to_string(path).unwrap();
    let count = text.lines().filter(|l| l.starts_with("v ")).count();
    let mut used = vec![false; count];
    for line in text.lines().filter(|l| l.starts_with("f ")) {
        for corner in line.split_whitespace().skip(1) {
            let v: usize = corner.split('/').next().unwrap().parse().unwrap();
            used[v - 1] = true;
        }
    }
    used.iter().filter(|u| !**u).count()
}

#[test]
fn bad_point_sets_fail_clearly_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.txt");
    let write = |name: &str, text: String| {
        let path = dir.path().join(name);
        fs::write(&path, text).unwrap();
        path
    };
    let line = write(
        "line.txt",
        (0..20).map(|i| format!("{i} {i} {i}\n")).collect(),
    );
    let few = write(
        "few.txt",
        (0..5).map(|i| format!("{i} {} 0\n", i * i)).collect(),
    );
    let grid: String = (0..30)
        .map(|i| format!("{} {} 0.1\n", i % 6, i / 6))
        .collect();
    let duplicate = write("dup.txt", grid.clone() + "2 3 0.1\n");
    let sphere = dir.path().join("sphere.txt");
    ok(&[
        "parametric",
        "sample",
        "sphere",
        "--points",
        "400",
        "--out",
        s(&sphere),
    ]);
    for (points, expected) in [
        (&line, "line"),
        (&few, "too few"),
        (&duplicate, "coincide"),
        (&sphere, "cannot flatten"),
    ] {
        let e = fails(&["parametric", "embed", s(points), "--out", s(&out)]);
        assert!(e.contains(expected), "{}: {e}", points.display());
        let blob = dir.path().join("x.nsb");
        let e = fails(&["parametric", "fit", s(points), "--out", s(&blob)]);
        assert!(e.contains(expected), "{}: {e}", points.display());
        assert!(!out.exists() && !blob.exists());
    }
    let e = fails(&["parametric", "tessellate", s(&line), "--out", s(&out)]);
    assert!(e.contains(s(&line)), "{e}");
}

#[test]
fn network_sizes_beyond_the_core_are_refused_before_fitting() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("wavy.txt");
    wavy_points(&points, 200);
    let out = dir.path().join("n.nsb");
    for (flag, value, limit) in [("--max-neurons", "33", "32"), ("--max-layers", "5", "4")] {
        let error = fails(&[
            "parametric",
            "fit",
            s(&points),
            flag,
            value,
            "--out",
            s(&out),
        ]);
        assert!(
            error.contains(flag) && error.contains(value) && error.contains(limit),
            "{error}"
        );
    }
    assert!(!out.exists());
}

#[test]
fn compare_measures_four_methods_on_any_patch_against_a_truth_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let points = dir.path().join("cylinder.txt");
    ok(&[
        "patch",
        "sample",
        "cylinder",
        "--points",
        "600",
        "--out",
        s(&points),
    ]);
    let table = ok(&["patch", "compare", s(&points), "--max-neurons", "6"]);
    for method in ["network", "rbf-low", "rbf-high", "delaunay"] {
        assert!(table.contains(method), "{table}");
    }
    // Against the fandisk itself, a patch cut out of it.
    let fandisk = format!("{}/../data/fandisk.obj", env!("CARGO_MANIFEST_DIR"));
    let mesh = neurosurf_trainer::io::read_mesh(Path::new(&fandisk)).unwrap();
    let center = mesh.positions[500];
    let radius = 0.125 * neurosurf_trainer::geometry::bounding_diagonal(&mesh);
    let patch: String = mesh
        .positions
        .iter()
        .filter(|p| (0..3).map(|k| (p[k] - center[k]).powi(2)).sum::<f64>() < radius * radius)
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    let cut = dir.path().join("fandisk-patch.txt");
    fs::write(&cut, patch).unwrap();
    let report = json(&ok(&[
        "patch",
        "compare",
        s(&cut),
        "--truth",
        &fandisk,
        "--max-neurons",
        "6",
        "--json",
    ]));
    assert_eq!(report["reference"], "truth mesh");
    let rows = report["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    for row in rows {
        let (held, mesh) = (
            row["held_out_rms"].as_f64().unwrap(),
            row["mesh_rms"].as_f64().unwrap(),
        );
        assert!(held > 0.0 && held < 0.02 && mesh < 0.02, "{row}");
    }
}

#[test]
fn fit_leaves_out_points_off_the_surface_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (points, blob) = (dir.path().join("wavy.txt"), dir.path().join("wavy.nsb"));
    ok(&[
        "patch",
        "sample",
        "wavy",
        "--points",
        "600",
        "--seed",
        "2",
        "--out",
        s(&points),
    ]);
    // Six points well above and below the patch.
    let mut text = fs::read_to_string(&points).unwrap();
    for k in 0..6 {
        let x = -0.8 + 0.3 * f64::from(k);
        text.push_str(&format!(
            "{x} {} {}\n",
            0.5 - 0.2 * f64::from(k),
            if k % 2 == 0 { 0.6 } else { -0.6 }
        ));
    }
    fs::write(&points, text).unwrap();
    let args = [
        "patch",
        "fit",
        s(&points),
        "--max-neurons",
        "6",
        "--out",
        s(&blob),
    ];
    let report = json(&ok(&[&args[..], &["--json"]].concat()));
    // The six, and at most two sparse surface points (this clean sample alone loses one).
    let left_out = report["outliers"].as_u64().unwrap();
    assert!((6..=8).contains(&left_out), "{report}");
    // Surface points the first fit misses by more than their neighbours: a few at most.
    let off_fit = report["off_fit"].as_u64().unwrap();
    assert!(off_fit <= 12, "{report}");
    let text = ok(&args);
    let said = match off_fit {
        0 => format!("less {left_out} off the surface (--keep-outliers fits them)"),
        m => format!(
            "less {left_out} off the surface and {m} off the first fit (--keep-outliers fits \
             them)"
        ),
    };
    assert!(text.contains(&said), "{text}");
    let kept = json(&ok(&[&args[..], &["--json", "--keep-outliers"]].concat()));
    assert_eq!(
        (&kept["outliers"], &kept["off_fit"]),
        (&0.into(), &0.into()),
        "{kept}"
    );
}

#[test]
fn the_blob_keeps_the_points_region_for_tessellate_and_eval() {
    // A saddle whose half x > 0 is sampled ten times more sparsely (a fixed pseudo-random
    // sequence, so the file is the same on every machine).
    let dir = tempfile::tempdir().unwrap();
    let (points, blob) = (dir.path().join("saddle.txt"), dir.path().join("saddle.nsb"));
    let mut text = String::new();
    let mut state = 0x2545_f491_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut count = 0;
    while count < 1_500 {
        let (x, y, keep) = (2.0 * next() - 1.0, 2.0 * next() - 1.0, next());
        if x < 0.0 || keep < 0.1 {
            text.push_str(&format!("{x} {y} {}\n", x * y));
            count += 1;
        }
    }
    fs::write(&points, text).unwrap();
    let fitted = json(&ok(&[
        "parametric",
        "fit",
        s(&points),
        "--out",
        s(&blob),
        "--json",
    ]));
    assert_eq!(fitted["parameterization"], "unrolled");
    let corners = fitted["region_corners"].as_u64().unwrap();
    assert!(corners >= 20, "{fitted}");
    assert!(ok(&["info", s(&blob)]).contains(&format!("region       {corners} corners")));
    // Without --parameters, both tessellations mesh the stored region: every vertex lies on
    // the saddle within the points' square (the trained box's corners lie far outside it).
    for method in ["coons", "delaunay"] {
        let mesh = dir.path().join(format!("{method}.obj"));
        ok(&[
            "parametric",
            "tessellate",
            s(&blob),
            "--method",
            method,
            "--out",
            s(&mesh),
        ]);
        let obj = fs::read_to_string(&mesh).unwrap();
        for line in obj.lines().filter(|l| l.starts_with("v ")) {
            let v: Vec<f64> = line[2..]
                .split_whitespace()
                .map(|t| t.parse().unwrap())
                .collect();
            assert!(v[0].abs() < 1.05 && v[1].abs() < 1.05, "{method}: {v:?}");
            assert!((v[2] - v[0] * v[1]).abs() < 0.07, "{method}: {v:?}");
        }
    }
    // eval warns about parameters outside the region, and only about those.
    let query = dir.path().join("uv.txt");
    fs::write(&query, "0 0\n40 40\n").unwrap();
    let out = common::neurosurf(&["eval", s(&blob), "--points", s(&query)]);
    assert!(out.status.success());
    let warning = String::from_utf8_lossy(&out.stderr);
    assert!(
        warning.contains("1 of 2 parameter points lie outside the region"),
        "{warning}"
    );
}

/// Writes an OBJ of the triangles of an `n × m` grid over (u, v) ∈ [0, 1]² mapped by `at`,
/// optionally wrapping u around (the last column is the first).
fn grid_obj(path: &Path, n: usize, m: usize, wrap: bool, at: impl Fn(f64, f64) -> [f64; 3]) {
    let columns = if wrap { n } else { n + 1 };
    let mut text = String::new();
    for j in 0..=m {
        for i in 0..columns {
            let p = at(i as f64 / n as f64, j as f64 / m as f64);
            text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
        }
    }
    let id = |i: usize, j: usize| j * columns + i % columns + 1;
    for j in 0..m {
        for i in 0..n {
            let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
            text += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
        }
    }
    fs::write(path, text).unwrap();
}

#[test]
fn a_can_of_three_patches_and_a_box_of_six_are_stitched_without_options() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let (r, h) = (0.5, 1.5);
    let tau = std::f64::consts::TAU;
    // The side wraps around: one column of vertices is both its first and its last.
    grid_obj(&path("side.obj"), 40, 8, true, |u, v| {
        [r * (tau * u).cos(), r * (tau * u).sin(), h * v]
    });
    for (name, z, sectors) in [("bottom.obj", 0.0, 30), ("top.obj", h, 52)] {
        // A disc: rings from radius r down to 0.02 r, the innermost ring closed by a polygon
        // fan written by hand.
        let rings = 5;
        let mut text = String::new();
        for ring in 0..=rings {
            let rho = r * (1.0 - 0.98 * ring as f64 / rings as f64);
            for s in 0..sectors {
                let a = tau * s as f64 / sectors as f64;
                text += &format!("v {} {} {z}\n", rho * a.cos(), rho * a.sin());
            }
        }
        text += &format!("v 0 0 {z}\n");
        let id = |ring: usize, s: usize| ring * sectors + s % sectors + 1;
        for ring in 0..rings {
            for s in 0..sectors {
                let (a, b, c, d) = (
                    id(ring, s),
                    id(ring, s + 1),
                    id(ring + 1, s + 1),
                    id(ring + 1, s),
                );
                text += &format!("f {a} {b} {c}\nf {a} {c} {d}\n");
            }
        }
        let centre = (rings + 1) * sectors + 1;
        for s in 0..sectors {
            text += &format!("f {} {} {centre}\n", id(rings, s), id(rings, s + 1));
        }
        fs::write(path(name), text).unwrap();
    }
    let report = json(&ok(&[
        "parametric",
        "stitch",
        s(&path("bottom.obj")),
        s(&path("side.obj")),
        s(&path("top.obj")),
        "--out",
        s(&path("can.ply")),
        "--json",
    ]));
    assert_eq!(report["watertight"], true, "{report}");
    assert_eq!(
        (report["seams"].as_u64(), report["partial_seams"].as_u64()),
        (Some(2), Some(0))
    );
    assert_eq!(report["boundary_loops"], 0);

    // A box whose six faces have six different grids: twelve partial seams.
    let corner = [-1.0, -1.0, -1.0];
    let faces: [([f64; 3], [f64; 3], [f64; 3]); 6] = [
        (corner, [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
        ([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
        (corner, [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
        ([-1.0, 1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
        (corner, [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
        ([1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
    ];
    let mut args: Vec<String> = vec!["parametric".into(), "stitch".into()];
    for (f, (o, du, dv)) in faces.iter().enumerate() {
        let file = path(&format!("face{f}.obj"));
        grid_obj(&file, 3 + f, 9 - f, false, |u, v| {
            [0, 1, 2].map(|c| o[c] + u * du[c] + v * dv[c])
        });
        args.push(s(&file).to_string());
    }
    args.extend([
        "--out".into(),
        s(&path("box.obj")).to_string(),
        "--json".into(),
    ]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let report = json(&ok(&args));
    assert_eq!(report["watertight"], true, "{report}");
    assert_eq!(
        (report["seams"].as_u64(), report["partial_seams"].as_u64()),
        (Some(12), Some(12))
    );
    // Two of the faces only, far apart: refused, nothing written.
    let e = fails(&[
        "parametric",
        "stitch",
        args[2],
        args[3],
        "--out",
        s(&path("pair.obj")),
    ]);
    assert!(e.contains("do not meet"), "{e}");
    assert!(!path("pair.obj").exists());
    // `closed` takes point clouds too, but not three points.
    fs::write(path("cloud.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    let e = fails(&[
        "parametric",
        "closed",
        s(&path("cloud.obj")),
        "--out",
        s(&path("cloud.ply")),
    ]);
    assert!(e.contains("3 points are too few"), "{e}");
    assert!(!path("cloud.ply").exists());
}

#[test]
fn the_bunny_is_rebuilt_closed_and_its_patch_blobs_meet_at_their_seams() {
    let Ok(bunny) = neurosurf_trainer::io::data_file("stanford-bunny.obj") else {
        eprintln!("stanford-bunny.obj not found: skipped");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (out, blobs) = (dir.path().join("bunny.ply"), dir.path().join("patches"));
    let report = json(&ok(&[
        "parametric",
        "closed",
        s(&bunny),
        "--out",
        s(&out),
        "--blobs",
        s(&blobs),
        "--max-layers",
        "1",
        "--json",
    ]));
    // One hidden layer keeps the test short. Measured: 51 patches, 5 holes capped, RMS
    // 0.33 % of the diagonal both ways (0.18 % with the default two layers).
    assert_eq!(report["watertight"], true, "{report}");
    assert_eq!(report["capped_holes"], 5);
    assert!(
        report["relative_rms_error"].as_f64().unwrap() < 0.005,
        "{report}"
    );
    let seams: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(blobs.join("seams.json")).unwrap()).unwrap();
    let patches = seams["patches"].as_array().unwrap();
    assert_eq!(Some(patches.len() as u64), report["patches"].as_u64());
    // The core evaluates both blobs of a seam at its points' two (u, v): the same points.
    let seam = &seams["seams"][0];
    let evaluate = |side: &str, patch: &serde_json::Value| -> Vec<[f64; 3]> {
        let uv = dir.path().join(format!("seam-{side}.txt"));
        let rows: String = seam[format!("parameters_{side}")]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| format!("{} {}\n", p[0], p[1]))
            .collect();
        fs::write(&uv, rows).unwrap();
        let blob = blobs.join(patches[patch.as_u64().unwrap() as usize].as_str().unwrap());
        ok(&["eval", s(&blob), "--points", s(&uv)])
            .lines()
            .filter_map(|line| {
                let c: Vec<f64> = line.split(',').filter_map(|x| x.parse().ok()).collect();
                (c.len() >= 5).then(|| [c[2], c[3], c[4]])
            })
            .collect()
    };
    let (a, b) = (
        evaluate("a", &seam["patch_a"]),
        evaluate("b", &seam["patch_b"]),
    );
    assert!(
        a.len() >= 3 && a.len() == b.len(),
        "{} {}",
        a.len(),
        b.len()
    );
    let gaps: Vec<f64> = a
        .iter()
        .zip(&b)
        .map(|(p, q)| {
            ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
        })
        .collect();
    let mean = gaps.iter().sum::<f64>() / gaps.len() as f64;
    let max = gaps.iter().copied().fold(0.0, f64::max);
    eprintln!("seam gaps: mean {mean:.2e}, max {max:.2e}");
    // The bunny's diagonal is 0.21. Each network fits the seam's input vertices on its own, so
    // the two miss each other by both fit errors (measured with one layer: mean 1.6 %, max
    // 3.5 % of the diagonal); the stitch closes the gap in the mesh.
    assert!(mean < 0.0042 && max < 0.0105, "mean {mean}, max {max}");
}

#[test]
fn a_closed_point_cloud_is_meshed_then_rebuilt_from_patches() {
    // spot's vertices alone, as text rows: no triangles to go by.
    let spot = neurosurf_trainer::io::read_mesh(
        &neurosurf_trainer::io::data_file("spot.obj").expect("spot.obj ships with the repository"),
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (cloud, out, blobs) = (
        dir.path().join("spot.xyz"),
        dir.path().join("spot.obj"),
        dir.path().join("patches"),
    );
    let rows: String = spot
        .positions
        .iter()
        .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
        .collect();
    fs::write(&cloud, rows).unwrap();
    let report = json(&ok(&[
        "parametric",
        "closed",
        s(&cloud),
        "--out",
        s(&out),
        "--blobs",
        s(&blobs),
        "--max-layers",
        "1",
        "--json",
    ]));
    // Measured with one layer: 30 patches, RMS 0.2 % of the diagonal from the points both ways.
    assert_eq!(report["watertight"], true, "{report}");
    assert_eq!(report["from_points"]["points"], spot.positions.len());
    assert_eq!(report["capped_holes"], 0);
    assert!(
        report["relative_rms_error"].as_f64().unwrap() < 0.005,
        "{report}"
    );
    let written = fs::read_dir(&blobs).unwrap().count() as u64;
    assert_eq!(Some(written), report["patches"].as_u64().map(|p| p + 1));
    // The text summary says the points were meshed first.
    let text = ok(&[
        "parametric",
        "closed",
        s(&cloud),
        "--out",
        s(&out),
        "--max-layers",
        "1",
        "--patches",
        "6",
    ]);
    assert!(text.contains("meshed 2930 points"), "{text}");
}

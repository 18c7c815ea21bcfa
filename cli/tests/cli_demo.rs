//! The README's main job, `neurosurf demo`, run as a user would: it trains and measures every
//! built-in model, writes what it says it writes, and reports numbers that hold the claims.

mod common;

use common::{fails, ok};

#[test]
fn the_demo_writes_every_model_and_reports_their_accuracy() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let text = ok(&["demo", "--quick", "--out", out.to_str().unwrap(), "--json"]);
    let report: serde_json::Value = serde_json::from_str(&text).unwrap();
    let models = report["models"].as_array().unwrap();
    let names: Vec<&str> = models.iter().map(|m| m["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["torus", "head"]);
    for model in models {
        for blob in model["blobs"].as_array().unwrap() {
            let path = blob[0].as_str().unwrap();
            assert_eq!(
                std::fs::metadata(path).unwrap().len(),
                blob[1].as_u64().unwrap()
            );
        }
    }
    let parametric = report["parametric"].as_array().unwrap();
    let curve = &parametric[0];
    assert_eq!(curve["name"], "curve");
    assert!(curve["quality"][0][1].as_f64().unwrap() >= 0.95, "{curve}");
    assert!(curve["quality"][1][1].as_f64().unwrap() <= 0.01, "{curve}");
    let cao_en = &parametric[1];
    assert!(cao_en["quality"][0][1].as_f64().unwrap() < 1e-9, "{cao_en}");
    for demo in parametric {
        assert_eq!(demo["deviation"].as_array().unwrap().len(), 2, "{demo}");
        for (precision, deviation) in demo["deviation"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| (d[0].as_str().unwrap(), &d[1]))
        {
            let limit = if precision == "F32" { 1e-5 } else { 1e-3 };
            let max = deviation["field_max"].as_f64().unwrap();
            assert!(max < limit, "{} {precision}: {max}", demo["name"]);
        }
    }
    let png = image::open(out.join("curve-peanut.png")).unwrap();
    assert_eq!((png.width(), png.height()), (720, 330));
    let obj = std::fs::read_to_string(out.join("cao-en.obj")).unwrap();
    assert_eq!(obj.lines().filter(|l| l.starts_with("v ")).count(), 2562);
    the_tour_learned_the_body_and_its_animation(&report["tour"]);
    the_report_page_shows_existing_pictures(&out, &report);
}

/// The §6–7 tour: 316 points in 17 features, 33 modules, none cut by the iteration cap, close
/// to the true body; the warm-started frames settle in fewer iterations than the cold start.
fn the_tour_learned_the_body_and_its_animation(tour: &serde_json::Value) {
    let body = &tour["body"];
    assert_eq!(body["control_points"], 316, "{body}");
    assert_eq!(body["features"].as_array().unwrap().len(), 17);
    assert_eq!(body["modules"].as_array().unwrap().len(), 33);
    assert_ne!(body["outcome"]["stop"], "iteration_cap", "{body}");
    let fidelity = &body["fidelity"];
    assert!(
        fidelity["median_distance_percent"].as_f64().unwrap() < 0.1,
        "{fidelity}"
    );
    assert!(
        fidelity["median_angle_degrees"].as_f64().unwrap() < 5.0,
        "{fidelity}"
    );
    let animation = &tour["animation"];
    assert_ne!(animation["outcome"]["stop"], "iteration_cap", "{animation}");
    assert_eq!(animation["per_frame"].as_array().unwrap().len(), 5);
    let warm = animation["iterations"]["average"].as_f64().unwrap();
    let cold = animation["cold_iterations"].as_f64().unwrap();
    assert!(warm < cold, "warm {warm} cold {cold}");
    let last = &animation["last_fidelity"];
    assert!(
        last["median_distance_percent"].as_f64().unwrap() < 0.1,
        "{last}"
    );
    // The mesh body (when the shared data is there): 17 automatic features, close to the slab
    // at most points even though its sharp edges keep the modules above the threshold.
    let woody = &tour["woody"];
    if !woody.is_null() {
        assert_eq!(woody["features"], 17, "{woody}");
        let median = woody["fidelity"]["median_distance_percent"]
            .as_f64()
            .unwrap();
        assert!(median < 0.5, "{woody}");
    }
    let tables: Vec<&str> = tour["timings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["table"].as_str().unwrap())
        .collect();
    for table in ["Table 2", "Table 3", "Table 4"] {
        assert!(tables.contains(&table), "{tables:?}");
    }
    the_tour_measured_table_5(&tour["table5"]);
}

/// Table 5 in the quick tour: the paper's first three point counts, each beside the paper's
/// row, both models trained and measured; the network beats the RBF on the fewest points.
fn the_tour_measured_table_5(rows: &serde_json::Value) {
    let rows = rows.as_array().unwrap();
    let points: Vec<u64> = rows.iter().map(|r| r["points"].as_u64().unwrap()).collect();
    assert_eq!(points, [48, 96, 160]);
    for row in rows {
        assert_eq!(row["paper"]["points"], row["points"], "{row}");
        assert_ne!(row["outcome"]["stop"], "iteration_cap", "{row}");
        assert!(row["iterations"].as_f64().unwrap() >= 1.0, "{row}");
        for key in ["network_seconds", "rbf_seconds"] {
            assert!(row[key].as_f64().unwrap() > 0.0, "{key}: {row}");
        }
        let network = row["network_distance_percent"].as_f64().unwrap();
        assert!(network < 0.2, "{row}");
        assert!(row["rbf_distance_percent"].as_f64().unwrap() > 0.0, "{row}");
    }
    let first = &rows[0];
    assert!(
        first["network_distance_percent"].as_f64().unwrap()
            < first["rbf_distance_percent"].as_f64().unwrap(),
        "{first}"
    );
}

/// Every picture the report names is a PNG in the folder, referenced relatively from
/// `index.html`; every `src` in the page is one of them.
fn the_report_page_shows_existing_pictures(out: &std::path::Path, report: &serde_json::Value) {
    let index = std::path::PathBuf::from(report["index"].as_str().unwrap());
    assert_eq!(index, out.join("index.html"));
    let page = std::fs::read_to_string(&index).unwrap();
    let sources: Vec<&str> = page
        .split("src=\"")
        .skip(1)
        .map(|rest| &rest[..rest.find('"').unwrap()])
        .collect();
    let tour = &report["tour"];
    let mut pictures: Vec<&str> = tour["pictures"]
        .as_array()
        .unwrap()
        .iter()
        .chain(tour["memorization"].as_array().unwrap())
        .map(|p| p["file"].as_str().unwrap())
        .collect();
    for expected in [
        "torus.png",
        "head.png",
        "body-front.png",
        "frame-00.png",
        "frame-03.png",
        "frame-05.png",
        "head-memorization-3.png",
    ] {
        assert!(pictures.contains(&expected), "{pictures:?}");
    }
    pictures.sort_unstable();
    let mut shown = sources.clone();
    shown.sort_unstable();
    assert_eq!(shown, pictures);
    for source in sources {
        assert!(!source.contains('/') && !source.contains(':'), "{source}");
        let png = image::open(out.join(source)).unwrap();
        assert!(png.width() >= 48 && png.height() >= 48, "{source}");
    }
    for table in [
        "Table 2", "Table 3", "Table 4", "Table 5", "352 s", "q16.16",
    ] {
        assert!(page.contains(table), "{table}");
    }
    // Table 5's rows: the measured numbers of the JSON report beside the paper's.
    for row in tour["table5"].as_array().unwrap() {
        let cells = format!(
            "<tr><td>{}</td><td>{:.0} ({}) (+ {:.0})</td>",
            row["points"],
            row["iterations"].as_f64().unwrap(),
            row["paper"]["iterations"],
            row["coarse_iterations"].as_f64().unwrap()
        );
        assert!(page.contains(&cells), "{cells}");
        let fidelity = format!(
            "<td>{:.3} % / {:.2}°</td>",
            row["network_distance_percent"].as_f64().unwrap(),
            row["network_angle_degrees"].as_f64().unwrap()
        );
        assert!(page.contains(&fidelity), "{fidelity}");
    }
    assert!(
        page.contains("(2.50 s)"),
        "the paper's 48-point network time"
    );
}

#[test]
fn an_output_folder_that_is_a_file_is_refused_clearly() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("taken");
    std::fs::write(&file, "not a folder").unwrap();
    let error = fails(&["demo", "--out", file.to_str().unwrap()]);
    assert!(error.contains("taken"), "{error}");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "not a folder");
}

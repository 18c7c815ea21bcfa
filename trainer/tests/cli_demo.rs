//! The README's main job, `neurosurf demo`, run as a user would: it trains and measures every
//! built-in model, writes what it says it writes, and reports numbers that hold the claims.

mod common;

use common::{fails, ok};

#[test]
fn the_demo_writes_every_model_and_reports_their_accuracy() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let text = ok(&["demo", "--out", out.to_str().unwrap(), "--json"]);
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

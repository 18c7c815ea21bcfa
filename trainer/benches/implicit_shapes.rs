//! Implicit models on real shapes: the scanned bunny (400 and 1 500 points), spot, fandisk, the
//! woody slab, a double torus and rounded cubes, each trained by the network and by the
//! built-in RBF on the same points, measured both ways against the true surface (see
//! `neurosurf_trainer::quality`); the network is measured as a user runs it, its blob in the
//! core in f32.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench implicit_shapes`, with after `--`:
//! `--case bunny-400,spot-1500` for some cases, `--seeds 1,2,3` for other seeds, `--no-rbf` to
//! skip the RBF, `--diagonal 0.01` to scale every shape first (units), `--set key=value,…` to
//! change a training option, `--save DIR` for the blobs, `--slices DIR` for pictures of three
//! slices (red: model inside where the points say outside, blue the reverse), `--body 50` for
//! the demo's body and its animation frame by frame instead, `--units` for each case scaled
//! ×0.01 and ×100 and moved by (1000, −1000, 500) instead, `--spread random` for points drawn
//! independently instead of spread evenly.

mod shapes;

use std::time::Instant;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions};
use neurosurf_trainer::io::{Mesh, data_file, read_mesh};
use neurosurf_trainer::quality::{
    MEASURE_RESOLUTION, STRAY_RESOLUTION, Truth, TwoSided, grown_bounds, two_sided,
};
use neurosurf_trainer::rbf::{self, RbfOptions};
use neurosurf_trainer::render::{DEFAULT_RBF_INFLATE, RbfField};
use neurosurf_trainer::sample::{Spread, sample_mesh};
use shapes::{double_torus, measure_core, rounded_cube};

struct Case {
    name: &'static str,
    mesh: Mesh,
    points: usize,
    features: usize,
}

fn cases(filter: &[String]) -> Vec<Case> {
    let obj = |name: &str| read_mesh(&data_file(name).expect("data")).expect("mesh");
    type MakeMesh = Box<dyn Fn() -> Mesh>;
    let all: Vec<(&'static str, MakeMesh, usize, usize)> = vec![
        (
            "bunny-400",
            Box::new(move || obj("stanford-bunny.obj")),
            400,
            8,
        ),
        (
            "bunny-1500",
            Box::new(move || obj("stanford-bunny.obj")),
            1500,
            16,
        ),
        ("spot-1500", Box::new(move || obj("spot.obj")), 1500, 16),
        ("double-torus", Box::new(double_torus), 400, 8),
        ("rounded-cube", Box::new(rounded_cube), 200, 8),
        ("rounded-cube-800", Box::new(rounded_cube), 800, 8),
        (
            "woody-slab-800",
            Box::new(|| neurosurf_trainer::demo::woody_mesh().expect("woody")),
            800,
            8,
        ),
        ("fandisk-800", Box::new(move || obj("fandisk.obj")), 800, 8),
    ];
    all.into_iter()
        .filter(|(name, ..)| filter.is_empty() || filter.iter().any(|f| f == name))
        .map(|(name, mesh, points, features)| Case {
            name,
            mesh: mesh(),
            points,
            features,
        })
        .collect()
}

/// One table row; `rbf` is the RBF's (time, truth → model median) on the same points, for
/// the ratio columns.
fn row(what: &str, seconds: f64, m: &TwoSided, rbf: Option<(f64, f64)>) {
    let ratios = match rbf {
        Some((t, d)) => format!(
            "{:.2}× | {:.2}×",
            seconds / t,
            m.truth_to_model.median_percent / d
        ),
        None => "– | –".to_string(),
    };
    emit(&format!(
        "| {what} | {seconds:.2} s | {:.4} % | {:.4} % | {:.3} % | {:.2}° | {} | {} | {:.2} % | {ratios} |",
        m.truth_to_model.median_percent,
        m.model_to_truth.median_percent,
        m.model_to_truth.p90_percent,
        m.normal_median_degrees,
        m.stray.sign_changes,
        m.mesh.components,
        m.mesh.far_vertices_percent,
    ));
}

/// Slices through the middle of the grown box along each axis, as a PNG: white where model and
/// winding number agree on inside, dark where they agree on outside, red where the model is
/// inside and the points say outside, blue the reverse; pixels near the surface are dimmed.
fn slices(
    field: &dyn Fn([f64; 3]) -> f64,
    points: &neurosurf_trainer::PointSet,
    truth: &Truth,
    path: &str,
) {
    let model: Vec<[f64; 3]> = points.positions.clone();
    let oracle = implicit::Oracle::new(&model, &points.normals).expect("oracle");
    let b = neurosurf_trainer::quality::grown_bounds(truth, 0.1);
    let n = 200;
    let mut img = image::RgbImage::new(3 * n, n);
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for j in 0..n {
            for i in 0..n {
                let mut p = b.center();
                p[u] = b.lo[u] + (b.hi[u] - b.lo[u]) * (i as f64 + 0.5) / n as f64;
                p[v] = b.lo[v] + (b.hi[v] - b.lo[v]) * ((n - 1 - j) as f64 + 0.5) / n as f64;
                let mine = field(p) > 0.0;
                let theirs = oracle.inside(p);
                let near = truth.distance(p) < 0.05 * truth.diagonal();
                let mut c = match (mine, theirs) {
                    (true, true) => [230, 230, 230],
                    (false, false) => [60, 60, 70],
                    (true, false) => [230, 40, 40],
                    (false, true) => [40, 80, 230],
                };
                if near {
                    c = c.map(|x| x / 2 + 40);
                }
                img.put_pixel(axis as u32 * n + i, j, image::Rgb(c.map(|x| x as u8)));
            }
        }
    }
    img.save(path).expect("png");
}

/// The demo's body, cold in the rest pose, then `frames − 1` animation frames each warm from
/// the previous one, every frame measured against its true body (meshed from its signed
/// distance).
fn body_animation(frames: usize, save: Option<String>) {
    use neurosurf_trainer::demo::{body_points, train_body};
    use neurosurf_trainer::sample::{Body, Pose};
    let options = ImplicitOptions::default();
    let mut previous: Option<(implicit::ImplicitNetwork, Vec<usize>)> = None;
    for frame in 0..frames.max(1) {
        let pose = if frame == 0 {
            Pose::REST
        } else {
            Pose::animation(frame, frames)
        };
        let points = body_points(&pose, 1).expect("body points");
        let start = Instant::now();
        let init = previous.as_ref().map(|(n, c)| (n, c.as_slice()));
        let trained = train_body(&points, &options, init, &|_| {}).expect("training");
        let seconds = start.elapsed().as_secs_f64();
        let body = Body::new(&pose);
        let grown = grown_bounds(&Truth::from_points(&points).expect("points"), 0.2);
        let truth =
            Truth::from_signed_distance(|p| body.signed_distance(p), grown, 160).expect("truth");
        let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
        if let Some(dir) = &save {
            std::fs::write(format!("{dir}/body-{frame}.nsb"), &blob).expect("save");
        }
        let m = measure_core(&blob, &trained.network, &truth);
        let s = &trained.summary;
        row(
            &format!(
                "body frame {frame} ({} it, {})",
                s.iterations(),
                s.outcome()
            ),
            seconds,
            &m,
            None,
        );
        let cold = match &previous {
            Some((_, c)) => c.clone(),
            None => s.cold_iterations.clone(),
        };
        previous = Some((trained.network, cold));
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| shapes::flag(&args, flag);
    let filter: Vec<String> = value("--case")
        .map(|c| c.split(',').map(String::from).collect())
        .unwrap_or_default();
    let seeds: Vec<u64> = value("--seeds")
        .map(|s| s.split(',').map(|v| v.parse().expect("seed")).collect())
        .unwrap_or_else(|| vec![1]);
    let rbf = !args.iter().any(|a| a == "--no-rbf");
    // Scale every case to this bounding diagonal (as given when absent).
    let to_diagonal: Option<f64> = value("--diagonal").map(|v| v.parse().expect("diagonal"));
    let in_units = args.iter().any(|a| a == "--units");
    if in_units {
        emit(
            "| case | units | time | truth → model median, f32 | truth → model median, Q16.16 | model → truth median | normal median | stray sign changes, f32 | stray sign changes, Q16.16 | mesh pieces | far vertices | truth → model ÷ as given |",
        );
        emit("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
        units(&filter, spread(&value));
    } else {
        emit(
            "| case | time | truth → model median | model → truth median | model → truth p90 | normal median | stray sign changes | mesh pieces | far vertices | time ÷ RBF | truth → model ÷ RBF |",
        );
        emit("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
        match value("--body") {
            Some(frames) => body_animation(frames.parse().expect("--body FRAMES"), value("--save")),
            None => shapes(&filter, &seeds, rbf, to_diagonal, &value),
        }
    }
    if let Some(path) = value("--out").map(|p| shapes::in_workspace(&p)) {
        let command = shapes::arguments(&args);
        let text = format!(
            "# {}\n\nWritten by `cargo bench -p neurosurf-trainer \
             --bench implicit_shapes -- {command}` on {} threads. Distances are medians in % of \
             the true surface's bounding diagonal; \"stray sign changes\" counts neighbours on \
             a 48³ grid over the bounding box grown by 10 %, both farther than 5 % of the \
             diagonal from the surface, where Φ changes sign (0 for a clean model); \"far \
             vertices\" are mesh vertices (resolution 96) that far away. {}\n\n{}",
            if value("--body").is_some() {
                "The demo's body and its animation, frame by frame"
            } else if in_units {
                "Implicit models in other units"
            } else {
                "Implicit models on real shapes"
            },
            rayon::current_num_threads(),
            if in_units {
                "Each case is sampled with the same seed after the change of units; the last \
                 column is the truth → model median against the case as given. Q16.16 takes \
                 the points in the data's units, in steps of 2⁻¹⁶: at ×0.01 the bunny is \
                 0.0025 across and a step is 0.6 % of its diagonal, which bounds its Q16.16 \
                 figure. \"Not storable\": the core's Q16.16 range cannot hold the model (the \
                 trainer says why and what to change)."
            } else {
                "Ratios are against the built-in RBF on the same points, in the same run."
            },
            TABLE.lock().expect("table").as_str()
        );
        std::fs::write(&path, text).expect("write --out");
        eprintln!("wrote {}", path.display());
    }
}

/// Every case of `filter` in other units: scaled ×0.01 and ×100 and moved by
/// (1000, −1000, 500), beside the data as given; measured in f32 and Q16.16.
fn units(filter: &[String], spread: Spread) {
    use neurosurf_trainer::render::{DEFAULT_BOX_SIZE, DEFAULT_INFLATE, Q16Field, Region};
    let transforms: [(&str, f64, [f64; 3]); 4] = [
        ("as given", 1.0, [0.0; 3]),
        ("×0.01", 0.01, [0.0; 3]),
        ("×100", 100.0, [0.0; 3]),
        ("moved by (1000, −1000, 500)", 1.0, [1000.0, -1000.0, 500.0]),
    ];
    for case in cases(filter) {
        let mut reference = None;
        for (label, scale, offset) in transforms {
            let mut mesh = case.mesh.clone();
            for p in &mut mesh.positions {
                *p = [0, 1, 2].map(|k| p[k] * scale + offset[k]);
            }
            let truth = Truth::from_mesh(&mesh).expect("truth");
            let mut points = sample_mesh(&mesh, case.points, 1, spread).expect("sample");
            // Decomposed here, as `implicit::fit` would: with the seam band it then turns on.
            let options = ImplicitOptions {
                seam_band: true,
                ..ImplicitOptions::default()
            };
            points.features = Some(
                implicit::decompose(&points.positions, case.features, options.min_points)
                    .expect("features"),
            );
            let request = FitRequest {
                features: Some(case.features),
                ..FitRequest::default()
            };
            let start = Instant::now();
            let trained = implicit::fit(points, &request, &options, &|_| {}).expect("training");
            let seconds = start.elapsed().as_secs_f64();
            let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
            let m = measure_core(&blob, &trained.network, &truth);
            // Q16.16 when the blob can hold the model (it refuses data too small or too far
            // from the origin for its range, by name).
            let fixed = match implicit::to_blob(&trained.network, None, ScalarKind::Q16_16) {
                Ok(q16) => {
                    let regions =
                        Region::of_network(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
                    let field = Q16Field::new(&q16, regions).expect("the core loads the blob");
                    let f = two_sided(&field, &truth, MEASURE_RESOLUTION, STRAY_RESOLUTION)
                        .expect("measure");
                    (
                        format!("{:.4} %", f.truth_to_model.median_percent),
                        f.stray.sign_changes.to_string(),
                    )
                }
                Err(e) => {
                    eprintln!("{} {label}: {e}", case.name);
                    ("not storable".to_string(), "–".to_string())
                }
            };
            let median = m.truth_to_model.median_percent;
            let ratio = *reference.get_or_insert(median);
            emit(&format!(
                "| {} | {label} | {seconds:.2} s | {median:.4} % | {} | {:.4} % | {:.2}° | {} | {} | {} | {:.2} % | {:.2}× |",
                case.name,
                fixed.0,
                m.model_to_truth.median_percent,
                m.normal_median_degrees,
                m.stray.sign_changes,
                fixed.1,
                m.mesh.components,
                m.mesh.far_vertices_percent,
                median / ratio,
            ));
        }
    }
}

/// The table so far, for `--out`.
static TABLE: std::sync::Mutex<String> = std::sync::Mutex::new(String::new());

/// Prints a table line and keeps it for `--out`.
fn emit(line: &str) {
    println!("{line}");
    let mut table = TABLE.lock().expect("table");
    table.push_str(line);
    table.push('\n');
}

/// How the points are placed on each mesh: `--spread random` or, by default, evenly (as
/// `neurosurf sample` does).
fn spread(value: &dyn Fn(&str) -> Option<String>) -> Spread {
    match value("--spread").as_deref() {
        None | Some("even") => Spread::Even,
        Some("random") => Spread::Random,
        Some(other) => panic!("--spread {other}: expected even or random"),
    }
}

/// Every case of `filter` (all when empty) for every seed.
fn shapes(
    filter: &[String],
    seeds: &[u64],
    rbf: bool,
    to_diagonal: Option<f64>,
    value: &dyn Fn(&str) -> Option<String>,
) {
    let spread = spread(value);
    for mut case in cases(filter) {
        if let Some(target) = to_diagonal {
            let d = neurosurf_trainer::caoen::bounding_diagonal(&case.mesh);
            for p in &mut case.mesh.positions {
                *p = p.map(|v| v * target / d);
            }
        }
        let truth = Truth::from_mesh(&case.mesh).expect("truth");
        for &seed in seeds {
            let points = sample_mesh(&case.mesh, case.points, seed, spread).expect("sample");
            // The built-in RBF on the same points, first, so the network's row can give ratios.
            let rbf_row = rbf.then(|| {
                let start = Instant::now();
                let (model, _) = rbf::fit(&points, &RbfOptions::default()).expect("rbf");
                let seconds = start.elapsed().as_secs_f64();
                let field = RbfField::new(&model, DEFAULT_RBF_INFLATE).expect("rbf field");
                let m = two_sided(&field, &truth, MEASURE_RESOLUTION, STRAY_RESOLUTION)
                    .expect("measure");
                (seconds, m)
            });
            let start = Instant::now();
            let request = FitRequest {
                features: Some(case.features),
                ..FitRequest::default()
            };
            // Decomposed below, as `implicit::fit` would: with the seam band it then turns on.
            let mut options = ImplicitOptions {
                seed,
                seam_band: true,
                ..ImplicitOptions::default()
            };
            for setting in value("--set").iter().flat_map(|s| s.split(',')) {
                let (key, v) = setting.split_once('=').expect("--set key=value");
                let v: f64 = v.parse().expect("number");
                match key {
                    "offset" => options.offset = v,
                    "sign_points" => options.sign_points = v,
                    "clearance" => options.clearance = v,
                    "sign_margin" => options.sign_margin = v,
                    "sign_weight" => options.sign_weight = v,
                    "lambda" => options.lm.lambda = v,
                    "gamma" => options.gamma = v,
                    "width" => options.width = v as usize,
                    "max_iterations" => options.lm.max_iterations = v as usize,
                    "threshold" => options.lm.threshold = v,
                    "window" => options.lm.stagnation_window = v as usize,
                    "decrease" => options.lm.stagnation_decrease = v,
                    "node_decrease" => options.node_stagnation_decrease = v,
                    "acceleration" => options.lm.acceleration = v != 0.0,
                    "coarse" => options.coarse_start = v != 0.0,
                    other => panic!("unknown setting {other}"),
                }
            }
            let mut points = points;
            points.features = Some(
                implicit::decompose(&points.positions, case.features, options.min_points)
                    .expect("features"),
            );
            let trained =
                implicit::fit(points.clone(), &request, &options, &|_| {}).expect("training");
            if let Some(dir) = value("--slices") {
                let net = &trained.network;
                slices(
                    &|p| net.eval(p).0,
                    &points,
                    &truth,
                    &format!("{dir}/{}-{seed}-slices.png", case.name),
                );
            }
            let seconds = start.elapsed().as_secs_f64();
            let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
            if let Some(dir) = value("--save") {
                let path = format!("{dir}/{}-{seed}.nsb", case.name);
                std::fs::write(&path, &blob).expect("save");
            }
            let m = measure_core(&blob, &trained.network, &truth);
            let s = &trained.summary;
            row(
                &format!(
                    "{} seed {seed} network ({} modules, {} it, {})",
                    case.name,
                    s.modules.len(),
                    s.iterations(),
                    s.outcome()
                ),
                seconds,
                &m,
                rbf_row
                    .as_ref()
                    .map(|(t, r)| (*t, r.truth_to_model.median_percent)),
            );
            if let Some((t, r)) = &rbf_row {
                row(&format!("{} seed {seed} RBF", case.name), *t, r, None);
            }
        }
    }
}

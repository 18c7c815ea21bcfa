//! Implicit models on real shapes: the scanned bunny (400 and 1 500 points), spot, a double
//! torus and a rounded cube, each trained by the network and by the built-in RBF, measured both
//! ways against the true surface (see `neurosurf_trainer::quality`).
//!
//! Run: `cargo bench -p neurosurf-trainer --bench implicit_shapes` (`-- --case bunny-400` for
//! one case, `-- --seeds 1,2,3` for other seeds, `-- --no-rbf` to skip the RBF).

use std::time::Instant;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions};
use neurosurf_trainer::io::{Mesh, data_file, read_mesh};
use neurosurf_trainer::quality::{Truth, TwoSided, two_sided};
use neurosurf_trainer::render::{CoreField, Field, Region, extract_mesh};
use neurosurf_trainer::sample::sample_mesh;

/// An analytic signed distance (negative inside) as a field for the mesher: Φ = −d.
struct Analytic<F> {
    distance: F,
    regions: Vec<Region>,
}

impl<F: Fn([f64; 3]) -> f64 + Sync> Field for Analytic<F> {
    fn value(&self, p: [f64; 3]) -> f64 {
        -(self.distance)(p)
    }
    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let h = 1e-6;
        let g = [0, 1, 2].map(|k| {
            let mut a = p;
            let mut b = p;
            a[k] += h;
            b[k] -= h;
            (self.value(a) - self.value(b)) / (2.0 * h)
        });
        (self.value(p), g)
    }
    fn regions(&self) -> &[Region] {
        &self.regions
    }
}

fn analytic_mesh(distance: impl Fn([f64; 3]) -> f64 + Sync, half: [f64; 3]) -> Mesh {
    let normalization = implicit::Normalization {
        center: [0.0; 3],
        matrix: [0, 1, 2].map(|r| [0, 1, 2].map(|c| if r == c { 1.0 / half[r] } else { 0.0 })),
    };
    let field = Analytic {
        distance,
        regions: vec![Region::new(normalization, 2.0, 1.0).expect("region")],
    };
    extract_mesh(&field, 160, &|_, _| {}).expect("mesh").mesh
}

fn torus(p: [f64; 3], c: [f64; 3], big: f64, small: f64) -> f64 {
    let q = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
    ((q[0] * q[0] + q[1] * q[1]).sqrt() - big).hypot(q[2]) - small
}

fn double_torus() -> Mesh {
    analytic_mesh(
        |p| torus(p, [-0.9, 0.0, 0.0], 1.0, 0.35).min(torus(p, [0.9, 0.0, 0.0], 1.0, 0.35)),
        [2.4, 1.5, 0.5],
    )
}

fn rounded_cube() -> Mesh {
    analytic_mesh(
        |p| {
            let q = p.map(|v| v.abs() - 0.8);
            let outside = q.map(|v| v.max(0.0));
            (outside[0].hypot(outside[1]).hypot(outside[2])) + q[0].max(q[1]).max(q[2]).min(0.0)
                - 0.2
        },
        [1.2; 3],
    )
}

struct Case {
    name: &'static str,
    mesh: Mesh,
    points: usize,
    features: usize,
}

fn cases(filter: &[String]) -> Vec<Case> {
    let obj = |name: &str| read_mesh(&data_file(name).expect("data")).expect("mesh");
    let all: Vec<(&'static str, Box<dyn Fn() -> Mesh>, usize, usize)> = vec![
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
        ("woody-400", Box::new(move || obj("woody.obj")), 400, 8),
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

fn row(what: &str, seconds: f64, m: &TwoSided) {
    println!(
        "| {what} | {seconds:.2} s | {:.4} % | {:.4} % | {:.3} % | {:.2}° | {} | {} | {:.2} % |",
        m.truth_to_model.median_percent,
        m.model_to_truth.median_percent,
        m.model_to_truth.p90_percent,
        m.normal_median_degrees,
        m.stray.sign_changes,
        m.mesh.components,
        m.mesh.far_vertices_percent,
    );
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
                img.put_pixel(
                    axis as u32 * n as u32 + i as u32,
                    j as u32,
                    image::Rgb(c.map(|x| x as u8)),
                );
            }
        }
    }
    img.save(path).expect("png");
}

/// The exact winding number of a closed (or nearly closed) triangle mesh at q (Van Oosterom
/// and Strackee's solid angle per triangle).
fn mesh_winding(mesh: &Mesh, q: [f64; 3]) -> f64 {
    let mut sum = 0.0;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| {
            let p = mesh.positions[v as usize];
            [p[0] - q[0], p[1] - q[1], p[2] - q[2]]
        });
        let n = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
        let cross = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let (la, lb, lc) = (n(a), n(b), n(c));
        let det = dot(cross, c);
        let den = la * lb * lc + dot(a, b) * lc + dot(b, c) * la + dot(c, a) * lb;
        sum += 2.0 * det.atan2(den);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// How often the points' winding number disagrees with the mesh's on far random points.
fn check_oracle(mesh: &Mesh, points: &neurosurf_trainer::PointSet, truth: &Truth) {
    use rand::{Rng, SeedableRng};
    let oracle = implicit::Oracle::new(&points.positions, &points.normals).expect("oracle");
    let b = neurosurf_trainer::quality::grown_bounds(truth, 0.1);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let mut checked = 0;
    let mut wrong = 0;
    let mut examples = Vec::new();
    while checked < 1500 {
        let q = [0, 1, 2].map(|k| rng.random_range(b.lo[k]..b.hi[k]));
        if truth.distance(q) < 0.02 * truth.diagonal() {
            continue;
        }
        checked += 1;
        let exact = mesh_winding(mesh, q);
        if (exact > 0.5) != oracle.inside(q) {
            wrong += 1;
            if examples.len() < 5 {
                examples.push((
                    exact,
                    oracle.winding(q),
                    truth.distance(q) / truth.diagonal(),
                ));
            }
        }
    }
    eprintln!(
        "  oracle: {wrong} of {checked} far points disagree with the mesh; e.g. {examples:?}"
    );
}

/// Prints where the stray grid finds sign changes between far neighbours.
fn locate_strays(
    field: &dyn Fn([f64; 3]) -> f64,
    points: &neurosurf_trainer::PointSet,
    truth: &Truth,
) {
    let oracle = implicit::Oracle::new(&points.positions, &points.normals).expect("oracle");
    let b = neurosurf_trainer::quality::grown_bounds(truth, 0.1);
    let n = 48;
    let at = |i: [usize; 3]| {
        [0, 1, 2].map(|k| b.lo[k] + (b.hi[k] - b.lo[k]) * i[k] as f64 / (n - 1) as f64)
    };
    let far = 0.05 * truth.diagonal();
    let mut shown = 0;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let p = at([x, y, z]);
                if truth.distance(p) <= far {
                    continue;
                }
                for d in 0..3 {
                    let mut j = [x, y, z];
                    j[d] += 1;
                    if j[d] >= n {
                        continue;
                    }
                    let q = at(j);
                    if truth.distance(q) <= far {
                        continue;
                    }
                    let (a, c) = (field(p), field(q));
                    if (a > 0.0) != (c > 0.0) && shown < 12 {
                        shown += 1;
                        let rel = [0, 1, 2]
                            .map(|k| ((p[k] - b.lo[k]) / (b.hi[k] - b.lo[k]) * 100.0).round());
                        eprintln!(
                            "  stray at {rel:?}% of the box: Φ {a:.3} / {c:.3}, winding {:.2} / {:.2}, distance {:.1} % diag",
                            oracle.winding(p),
                            oracle.winding(q),
                            100.0 * truth.distance(p) / truth.diagonal()
                        );
                    }
                }
            }
        }
    }
}

/// Lists the pieces of the model's mesh over the grown box: size, where, how far.
fn pieces(field: &dyn Field, truth: &Truth) {
    let b = neurosurf_trainer::quality::grown_bounds(truth, 0.1);
    let half = b.half();
    let normalization = implicit::Normalization {
        center: b.center(),
        matrix: [0, 1, 2].map(|r| [0, 1, 2].map(|c| if r == c { 1.0 / half[r] } else { 0.0 })),
    };
    struct W<'a> {
        f: &'a dyn Field,
        r: Vec<Region>,
    }
    impl Field for W<'_> {
        fn value(&self, p: [f64; 3]) -> f64 {
            self.f.value(p)
        }
        fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
            self.f.value_gradient(p)
        }
        fn regions(&self) -> &[Region] {
            &self.r
        }
        fn values(&self, p: &[[f64; 3]], o: &mut [f64]) {
            self.f.values(p, o)
        }
    }
    let mut regions = vec![Region::new(normalization, 2.0, 1.0).expect("region")];
    regions.extend(field.regions().iter().copied());
    let w = W {
        f: field,
        r: regions,
    };
    let mesh = extract_mesh(&w, 96, &|_, _| {}).expect("mesh").mesh;
    let mut parent: Vec<usize> = (0..mesh.positions.len()).collect();
    fn find(p: &mut [usize], mut v: usize) -> usize {
        while p[v] != v {
            p[v] = p[p[v]];
            v = p[v];
        }
        v
    }
    for t in &mesh.triangles {
        let a = find(&mut parent, t[0] as usize);
        for &v in &t[1..] {
            let c = find(&mut parent, v as usize);
            if a != c {
                parent[c] = a;
            }
        }
    }
    let mut groups: std::collections::HashMap<usize, Vec<usize>> = Default::default();
    for v in 0..mesh.positions.len() {
        let r = find(&mut parent, v);
        groups.entry(r).or_default().push(v);
    }
    let mut list: Vec<Vec<usize>> = groups.into_values().collect();
    list.sort_by_key(|g| std::cmp::Reverse(g.len()));
    for g in list.iter().skip(1).take(8) {
        let c = g
            .iter()
            .fold([0.0; 3], |a, &v| {
                let p = mesh.positions[v];
                [a[0] + p[0], a[1] + p[1], a[2] + p[2]]
            })
            .map(|x| x / g.len() as f64);
        let rel = [0, 1, 2].map(|k| ((c[k] - b.lo[k]) / (b.hi[k] - b.lo[k]) * 100.0).round());
        let dmax = g
            .iter()
            .map(|&v| truth.distance(mesh.positions[v]))
            .fold(0.0, f64::max);
        eprintln!(
            "  piece of {} vertices at {rel:?}% of the box, farthest {:.2} % diag from the truth",
            g.len(),
            100.0 * dmax / truth.diagonal()
        );
    }
}

/// For every module: how far its subtree's zero set is from the true surface where that
/// module's features are nearest (first-order |Φ|/|∇Φ|, % of the diagonal), and its normals.
fn diagnose(
    network: &implicit::ImplicitNetwork,
    points: &neurosurf_trainer::PointSet,
    truth: &Truth,
) {
    let labels = points.features.as_ref().expect("labels");
    let tree: kiddo::ImmutableKdTree<f64, 3> =
        kiddo::ImmutableKdTree::new_from_slice(&points.positions).expect("tree");
    let owner: Vec<u32> = truth
        .positions()
        .iter()
        .map(|p| {
            let n = tree
                .query(p)
                .nearest_one::<kiddo::SquaredEuclidean<f64>>()
                .execute();
            labels[n.item as usize]
        })
        .collect();
    for i in 0..network.module_count() {
        let sub = network.subtree(i).expect("subtree");
        let features: Vec<u32> = network
            .subtree_leaves(i)
            .iter()
            .map(|&l| network.leaf_features()[l].unwrap_or(0))
            .collect();
        let mut d = Vec::new();
        let mut a = Vec::new();
        for ((p, n), o) in truth.positions().iter().zip(truth.normals()).zip(&owner) {
            if !features.contains(o) {
                continue;
            }
            let (phi, g) = sub.eval(*p);
            let len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
            d.push(phi.abs() / len);
            a.push(
                (-(g[0] * n[0] + g[1] * n[1] + g[2] * n[2]) / len)
                    .clamp(-1.0, 1.0)
                    .acos()
                    .to_degrees(),
            );
        }
        d.sort_by(f64::total_cmp);
        a.sort_by(f64::total_cmp);
        eprintln!(
            "  module {i:2} ({} features): {} truth samples, median {:.4} %, p90 {:.3} %, normal median {:.2}°",
            features.len(),
            d.len(),
            100.0 * d[d.len() / 2] / truth.diagonal(),
            100.0 * d[d.len() * 9 / 10] / truth.diagonal(),
            a[a.len() / 2]
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let filter: Vec<String> = value("--case")
        .map(|c| c.split(',').map(String::from).collect())
        .unwrap_or_default();
    let seeds: Vec<u64> = value("--seeds")
        .map(|s| s.split(',').map(|v| v.parse().expect("seed")).collect())
        .unwrap_or_else(|| vec![1]);
    let rbf = !args.iter().any(|a| a == "--no-rbf");
    // Scale every case to this bounding diagonal (as given when absent).
    let to_diagonal: Option<f64> = value("--diagonal").map(|v| v.parse().expect("diagonal"));
    println!(
        "| case | time | truth → model median | model → truth median | model → truth p90 | normal median | stray sign changes | mesh pieces | far vertices |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for mut case in cases(&filter) {
        if let Some(target) = to_diagonal {
            let d = neurosurf_trainer::caoen::bounding_diagonal(&case.mesh);
            for p in &mut case.mesh.positions {
                *p = p.map(|v| v * target / d);
            }
        }
        let truth = Truth::from_mesh(&case.mesh).expect("truth");
        for &seed in &seeds {
            let points = sample_mesh(&case.mesh, case.points, seed).expect("sample");
            let start = Instant::now();
            let request = FitRequest {
                features: Some(case.features),
                ..FitRequest::default()
            };
            let mut options = ImplicitOptions {
                seed,
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
                    other => panic!("unknown setting {other}"),
                }
            }
            let mut points = points;
            points.features = Some(
                implicit::decompose(&points.positions, case.features, options.min_points)
                    .expect("features"),
            );
            let trace = std::env::var_os("TRACE").is_some();
            let trained = implicit::fit(points.clone(), &request, &options, &|p| {
                if let (
                    true,
                    implicit::Progress::Iteration {
                        module,
                        iteration,
                        error,
                    },
                ) = (trace, p)
                    && iteration % 10 == 0
                {
                    eprintln!("    trace module {module} it {iteration} E {error:.3e}");
                }
            })
            .expect("training");
            if std::env::var_os("VERBOSE").is_some() {
                diagnose(&trained.network, &points, &truth);
            }
            if std::env::var_os("ORACLE").is_some() {
                check_oracle(&case.mesh, &points, &truth);
            }
            if std::env::var_os("PIECES").is_some() {
                let f = neurosurf_trainer::render::NetworkField::new(&trained.network, 2.0, 1.25)
                    .expect("field");
                pieces(&f, &truth);
            }
            if std::env::var_os("STRAYS").is_some() {
                let net = &trained.network;
                locate_strays(&|p| net.eval(p).0, &points, &truth);
            }
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
            let regions = Region::of_network(&trained.network, 2.0, 1.25);
            let _ = CoreField::new;
            let field = neurosurf_trainer::render::NetworkField::new(&trained.network, 2.0, 1.25)
                .expect("field");
            let _ = regions;
            let m = two_sided(&field, &truth, 96, 48).expect("measure");
            let s = &trained.summary;
            if std::env::var_os("VERBOSE").is_some() {
                for m in &s.modules {
                    eprintln!(
                        "  module {:2} {} {:5} rows {:5} it E {:.2e} -> {:.2e} {:?} {:.2}s",
                        m.module,
                        if m.node { "node" } else { "leaf" },
                        m.points,
                        m.lm.iterations,
                        m.lm.initial_error,
                        m.lm.error,
                        m.lm.stop,
                        m.seconds
                    );
                }
            }
            row(
                &format!(
                    "{} seed {seed} network ({} modules, {} it, {})",
                    case.name,
                    s.modules.len(),
                    s.iterations(),
                    if s.converged() {
                        "converged"
                    } else {
                        "not converged"
                    }
                ),
                seconds,
                &m,
            );
            if rbf {
                let _ = &points;
            }
        }
    }
}

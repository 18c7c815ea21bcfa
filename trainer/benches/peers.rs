//! The core's host evaluation against the peer a Python user would reach for: Φ and ∇Φ of the
//! demo's torus leaf (3 → 9 → 9 → 1) and 3-feature head (three leaves, two nodes), as
//! `jax.jit(jax.vmap(jax.value_and_grad(Φ)))` in float32 (`benches/peers/implicit_jax.py`),
//! one core each. Every time is also a ratio to JAX measured in the same run; without JAX the
//! JAX row says so and the ratios are to the core's portable single-point evaluation.
//!
//! Run: `taskset -c 1 cargo bench -p neurosurf-trainer --bench peers [-- --out FILE]` (set
//! `NEUROSURF_PYTHON` to a Python with `jax` installed; default `python3`); `--out` also writes
//! the table as Markdown (`docs/performance/host.md`). The models are the demo's blobs kept
//! in the fuzz corpus (`fuzz/corpus/{torus,head}-f32.nsb`); the 4 096 query points fill the cube
//! [−1.5, 1.5]³.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use neurosurf_core::implicit::{FieldGradient, ImplicitModel};
use neurosurf_core::scalar::{Q16, Scalar};
use neurosurf_trainer::demo::{TABLE5_TORUS, paper_points};
use neurosurf_trainer::fidelity::median;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions, from_blob};
use neurosurf_trainer::sample::sample_shape;

const QUERIES: usize = 4096;
/// Rounds over all evaluators.
const ROUNDS: usize = 3;

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let python = std::env::var("NEUROSURF_PYTHON").unwrap_or_else(|_| "python3".into());
    let mut rows: Vec<(String, Vec<Option<f64>>)> = Vec::new();
    let names = ["torus", "head"];
    let mut columns = Vec::new();
    for name in names {
        let f32_blob =
            std::fs::read(root.join(format!("fuzz/corpus/{name}-f32.nsb"))).expect("blob");
        let q16_blob =
            std::fs::read(root.join(format!("fuzz/corpus/{name}-q16.16.nsb"))).expect("blob");
        let decoded = from_blob(&f32_blob, Path::new(name)).expect("trainer reads the blob");
        let points = queries();
        // Rounds that visit every evaluator in turn, each keeping its best: a shared machine
        // that slows down for a while then slows all of them alike.
        let mut best = [f64::INFINITY; 5];
        let mut jax_seen = true;
        for _ in 0..ROUNDS {
            let times = [
                jax_time(&python, &decoded.network, &points, &f32_blob),
                Some(throughput::<f32>(&f32_blob, &points, true)),
                Some(throughput::<f32>(&f32_blob, &points, false)),
                Some(throughput::<Q16>(&q16_blob, &points, true)),
                Some(throughput::<Q16>(&q16_blob, &points, false)),
            ];
            jax_seen &= times[0].is_some();
            for (best, time) in best.iter_mut().zip(times) {
                *best = best.min(time.unwrap_or(f64::INFINITY));
            }
        }
        let [jax, rest @ ..] = best;
        columns.push([
            jax_seen.then_some(jax),
            Some(rest[0]),
            Some(rest[1]),
            Some(rest[2]),
            Some(rest[3]),
        ]);
    }
    let labels = [
        "JAX jit(vmap(value_and_grad)), f32",
        "core f32, batch",
        "core f32, one point at a time",
        "core Q16.16, batch",
        "core Q16.16, one point at a time",
    ];
    for (row, label) in labels.iter().enumerate() {
        rows.push((label.to_string(), columns.iter().map(|c| c[row]).collect()));
    }
    let mut table =
        String::from("| evaluator | torus leaf, N = 9 | 3-feature head |\n|---|---:|---:|\n");
    for (label, times) in &rows {
        let cells: Vec<String> = times
            .iter()
            .zip(&columns)
            .map(|(t, column)| match (t, column[0]) {
                (Some(t), Some(jax)) => format!("{:.1} ({:.2}×)", t * 1e9, jax / t),
                (Some(t), None) => format!("{:.1}", t * 1e9),
                (None, _) => "JAX not installed".into(),
            })
            .collect();
        table.push_str(&format!("| {label} | {} |\n", cells.join(" | ")));
    }
    println!("Field + gradient, {QUERIES} points, one core; ns per point (speed against JAX)\n");
    print!("{table}");
    let training = training_table(&python);
    println!("\nTable 5 training, one core; median seconds (iterations) over seeds {SEEDS:?}\n");
    print!("{training}");
    let args: Vec<String> = std::env::args().collect();
    if let Some(path) = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1))
    {
        let text = format!(
            "# The core on the host against JAX\n\nWritten by `taskset -c 1 cargo bench -p \
             neurosurf-trainer --bench peers -- --out {path}` with `NEUROSURF_PYTHON` naming a \
             Python that has JAX. Φ and ∇Φ at {QUERIES} points in [−1.5, 1.5]³, one core \
             each; ns per point, and in brackets the speed against \
             `jax.jit(jax.vmap(jax.value_and_grad(Φ)))` in float32 \
             (`trainer/benches/peers/implicit_jax.py`) measured in the same run, after checking \
             that both compute the same Φ. The models are the demo's torus and head \
             (`fuzz/corpus/{{torus,head}}-f32.nsb`). The core's `f32` batches run the AVX2 \
             kernels of `core/avx2/` where the processor has AVX2; every result has the same \
             bits as the Cortex-M4F's. The machine is a shared 2-core virtual machine: compare \
             ratios, not times.\n\n{table}\n## Training: Table 5\n\nThe trainer's \
             Levenberg–Marquardt (`neurosurf_trainer::implicit::fit` with `ImplicitOptions::paper()` \
             and no sign guards, as in `cargo bench --bench table5`) against the paper's LM loop for one \
             leaf in numpy with JAX's exact Jacobian, float64 \
             (`trainer/benches/peers/table5_lm_jax.py`: Table 1's objective and settings, the \
             same damping schedule), on the same area-uniform torus points (R = 1, r = 0.4) and \
             seeds {SEEDS:?}, one core each. Median seconds and iterations over the seeds; \
             \"reached\" counts the runs that ended with E_s ≤ 10⁻⁵. The trainer corrects \
             each step by geodesic acceleration and starts a module of 128 points or more \
             with a coarse fit of every 4th point (\"coarse\": those iterations, each about a \
             quarter of a full one or less); the column \"paper's LM\" is the same trainer \
             with both off (`--no-acceleration --no-coarse-start`).\n\n\
             {training}"
        );
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(path);
        std::fs::write(&path, text).expect("write --out");
        eprintln!("wrote {}", path.display());
    }
}

/// Seeds of every Table 5 training run.
const SEEDS: [u64; 5] = [1, 2, 3, 4, 5];
/// Iterations the peer's LM loop may take before it gives up.
const PEER_ITERATIONS: usize = 500;

/// Table 5's trainings through the trainer and through the numpy + JAX peer (when JAX is
/// installed): a Markdown table of median times, iterations and the trainer's speed against
/// the peer.
fn training_table(python: &str) -> String {
    let options = ImplicitOptions::paper();
    let mut sets = Vec::new();
    let mut ours = Vec::new();
    for points in paper_points() {
        let (mut runs, mut plain_runs, mut coarse) = (Vec::new(), Vec::new(), Vec::new());
        for seed in SEEDS {
            let sample = sample_shape(&TABLE5_TORUS, points, seed).expect("torus samples");
            for plain in [false, true] {
                let mut options = ImplicitOptions {
                    seed,
                    ..options.clone()
                };
                // The paper's LM alone: no geodesic acceleration, no coarse start.
                options.lm.acceleration = !plain;
                options.coarse_start = !plain;
                // The paper's procedure: no sign guards (nor off-surface or sign points).
                let request = FitRequest {
                    unguarded: true,
                    ..FitRequest::default()
                };
                let start = Instant::now();
                let trained =
                    implicit::fit(sample.clone(), &request, &options, &|_| {}).expect("training");
                let seconds = start.elapsed().as_secs_f64();
                let module = trained.summary.modules.first().expect("one leaf");
                let run = (
                    seconds,
                    module.lm.iterations as f64,
                    module.lm.error <= options.lm.threshold,
                );
                if plain {
                    plain_runs.push(run);
                } else {
                    runs.push(run);
                    coarse.push(module.coarse_iterations as f64);
                }
            }
            sets.push(serde_json::json!({
                "seed": seed,
                "points": sample.positions,
                "normals": sample.normals,
            }));
        }
        ours.push((points, runs, plain_runs, median(&mut coarse)));
    }
    let lm = &options.lm;
    let request = serde_json::json!({
        "settings": {
            "width": options.width,
            "slope": options.slope,
            "gamma": options.gamma,
            "lambda": lm.lambda,
            "mu0": lm.mu0,
            "theta": lm.theta,
            "mu_max": lm.mu_max,
            "threshold": lm.threshold,
            "init_range": options.init_range,
            "box_size": options.box_size,
            "max_iterations": PEER_ITERATIONS,
        },
        "sets": sets,
    });
    let peer = run_peer(python, "table5_lm_jax.py", &request);
    let mut table = String::from(
        "| points | trainer s (iterations + coarse, reached) | trainer, paper's LM s \
         (iterations, reached) | numpy + JAX paper LM s (iterations, reached) | trainer vs \
         peer | trainer vs its paper's LM |\n|---:|---:|---:|---:|---:|---:|\n",
    );
    for (points, runs, plain_runs, coarse) in &ours {
        let (seconds, iterations, reached) = summarize(runs);
        let (plain_seconds, plain_iterations, plain_reached) = summarize(plain_runs);
        let theirs: Option<Vec<(f64, f64, bool)>> = peer.as_ref().map(|report| {
            report["runs"]
                .as_array()
                .into_iter()
                .flatten()
                .filter(|run| run["points"].as_u64() == Some(*points as u64))
                .map(|run| {
                    let error = run["error"].as_f64().unwrap_or(f64::INFINITY);
                    (
                        run["seconds"].as_f64().unwrap_or(f64::NAN),
                        run["iterations"].as_f64().unwrap_or(f64::NAN),
                        error <= lm.threshold,
                    )
                })
                .collect()
        });
        let (peer_cell, ratio) = match theirs.as_deref().map(summarize) {
            Some((peer_seconds, peer_iterations, peer_reached)) => (
                format!(
                    "{peer_seconds:.3} ({peer_iterations:.0}, {peer_reached}/{})",
                    SEEDS.len()
                ),
                format!("{:.1}×", peer_seconds / seconds),
            ),
            None => ("JAX not installed".into(), "—".into()),
        };
        let seeds = SEEDS.len();
        table.push_str(&format!(
            "| {points} | {seconds:.4} ({iterations:.0} + {coarse:.0}, {reached}/{seeds}) | \
             {plain_seconds:.4} ({plain_iterations:.0}, {plain_reached}/{seeds}) | {peer_cell} \
             | {ratio} | {:.1}× |\n",
            plain_seconds / seconds
        ));
    }
    table
}

/// Median seconds, median iterations and how many runs reached the threshold.
fn summarize(runs: &[(f64, f64, bool)]) -> (f64, f64, usize) {
    let mut seconds: Vec<f64> = runs.iter().map(|r| r.0).collect();
    let mut iterations: Vec<f64> = runs.iter().map(|r| r.1).collect();
    (
        median(&mut seconds),
        median(&mut iterations),
        runs.iter().filter(|r| r.2).count(),
    )
}

/// Runs a peer script of `benches/peers/` on `request` (handed over in a temporary JSON file)
/// and returns its last line of output as JSON; `None` when Python or JAX is missing. Panics
/// when the script fails.
fn run_peer(python: &str, script: &str, request: &serde_json::Value) -> Option<serde_json::Value> {
    let available = Command::new(python)
        .args(["-c", "import jax"])
        .output()
        .is_ok_and(|out| out.status.success());
    if !available {
        return None;
    }
    let file: PathBuf = std::env::temp_dir().join(format!(
        "neurosurf-peer-{}-{script}.json",
        std::process::id()
    ));
    std::fs::write(&file, request.to_string()).expect("temporary file");
    let script = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("benches/peers")
        .join(script);
    let out = Command::new(python)
        .arg(script)
        .arg(&file)
        .output()
        .expect("python runs");
    let _ = std::fs::remove_file(&file);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(out.stdout.rsplit(|&b| b == b'\n').find(|l| !l.is_empty())?).ok()
}

/// Points spread over the cube [−1.5, 1.5]³ by a fixed xorshift sequence.
fn queries() -> Vec<[f32; 3]> {
    let mut state = 0x9e37_79b9_u32;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        f64::from(state) / f64::from(u32::MAX) * 2.0 - 1.0
    };
    (0..QUERIES)
        .map(|_| [next() * 1.5, next() * 1.5, next() * 1.5].map(|c| c as f32))
        .collect()
}

/// Seconds per point of the JAX peer, or `None` when Python or JAX is missing. Panics when
/// JAX and the core disagree on Φ (a wrong peer would make the ratio meaningless).
fn jax_time(
    python: &str,
    network: &neurosurf_trainer::implicit::ImplicitNetwork,
    points: &[[f32; 3]],
    blob: &[u8],
) -> Option<f64> {
    let kinds: Vec<&str> = network
        .kinds()
        .iter()
        .map(|k| match k {
            neurosurf_core::implicit::ModuleKind::Leaf => "leaf",
            neurosurf_core::implicit::ModuleKind::Node => "node",
        })
        .collect();
    let guards: Vec<[f64; 5]> = network.guards().iter().map(|g| g.parameters()).collect();
    let model = serde_json::json!({
        "width": network.width(),
        "kinds": kinds,
        "params": network.params(),
        "guards": guards,
        "points": points,
    });
    let report = run_peer(python, "implicit_jax.py", &model)?;
    let model = ImplicitModel::<f32>::from_blob(blob).expect("core loads the blob");
    for (k, phi) in report["phi"].as_array()?.iter().enumerate() {
        let core = model.field_gradient(points[k]).value;
        let jax = phi.as_f64()? as f32;
        assert!(
            (core - jax).abs() < 1e-4,
            "point {k}: core {core}, JAX {jax}"
        );
    }
    report["ns_per_point"].as_f64().map(|ns| ns * 1e-9)
}

/// Seconds per field + gradient through the core: the best of 5 runs of 5 passes.
fn throughput<S: Scalar>(blob: &[u8], points: &[[f32; 3]], batch: bool) -> f64 {
    let model = ImplicitModel::<S>::from_blob(blob).expect("core loads the blob");
    let points: Vec<[S; 3]> = points
        .iter()
        .map(|p| p.map(S::from_f32_saturating))
        .collect();
    let mut out = vec![FieldGradient::<S>::default(); points.len()];
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let start = Instant::now();
        for _ in 0..5 {
            if batch {
                model
                    .field_gradient_batch(black_box(&points), &mut out)
                    .expect("same lengths");
            } else {
                for (p, o) in points.iter().zip(out.iter_mut()) {
                    *o = model.field_gradient(black_box(*p));
                }
            }
            black_box(&out);
        }
        best = best.min(start.elapsed().as_secs_f64() / (5 * points.len()) as f64);
    }
    best
}

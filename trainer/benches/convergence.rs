//! How often training settles, over many seeds: Carcenac's torus from 96 points (one leaf,
//! seeds 1–100), the double torus with 4 features and the shared bunny from 400 points with 8
//! features (seeds 1–20 each). Each seed draws its own sample and initial weights. A row gives
//! the share of seeds that converged (every module reached the error threshold), stalled (E_s
//! stopped falling above it) or ran into the iteration cap, and the worst seed's figures, the
//! model measured as a user runs it (its blob in the core, in f32).
//!
//! Run: `cargo bench -p neurosurf-trainer --bench convergence`, with after `--`: `--seeds 10`
//! for fewer seeds per row (at most the row's own count), `--rows 1,3` for some rows, `--out
//! FILE` to write the table (relative to the workspace). Each seed's figures go to stderr.

mod shapes;

use std::time::Instant;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::PointSet;
use neurosurf_trainer::demo::TABLE5_TORUS;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions, Outcome};
use neurosurf_trainer::io::{data_file, read_mesh};
use neurosurf_trainer::quality::Truth;
use neurosurf_trainer::sample::{Spread, sample_mesh, sample_shape};
use shapes::{double_torus, measure_core, table5_torus};

/// One row: a shape, how it is sampled, and over how many seeds.
struct Row {
    name: &'static str,
    truth: Truth,
    sample: Box<dyn Fn(u64) -> PointSet>,
    features: Option<usize>,
    seeds: u64,
}

fn rows() -> Vec<Row> {
    let bunny = read_mesh(&data_file("stanford-bunny.obj").expect("data")).expect("bunny");
    let double = double_torus();
    vec![
        Row {
            name: "torus, 96 points, 1 leaf",
            truth: Truth::from_mesh(&table5_torus()).expect("torus"),
            sample: Box::new(|seed| sample_shape(&TABLE5_TORUS, 96, seed).expect("sample")),
            features: None,
            seeds: 100,
        },
        Row {
            name: "double torus, 400 points, `--features 4`",
            truth: Truth::from_mesh(&double).expect("double torus"),
            sample: Box::new(move |seed| {
                sample_mesh(&double, 400, seed, Spread::Even).expect("sample")
            }),
            features: Some(4),
            seeds: 20,
        },
        Row {
            name: "shared bunny, 400 points, `--features 8`",
            truth: Truth::from_mesh(&bunny).expect("bunny"),
            sample: Box::new(move |seed| {
                sample_mesh(&bunny, 400, seed, Spread::Even).expect("sample")
            }),
            features: Some(8),
            seeds: 20,
        },
    ]
}

/// What one row's seeds came to.
#[derive(Default)]
struct Tally {
    seeds: usize,
    converged: usize,
    stalled: usize,
    capped: usize,
    worst_truth_to_model: (f64, u64),
    worst_model_to_truth: (f64, u64),
    worst_stray: (usize, u64),
    worst_pieces: (usize, u64),
    largest_error: (f64, u64),
    seconds: Vec<f64>,
}

impl Tally {
    fn add(
        &mut self,
        seed: u64,
        outcome: Outcome,
        error: f64,
        m: &neurosurf_trainer::quality::TwoSided,
    ) {
        self.seeds += 1;
        match outcome {
            Outcome::Converged => self.converged += 1,
            Outcome::Stalled { .. } => self.stalled += 1,
            Outcome::IterationCap { .. } => self.capped += 1,
        }
        let worse = |slot: &mut (f64, u64), v: f64| {
            if v > slot.0 {
                *slot = (v, seed);
            }
        };
        worse(&mut self.largest_error, error);
        worse(
            &mut self.worst_truth_to_model,
            m.truth_to_model.median_percent,
        );
        worse(
            &mut self.worst_model_to_truth,
            m.model_to_truth.median_percent,
        );
        if m.stray.sign_changes > self.worst_stray.0 {
            self.worst_stray = (m.stray.sign_changes, seed);
        }
        if m.mesh.components > self.worst_pieces.0 {
            self.worst_pieces = (m.mesh.components, seed);
        }
    }

    fn share(&self, n: usize) -> String {
        format!(
            "{n} / {} ({:.0} %)",
            self.seeds,
            100.0 * n as f64 / self.seeds as f64
        )
    }

    fn median_seconds(&mut self) -> f64 {
        self.seconds.sort_by(f64::total_cmp);
        self.seconds[self.seconds.len() / 2]
    }
}

/// A count and the first seed that reached it ("0" alone when no seed counted any).
fn with_seed((count, seed): (usize, u64)) -> String {
    if count == 0 {
        "0".into()
    } else {
        format!("{count} (seed {seed})")
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| shapes::flag(&args, flag);
    let most_seeds: Option<u64> = value("--seeds").map(|v| v.parse().expect("--seeds N"));
    let mut table = String::from(
        "| shape | seeds | converged | stalled | at the iteration cap | median time | largest final E_s | worst truth → model median | worst model → truth median | most stray sign changes | most mesh pieces |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    print!("{table}");
    let chosen: Option<Vec<usize>> = value("--rows").map(|v| {
        v.split(',')
            .map(|r| r.parse().expect("--rows 1,3"))
            .collect()
    });
    for (index, row) in rows().into_iter().enumerate() {
        if chosen.as_ref().is_some_and(|c| !c.contains(&(index + 1))) {
            continue;
        }
        let seeds = most_seeds.map_or(row.seeds, |n| n.min(row.seeds));
        let mut tally = Tally::default();
        for seed in 1..=seeds {
            let mut points = (row.sample)(seed);
            // Decomposed below, as `implicit::fit` would: with the seam band it then turns on.
            let options = ImplicitOptions {
                seed,
                seam_band: row.features.is_some(),
                ..ImplicitOptions::default()
            };
            if let Some(features) = row.features {
                points.features = Some(
                    implicit::decompose(&points.positions, features, options.min_points)
                        .expect("features"),
                );
            }
            let request = FitRequest {
                features: row.features,
                ..FitRequest::default()
            };
            let start = Instant::now();
            let trained = implicit::fit(points, &request, &options, &|_| {}).expect("training");
            tally.seconds.push(start.elapsed().as_secs_f64());
            let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
            let m = measure_core(&blob, &trained.network, &row.truth);
            eprintln!(
                "{} seed {seed}: {}, {:.4} % / {:.4} %, {} stray sign changes, {} pieces",
                row.name,
                trained.summary.outcome(),
                m.truth_to_model.median_percent,
                m.model_to_truth.median_percent,
                m.stray.sign_changes,
                m.mesh.components
            );
            let error = trained
                .summary
                .modules
                .iter()
                .map(|module| module.lm.error)
                .fold(0.0, f64::max);
            tally.add(seed, trained.summary.outcome(), error, &m);
        }
        let line = format!(
            "| {} | 1–{seeds} | {} | {} | {} | {:.2} s | {:.2e} (seed {}) | {:.4} % (seed {}) | {:.4} % (seed {}) | {} | {} |\n",
            row.name,
            tally.share(tally.converged),
            tally.share(tally.stalled),
            tally.share(tally.capped),
            tally.median_seconds(),
            tally.largest_error.0,
            tally.largest_error.1,
            tally.worst_truth_to_model.0,
            tally.worst_truth_to_model.1,
            tally.worst_model_to_truth.0,
            tally.worst_model_to_truth.1,
            with_seed(tally.worst_stray),
            match tally.worst_pieces {
                (0 | 1, _) => "1".to_string(),
                most => with_seed(most),
            },
        );
        print!("{line}");
        table.push_str(&line);
    }
    if let Some(path) = value("--out").map(|p| shapes::in_workspace(&p)) {
        let command = shapes::arguments(&args);
        let text = format!(
            "# Convergence over seeds\n\nWritten by `cargo bench -p neurosurf-trainer --bench \
             convergence -- {command}` on {} threads. Each seed draws its own sample and \
             initial weights; default training options. \"Converged\": every module reached \
             the error threshold; \"stalled\": E_s stopped falling above it (normal when the \
             off-surface and sign constraints cannot all be met exactly). Distances are \
             medians in % of the true surface's bounding diagonal, measured with the blob in \
             the core in f32; stray sign changes and mesh pieces as in \
             [implicit-shapes.md](implicit-shapes.md).\n\n{table}",
            rayon::current_num_threads(),
        );
        std::fs::write(&path, text).expect("write --out");
        eprintln!("wrote {}", path.display());
    }
}

//! Carcenac's Table 5 on this machine: the torus (R = 1, r = 0.4) from 48…576 control points,
//! learned by one network module (Levenberg–Marquardt, Table 1 settings) and by the
//! multiquadric RBF baseline (two-sided off-surface points, lengths relative to the bounding
//! diagonal: `rbf::RbfOptions::default()`); training times, iterations, and the fidelity of
//! both on 2000 held-out points of the true torus. Then the core's evaluation throughput,
//! single point vs batch, in f32 and Q16.16.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench table5` (add `-- --quick` for one seed).
//! Training runs on one thread (the module tree of a torus is one leaf); times are medians
//! over seeds. Every speed is also given as a ratio to a baseline measured in the same run.

use std::hint::black_box;
use std::time::Instant;

use neurosurf_core::implicit::{FieldGradient, ImplicitModel};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use neurosurf_trainer::demo::{TABLE5_HELD_OUT, TABLE5_TORUS, paper_points, table5};
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions};
use neurosurf_trainer::sample::sample_shape;

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let seeds: &[u64] = if quick { &[1] } else { &[1, 2, 3, 4, 5] };

    println!(
        "Table 5 — torus R=1 r=0.4, network N=9 (Table 1 settings) vs multiquadric RBF \
         (c = 0.0078·D, c² ≈ 1e-3; off-surface points at ±1 % of D, Hermite-style)"
    );
    println!(
        "median over seeds {seeds:?}; fidelity on {TABLE5_HELD_OUT} held-out surface points (median distance %D / median normal error)"
    );
    println!();
    println!(
        "| points | iterations (paper) + coarse | network time (paper) | RBF time (paper) | network fidelity | RBF fidelity | network outcome |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---|");
    for row in table5(&paper_points(), seeds).expect("Table 5") {
        let paper = row.paper.expect("a paper row");
        println!(
            "| {} | {:.0} ({}) + {:.0} | {} ({} s) | {} ({}) | {:.3} % / {:.2}° | {:.3} % / {:.2}° | {} |",
            row.points,
            row.iterations,
            paper.iterations,
            row.coarse_iterations,
            seconds(row.network_seconds),
            paper.network_seconds,
            seconds(row.rbf_seconds),
            seconds(paper.rbf_seconds),
            row.network_distance_percent,
            row.network_angle_degrees,
            row.rbf_distance_percent,
            row.rbf_angle_degrees,
            row.outcome,
        );
    }

    println!();
    println!("Core evaluation throughput, 576-point torus model, 4096 points (field + gradient)");
    let points = sample_shape(&TABLE5_TORUS, 576, 1).expect("torus sample");
    let trained = implicit::fit(
        points,
        &FitRequest::default(),
        &ImplicitOptions::default(),
        &|_| {},
    )
    .expect("training");
    let queries: Vec<[f64; 3]> = sample_shape(&TABLE5_TORUS, 4096, 5)
        .expect("queries")
        .positions;
    let f32_blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
    let q16_blob = implicit::to_blob(&trained.network, None, ScalarKind::Q16_16).expect("blob");
    let reference = {
        let start = Instant::now();
        let mut reps = 0;
        while start.elapsed().as_secs_f64() < 0.5 {
            for &q in &queries {
                black_box(trained.network.eval(black_box(q)));
            }
            reps += 1;
        }
        start.elapsed().as_secs_f64() / (reps * queries.len()) as f64
    };
    println!();
    println!("| evaluator | ns / point | speed vs trainer f64 |");
    println!("|---|---:|---:|");
    println!(
        "| trainer f64 (reference) | {:.0} | 1.00× |",
        reference * 1e9
    );
    for (name, t) in [
        (
            "core f32 single",
            throughput::<f32>(&f32_blob, &queries, false),
        ),
        (
            "core f32 batch",
            throughput::<f32>(&f32_blob, &queries, true),
        ),
        (
            "core Q16.16 single",
            throughput::<Q16>(&q16_blob, &queries, false),
        ),
        (
            "core Q16.16 batch",
            throughput::<Q16>(&q16_blob, &queries, true),
        ),
    ] {
        println!("| {name} | {:.0} | {:.2}× |", t * 1e9, reference / t);
    }
}

/// Seconds per field+gradient evaluation through the core.
fn throughput<S: Scalar>(blob: &[u8], queries: &[[f64; 3]], batch: bool) -> f64 {
    let model = ImplicitModel::<S>::from_blob(blob).expect("core loads the blob");
    let points: Vec<[S; 3]> = queries
        .iter()
        .map(|p| p.map(|c| S::from_f32_saturating(c as f32)))
        .collect();
    let mut out = vec![FieldGradient::<S>::default(); points.len()];
    let start = Instant::now();
    let mut reps = 0;
    while start.elapsed().as_secs_f64() < 0.5 {
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
        reps += 1;
    }
    start.elapsed().as_secs_f64() / (reps * points.len()) as f64
}

fn seconds(s: f64) -> String {
    if s < 1.0 {
        format!("{:.1} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

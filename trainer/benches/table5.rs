//! Carcenac's Table 5 on this machine: the torus (R = 1, r = 0.4) from 48…576 control points,
//! learned by one network module (Levenberg–Marquardt, Table 1 settings) and by the
//! multiquadric RBF baseline; training times, iterations, and the fidelity of both on 2000
//! held-out points of the true torus. Then the core's evaluation throughput, single point vs
//! batch, in f32 and Q16.16.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench table5` (add `-- --quick` for one seed).
//! Training runs on one thread (the module tree of a torus is one leaf); times are medians
//! over seeds. Every speed is also given as a ratio to a baseline measured in the same run.

use std::hint::black_box;
use std::time::Instant;

use neurosurf_core::implicit::{FieldGradient, ImplicitModel};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use neurosurf_trainer::fidelity::{Fidelity, median};
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions, StopReason};
use neurosurf_trainer::rbf::{self, RbfOptions};
use neurosurf_trainer::sample::{Shape, sample_shape};

const TORUS: Shape = Shape::Torus {
    major: 1.0,
    minor: 0.4,
};
const DIAMETER: f64 = 2.8;
/// The paper's Table 5 (1.7 GHz Pentium IV): points, iterations, network s, RBF s.
const PAPER: [(usize, usize, f64, f64); 5] = [
    (48, 73, 2.5, 0.0018),
    (96, 61, 3.6, 0.027),
    (160, 67, 6.2, 0.18),
    (336, 58, 10.9, 1.88),
    (576, 59, 17.8, 8.3),
];

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let seeds: &[u64] = if quick { &[1] } else { &[1, 2, 3, 4, 5] };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread pool");
    let held_out = sample_shape(&TORUS, 2000, 999).expect("held-out torus");

    println!(
        "Table 5 — torus R=1 r=0.4, network N=9 (Table 1 settings) vs multiquadric RBF (c²=1e-3)"
    );
    println!(
        "median over seeds {seeds:?}; fidelity on 2000 held-out surface points (median distance %D / median normal error)"
    );
    println!();
    println!(
        "| points | iterations (paper) | network time (paper) | RBF time (paper) | network fidelity | RBF fidelity | network ms / iteration |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    for (n, paper_it, paper_net, paper_rbf) in PAPER {
        let mut iterations = Vec::new();
        let mut net_times = Vec::new();
        let mut rbf_times = Vec::new();
        let mut net_fid = Vec::new();
        let mut rbf_fid = Vec::new();
        let mut converged = true;
        for &seed in seeds {
            let points = sample_shape(&TORUS, n, seed).expect("torus sample");
            let options = ImplicitOptions {
                seed,
                ..ImplicitOptions::default()
            };
            let start = Instant::now();
            let trained = pool
                .install(|| {
                    implicit::fit(points.clone(), &FitRequest::default(), &options, &|_| {})
                })
                .expect("training");
            net_times.push(start.elapsed().as_secs_f64());
            let module = &trained.summary.modules[0];
            converged &= module.lm.stop == StopReason::Converged;
            iterations.push(module.lm.iterations as f64);
            let f = Fidelity::measure(&held_out, DIAMETER, |p| trained.network.eval(p))
                .expect("fidelity");
            net_fid.push((f.median_distance_percent, f.median_angle_degrees));

            let start = Instant::now();
            let (model, _) = rbf::fit(&points, &RbfOptions::default()).expect("RBF fit");
            rbf_times.push(start.elapsed().as_secs_f64());
            let f = Fidelity::measure(&held_out, DIAMETER, |p| model.field_gradient(p))
                .expect("fidelity");
            rbf_fid.push((f.median_distance_percent, f.median_angle_degrees));
        }
        let it = median(&mut iterations);
        let net = median(&mut net_times);
        let rbf = median(&mut rbf_times);
        let fid = |v: &[(f64, f64)]| {
            let mut d: Vec<f64> = v.iter().map(|x| x.0).collect();
            let mut a: Vec<f64> = v.iter().map(|x| x.1).collect();
            format!("{:.3} % / {:.2}°", median(&mut d), median(&mut a))
        };
        println!(
            "| {n} | {it:.0} ({paper_it}) | {} ({paper_net} s) | {} ({}) | {} | {} | {:.2}{} |",
            seconds(net),
            seconds(rbf),
            seconds(paper_rbf),
            fid(&net_fid),
            fid(&rbf_fid),
            1000.0 * net / it.max(1.0),
            if converged {
                ""
            } else {
                " (not all converged)"
            },
        );
    }

    println!();
    println!("Core evaluation throughput, 576-point torus model, 4096 points (field + gradient)");
    let points = sample_shape(&TORUS, 576, 1).expect("torus sample");
    let trained = implicit::fit(
        points,
        &FitRequest::default(),
        &ImplicitOptions::default(),
        &|_| {},
    )
    .expect("training");
    let queries: Vec<[f64; 3]> = sample_shape(&TORUS, 4096, 5).expect("queries").positions;
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

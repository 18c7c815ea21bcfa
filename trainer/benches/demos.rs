//! Carcenac's Tables 2–4 (learning columns) on this machine: the head (99 points, 5
//! modules), the body (316 points, 33 modules) and the 50-frame animation learned
//! incrementally (average / min / max per frame), against the paper's 500 MHz Pentium III.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench demos` (`-- --quick`: one run each, 10
//! frames). Head and body are the median of 3 trainings (seeds 1–3 for the body's points and
//! weights; the head with seed 1 as in `neurosurf demo`), on all cores; the animation is one
//! run from the seed-1 body. Ratios are the paper's time over ours.

use std::time::Instant;

use neurosurf_trainer::demo::{PAPER_FRAMES, animate, body_points, train_body};
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions, Trained, TreeSpec};
use neurosurf_trainer::sample::{Pose, Shape, sample_shape};

/// The paper's learning times, seconds (Tables 2, 3 and 4).
const PAPER_HEAD: f64 = 69.0;
const PAPER_BODY: f64 = 352.0;
const PAPER_FRAME: [f64; 3] = [38.0, 15.0, 62.0];

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn options(seed: u64) -> ImplicitOptions {
    ImplicitOptions {
        seed,
        ..ImplicitOptions::default()
    }
}

fn head(seed: u64) -> Trained {
    let points = sample_shape(&Shape::Head, 99, seed).expect("head points");
    let request = FitRequest {
        tree: Some("((0,1),2)".parse::<TreeSpec>().expect("tree")),
        ..FitRequest::default()
    };
    implicit::fit(points, &request, &options(seed), &|_| {}).expect("head training")
}

fn body(seed: u64) -> Trained {
    let points = body_points(&Pose::REST, seed).expect("body points");
    train_body(&points, &options(seed), None, &|_| {}).expect("body training")
}

fn row(what: &str, paper: f64, ours: f64, iterations: String) {
    println!(
        "| {what} | {paper} s | {:.3} s | {:.0}× | {iterations} |",
        ours,
        paper / ours
    );
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let runs = if quick { 1 } else { 3 };
    let frames = if quick { 10 } else { PAPER_FRAMES };
    println!(
        "threads: {}; paper: C on a 500 MHz Pentium III\n",
        rayon::current_num_threads()
    );
    println!("| learning | paper | here | speed-up | LM iterations |\n|---|---:|---:|---:|---|");
    let heads: Vec<Trained> = (0..runs).map(|_| head(1)).collect();
    row(
        "head (99 points, 5 modules), median of 3",
        PAPER_HEAD,
        median(heads.iter().map(|t| t.summary.seconds).collect()),
        format!("{}", heads[0].summary.iterations()),
    );
    let bodies: Vec<Trained> = (1..=runs as u64).map(body).collect();
    row(
        "body (316 points, 33 modules), median of seeds 1–3",
        PAPER_BODY,
        median(bodies.iter().map(|t| t.summary.seconds).collect()),
        bodies
            .iter()
            .map(|t| {
                format!(
                    "{}{}",
                    t.summary.iterations(),
                    if t.summary.converged() {
                        ""
                    } else {
                        " (not converged)"
                    }
                )
            })
            .collect::<Vec<_>>()
            .join(", "),
    );
    let start = Instant::now();
    let animation =
        animate(&bodies[0], frames, 1, &options(1), &[], &|_, _| {}).expect("animation");
    let wall = start.elapsed().as_secs_f64();
    let seconds = animation.seconds();
    let iterations = animation.iterations();
    let cold = bodies[0].summary.iterations() as f64;
    for (what, paper, ours) in [
        ("frame, average", PAPER_FRAME[0], seconds.average),
        ("frame, minimum", PAPER_FRAME[1], seconds.min),
        ("frame, maximum", PAPER_FRAME[2], seconds.max),
    ] {
        row(
            &format!("{what} ({} incremental frames)", frames - 1),
            paper,
            ours,
            format!(
                "{:.0} / {:.0} / {:.0} (cold: {cold})",
                iterations.average, iterations.min, iterations.max
            ),
        );
    }
    let converged = animation
        .frames
        .iter()
        .filter(|f| f.outcome == neurosurf_trainer::implicit::Outcome::Converged)
        .count();
    println!(
        "\nanimation: {frames} frames in {wall:.2} s; {converged} of {} incremental frames \
         converged; warm frames need {:.1}× fewer iterations and {:.1}× less time than the \
         cold body (the paper: 352 s / 38 s = 9.3×)",
        animation.frames.len(),
        cold / iterations.average,
        bodies[0].summary.seconds / seconds.average
    );
}

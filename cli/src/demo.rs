//! `neurosurf demo`: the README's main job.

use std::path::PathBuf;

use anyhow::Result;

use neurosurf_trainer::demo::{self, HELD_OUT, TABLE5_HELD_OUT, Tour, TourSize};

use super::{output, progress};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folder for the point sets and blobs.
    #[arg(long, short, default_value = "out/demo")]
    out: PathBuf,
    /// Seed of the samples and the weight initialization.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// A small tour (6 animation frames, small pictures, 1 ray per pixel): seconds, not
    /// minutes.
    #[arg(long)]
    quick: bool,
    /// Print a JSON report instead of the table.
    #[arg(long)]
    json: bool,
}

pub fn run(args: &Args) -> Result<()> {
    let bar = progress::training_bar("demo", args.json);
    let size = if args.quick {
        TourSize::QUICK
    } else {
        TourSize::PAPER
    };
    let report = demo::run(&args.out, args.seed, Some(size), &|name, event| {
        bar.set_prefix(name.to_string());
        progress::update(&bar, event);
    })?;
    bar.finish_and_clear();
    if args.json {
        return output::json(&report);
    }
    println!(
        "neurosurf demo: Carcenac modular implicit surfaces, trained in f64, evaluated by the core\n\
         accuracy on {HELD_OUT} held-out points of the true surface (distance ≈ |Φ|/|∇Φ| in % of the diameter D)\n"
    );
    println!(
        "{:<6} {:>6} {:<10} {:>5} {:>8}  {:<7} {:>11} {:>10} {:>12} {:>10} {:>12}",
        "model",
        "points",
        "tree",
        "iters",
        "train",
        "scalar",
        "median %D",
        "max %D",
        "median angle",
        "max angle",
        "max |ΔΦ|"
    );
    for m in &report.models {
        for (i, (precision, f)) in m.fidelity.iter().enumerate() {
            let deviation = m
                .max_field_deviation
                .iter()
                .find(|(p, _)| p == precision)
                .map_or("reference".to_string(), |(_, d)| format!("{d:.2e}"));
            let head = if i == 0 {
                format!(
                    "{:<6} {:>6} {:<10} {:>5} {:>7.3}s",
                    m.name, m.control_points, m.tree, m.iterations, m.seconds
                )
            } else {
                format!("{:<6} {:>6} {:<10} {:>5} {:>8}", "", "", "", "", "")
            };
            println!(
                "{head}  {:<7} {:>11.4} {:>10.4} {:>11.3}° {:>9.3}° {:>12}",
                precision.name(),
                f.median_distance_percent,
                f.max_distance_percent,
                f.median_angle_degrees,
                f.max_angle_degrees,
                deviation
            );
        }
        if m.outcome != neurosurf_trainer::implicit::Outcome::Converged {
            println!("       (training {})", m.outcome);
        }
    }
    for demo in &report.parametric {
        println!(
            "\n{}: {} ({:.3} s)",
            demo.name, demo.description, demo.seconds
        );
        for (what, value) in &demo.quality {
            if value.abs() >= 0.01 {
                println!("  {what}: {value:.4}");
            } else {
                println!("  {what}: {value:.2e}");
            }
        }
        for (precision, d) in &demo.deviation {
            println!(
                "  {:<7} against f64: max |Δ| {:.2e}, RMS {:.2e}, median angle {:.2e}°",
                precision.name(),
                d.field_max.unwrap_or(f64::NAN),
                d.field_rms.unwrap_or(f64::NAN),
                d.normal_median_degrees.unwrap_or(f64::NAN)
            );
        }
    }
    if let Some(tour) = &report.tour {
        print_tour(tour);
    }
    println!();
    for m in &report.models {
        for (path, bytes) in &m.blobs {
            println!("wrote {} ({bytes} bytes)", path.display());
        }
    }
    for demo in &report.parametric {
        for (path, bytes) in &demo.files {
            println!("wrote {} ({bytes} bytes)", path.display());
        }
    }
    if let Some(tour) = &report.tour {
        for p in tour.pictures.iter().chain(&tour.memorization) {
            println!("wrote {}", report.out_dir.join(&p.file).display());
        }
    }
    if let Some(index) = &report.index {
        println!("\nreport: {} (open it in a browser)", index.display());
    }
    Ok(())
}

fn print_tour(tour: &Tour) {
    let b = &tour.body;
    println!(
        "\nbody: {} control points, {} features, {} modules, {} iterations, {:.3} s, {}; \
         median distance {:.4} %D, median angle {:.2}°\n  both ways: {}",
        b.control_points,
        b.features.len(),
        b.modules.len(),
        b.iterations,
        b.seconds,
        b.outcome,
        b.fidelity.median_distance_percent,
        b.fidelity.median_angle_degrees,
        b.two_sided
    );
    let a = &tour.animation;
    println!(
        "animation: {} frames, warm-started: {:.3} s per frame (min {:.3}, max {:.3}), \
         {:.0} iterations per frame against {} cold, {}\n  last frame both ways: {}",
        a.frames,
        a.seconds.average,
        a.seconds.min,
        a.seconds.max,
        a.iterations.average,
        a.cold_iterations,
        a.outcome,
        a.last_two_sided
    );
    if let Some(w) = &tour.woody {
        println!(
            "woody.obj cookie: {} control points, {} automatic features, {} iterations, {:.3} s, \
             {}; median distance {:.4} %D, median angle {:.2}°\n  both ways: {}",
            w.control_points,
            w.features,
            w.iterations,
            w.seconds,
            w.outcome,
            w.fidelity.median_distance_percent,
            w.fidelity.median_angle_degrees,
            w.two_sided
        );
    }
    println!(
        "\n{:<8} {:<55} {:>9} {:>10} {:>9}",
        "table", "what", "paper", "here", "speed-up"
    );
    for t in &tour.timings {
        println!(
            "{:<8} {:<55} {:>7.0} s {:>8.3} s {:>8.0}×  {}",
            t.table,
            t.what,
            t.paper_seconds,
            t.seconds,
            t.paper_seconds / t.seconds.max(1e-9),
            t.note
        );
    }
    println!(
        "\nTable 5: torus by one network module vs the RBF, one thread (paper in parentheses); \
         median distance %D / angle on {TABLE5_HELD_OUT} held-out points"
    );
    println!(
        "{:>6} {:>10} {:>20} {:>20} {:>17} {:>17}",
        "points", "iterations", "network", "RBF", "network fidelity", "RBF fidelity"
    );
    for r in &tour.table5 {
        println!(
            "{:>6} {:>10} {:>20} {:>20} {:>8.3}% {:>6.2}° {:>8.3}% {:>6.2}°{}",
            r.points,
            format!(
                "{:.0}{}",
                r.iterations,
                r.beside_paper(|p| p.iterations.to_string())
            ),
            format!(
                "{:.4} s{}",
                r.network_seconds,
                r.beside_paper(|p| format!("{} s", p.network_seconds))
            ),
            format!(
                "{:.4} s{}",
                r.rbf_seconds,
                r.beside_paper(|p| format!("{} s", p.rbf_seconds))
            ),
            r.network_distance_percent,
            r.network_angle_degrees,
            r.rbf_distance_percent,
            r.rbf_angle_degrees,
            if r.outcome == neurosurf_trainer::implicit::Outcome::Converged {
                String::new()
            } else {
                format!("  ({})", r.outcome)
            }
        );
    }
}

//! Curves from noisy bands: closed and open curves of our own, sampled at random along their
//! length with Gaussian noise of σ × the bounding-box diagonal in each coordinate, fitted by
//! `curve fit`'s pipeline with default options, and measured by the Hausdorff distance both
//! ways between the fitted curve and the true one (worst and mean over the seeds, % of the
//! diagonal).
//!
//! Run: `cargo bench -p neurosurf-trainer --bench curve_bands`, with after `--`:
//! `--points 1000,5000` for the sizes, `--noise 0.05` for σ, `--seeds 8` for seeds 1 to 8,
//! `--case sine,arc` for some curves, `--save DIR` for each sample, fit and truth as
//! `x y z` lines, `--markdown FILE` to write the table as well
//! (`docs/performance/curve-bands.md`).

mod arguments;
use arguments::{given, in_workspace, option};

use std::f64::consts::{PI, TAU};
use std::fmt::Write as _;

use neurosurf_trainer::curve::{
    CurveOptions, CurvePoints, Topology, hausdorff_distance, reconstruct_curve,
};
use neurosurf_trainer::geometry::vector::{bounds, distance};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Vertices of the true curve and of the fitted one the distances are measured between.
const VERTICES: usize = 4_000;

/// A test curve: its name, what it is, whether closed, its dimension, the point at t ∈ [0, 1]
/// and where a sample's t falls for a uniform u (uneven density).
struct Case {
    name: &'static str,
    about: &'static str,
    closed: bool,
    dimension: usize,
    at: fn(f64) -> [f64; 3],
    density: fn(f64) -> f64,
}

fn even(u: f64) -> f64 {
    u
}

/// 10 of every 11 samples on the first half of the curve: a 10:1 density step.
fn step(u: f64) -> f64 {
    if u < 10.0 / 11.0 {
        u * 11.0 / 20.0
    } else {
        0.5 + (u - 10.0 / 11.0) * 5.5
    }
}

fn epitrochoid(t: f64) -> [f64; 3] {
    let a = TAU * t;
    [
        4.0 * a.cos() - 0.5 * (4.0 * a).cos(),
        4.0 * a.sin() - 0.5 * (4.0 * a).sin(),
        0.0,
    ]
}

/// A hairpin of arc length parameter: an arm from (3, 0.6) to (0, 0.6), a half circle of
/// radius 0.6 round the left, an arm back to (3, −0.6).
fn hairpin(t: f64) -> [f64; 3] {
    let (arm, bend) = (3.0, PI * 0.6);
    let s = t * (2.0 * arm + bend);
    if s < arm {
        [arm - s, 0.6, 0.0]
    } else if s < arm + bend {
        let a = (s - arm) / 0.6;
        [-0.6 * a.sin(), 0.6 * a.cos(), 0.0]
    } else {
        [s - arm - bend, -0.6, 0.0]
    }
}

fn cases() -> Vec<Case> {
    let closed = |name, about, dimension, at| Case {
        name,
        about,
        closed: true,
        dimension,
        at,
        density: even,
    };
    let open = |name, about, dimension, at| Case {
        name,
        about,
        closed: false,
        dimension,
        at,
        density: even,
    };
    vec![
        closed("ellipse", "2:1", 2, |t| {
            let a = TAU * t;
            [2.0 * a.cos(), a.sin(), 0.0]
        }),
        closed("cardioid", "r = 1 − 0.8 cos θ", 2, |t| {
            let a = TAU * t;
            let r = 1.0 - 0.8 * a.cos();
            [r * a.cos(), r * a.sin(), 0.0]
        }),
        closed("ring-3d", "unit circle, z = ½ sin 2θ", 3, |t| {
            let a = TAU * t;
            [a.cos(), a.sin(), 0.5 * (2.0 * a).sin()]
        }),
        closed("squircle", "x⁴ + y⁴ = 1, even in angle", 2, |t| {
            let (c, s) = ((TAU * t).cos(), (TAU * t).sin());
            [
                c.signum() * c.abs().sqrt(),
                s.signum() * s.abs().sqrt(),
                0.0,
            ]
        }),
        closed("epitrochoid", "4e^{iθ} − ½e^{4iθ}", 2, epitrochoid),
        Case {
            density: step,
            ..closed(
                "epitrochoid-step",
                "the same, 10:1 density step",
                2,
                epitrochoid,
            )
        },
        closed("wobbly-ring", "r = 1 + 0.15 sin 5θ", 2, |t| {
            let a = TAU * t;
            let r = 1.0 + 0.15 * (5.0 * a).sin();
            [r * a.cos(), r * a.sin(), 0.0]
        }),
        closed(
            "trefoil",
            "3-D knot, strands 3.1σ apart at closest",
            3,
            |t| {
                let a = TAU * t;
                [
                    a.sin() + 2.0 * (2.0 * a).sin(),
                    a.cos() - 2.0 * (2.0 * a).cos(),
                    -(3.0 * a).sin(),
                ]
            },
        ),
        open("sine", "1.3 periods", 2, |t| {
            [8.0 * t, (8.0 * t).sin(), 0.0]
        }),
        open("hook", "216°, radius 1 → 2", 2, |t| {
            let a = 1.2 * PI * t;
            [a.cos() * (1.0 + t), a.sin() * (1.0 + t), 0.0]
        }),
        open("arc-3d", "¾ of a 2:1 ellipse, rising", 3, |t| {
            let a = 1.5 * PI * t;
            [2.0 * a.cos(), a.sin(), 0.3 * a]
        }),
        open("c-curve", "330° of a unit circle", 2, |t| {
            let a = (15.0 + 330.0 * t).to_radians();
            [a.cos(), a.sin(), 0.0]
        }),
        open("helix", "2 turns, radius 1, pitch 1", 3, |t| {
            let a = 2.0 * TAU * t;
            [a.cos(), a.sin(), 2.0 * t]
        }),
        open("hairpin", "arms 1.2 apart, 3 long", 2, hairpin),
        open("s-curve", "x = sin πs, y = ¾s, s ∈ [−1, 1]", 2, |t| {
            let s = 2.0 * t - 1.0;
            [(PI * s).sin(), 0.75 * s, 0.0]
        }),
        open("spiral", "1.5 turns, r = ½ → 1½", 2, |t| {
            let (a, r) = (3.0 * PI * t, 0.5 + t);
            [r * a.cos(), r * a.sin(), 0.0]
        }),
    ]
}

fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let (a, b) = (rng.random::<f64>(), rng.random::<f64>());
    (-2.0 * (1.0 - a).ln()).sqrt() * (TAU * b).cos()
}

/// The Hausdorff distance over the diagonal for one seed, or the pipeline's error.
fn measure(
    case: &Case,
    points: usize,
    noise: f64,
    seed: u64,
    save: Option<&str>,
) -> Result<f64, String> {
    let truth: Vec<[f64; 3]> = (0..=VERTICES)
        .map(|j| (case.at)(j as f64 / VERTICES as f64))
        .collect();
    let (lo, hi) = bounds(&truth);
    let diagonal = distance(lo, hi);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let raw: Vec<[f64; 3]> = (0..points)
        .map(|_| {
            let p = (case.at)((case.density)(rng.random::<f64>()));
            [0, 1, 2].map(|k| {
                if k < case.dimension {
                    p[k] + noise * diagonal * gaussian(&mut rng)
                } else {
                    0.0
                }
            })
        })
        .collect();
    let count = raw.len();
    let points = CurvePoints::new(case.dimension, raw).map_err(|e| e.to_string())?;
    let topology = if case.closed {
        Topology::Closed
    } else {
        Topology::Open
    };
    let fit = reconstruct_curve(&points, &CurveOptions::new(topology, seed))
        .map_err(|e| e.to_string())?;
    let polyline = fit.approximation.curve.polyline(VERTICES);
    if let Some(dir) = save {
        let write = |suffix: &str, list: &[[f64; 3]]| {
            let text: String = list
                .iter()
                .map(|p| format!("{} {} {}\n", p[0], p[1], p[2]))
                .collect();
            let name = format!("{}-{count}-{seed}{suffix}.xyz", case.name);
            let dir = in_workspace(dir);
            std::fs::create_dir_all(&dir).expect("--save DIR: a folder that can be made");
            std::fs::write(dir.join(name), text).expect("--save DIR");
        };
        write("", points.points());
        write("-fit", &polyline);
        write("-truth", &truth);
    }
    Ok(hausdorff_distance(&polyline, &truth) / diagonal)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let sizes: Vec<usize> = option(&args, "--points")
        .unwrap_or("1000,5000")
        .split(',')
        .map(|s| s.parse().expect("--points: sizes separated by commas"))
        .collect();
    let noise: f64 = option(&args, "--noise")
        .unwrap_or("0.05")
        .parse()
        .expect("--noise: σ as a fraction of the diagonal");
    let seeds: u64 = option(&args, "--seeds")
        .unwrap_or("8")
        .parse()
        .expect("--seeds: a count");
    let save = option(&args, "--save");
    let filter: Vec<&str> = option(&args, "--case")
        .map(|c| c.split(',').collect())
        .unwrap_or_default();
    let mut table = String::from(
        "| curve | | points | worst | mean | per seed |\n|---|---|---:|---:|---:|---|\n",
    );
    for case in cases()
        .into_iter()
        .filter(|c| filter.is_empty() || filter.contains(&c.name))
    {
        for &points in &sizes {
            let results: Vec<Result<f64, String>> = (1..=seeds)
                .into_par_iter()
                .map(|seed| measure(&case, points, noise, seed, save))
                .collect();
            let values: Vec<f64> = results
                .iter()
                .filter_map(|r| r.as_ref().ok())
                .copied()
                .collect();
            let failed = results.len() - values.len();
            for error in results.iter().filter_map(|r| r.as_ref().err()) {
                eprintln!("{} ({points} points): {error}", case.name);
            }
            let worst = values.iter().copied().fold(0.0, f64::max);
            let mean = values.iter().sum::<f64>() / values.len().max(1) as f64;
            let each: Vec<String> = results
                .iter()
                .map(|r| {
                    r.as_ref()
                        .map_or("error".into(), |v| format!("{:.1}", 100.0 * v))
                })
                .collect();
            let failed = if failed > 0 {
                format!(" ({failed} refused)")
            } else {
                String::new()
            };
            let row = format!(
                "| {} | {}{} | {points} | {:.2} % | {:.2} % | {} |",
                case.name,
                if case.closed { "closed, " } else { "open, " },
                case.about,
                100.0 * worst,
                100.0 * mean,
                each.join(" ") + &failed
            );
            println!("{row}");
            let _ = writeln!(table, "{row}");
        }
    }
    if let Some(path) = option(&args, "--markdown") {
        let text = format!(
            "# Curves from noisy bands\n\nWritten by `cargo bench -p neurosurf-trainer --bench \
             curve_bands -- {}`: σ = {} % of the diagonal (Gaussian in each \
             coordinate), points at random along each curve, seeds 1–{seeds}, default options; \
             the Hausdorff distance both ways between the fitted and the true curve, % of the \
             diagonal.\n\n{table}",
            given(&args),
            100.0 * noise
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

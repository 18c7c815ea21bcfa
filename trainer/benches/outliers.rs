//! Patches with 2 % outliers against the same patches without them, rebuilt as `patch fit`
//! and `patch tessellate` do (outliers left out, the network fitted, a 30 × 30 Coons grid of
//! the covered region) and measured both ways against the true surface:
//!
//! - **mesh → truth**: RMS distance of the mesh's vertices from the true surface;
//! - **truth → mesh**: RMS distance of the true surface's vertices (a 200 × 200 grid of its
//!   parameters, within the convex hull of the samples' true parameters) from the mesh;
//! - **largest**: the largest distance of a mesh vertex from the truth, which shows surface
//!   grown away from the data.
//!
//! Every distance is a share of the true surface's bounding diagonal. Each surface is sampled
//! at `--points` (1 500) points uniform in its parameters with uniform noise of standard
//! deviation `--noise` (0.002) of the diagonal; the outliers, 2 % more, are uniform in the
//! points' bounding box grown by 10 % per side. The table gives the median over `--seeds`
//! (1–4) and the worst ratio of a run with outliers to the clean run of the same seed.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench outliers`, with after `--`:
//! `--points 1500`, `--seeds 4`, `--noise 0.002`, `--markdown FILE` to write the table as
//! well (`docs/performance/outliers.md`), `--meshes DIR` to write every mesh with its points
//! (OBJ).

mod arguments;
mod hull;
use arguments::{given, in_workspace, option, parsed};
use hull::{convex_hull, grid_mesh, inside_convex};

use std::f64::consts::PI;
use std::fmt::Write as _;

use neurosurf_trainer::caoen::surface_distance;
use neurosurf_trainer::io::{Mesh, write_mesh};
use neurosurf_trainer::parametric::{
    LleOptions, OutlierOptions, TopologyOptions, coons_boundary_of_polygon, coons_grid,
    fit_robustly, parameter_region, synthesize,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Outliers per 100 surface points.
const OUTLIER_PERCENT: usize = 2;

/// Coons grid vertices per side, as `patch tessellate`'s default.
const RESOLUTION: usize = 30;

/// A surface by its parameterization over a parameter rectangle.
struct Surface {
    name: &'static str,
    position: fn(f64, f64) -> [f64; 3],
    domain: [[f64; 2]; 2],
}

fn surfaces() -> Vec<Surface> {
    vec![
        Surface {
            name: "horn",
            position: |s, t| {
                let r = 0.2 + 0.6 * t * t;
                [r * s.cos(), 1.5 * t, 0.5 * t * t + r * s.sin()]
            },
            domain: [[0.0, 1.2 * PI], [0.0, 1.0]],
        },
        Surface {
            name: "saddle",
            position: |s, t| [s, t, s * t],
            domain: [[-1.0, 1.0], [-1.0, 1.0]],
        },
        Surface {
            name: "bump",
            position: |s, t| [s, t, 0.5 * (-4.0 * (s * s + t * t)).exp()],
            domain: [[-1.0, 1.0], [-1.0, 1.0]],
        },
        Surface {
            name: "open cylinder",
            position: |s, t| [s.cos(), s.sin(), t],
            domain: [[0.0, 1.5 * PI], [0.0, 2.5]],
        },
        Surface {
            name: "paraboloid",
            position: |s, t| [s, 0.7 * t, 0.5 * (s * s + 0.49 * t * t)],
            domain: [[-1.0, 1.0], [-1.0, 1.0]],
        },
        Surface {
            name: "wavy sheet",
            position: |s, t| [s, t, 0.25 * (2.5 * s).sin() * (2.0 * t).cos()],
            domain: [[-1.0, 1.0], [-1.0, 1.0]],
        },
        Surface {
            name: "ripple",
            position: |s, t| [s, t, 0.15 * (3.0 * (s * s + t * t).sqrt()).cos()],
            domain: [[-1.0, 1.0], [-1.0, 1.0]],
        },
    ]
}

/// One seed's samples: the noisy surface points, their true parameters, and the outliers.
struct Sample {
    points: Vec<[f64; 3]>,
    parameters: Vec<[f64; 2]>,
    outliers: Vec<[f64; 3]>,
}

fn sample(surface: &Surface, count: usize, noise: f64, seed: u64) -> Sample {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let [s, t] = surface.domain;
    let parameters: Vec<[f64; 2]> = (0..count)
        .map(|_| [rng.random_range(s[0]..s[1]), rng.random_range(t[0]..t[1])])
        .collect();
    let mut points: Vec<[f64; 3]> = parameters
        .iter()
        .map(|&[s, t]| (surface.position)(s, t))
        .collect();
    let (lo, hi) = neurosurf_trainer::geometry::vector::bounds(&points);
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    // Uniform noise of standard deviation `noise` of the diagonal (half-width √3 σ).
    let half = 3f64.sqrt() * noise * diagonal;
    for p in &mut points {
        for c in p.iter_mut() {
            *c += rng.random_range(-half..half);
        }
    }
    let outliers = (0..count * OUTLIER_PERCENT / 100)
        .map(|_| {
            [0, 1, 2].map(|k| {
                let grow = 0.1 * (hi[k] - lo[k]);
                rng.random_range(lo[k] - grow..hi[k] + grow)
            })
        })
        .collect();
    Sample {
        points,
        parameters,
        outliers,
    }
}

/// The true surface triangulated on a `side × side` grid of its parameters, the cells with a
/// corner outside `reach` left out.
fn truth(surface: &Surface, side: usize, reach: &[[f64; 2]]) -> Mesh {
    grid_mesh(side, surface.domain, surface.position, |p| {
        inside_convex(p, reach)
    })
}

/// What one rebuild gave: (mesh → truth RMS, truth → mesh RMS, largest mesh → truth, points
/// left out), distances over the truth's diagonal.
type Measured = (f64, f64, f64, usize);

/// `points` rebuilt as `patch fit` and `patch tessellate` do, measured against `reference`.
fn rebuild(
    points: &[[f64; 3]],
    reference: &Mesh,
    seed: u64,
    keep: Option<String>,
) -> Result<Measured, String> {
    let topology = TopologyOptions {
        seed,
        ..TopologyOptions::default()
    };
    let fit = fit_robustly(
        points,
        None,
        &LleOptions::default(),
        &topology,
        Some(&OutlierOptions::default()),
    )
    .map_err(|e| e.to_string())?;
    // The region `patch fit` stores in the blob, which `patch tessellate` meshes.
    let region = parameter_region(&fit.parameters).map_err(|e| e.to_string())?;
    let boundary = coons_boundary_of_polygon(&region).map_err(|e| e.to_string())?;
    let grid = coons_grid(&boundary, RESOLUTION, RESOLUTION).map_err(|e| e.to_string())?;
    let mesh = synthesize(&fit.fit.network, &grid).mesh;
    if let Some(name) = keep {
        write_mesh(std::path::Path::new(&format!("{name}.obj")), &mesh, None)
            .map_err(|e| e.to_string())?;
        let cloud = Mesh {
            positions: points.to_vec(),
            triangles: Vec::new(),
        };
        write_mesh(
            std::path::Path::new(&format!("{name}-points.obj")),
            &cloud,
            None,
        )
        .map_err(|e| e.to_string())?;
    }
    let d = surface_distance(&mesh, reference).map_err(|e| e.to_string())?;
    Ok((
        d.rms_to_reference,
        d.rms_to_surface,
        d.max_to_reference,
        points.len() - fit.kept.len(),
    ))
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let count: usize = parsed(&args, "--points", "1500", "a count");
    let seeds: u64 = parsed(&args, "--seeds", "4", "a count");
    let noise: f64 = parsed(&args, "--noise", "0.002", "a share of the diagonal");
    let mut table = String::from(
        "| surface | clean: mesh → truth | truth → mesh | outliers: mesh → truth | truth → mesh \
         | worst ratio (mesh → truth / truth → mesh) | largest, clean / outliers | left out, \
         clean / outliers | failed seeds |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let meshes = option(&args, "--meshes");
    for surface in surfaces() {
        let runs: Vec<Result<(Measured, Measured), String>> = (1..=seeds)
            .into_par_iter()
            .map(|seed| {
                let sample = sample(&surface, count, noise, seed);
                let reference = truth(&surface, 200, &convex_hull(&sample.parameters));
                let keep = |what: &str| {
                    meshes.map(|dir| {
                        format!("{dir}/{}-{seed}-{what}", surface.name.replace(' ', "-"))
                    })
                };
                let clean = rebuild(&sample.points, &reference, seed, keep("clean"))?;
                let mut all = sample.points.clone();
                all.extend(&sample.outliers);
                let with = rebuild(&all, &reference, seed, keep("outliers"))?;
                Ok((clean, with))
            })
            .collect();
        let ok: Vec<&(Measured, Measured)> = runs.iter().filter_map(|r| r.as_ref().ok()).collect();
        for e in runs.iter().filter_map(|r| r.as_ref().err()) {
            eprintln!("{}: {e}", surface.name);
        }
        let of =
            |f: fn(&(Measured, Measured)) -> f64| -> Vec<f64> { ok.iter().map(|r| f(r)).collect() };
        let worst = |values: Vec<f64>| values.into_iter().fold(0.0, f64::max);
        let percent = |v: f64| format!("{:.3} %", 100.0 * v);
        let row = format!(
            "| {} | {} | {} | {} | {} | {:.2} / {:.2} | {} / {} | {:.0} / {:.0} | {} |",
            surface.name,
            percent(median(of(|r| r.0.0))),
            percent(median(of(|r| r.0.1))),
            percent(median(of(|r| r.1.0))),
            percent(median(of(|r| r.1.1))),
            worst(of(|r| r.1.0 / r.0.0)),
            worst(of(|r| r.1.1 / r.0.1)),
            percent(worst(of(|r| r.0.2))),
            percent(worst(of(|r| r.1.2))),
            median(of(|r| r.0.3 as f64)),
            median(of(|r| r.1.3 as f64)),
            runs.len() - ok.len()
        );
        println!("{row}");
        let _ = writeln!(table, "{row}");
    }
    if let Some(path) = option(&args, "--markdown") {
        let text = format!(
            "# Outliers\n\nWritten by `cargo bench -p neurosurf-trainer --bench outliers -- {}`: \
             seven surfaces sampled at {count} points with noise of σ = {} % of the diagonal, \
             and the same points with {OUTLIER_PERCENT} % outliers uniform in their bounding box \
             grown by 10 % per side, each rebuilt as `patch fit` and `patch tessellate` do \
             (outliers left out, a {RESOLUTION} × {RESOLUTION} Coons grid of the covered \
             region). Mesh → truth: RMS distance of the mesh's vertices from the true surface; \
             truth → mesh: RMS distance of the true surface within the samples' reach from the \
             mesh; both as % of the diagonal, median of {seeds} seeds. Worst ratio: the largest, \
             over the seeds, of the run with outliers over the clean run. Largest: the farthest \
             mesh vertex from the truth over the seeds, clean / with outliers (surface grown \
             away from the data). Left \
             out: the median count of points `fit` left out, of {count} and {} given.\n\n{table}",
            given(&args),
            100.0 * noise,
            count + count * OUTLIER_PERCENT / 100
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

//! Patches whose sampling density changes 10:1, reconstructed end to end (embedding, network,
//! both tessellations of §5.3) and measured both ways against the true surface:
//!
//! - **uncovered**: the share of the true surface (a dense grid of its parameters) farther than
//!   1 % of the diagonal from the mesh;
//! - **stray**: the share of the mesh's area farther than 1 % of the diagonal from the true
//!   surface;
//! - **folded**: triangles of the parameter-plane tessellation turned over (a folded Coons
//!   grid).
//!
//! Each surface is sampled at `--points` (2 000) points over `--seeds` (1–4); the worst seed
//! is reported.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench uneven_density`, with after `--`:
//! `--points 2000`, `--seeds 4`, `--markdown FILE` to write the table as well
//! (`docs/performance/uneven-density.md`).

mod arguments;
use arguments::{given, in_workspace, option};

use std::fmt::Write as _;

use neurosurf_trainer::io::Mesh;
use neurosurf_trainer::parametric::{
    PlanarMesh, ReconstructOptions, Tessellation, reconstruct, signed_area,
};
use neurosurf_trainer::quality::Truth;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// A distance larger than this share of the diagonal counts as uncovered or stray.
const TOLERANCE: f64 = 0.01;

/// A test surface: its position at true parameters in [0, 1]², whether a parameter point
/// belongs to it, and the relative sampling density there (the largest is 1).
struct Surface {
    name: &'static str,
    position: fn(f64, f64) -> [f64; 3],
    inside: fn(f64, f64) -> bool,
    density: fn(f64, f64) -> f64,
}

fn surfaces() -> Vec<Surface> {
    fn square(_: f64, _: f64) -> bool {
        true
    }
    vec![
        Surface {
            name: "saddle, one half 10× sparser",
            position: |s, t| {
                let (x, y) = (2.0 * s - 1.0, 2.0 * t - 1.0);
                [x, y, x * y]
            },
            inside: square,
            density: |s, _| if s < 0.5 { 1.0 } else { 0.1 },
        },
        Surface {
            name: "wavy patch thinned 10:1 across",
            position: |s, t| {
                let (x, y) = (2.0 * s - 1.0, 2.0 * t - 1.0);
                [x, y, 0.25 * (2.5 * x).sin() * (2.0 * y).cos()]
            },
            inside: square,
            density: |s, _| 0.1_f64.powf(s),
        },
        Surface {
            name: "open cylinder, 10× sparser beyond 180°",
            position: |s, t| {
                let a = 1.5 * std::f64::consts::PI * s;
                [a.cos(), a.sin(), 2.5 * t]
            },
            inside: square,
            density: |s, _| if s < 2.0 / 3.0 { 1.0 } else { 0.1 },
        },
        Surface {
            name: "paraboloid disc, one quadrant 10× sparser",
            position: |s, t| {
                let (x, y) = (2.0 * s - 1.0, 2.0 * t - 1.0);
                [x, y, 0.5 * (x * x + y * y)]
            },
            inside: |s, t| (2.0 * s - 1.0).powi(2) + (2.0 * t - 1.0).powi(2) <= 1.0,
            density: |s, t| if s > 0.5 && t > 0.5 { 0.1 } else { 1.0 },
        },
    ]
}

/// `count` points of `surface`, accepted with its density, and their true parameters.
fn sample(surface: &Surface, count: usize, seed: u64) -> (Vec<[f64; 3]>, Vec<[f64; 2]>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut points, mut parameters) = (Vec::with_capacity(count), Vec::with_capacity(count));
    while points.len() < count {
        let (s, t): (f64, f64) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
        if (surface.inside)(s, t) && rng.random_range(0.0..1.0) < (surface.density)(s, t) {
            points.push((surface.position)(s, t));
            parameters.push([s, t]);
        }
    }
    (points, parameters)
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(sorted.iter())
        } else {
            Box::new(sorted.iter().rev())
        };
        for &p in ordered {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

fn inside_convex(p: [f64; 2], hull: &[[f64; 2]]) -> bool {
    (0..hull.len()).all(|i| {
        let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= 0.0
    })
}

/// The true surface triangulated on a `side × side` grid of its parameters; cells with a
/// corner outside the surface, or outside `reach` when given, are left out.
fn truth(surface: &Surface, side: usize, reach: Option<&[[f64; 2]]>) -> Mesh {
    let at = |i: usize, j: usize| (i as f64 / side as f64, j as f64 / side as f64);
    let positions = (0..=side)
        .flat_map(|j| (0..=side).map(move |i| (i, j)))
        .map(|(i, j)| {
            let (s, t) = at(i, j);
            (surface.position)(s, t)
        })
        .collect();
    let index = |i: usize, j: usize| (j * (side + 1) + i) as u32;
    let mut triangles = Vec::new();
    for j in 0..side {
        for i in 0..side {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            if corners.iter().all(|&(i, j)| {
                let (s, t) = at(i, j);
                (surface.inside)(s, t) && reach.is_none_or(|hull| inside_convex([s, t], hull))
            }) {
                triangles.push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
                triangles.push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

/// Area-weighted samples of `mesh`: every triangle's centroid and its area.
fn area_samples(mesh: &Mesh) -> Vec<([f64; 3], f64)> {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            let centroid: [f64; 3] = std::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0);
            let e1: [f64; 3] = std::array::from_fn(|k| b[k] - a[k]);
            let e2: [f64; 3] = std::array::from_fn(|k| c[k] - a[k]);
            let cross = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            (
                centroid,
                0.5 * cross.iter().map(|x| x * x).sum::<f64>().sqrt(),
            )
        })
        .collect()
}

/// The share of `from`'s area farther than `tolerance` from `to`.
fn far_share(from: &Mesh, to: &Truth, tolerance: f64) -> f64 {
    let samples = area_samples(from);
    let total: f64 = samples.iter().map(|s| s.1).sum();
    let far: f64 = samples
        .par_iter()
        .filter(|s| to.distance(s.0) > tolerance)
        .map(|s| s.1)
        .sum();
    if total > 0.0 { far / total } else { 1.0 }
}

fn folded(grid: &PlanarMesh) -> usize {
    grid.triangles
        .iter()
        .filter(|t| signed_area(&t.map(|v| grid.vertices[v as usize])) <= 0.0)
        .count()
}

/// (uncovered, stray, folded) of one reconstruction, or the error.
fn measure(
    surface: &Surface,
    (points, parameters): (&[[f64; 3]], &[[f64; 2]]),
    tessellation: Tessellation,
    seed: u64,
) -> Result<(f64, f64, usize), String> {
    let mut options = ReconstructOptions {
        tessellation,
        ..ReconstructOptions::default()
    };
    options.topology.seed = seed;
    options.embedding.more_neighbors = true;
    let result = reconstruct(points, &options).map_err(|e| e.to_string())?;
    let true_surface = Truth::from_mesh(&truth(surface, 200, None)).map_err(|e| e.to_string())?;
    let reach = truth(surface, 200, Some(&convex_hull(parameters)));
    let tolerance = TOLERANCE * true_surface.diagonal();
    let mesh = &result.surface.mesh;
    let model = Truth::from_mesh(mesh).map_err(|e| e.to_string())?;
    Ok((
        far_share(&reach, &model, tolerance),
        far_share(mesh, &true_surface, tolerance),
        folded(&result.grid),
    ))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let count: usize = option(&args, "--points")
        .unwrap_or("2000")
        .parse()
        .expect("--points: a count");
    let seeds: u64 = option(&args, "--seeds")
        .unwrap_or("4")
        .parse()
        .expect("--seeds: a count");
    let mut table = String::from(
        "| surface | tessellation | uncovered | stray | folded triangles | failed seeds |\n\
         |---|---|---:|---:|---:|---:|\n",
    );
    for surface in surfaces() {
        for (label, tessellation) in [
            ("Coons 30 × 30", Tessellation::Coons { resolution: 30 }),
            ("Delaunay ~900", Tessellation::Delaunay { vertices: 900 }),
        ] {
            let results: Vec<Result<(f64, f64, usize), String>> = (1..=seeds)
                .map(|seed| {
                    let (points, parameters) = sample(&surface, count, seed);
                    measure(&surface, (&points, &parameters), tessellation, seed)
                })
                .collect();
            let ok: Vec<(f64, f64, usize)> =
                results.iter().filter_map(|r| r.clone().ok()).collect();
            for e in results.iter().filter_map(|r| r.as_ref().err()) {
                eprintln!("{}, {label}: {e}", surface.name);
            }
            let worst_uncovered = ok.iter().map(|r| r.0).fold(0.0, f64::max);
            let worst_stray = ok.iter().map(|r| r.1).fold(0.0, f64::max);
            let worst_folded = ok.iter().map(|r| r.2).max().unwrap_or(0);
            let row = format!(
                "| {} | {label} | {:.1} % | {:.1} % | {worst_folded} | {} |",
                surface.name,
                100.0 * worst_uncovered,
                100.0 * worst_stray,
                results.len() - ok.len()
            );
            println!("{row}");
            let _ = writeln!(table, "{row}");
        }
    }
    if let Some(path) = option(&args, "--markdown") {
        let text = format!(
            "# Uneven density\n\nWritten by `cargo bench -p neurosurf-trainer --bench \
             uneven_density -- {}`: patches sampled at {count} points whose density changes \
             10:1, reconstructed with the default options and both tessellations, worst of \
             {seeds} seeds. Uncovered: the share of the true surface farther than {} % of the \
             diagonal from the mesh; stray: the share of the mesh's area farther than that \
             from the true surface; folded: triangles of the parameter-plane tessellation \
             turned over.\n\n{table}",
            given(&args),
            100.0 * TOLERANCE
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

//! Patches whose sampling density changes 10:1, reconstructed end to end (embedding, network,
//! both tessellations of §5.3) and measured both ways against the true surface:
//!
//! - **uncovered**: the share of the true surface within the samples' reach (the convex hull
//!   of their true parameters, triangulated on a 200 × 200 grid) farther than 1 % of the
//!   diagonal from the mesh;
//! - **stray**: the share of the mesh's area farther than 1 % of the diagonal from the true
//!   surface;
//! - **folded**: triangles of the parameter-plane tessellation turned over (a folded Coons
//!   grid).
//!
//! Each surface is sampled at `--points` (2 000) points over `--seeds` (1–4); the worst seed
//! is reported.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench uneven_density`, with after `--`:
//! `--points 2000`, `--seeds 4`, `--surfaces WORD` for the surfaces whose name holds it,
//! `--markdown FILE` to write the table as well
//! (`docs/performance/uneven-density.md`), `--pictures DIR` to draw every mesh with its points
//! and every parameter-plane grid with the points' parameters (PNG).

mod arguments;
mod hull;
use arguments::{given, in_workspace, option, parsed};
use hull::{convex_hull, grid_mesh, inside_convex};

use std::fmt::Write as _;

use std::path::Path;

use neurosurf_trainer::io::Mesh;
use neurosurf_trainer::parametric::{
    Parameterization, PlanarMesh, ReconstructOptions, Tessellation, reconstruct, signed_area,
    wireframe,
};
use neurosurf_trainer::plot::write_picture;
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
    fn saddle(s: f64, t: f64) -> [f64; 3] {
        let (x, y) = (2.0 * s - 1.0, 2.0 * t - 1.0);
        [x, y, x * y]
    }
    vec![
        Surface {
            name: "saddle, one half 10× sparser",
            position: saddle,
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
            name: "C-shaped sheet, one arm 10× sparser",
            position: |s, t| {
                let (a, r) = (1.5 * std::f64::consts::PI * s, 0.5 + 0.5 * t);
                [r * a.cos(), r * a.sin(), 0.3 * r * r]
            },
            inside: square,
            density: |s, _| if s > 0.6 { 0.1 } else { 1.0 },
        },
        Surface {
            name: "saddle, even (control)",
            position: saddle,
            inside: square,
            density: |_, _| 1.0,
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

/// The true surface triangulated on a `side × side` grid of its parameters; cells with a
/// corner outside the surface, or outside `reach` when given, are left out.
fn truth(surface: &Surface, side: usize, reach: Option<&[[f64; 2]]>) -> Mesh {
    grid_mesh(
        side,
        [[0.0, 1.0], [0.0, 1.0]],
        surface.position,
        |[s, t]| (surface.inside)(s, t) && reach.is_none_or(|hull| inside_convex([s, t], hull)),
    )
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

/// A point of the parameter plane placed in space so that [`wireframe`]'s oblique view shows
/// the plane from straight above.
fn seen_from_above(p: &[f64; 2]) -> [f64; 3] {
    let (turn, tilt) = (30f64.to_radians(), 55f64.to_radians());
    let (x, y) = (p[0], p[1] * tilt.cos());
    [
        x * turn.cos() + y * turn.sin(),
        -x * turn.sin() + y * turn.cos(),
        p[1] * tilt.sin(),
    ]
}

fn folded(grid: &PlanarMesh) -> usize {
    grid.triangles
        .iter()
        .filter(|t| signed_area(&t.map(|v| grid.vertices[v as usize])) <= 0.0)
        .count()
}

/// One reconstruction measured, or the error.
fn measure(
    surface: &Surface,
    (points, parameters): (&[[f64; 3]], &[[f64; 2]]),
    tessellation: Tessellation,
    seed: u64,
    pictures: Option<&str>,
) -> Result<Outcome, String> {
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
    if let Some(dir) = pictures {
        let name = format!(
            "{dir}/{}-{}-{seed}",
            surface.name.split([',', ' ']).next().unwrap_or("surface"),
            match tessellation {
                Tessellation::Coons { .. } => "coons",
                Tessellation::Delaunay { .. } => "delaunay",
            }
        );
        let flat = Mesh {
            positions: result.grid.vertices.iter().map(seen_from_above).collect(),
            triangles: result.grid.triangles.clone(),
        };
        let uv: Vec<[f64; 3]> = result
            .embedding
            .parameters
            .iter()
            .map(seen_from_above)
            .collect();
        for (suffix, scene) in [
            ("", wireframe(mesh, points, 640)),
            ("-parameters", wireframe(&flat, &uv, 640)),
        ] {
            write_picture(Path::new(&format!("{name}{suffix}.png")), &scene)
                .map_err(|e| e.to_string())?;
        }
    }
    let model = Truth::from_mesh(mesh).map_err(|e| e.to_string())?;
    Ok(Outcome {
        uncovered: far_share(&reach, &model, tolerance),
        stray: far_share(mesh, &true_surface, tolerance),
        folded: folded(&result.grid),
        unrolled: result.embedding.parameterization == Parameterization::Unrolled,
    })
}

/// One reconstruction measured.
#[derive(Clone)]
struct Outcome {
    uncovered: f64,
    stray: f64,
    folded: usize,
    unrolled: bool,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let count: usize = parsed(&args, "--points", "2000", "a count");
    let seeds: u64 = parsed(&args, "--seeds", "4", "a count");
    let pictures = option(&args, "--pictures");
    let only = option(&args, "--surfaces").unwrap_or("");
    let mut table = String::from(
        "| surface | tessellation | uncovered | stray | folded triangles | seeds unrolled | failed \
         seeds |\n|---|---|---:|---:|---:|---:|---:|\n",
    );
    for surface in surfaces().into_iter().filter(|s| s.name.contains(only)) {
        for (label, tessellation) in [
            ("Coons 30 × 30", Tessellation::Coons { resolution: 30 }),
            ("Delaunay ~900", Tessellation::Delaunay { vertices: 900 }),
        ] {
            let results: Vec<Result<Outcome, String>> = (1..=seeds)
                .map(|seed| {
                    let (points, parameters) = sample(&surface, count, seed);
                    measure(
                        &surface,
                        (&points, &parameters),
                        tessellation,
                        seed,
                        pictures,
                    )
                })
                .collect();
            let ok: Vec<Outcome> = results.iter().filter_map(|r| r.clone().ok()).collect();
            for e in results.iter().filter_map(|r| r.as_ref().err()) {
                eprintln!("{}, {label}: {e}", surface.name);
            }
            let worst = |f: fn(&Outcome) -> f64| ok.iter().map(f).fold(0.0, f64::max);
            let row = format!(
                "| {} | {label} | {:.1} % | {:.1} % | {} | {} | {} |",
                surface.name,
                100.0 * worst(|o| o.uncovered),
                100.0 * worst(|o| o.stray),
                ok.iter().map(|o| o.folded).max().unwrap_or(0),
                ok.iter().filter(|o| o.unrolled).count(),
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
             {seeds} seeds. Uncovered: the share of the true surface within the samples' reach \
             (the convex hull of their true parameters) farther than {} % of the diagonal \
             from the mesh; stray: the share of the mesh's area farther than that \
             from the true surface; folded: triangles of the parameter-plane tessellation \
             turned over; seeds unrolled: how many seeds' patches were unrolled rather than \
             embedded by LLE (their sampling density changes).\n\n{table}",
            given(&args),
            100.0 * TOLERANCE
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

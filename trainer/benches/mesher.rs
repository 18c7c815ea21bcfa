//! Our mesher against a well-kept crate, on the same sampled grids.
//!
//! `render::extract_mesh` (marching tetrahedra over the blocks of 8³ cells that meet the leaf
//! boxes) against `fast-surface-nets` 0.2 (Naive Surface Nets on a whole regular grid), on
//! the demo's torus (96 points, one leaf) and 3-feature head (99 points, tree ((0,1),2)),
//! seed 1, through the core in f32, at 64 and 128 cells along the longest side of the boxes.
//! Both get the same grid (`MeshGrid`: same origin, cell and values — Φ inside a box, −1
//! outside); the crate's grid is sampled whole (z-slabs in parallel), then meshed, and its
//! vertex normals come from ∇Φ through the core as ours do. Measured per mesh:
//! - time: median of 3 on the rayon pool (both cores here), and the crate's meshing alone;
//! - Φ evaluations of the grid, triangles;
//! - watertightness (`Mesh::edge_report`): edges not shared by exactly two triangles (open or
//!   non-manifold), edges two triangles run along the same way (inconsistent winding), the
//!   Euler characteristic V − E + F (torus 0, head 2), triangles facing inward (geometric
//!   normal against −∇Φ), thin triangles (smallest angle under 5°);
//! - accuracy: the trainer's f64 network at every vertex: max |Φ|, and the distance
//!   |Φ|/|∇Φ| in cells h (median, max).
//!
//! Ratios are against our mesher in the same run.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench mesher`.

use std::time::Instant;

use fast_surface_nets::ndshape::RuntimeShape;
use fast_surface_nets::{SurfaceNetsBuffer, surface_nets};
use nalgebra::Vector3;
use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::fidelity::median;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions, Trained, TreeSpec};
use neurosurf_trainer::io::Mesh;
use neurosurf_trainer::render::{
    CoreField, DEFAULT_BOX_SIZE, DEFAULT_INFLATE, Field, MeshGrid, Region, extract_mesh,
};
use neurosurf_trainer::sample::{Shape, sample_shape};
use rayon::prelude::*;

/// One mesh and how it was made.
struct Made {
    mesh: Mesh,
    seconds: f64,
    /// The crate's meshing alone (no sampling, no normals); `None` for ours.
    meshing_seconds: Option<f64>,
    evaluations: u64,
}

/// What a mesh is like.
struct Quality {
    triangles: usize,
    bad_edges: usize,
    same_way: usize,
    euler: i64,
    inward: usize,
    thin: usize,
    max_phi: f64,
    median_distance: f64,
    max_distance: f64,
}

fn main() {
    let torus = train(
        &Shape::Torus {
            major: 1.0,
            minor: 0.4,
        },
        96,
        None,
    );
    let head = train(&Shape::Head, 99, Some("((0,1),2)"));
    println!(
        "threads: {}; times: median of 3; ratios: fast-surface-nets / ours (same run)",
        rayon::current_num_threads()
    );
    println!();
    println!(
        "| model, cells | mesher | time ms | time vs ours | Φ evaluations | triangles | \
         triangles vs ours | edges not shared by 2 | edges wound the same way | χ | inward | thin < 5° | max \\|Φ\\| | \
         median dist / h | max dist / h | max dist vs ours |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, trained) in [("torus", &torus), ("head", &head)] {
        let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
        let regions = Region::of_network(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
        let core = CoreField::new(&blob, regions).expect("core field");
        for resolution in [64, 128] {
            let grid = MeshGrid::new(&core, resolution).expect("grid");
            let ours = best_of_3(|| {
                let m = extract_mesh(&core, resolution, &|_, _| {}).expect("mesh");
                Made {
                    mesh: m.mesh,
                    seconds: m.stats.seconds,
                    meshing_seconds: None,
                    evaluations: m.stats.evaluations,
                }
            });
            let theirs = best_of_3(|| surface_nets_mesh(&core, &grid));
            let base = quality(&ours.mesh, trained, &core, grid.cell);
            for (mesher, made) in [("ours", &ours), ("fast-surface-nets", &theirs)] {
                let q = quality(&made.mesh, trained, &core, grid.cell);
                let time = match made.meshing_seconds {
                    Some(m) => format!("{:.1} (meshing {:.1})", made.seconds * 1e3, m * 1e3),
                    None => format!("{:.1}", made.seconds * 1e3),
                };
                println!(
                    "| {name}, {resolution} | {mesher} | {time} | {:.2}× | {} | {} | {:.2}× | {} \
                     | {} | {} | {} | {:.1} % | {:.1e} | {:.4} | {:.3} | {:.2}× |",
                    made.seconds / ours.seconds,
                    made.evaluations,
                    q.triangles,
                    q.triangles as f64 / base.triangles as f64,
                    q.bad_edges,
                    q.same_way,
                    q.euler,
                    q.inward,
                    100.0 * q.thin as f64 / q.triangles as f64,
                    q.max_phi,
                    q.median_distance,
                    q.max_distance,
                    q.max_distance / base.max_distance,
                );
            }
        }
    }
}

/// The demo's model: `count` points of `shape`, seed 1.
fn train(shape: &Shape, count: usize, tree: Option<&str>) -> Trained {
    let points = sample_shape(shape, count, 1).expect("samples");
    let request = FitRequest {
        tree: tree.map(|t| t.parse::<TreeSpec>().expect("tree")),
        ..FitRequest::default()
    };
    implicit::fit(points, &request, &ImplicitOptions::default(), &|_| {}).expect("training")
}

/// Runs `make` 3 times; the run of median time.
fn best_of_3(make: impl Fn() -> Made) -> Made {
    let mut runs: Vec<Made> = (0..3).map(|_| make()).collect();
    runs.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    runs.swap_remove(1)
}

/// The crate on the whole grid: sample it (z-slabs in parallel, the values our mesher
/// marches over), mesh it, move the vertices to world coordinates.
fn surface_nets_mesh(field: &CoreField, grid: &MeshGrid) -> Made {
    let start = Instant::now();
    let [nx, ny, nz] = grid.cells;
    let slabs: Vec<(Vec<f64>, u64)> = (0..=nz)
        .into_par_iter()
        .map(|z| grid.sample(field, [0, 0, z], [nx, ny, z]))
        .collect();
    let evaluations = slabs.iter().map(|s| s.1).sum();
    // The crate's distances are negative inside; Φ is positive inside.
    let sdf: Vec<f32> = slabs
        .iter()
        .flat_map(|s| s.0.iter().map(|&v| -v as f32))
        .collect();
    let shape = RuntimeShape::<u32, 3>::new([nx, ny, nz].map(|n| n as u32 + 1));
    let meshing = Instant::now();
    let mut buffer = SurfaceNetsBuffer::default();
    surface_nets(
        &sdf,
        &shape,
        [0; 3],
        [nx, ny, nz].map(|n| n as u32),
        &mut buffer,
    );
    let meshing_seconds = meshing.elapsed().as_secs_f64();
    let positions: Vec<[f64; 3]> = buffer
        .positions
        .iter()
        .map(|p| [0, 1, 2].map(|k| grid.origin[k] + grid.cell * f64::from(p[k])))
        .collect();
    // Normals from ∇Φ, as ours (only the cost matters here: the mesh keeps none).
    let mut gradients = vec![(0.0, [0.0; 3]); positions.len()];
    field.value_gradients(&positions, &mut gradients);
    std::hint::black_box(&gradients);
    let triangles = buffer
        .indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    Made {
        mesh: Mesh {
            positions,
            triangles,
        },
        seconds: start.elapsed().as_secs_f64(),
        meshing_seconds: Some(meshing_seconds),
        evaluations,
    }
}

fn quality(mesh: &Mesh, trained: &Trained, field: &CoreField, cell: f64) -> Quality {
    let v = |i: u32| Vector3::from(mesh.positions[i as usize]);
    let mut inward = 0;
    let mut thin = 0;
    for t in &mesh.triangles {
        let [p, q, r] = t.map(v);
        let normal = (q - p).cross(&(r - p));
        let centroid: [f64; 3] = ((p + q + r) / 3.0).into();
        // Φ > 0 inside: the outward normal is −∇Φ.
        let (_, gradient) = field.value_gradient(centroid);
        if normal.dot(&Vector3::from(gradient)) > 0.0 {
            inward += 1;
        }
        let smallest = [(p, q, r), (q, r, p), (r, p, q)]
            .map(|(a, b, c)| (b - a).angle(&(c - a)).to_degrees())
            .into_iter()
            .fold(f64::INFINITY, f64::min);
        if smallest.is_nan() || smallest < 5.0 {
            thin += 1;
        }
    }
    let edges = mesh.edge_report();
    let mut distances = Vec::with_capacity(mesh.positions.len());
    let mut max_phi: f64 = 0.0;
    for &p in &mesh.positions {
        let (phi, g) = trained.network.eval(p);
        max_phi = max_phi.max(phi.abs());
        distances.push(phi.abs() / Vector3::from(g).norm() / cell);
    }
    let max_distance = distances.iter().copied().fold(0.0, f64::max);
    Quality {
        triangles: mesh.triangles.len(),
        bad_edges: edges.not_shared_by_two,
        same_way: edges.same_way,
        euler: edges.euler_characteristic,
        inward,
        thin,
        max_phi,
        median_distance: median(&mut distances),
        max_distance,
    }
}

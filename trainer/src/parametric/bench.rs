//! The timing benchmark of Table 2: embedding and fitting time against the number of points,
//! on a patch of the Stanford bunny.
//!
//! The scan is closed except for holes at the bottom and cannot be flattened whole, so the
//! points come from one patch on the bunny's back: the [`PATCH_VERTICES`] vertices nearest
//! (Euclidean) to the seed vertex [`BACK_SEED`]. A row of n ≤ [`PATCH_VERTICES`] points uses
//! the n vertices nearest to the seed. A larger n (the 35 947 of the whole scan) cannot take
//! more of the scan's vertices without reaching round the body, so it densifies the patch: its
//! vertices plus every edge's midpoint (one 1-to-4 subdivision, about 40 000 points on the
//! scan's own triangles), the n nearest to the seed. Uniform random samples on the triangles
//! were tried first and do not embed: random points come arbitrarily close to each other, and
//! 32 % of them collapse in the k = 10 embedding (also at k = 15, 20 and 30: 13–15 %).

use std::time::Instant;

use super::embedding::{LleOptions, embed_points};
use super::fit::fit_network;
use super::topology::TopologyOptions;
use crate::error::{Error, Result};
use crate::io::Mesh;

/// Point counts of the benchmark (Table 2's plus the bunny's vertex count).
pub const BENCHMARK_SIZES: [usize; 4] = [100, 1_000, 10_000, 35_947];
/// Vertices of the back patch.
pub const PATCH_VERTICES: usize = 10_000;
/// The seed vertex on the bunny's back (`stanford-bunny.obj` indexing): 12 676, the rearmost
/// vertex (largest x). Its 10 000-vertex patch embeds with 0.1 % flipped neighbour pairs; the
/// extreme vertices in the other five axis directions (ears, face, feet) give patches that
/// fold.
pub const BACK_SEED: u32 = 12_676;

/// One size.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct BenchmarkRow {
    /// Points embedded and fitted.
    pub points: usize,
    /// `"vertices"` or `"subdivided"` (see the module docs).
    pub source: &'static str,
    /// LLE time (s).
    pub embedding_seconds: f64,
    /// Topology search and training time (s).
    pub fitting_seconds: f64,
    /// Of that, the §5.2 search (s).
    pub search_seconds: f64,
    /// Of that, the final refinement on all training points (s).
    pub refinement_seconds: f64,
    /// Accepted LM steps of the search, summed over the configurations' kept starts.
    pub search_steps: usize,
    /// LM trial steps (accepted or not) of the same runs: each a solve and a training pass.
    pub search_trials: usize,
    /// Eigen-solver iterations.
    pub eigen_iterations: usize,
    /// Chosen hidden layers.
    pub layers: usize,
    /// Chosen neurons per layer.
    pub neurons: usize,
    /// RMS fitting error over the bounding-box diagonal.
    pub relative_rms_error: f64,
}

/// `count` points of the bunny's back patch around vertex `seed` (see the module docs).
///
/// # Errors
/// [`Error::InvalidInput`] when the mesh has fewer than [`PATCH_VERTICES`] vertices, `seed`
/// is out of range, or the subdivided patch has fewer than `count` points.
pub fn back_patch_points(
    mesh: &Mesh,
    seed: u32,
    count: usize,
) -> Result<(Vec<[f64; 3]>, &'static str)> {
    let n = mesh.positions.len();
    if (seed as usize) >= n || n < PATCH_VERTICES {
        return Err(Error::invalid(format!(
            "the benchmark needs a mesh of at least {PATCH_VERTICES} vertices and a seed below {n}"
        )));
    }
    let s = mesh.positions[seed as usize];
    let d2 = |p: &[f64; 3]| (p[0] - s[0]).powi(2) + (p[1] - s[1]).powi(2) + (p[2] - s[2]).powi(2);
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| d2(&mesh.positions[a]).total_cmp(&d2(&mesh.positions[b])));
    if count <= PATCH_VERTICES {
        return Ok((
            order[..count].iter().map(|&i| mesh.positions[i]).collect(),
            "vertices",
        ));
    }
    // Denser than the patch's vertices: add the midpoint of every edge of the triangles
    // inside the patch (one 1-to-4 subdivision, about 40 000 points on the scan's own surface), then keep the
    // `count` nearest to the seed.
    let mut inside = vec![false; n];
    for &i in &order[..PATCH_VERTICES] {
        inside[i] = true;
    }
    let mut points: Vec<[f64; 3]> = order[..PATCH_VERTICES]
        .iter()
        .map(|&i| mesh.positions[i])
        .collect();
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .filter(|t| t.iter().all(|&v| inside[v as usize]))
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    points.extend(edges.iter().map(|&(a, b)| {
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        std::array::from_fn(|c| 0.5 * (p[c] + q[c]))
    }));
    if points.len() < count {
        return Err(Error::invalid(format!(
            "the subdivided patch has {} points, fewer than the {count} asked for",
            points.len()
        )));
    }
    points.sort_by(|a, b| d2(a).total_cmp(&d2(b)));
    points.truncate(count);
    Ok((points, "subdivided"))
}

/// Times embedding and fitting for each size.
///
/// # Errors
/// Any error of [`back_patch_points`], [`embed_points`] or [`fit_network`].
pub fn benchmark(
    mesh: &Mesh,
    seed: u32,
    sizes: &[usize],
    embedding: &LleOptions,
    topology: &TopologyOptions,
) -> Result<Vec<BenchmarkRow>> {
    let mut rows = Vec::new();
    for &size in sizes {
        let (points, source) = back_patch_points(mesh, seed, size)?;
        let start = Instant::now();
        let lle = embed_points(&points, embedding)?;
        let embedding_seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let fit = fit_network(&points, &lle.parameters, topology)?;
        let fitting_seconds = start.elapsed().as_secs_f64();
        let best = fit.search.best();
        rows.push(BenchmarkRow {
            points: size,
            source,
            embedding_seconds,
            fitting_seconds,
            search_seconds: fit.search_seconds,
            refinement_seconds: fit.refinement_seconds,
            search_steps: fit.search.candidates.iter().map(|c| c.iterations).sum(),
            search_trials: fit.search.candidates.iter().map(|c| c.trials).sum(),
            eigen_iterations: lle.iterations,
            layers: best.layers,
            neurons: best.neurons,
            relative_rms_error: fit.relative_rms_error,
        });
    }
    Ok(rows)
}

//! The parameterization of a patch whose sampling density changes: the patch unrolled by
//! landmark MDS of path lengths along it (Isomap; de Silva & Tenenbaum 2004), then smoothed by
//! the LLE matrix.
//!
//! LLE squeezes a region sampled ten times more sparsely than the rest: its constraint counts
//! points, not area, so the sparse region costs little wherever it goes, and the tessellation
//! then spreads the dense region's share of the grid over it. Path lengths through the
//! neighbourhoods measure the surface itself, so the unrolled patch keeps its proportions,
//! but they run along graph edges and come out jagged from point to point, which a network
//! cannot fit smoothly. The smoothing solves (M + μ·I)·u = μ·u₀ for both coordinates, M =
//! (I − W)ᵀ(I − W) the LLE matrix and u₀ the unrolled coordinates, μ = [`SMOOTHING_ANCHOR`]
//! of M's mean diagonal entry: detail finer than a few neighbourhoods follows the local linear
//! reconstructions, the layout follows the path lengths.
//!
//! [`sparse_area_share`] decides when: LLE stays the parameterization of evenly sampled
//! patches (the paper's), this one takes over where at least [`UNEVEN_AREA_SHARE`] of the
//! patch's area is sampled at more than twice the typical spacing. Measured on four patches
//! with a 10:1 density change (`trainer/benches/uneven_density.rs`): a saddle's uncovered
//! surface drops from 5.1–5.3 % to 1.0 %. Isometric unrolling bends a patch whose parameter
//! region is far from convex (a 'C' of a sheet), which is why it is not the default for
//! every patch.

use super::sparse::SymmetricMatrix;
use crate::curve::{list_both_ways, unroll_graph};
use crate::error::{Error, Result};
use crate::geometry::vector::{norm, sub};

/// Landmarks of the unrolling.
pub const UNROLL_LANDMARKS: usize = 48;
/// μ as a share of M's mean diagonal entry: 0.02 left the sparse half of a saddle jagged
/// enough to fit 2–3 times worse than its dense half, 0.001 let LLE's squeeze back in.
pub const SMOOTHING_ANCHOR: f64 = 0.005;
/// The share of a patch's area, sampled at more than twice the median spacing, from which
/// its parameterization is unrolled instead of LLE's. An evenly sampled patch has none: its
/// rim points, with half a neighbourhood, reach about 1.4 times the median.
pub const UNEVEN_AREA_SHARE: f64 = 0.1;

/// Every point's spacing: the mean distance to its neighbours, averaged once more over the
/// neighbourhood so that the random spread of an even sample barely shows.
pub fn local_spacing(points: &[[f64; 3]], neighbors: &[Vec<usize>]) -> Vec<f64> {
    let raw: Vec<f64> = neighbors
        .iter()
        .enumerate()
        .map(|(i, list)| {
            list.iter()
                .map(|&j| distance(points[i], points[j]))
                .sum::<f64>()
                / list.len().max(1) as f64
        })
        .collect();
    neighbors
        .iter()
        .enumerate()
        .map(|(i, list)| {
            (raw[i] + list.iter().map(|&j| raw[j]).sum::<f64>()) / (list.len() + 1) as f64
        })
        .collect()
}

/// The share of the patch's area (each point standing for its spacing squared) sampled at
/// more than twice the median spacing.
pub fn sparse_area_share(points: &[[f64; 3]], neighbors: &[Vec<usize>]) -> f64 {
    let spacing = local_spacing(points, neighbors);
    let mut sorted = spacing.clone();
    sorted.sort_by(f64::total_cmp);
    let Some(&median) = sorted.get(sorted.len() / 2) else {
        return 0.0;
    };
    let total: f64 = spacing.iter().map(|h| h * h).sum();
    let sparse: f64 = spacing
        .iter()
        .filter(|&&h| h > 2.0 * median)
        .map(|h| h * h)
        .sum();
    if total > 0.0 { sparse / total } else { 0.0 }
}

/// The points unrolled along the surface: landmark MDS of path lengths through their
/// neighbourhoods (Isomap), which keeps a sparsely sampled region's area where LLE squeezes
/// it, then smoothed by `m`, the LLE matrix of the same neighbourhoods, by solving
/// (M + μ·I)·u = μ·u₀ (μ = [`SMOOTHING_ANCHOR`] of M's mean diagonal), so that the jagged
/// path lengths give a parameterization a network can fit. Each coordinate comes with mean 0
/// and variance 1, and with its LLE cost uᵀMu / uᵀu.
///
/// # Errors
/// [`Error::InvalidInput`] when the neighbourhoods fall apart in pieces or unroll onto a
/// line, or when the smoothing system cannot be factored.
pub fn unrolled_parameters(
    points: &[[f64; 3]],
    neighbors: &[Vec<usize>],
    m: &SymmetricMatrix,
) -> Result<(Vec<[f64; 2]>, [f64; 2])> {
    let mut graph: Vec<Vec<(usize, f64)>> = neighbors
        .iter()
        .enumerate()
        .map(|(i, list)| {
            list.iter()
                .map(|&j| (j, distance(points[i], points[j])))
                .collect()
        })
        .collect();
    list_both_ways(&mut graph);
    let start = unroll_graph(&graph, UNROLL_LANDMARKS).ok_or_else(|| {
        Error::invalid(
            "the points cannot be unrolled: their neighbourhoods fall apart in pieces or \
             span a line",
        )
    })?;
    let n = points.len();
    let mu = SMOOTHING_ANCHOR * m.trace() / n as f64;
    let matrix = m.compress()?;
    let factor = matrix
        .with_diagonal_added(mu)
        .ok_or_else(|| Error::invalid("the embedding matrix lacks a diagonal entry"))?
        .cholesky()?;
    let mut columns: Vec<Vec<f64>> = (0..2)
        .map(|a| start.iter().map(|p| mu * p[a]).collect())
        .collect();
    factor.solve(&mut columns);
    let mut costs = [0.0; 2];
    for (column, cost) in columns.iter_mut().zip(&mut costs) {
        let mean = column.iter().sum::<f64>() / n as f64;
        column.iter_mut().for_each(|v| *v -= mean);
        let deviation = (column.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        if !(deviation.is_finite() && deviation > 0.0) {
            return Err(Error::invalid("the unrolled points collapse onto a line"));
        }
        column.iter_mut().for_each(|v| *v /= deviation);
        let mut product = vec![0.0; n];
        matrix.multiply(column, &mut product);
        *cost = column.iter().zip(&product).map(|(a, b)| a * b).sum::<f64>() / n as f64;
    }
    Ok((
        (0..n).map(|i| [columns[0][i], columns[1][i]]).collect(),
        costs,
    ))
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(sub(a, b))
}

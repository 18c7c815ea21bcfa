//! Fitting: the Hermite-style constraints of an oriented point set, one dense solve in the
//! data's unit-diagonal frame, and the checks and measurements reported with the model.

use std::time::Instant;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::points::PointSet;

use super::condition::symmetric_inverse_norm1;
use super::kernel::multiquadric;
use super::model::RbfModel;
use super::options::{MAX_HALVINGS, MAX_POINTS, MIN_POINTS, RbfKernel, RbfOptions};
use super::solve::SaddleSolver;

/// Two centres closer than this fraction of the control points' bounding diagonal are
/// rejected as duplicates before the solve.
pub const DUPLICATE_TOLERANCE: f64 = 1e-9;

/// A fit whose largest constraint residual exceeds this fraction of the smallest off-surface
/// target s·min εᵢ is rejected as numerically singular. Well-posed fits stay 10⁴–10⁶ times
/// below the limit (the 1 500-point bunny: 7·10⁻¹³ against 3·10⁻⁹).
pub const RESIDUAL_TOLERANCE: f64 = 1e-6;

/// What a fit measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RbfReport {
    /// Control points n.
    pub points: usize,
    /// Unknowns of the linear system, 3n + 4 (one weight per centre, four for a·x + b).
    pub unknowns: usize,
    /// The radial function.
    pub kernel: RbfKernel,
    /// The control points' bounding diagonal D, the unit of every relative setting.
    pub diagonal: f64,
    /// The multiquadric c² in the data's units ((c/D · D)²; 0 for the biharmonic kernel).
    pub c2: f64,
    /// The starting offset ε₀ of the off-surface points, in the data's units.
    pub epsilon: f64,
    /// Off-surface points (of 2n) whose offset had to be halved at least once, because
    /// another control point was nearer than their own.
    pub halved: usize,
    /// The smallest offset used, in the data's units (ε₀ when nothing was halved).
    pub min_epsilon: f64,
    /// Wall-clock seconds of the whole fit: offsets, assembly, factorization, solve,
    /// condition estimate and residual check.
    pub seconds: f64,
    /// Of which the Cholesky factorization (on every thread of the current rayon pool).
    pub factorization_seconds: f64,
    /// Estimated 1-norm condition number κ₁(M) = ‖M‖₁·‖M⁻¹‖₁ of the (3n + 4)² saddle-point
    /// matrix as assembled and factored (centres in the unit-diagonal frame, polynomial block
    /// centroid-relative): ‖M‖₁ exact, ‖M⁻¹‖₁ by Hager–Higham from the factorization — a lower
    /// bound, usually within a factor of 3. About κ₁·10⁻¹⁶ relative error in the weights (the
    /// residuals below stay far smaller).
    pub condition_estimate: f64,
    /// Largest |f(cᵢ) − dᵢ| over the 3n interpolation constraints (0 on the control points,
    /// ∓s·εᵢ on the off-surface points), evaluated with the final model in the data's units.
    /// The polynomial orthogonality conditions Σwᵢ = Σwᵢcᵢ = 0 hold by construction of the
    /// solve.
    pub max_residual: f64,
}

/// Fits the RBF baseline (by default Carcenac's multiquadric) to oriented control points.
///
/// Centres are the n control points xᵢ (constraint f = 0) and, Hermite-style on both sides
/// (Carr et al. 2001), n outside points xᵢ + εᵢ⁺nᵢ (f = −s·εᵢ⁺) and n inside points
/// xᵢ − εᵢ⁻nᵢ (f = +s·εᵢ⁻), so f > 0 inside, f < 0 outside and ∇f ≈ −s·n on the surface, as for
/// the implicit network. Each offset starts at ε₀ = `epsilon_relative`·D (D: the control
/// points' bounding diagonal) and is halved, at most [`MAX_HALVINGS`] times, until the offset
/// point's nearest control point is its own (a k-d tree query per try). With the side
/// conditions Σwᵢ = 0, Σwᵢcᵢ = 0 the (3n + 4)-unknown system has a unique solution for
/// distinct, non-coplanar centres. Normals are rescaled to unit length.
///
/// The system is assembled and solved in the unit-diagonal frame x̂ = (x − o)/D (o: the
/// bounding box's centre), with c/D = `c_relative`, and mapped back exactly
/// (f(x) = D·f̂(x̂)): every length is relative to D, so scaled or moved data give the same
/// surface, scaled or moved, and the same conditioning. The solve is the null-space method
/// of `solve.rs`: one Cholesky factorization of order 3n − 4 (9n³ flops) by faer, on every
/// thread of the current rayon pool.
///
/// Cost (see [`MAX_POINTS`]): 1 500 points (4 504 unknowns) take 1–2 s in release on this
/// project's 2-core machine; time grows as n³ and memory as 72·n² bytes (one 3n×3n matrix).
///
/// Nearly coincident points are accepted as long as the interpolation still holds; the
/// residual check rejects the fit otherwise. The condition estimate is reported, never used to
/// reject.
///
/// # Errors
/// [`Error::InvalidInput`] for invalid options, fewer than [`MIN_POINTS`] or more than
/// [`MAX_POINTS`] points, positions and normals of different lengths, non-finite or
/// zero-length inputs, points spanning no volume, two centres within
/// [`DUPLICATE_TOLERANCE`]·D of each other, all centres coplanar, and a numerically singular
/// system (failed factorization, non-finite solution, or a residual above
/// [`RESIDUAL_TOLERANCE`]·s·min εᵢ).
pub fn fit(points: &PointSet, options: &RbfOptions) -> Result<(RbfModel, RbfReport)> {
    let start = Instant::now();
    options.check()?;
    let n = points.len();
    if n < MIN_POINTS {
        return Err(Error::invalid(format!(
            "the RBF fit needs at least {MIN_POINTS} control points, got {n}"
        )));
    }
    if n > MAX_POINTS {
        return Err(Error::invalid(format!(
            "the RBF fit takes at most {MAX_POINTS} control points, got {n}: its dense \
             system of {} unknowns would need {:.1} GB and minutes to factor",
            3 * n + 4,
            (9 * n * n * 8) as f64 / 1e9
        )));
    }
    let normals = unit_normals(points)?;
    let positions = &points.positions;
    let (center, diagonal) = frame(positions)?;
    check_distinct(positions, diagonal, n)?;
    let epsilon = options.epsilon_relative * diagonal;
    let offsets = Offsets::new(positions, &normals, epsilon)?;
    let slope = options.slope;
    let mut centers = positions.clone();
    let mut targets = vec![0.0; n];
    for (side, sign) in [(&offsets.outside, 1.0), (&offsets.inside, -1.0)] {
        for ((p, normal), &e) in positions.iter().zip(&normals).zip(side) {
            centers.push([0, 1, 2].map(|k| p[k] + sign * e * normal[k]));
            targets.push(-sign * slope * e);
        }
    }
    check_distinct(&centers, diagonal, n)?;

    // The unit-diagonal frame.
    let m = centers.len();
    let unit: Vec<[f64; 3]> = centers
        .iter()
        .map(|c| [0, 1, 2].map(|k| (c[k] - center[k]) / diagonal))
        .collect();
    let centroid = centroid(&unit);
    let rows: Vec<[f64; 4]> = unit
        .iter()
        .map(|c| {
            [
                c[0] - centroid[0],
                c[1] - centroid[1],
                c[2] - centroid[2],
                1.0,
            ]
        })
        .collect();
    let shape = options.shape();
    let c2_unit = shape * shape;
    let mut kernel = vec![0.0; m * m];
    kernel
        .par_chunks_mut(m)
        .enumerate()
        .for_each(|(j, column)| {
            let b = unit[j];
            for (v, a) in column.iter_mut().zip(&unit) {
                *v = multiquadric([a[0] - b[0], a[1] - b[1], a[2] - b[2]], c2_unit);
            }
        });
    let factor_start = Instant::now();
    let solver = SaddleSolver::new(kernel, &rows)?;
    let factorization_seconds = factor_start.elapsed().as_secs_f64();
    let unit_targets: Vec<f64> = targets.iter().map(|t| t / diagonal).collect();
    let (weights, poly) = solver.solve(&unit_targets, [0.0; 4]);
    if weights.iter().chain(&poly).any(|v| !v.is_finite()) {
        return Err(singular("its solution is not finite"));
    }
    // f(x) = D·f̂((x − o)/D) = Σ ŵᵢ √(|x − cᵢ|² + (cD)²) + â·(x − o − D·ḡ) + D·p̂₀.
    let linear = [poly[0], poly[1], poly[2]];
    let origin: [f64; 3] = [0, 1, 2].map(|k| center[k] + diagonal * centroid[k]);
    let constant =
        diagonal * poly[3] - linear[0] * origin[0] - linear[1] * origin[1] - linear[2] * origin[2];
    let c = shape * diagonal;
    let model = RbfModel::new(centers, weights, linear, constant, c * c)?;

    let condition_estimate =
        solver.norm1() * symmetric_inverse_norm1(m + 4, |x| solver.solve_stacked(x));
    let residuals: Vec<f64> = model
        .centers()
        .par_iter()
        .zip(&targets)
        .map(|(&c, &t)| (model.field(c) - t).abs())
        .collect();
    let max_residual = residuals.iter().fold(
        0.0,
        |worst, &r| {
            if r > worst || r.is_nan() { r } else { worst }
        },
    );
    let limit = RESIDUAL_TOLERANCE * slope * offsets.min;
    if max_residual.is_nan() || max_residual > limit {
        return Err(singular(&format!(
            "its largest constraint residual is {max_residual:.3e} (limit {limit:.1e})"
        )));
    }
    let report = RbfReport {
        points: n,
        unknowns: m + 4,
        kernel: options.kernel,
        diagonal,
        c2: model.c2(),
        epsilon,
        halved: offsets.halved,
        min_epsilon: offsets.min,
        seconds: start.elapsed().as_secs_f64(),
        factorization_seconds,
        condition_estimate,
        max_residual,
    };
    Ok((model, report))
}

fn singular(what: &str) -> Error {
    Error::invalid(format!(
        "the RBF system is numerically singular ({what}): some control points or \
         off-surface points nearly coincide"
    ))
}

/// The normals scaled to unit length, after checking positions and normals.
fn unit_normals(points: &PointSet) -> Result<Vec<[f64; 3]>> {
    let n = points.len();
    if points.normals.len() != n {
        return Err(Error::invalid(format!(
            "{n} positions but {} normals",
            points.normals.len()
        )));
    }
    points
        .positions
        .iter()
        .zip(&points.normals)
        .enumerate()
        .map(|(i, (p, normal))| {
            if p.iter().any(|v| !v.is_finite()) {
                return Err(Error::invalid(format!(
                    "control point {i} has a non-finite coordinate {p:?}"
                )));
            }
            let len = normal.iter().map(|v| v * v).sum::<f64>().sqrt();
            if !(len.is_finite() && len > 1e-12) {
                return Err(Error::invalid(format!(
                    "control point {i} has an unusable normal {normal:?}"
                )));
            }
            Ok(normal.map(|v| v / len))
        })
        .collect()
}

/// The centre and diagonal of the points' bounding box.
fn frame(positions: &[[f64; 3]]) -> Result<([f64; 3], f64)> {
    let mut lo = positions[0];
    let mut hi = lo;
    for p in positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let magnitude = (0..3)
        .map(|k| lo[k].abs().max(hi[k].abs()))
        .fold(0.0, f64::max);
    if !(diagonal.is_finite() && diagonal > 1e-12 * magnitude && diagonal > 0.0) {
        return Err(Error::invalid(format!(
            "the control points span no volume: their bounding box is {lo:?} … {hi:?}"
        )));
    }
    Ok(([0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])), diagonal))
}

/// The offsets εᵢ⁺ (outside) and εᵢ⁻ (inside) of every control point.
struct Offsets {
    outside: Vec<f64>,
    inside: Vec<f64>,
    /// How many were halved at least once.
    halved: usize,
    /// The smallest.
    min: f64,
}

impl Offsets {
    /// Starts every offset at `epsilon` and halves it until the offset point's nearest
    /// control point is its own (ties count as its own).
    fn new(positions: &[[f64; 3]], normals: &[[f64; 3]], epsilon: f64) -> Result<Offsets> {
        let tree = ImmutableKdTree::new_from_slice(positions)
            .map_err(|e| Error::invalid(format!("k-d tree construction failed: {e}")))?;
        let offset = |i: usize, sign: f64| -> Result<(f64, bool)> {
            let (p, normal) = (positions[i], normals[i]);
            let mut e = epsilon;
            for halvings in 0..=MAX_HALVINGS {
                let q = [0, 1, 2].map(|k| p[k] + sign * e * normal[k]);
                let nearest = tree
                    .query(&q)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                let own: f64 = (0..3).map(|k| (q[k] - p[k]) * (q[k] - p[k])).sum();
                if nearest.item as usize == i || own <= nearest.distance {
                    return Ok((e, halvings > 0));
                }
                e *= 0.5;
            }
            Err(Error::invalid(format!(
                "the {} off-surface point of control point {i} is still nearer another \
                 control point after {MAX_HALVINGS} halvings of its offset",
                if sign > 0.0 { "outside" } else { "inside" }
            )))
        };
        let sides: Vec<[(f64, bool); 2]> = (0..positions.len())
            .into_par_iter()
            .map(|i| Ok([offset(i, 1.0)?, offset(i, -1.0)?]))
            .collect::<Result<_>>()?;
        let halved = sides.iter().flatten().filter(|(_, h)| *h).count();
        let min = sides
            .iter()
            .flatten()
            .map(|(e, _)| *e)
            .fold(f64::INFINITY, f64::min);
        Ok(Offsets {
            outside: sides.iter().map(|s| s[0].0).collect(),
            inside: sides.iter().map(|s| s[1].0).collect(),
            halved,
            min,
        })
    }
}

/// Rejects centres closer than [`DUPLICATE_TOLERANCE`] × `diagonal` (sort-and-sweep along x:
/// O(m log m) for spread-out points). The first `n` centres are the control points, then
/// come the outside and the inside off-surface points.
fn check_distinct(centers: &[[f64; 3]], diagonal: f64, n: usize) -> Result<()> {
    let tolerance = DUPLICATE_TOLERANCE * diagonal;
    let mut order: Vec<usize> = (0..centers.len()).collect();
    order.sort_by(|&a, &b| centers[a][0].total_cmp(&centers[b][0]));
    let name = |i: usize| match i / n {
        0 => format!("control point {i}"),
        1 => format!("the outside off-surface point of control point {}", i - n),
        _ => format!(
            "the inside off-surface point of control point {}",
            i - 2 * n
        ),
    };
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            let (a, b) = (centers[i], centers[j]);
            if b[0] - a[0] > tolerance {
                break;
            }
            let d = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
            if d <= tolerance {
                let (first, second) = (i.min(j), i.max(j));
                return Err(Error::invalid(format!(
                    "{} and {} coincide (distance {d:.3e}): the RBF system would be singular",
                    name(first),
                    name(second)
                )));
            }
        }
    }
    Ok(())
}

fn centroid(centers: &[[f64; 3]]) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for c in centers {
        for k in 0..3 {
            sum[k] += c[k];
        }
    }
    sum.map(|s| s / centers.len() as f64)
}

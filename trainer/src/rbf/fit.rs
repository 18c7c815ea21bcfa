//! Fitting: the interpolation constraints of an oriented point set, one dense solve, and
//! the checks and measurements reported with the model.

use std::time::Instant;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::points::PointSet;

use super::condition::symmetric_inverse_norm1;
use super::kernel::multiquadric;
use super::model::RbfModel;
use super::options::{MAX_POINTS, MIN_POINTS, RbfOptions};
use super::solve::SaddleSolver;

/// Two centres closer than this fraction of the centres' bounding-box diagonal are
/// rejected as duplicates before the solve.
pub const DUPLICATE_TOLERANCE: f64 = 1e-9;

/// A fit whose largest constraint residual exceeds this fraction of the off-surface target
/// ε·s is rejected as numerically singular. Well-posed fits reach 10⁻¹³–10⁻¹¹ of it.
pub const RESIDUAL_TOLERANCE: f64 = 1e-6;

/// What a fit measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RbfReport {
    /// Control points n.
    pub points: usize,
    /// Unknowns of the linear system, 2n + 4 (one weight per centre, four for a·x + b).
    pub unknowns: usize,
    /// Wall-clock seconds of the whole fit: assembly, factorization, solve, condition
    /// estimate and residual check.
    pub seconds: f64,
    /// Estimated 1-norm condition number κ₁(M) = ‖M‖₁·‖M⁻¹‖₁ of the (2n + 4)² saddle-point
    /// matrix as assembled (polynomial block in centroid-relative coordinates): ‖M‖₁ exact,
    /// ‖M⁻¹‖₁ by Hager–Higham from the factorization — a lower bound, usually within a
    /// factor of 3. Expect ~10⁸ for a few hundred points on a unit-size shape; about
    /// κ₁·10⁻¹⁶ relative error in the weights (the residuals below stay far smaller).
    pub condition_estimate: f64,
    /// Largest |f(cᵢ) − dᵢ| over the 2n interpolation constraints (0 on the control points,
    /// −ε·s on the off-surface points), evaluated with the final model. The polynomial
    /// orthogonality conditions Σwᵢ = Σwᵢcᵢ = 0 hold by construction of the solve.
    pub max_residual: f64,
}

/// Fits Carcenac's multiquadric RBF baseline to oriented control points.
///
/// Centres are the n control points xᵢ (constraint f = 0) and n off-surface points
/// xᵢ + ε·nᵢ (constraint f = −ε·s), so f > 0 inside, f < 0 outside and ∇f ≈ −s·n on the
/// surface, as for the implicit network. With the side conditions Σwᵢ = 0, Σwᵢcᵢ = 0 the
/// (2n + 4)-unknown system has a unique solution for distinct, non-coplanar centres; it is
/// solved directly (see the solver in `solve.rs`: null-space method with one Cholesky
/// factorization, m³/3 flops for m = 2n). Normals are rescaled to unit length. Coplanar
/// control points are fine: their off-surface points leave the plane.
///
/// Cost: 576 points (1156 unknowns) take about 0.15 s in release (a single core; the
/// Cholesky factorization is 85 % of it); time grows as n³, memory as 32·n² bytes.
///
/// Nearly coincident points are accepted as long as the interpolation still holds: on the
/// 96-point torus, two points 10⁻⁷ apart still fit (κ₁ ≈ 10¹⁶, residual 5·10⁻⁸); at 10⁻⁸ the
/// residual check rejects the fit. The condition estimate is reported, never used to reject.
///
/// # Errors
/// [`Error::InvalidInput`] for invalid options, fewer than [`MIN_POINTS`] or more than
/// [`MAX_POINTS`] points, positions and normals of different lengths, non-finite or
/// zero-length inputs, two centres within [`DUPLICATE_TOLERANCE`] × the bounding-box
/// diagonal of each other, all
/// centres coplanar, and a numerically singular system (failed factorization, non-finite
/// solution, or a residual above [`RESIDUAL_TOLERANCE`]·ε·s).
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
            2 * n + 4,
            (2 * n * 2 * n * 8) as f64 / 1e9
        )));
    }
    let (centers, targets) = constraints(points, options)?;
    check_distinct(&centers, n)?;

    let m = centers.len();
    let centroid = centroid(&centers);
    let rows: Vec<[f64; 4]> = centers
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
    let c2 = options.c2;
    let kernel = DMatrix::from_fn(m, m, |i, j| {
        let (a, b) = (centers[i], centers[j]);
        multiquadric([a[0] - b[0], a[1] - b[1], a[2] - b[2]], c2)
    });
    let solver = SaddleSolver::new(kernel, &rows)?;
    let (weights, poly) = solver.solve(&targets, [0.0; 4]);
    if weights.iter().chain(&poly).any(|v| !v.is_finite()) {
        return Err(singular("its solution is not finite"));
    }
    let linear = [poly[0], poly[1], poly[2]];
    let constant =
        poly[3] - linear[0] * centroid[0] - linear[1] * centroid[1] - linear[2] * centroid[2];
    let model = RbfModel::new(centers, weights, linear, constant, c2)?;

    let condition_estimate =
        solver.norm1() * symmetric_inverse_norm1(m + 4, |x| solver.solve_stacked(x));
    let max_residual = model
        .centers()
        .iter()
        .zip(&targets)
        .map(|(&c, &t)| (model.field(c) - t).abs())
        .fold(
            0.0,
            |worst, r| if r > worst || r.is_nan() { r } else { worst },
        );
    let limit = RESIDUAL_TOLERANCE * options.epsilon * options.slope;
    if max_residual.is_nan() || max_residual > limit {
        return Err(singular(&format!(
            "its largest constraint residual is {max_residual:.3e} (limit {limit:.1e})"
        )));
    }
    let report = RbfReport {
        points: n,
        unknowns: m + 4,
        seconds: start.elapsed().as_secs_f64(),
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

/// The 2n centres (control points, then off-surface points) and their target values.
fn constraints(points: &PointSet, options: &RbfOptions) -> Result<(Vec<[f64; 3]>, Vec<f64>)> {
    let n = points.len();
    if points.normals.len() != n {
        return Err(Error::invalid(format!(
            "{n} positions but {} normals",
            points.normals.len()
        )));
    }
    let mut centers = Vec::with_capacity(2 * n);
    let mut offsets = Vec::with_capacity(n);
    for (i, (p, normal)) in points.positions.iter().zip(&points.normals).enumerate() {
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
        let step = options.epsilon / len;
        centers.push(*p);
        offsets.push([
            p[0] + step * normal[0],
            p[1] + step * normal[1],
            p[2] + step * normal[2],
        ]);
    }
    centers.extend(offsets);
    let mut targets = vec![0.0; n];
    targets.resize(2 * n, -options.epsilon * options.slope);
    Ok((centers, targets))
}

/// Rejects centres closer than [`DUPLICATE_TOLERANCE`] × the bounding-box diagonal
/// (sort-and-sweep along x: O(m log m) for spread-out points).
fn check_distinct(centers: &[[f64; 3]], n: usize) -> Result<()> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for c in centers {
        for k in 0..3 {
            lo[k] = lo[k].min(c[k]);
            hi[k] = hi[k].max(c[k]);
        }
    }
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let tolerance = DUPLICATE_TOLERANCE * diagonal;
    let mut order: Vec<usize> = (0..centers.len()).collect();
    order.sort_by(|&a, &b| centers[a][0].total_cmp(&centers[b][0]));
    let name = |i: usize| {
        if i < n {
            format!("control point {i}")
        } else {
            format!("the off-surface point of control point {}", i - n)
        }
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

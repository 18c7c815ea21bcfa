//! The interpolating surface: a uniform B-spline surface through every point, the smoothest
//! of those that pass through them.
//!
//! The paper's 3-D outlook fits "an interpolating or approximating surface" once the map
//! has ordered the points. With scattered points a surface can't have one control point per
//! point, as an interpolating curve does, so the control grid gets about
//! [`CONTROL_PER_POINT`] control points per point, and among the surfaces through the points
//! the one with the least bending of its control grid (Σ of squared second differences along
//! u and v, as the approximating fit's smoothing) is taken.
//!
//! It is found by iterated penalties (Bregman iteration): the least-squares fit with a tiny
//! second-difference penalty is solved, its residuals are added back to the targets, and the
//! fit is solved again with the same factored matrix until every point is met to
//! [`INTERPOLATION_TOLERANCE`] of the bounding diagonal. The limit is the least-bending
//! surface through the points when one exists. Points whose parameters crowd more points into
//! a few knot cells than those cells have control points can't all be met; the largest miss
//! is then reported, never hidden.

use nalgebra::DMatrix;

use crate::error::{Error, Result};

use super::spline::{BSplineSurface, MIN_CONTROL_POINTS};
use super::surface_fit::{basis_row, check_grid, open_along_v, second_differences};
use crate::geometry::vector::{bounds, distance};

/// Control points per data point of the interpolating grid: a uniform grid has to leave
/// freedom where the parameters crowd.
pub const CONTROL_PER_POINT: f64 = 2.0;

/// Distance, as a share of the points' bounding diagonal, within which every point counts as
/// met.
pub const INTERPOLATION_TOLERANCE: f64 = 1e-9;

/// Most rounds of the iterated penalty.
pub const INTERPOLATION_ROUNDS: usize = 400;

/// Weight of the second-difference penalty relative to the mean diagonal of the data term:
/// small, so that the rounds converge fast, large enough to keep the system well posed.
const PENALTY: f64 = 1e-8;

/// A surface through points, from [`interpolate_surface`].
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceInterpolation {
    /// The surface.
    pub surface: BSplineSurface,
    /// Largest |S(uⱼ, vⱼ) − Qⱼ|.
    pub max_residual: f64,
    /// Rounds of the iterated penalty that were run.
    pub rounds: usize,
    /// Whether every point is met within [`INTERPOLATION_TOLERANCE`] of the diagonal.
    pub exact: bool,
}

/// Sides `[count_u, count_v]` of an interpolating grid for `points` points in the proportions
/// of `shape` (an approximating grid's sides): about [`CONTROL_PER_POINT`] per point, at
/// least [`MIN_CONTROL_POINTS`] and more than `degree` per direction, and no more than `most`
/// in all where those minimums allow.
pub fn interpolation_grid(
    points: usize,
    shape: [usize; 2],
    degree: usize,
    most: usize,
) -> [usize; 2] {
    let wanted = (CONTROL_PER_POINT * points as f64).min(most as f64);
    let ratio = shape[1].max(1) as f64 / shape[0].max(1) as f64;
    let least = MIN_CONTROL_POINTS.max(degree + 1);
    let count_u = ((wanted / ratio).sqrt().round() as usize).max(least);
    let mut count_v = ((wanted / count_u as f64).round() as usize).max(least);
    while count_u * count_v > most && count_v > least {
        count_v -= 1;
    }
    [count_u, count_v]
}

/// The least-bending surface of `count_u × count_v` control points and `degree` (open along
/// v; closed around u when `closed_u`) through every point at its parameters.
///
/// # Errors
/// [`Error::InvalidInput`] as [`super::fit_surface_of_degree`] for the grid, the degree and
/// the parameters, and when the penalized system is singular.
pub fn interpolate_surface(
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    [count_u, count_v]: [usize; 2],
    closed_u: bool,
    degree: usize,
) -> Result<SurfaceInterpolation> {
    check_grid(points, parameters, [count_u, count_v], degree)?;
    let unknowns = count_u * count_v;
    let segments = [
        if closed_u { count_u } else { count_u - degree },
        count_v - degree,
    ];
    let rows: Vec<Vec<(usize, f64)>> = parameters
        .iter()
        .map(|&p| basis_row(p, segments, count_u, degree))
        .collect();
    let mut matrix = DMatrix::<f64>::zeros(unknowns, unknowns);
    for row in &rows {
        for &(f, a) in row {
            for &(g, b) in row {
                matrix[(f, g)] += a * b;
            }
        }
    }
    let weight = PENALTY * matrix.diagonal().sum() / unknowns as f64;
    for row in second_differences([count_u, count_v], closed_u) {
        for (f, a) in row {
            for (g, b) in row {
                matrix[(f, g)] += weight * a * b;
            }
        }
    }
    let singular = || {
        Error::invalid(format!(
            "the interpolation system for {count_u} × {count_v} control points through {} \
             points is singular",
            points.len()
        ))
    };
    let factor = matrix.cholesky().ok_or_else(singular)?;
    let diagonal = diagonal(points);
    let tolerance = INTERPOLATION_TOLERANCE * diagonal;
    let mut targets = points.to_vec();
    let mut control = vec![[0.0; 3]; unknowns];
    let mut max_residual = f64::INFINITY;
    let mut rounds = 0;
    while rounds < INTERPOLATION_ROUNDS && max_residual > tolerance {
        let mut rhs = DMatrix::<f64>::zeros(unknowns, 3);
        for (row, target) in rows.iter().zip(&targets) {
            for &(f, a) in row {
                for k in 0..3 {
                    rhs[(f, k)] += a * target[k];
                }
            }
        }
        let solution = factor.solve(&rhs);
        control = (0..unknowns)
            .map(|i| [solution[(i, 0)], solution[(i, 1)], solution[(i, 2)]])
            .collect();
        if !control.iter().flatten().all(|c| c.is_finite()) {
            return Err(singular());
        }
        max_residual = 0.0;
        for ((row, target), &q) in rows.iter().zip(&mut targets).zip(points) {
            let mut s = [0.0; 3];
            for &(f, a) in row {
                for k in 0..3 {
                    s[k] += a * control[f][k];
                }
            }
            max_residual = f64::max(max_residual, distance(s, q));
            for k in 0..3 {
                target[k] += q[k] - s[k];
            }
        }
        rounds += 1;
    }
    Ok(SurfaceInterpolation {
        surface: open_along_v(closed_u, degree, [count_u, count_v], control),
        max_residual,
        rounds,
        exact: max_residual <= tolerance,
    })
}

/// The bounding diagonal of `points` (1 when they have no extent).
fn diagonal(points: &[[f64; 3]]) -> f64 {
    let (lower, upper) = bounds(points);
    let d = distance(lower, upper);
    if d > 0.0 && d.is_finite() { d } else { 1.0 }
}

/// Cells per direction of the parameter grid over which [`swing`] measures.
pub const SWING_CELLS: usize = 64;

/// The largest distance of `through` from `fitted` (each sample of `through` projected onto
/// `fitted`, starting from the same parameters) at the centres of the cells of a
/// [`SWING_CELLS`]² grid over the parameters that hold one of `parameters`: how far a surface
/// through the points strays from a smooth fit between them, not counting the parameter box's
/// corners beyond the points, where both extrapolate.
pub fn swing(through: &BSplineSurface, fitted: &BSplineSurface, parameters: &[[f64; 2]]) -> f64 {
    let g = SWING_CELLS;
    let cell = |t: f64| ((t.clamp(0.0, 1.0) * g as f64) as usize).min(g - 1);
    let mut covered = vec![false; g * g];
    for p in parameters {
        covered[cell(p[1]) * g + cell(p[0])] = true;
    }
    let mut largest: f64 = 0.0;
    for (k, _) in covered.iter().enumerate().filter(|(_, c)| **c) {
        let (u, v) = (
            ((k % g) as f64 + 0.5) / g as f64,
            ((k / g) as f64 + 0.5) / g as f64,
        );
        let q = through.point(u, v);
        let foot = super::surface::project(fitted, q, [u, v]);
        largest = largest.max(distance(fitted.point(foot[0], foot[1]), q));
    }
    largest
}

//! Least-squares fit of a uniform B-spline surface (bicubic, or of degree 2 to 5 in both
//! directions), open or closed along u, to parametrized points.

use crate::error::{Error, Result};

use super::basis::{cubic_basis, locate, uniform_basis};
use super::least_squares::{Affine, NormalEquations};
use super::spline::{BSplineSurface, MIN_CONTROL_POINTS};

/// Most control points of a fitted surface (the normal equations are dense: F² memory,
/// F³/3 work).
pub const MAX_SURFACE_CONTROL_POINTS: usize = 4_096;

/// Fits `count_u × count_v` control points (open along v; along u closed, wrapping around,
/// when `closed_u`) so that S(uⱼ, vⱼ) ≈ Qⱼ in least squares, plus λ · Σ (second differences
/// of the control grid along u and along v)², λ = `smoothing` × the mean diagonal of the data
/// term.
///
/// # Errors
/// [`Error::InvalidInput`] for counts below [`MIN_CONTROL_POINTS`] or a grid above
/// [`MAX_SURFACE_CONTROL_POINTS`], mismatched lengths, non-finite parameters or a negative
/// smoothing, or a singular system.
pub fn fit_surface_to_parameters(
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    count_u: usize,
    count_v: usize,
    closed_u: bool,
    smoothing: f64,
) -> Result<BSplineSurface> {
    fit_surface_of_degree(
        points,
        parameters,
        [count_u, count_v],
        closed_u,
        smoothing,
        3,
    )
}

/// [`fit_surface_to_parameters`] of `degree` (2 to 5) in both directions.
///
/// # Errors
/// As [`fit_surface_to_parameters`], and for a degree outside 2 to 5 or a direction with no
/// more control points than the degree.
pub fn fit_surface_of_degree(
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    [count_u, count_v]: [usize; 2],
    closed_u: bool,
    smoothing: f64,
    degree: usize,
) -> Result<BSplineSurface> {
    check_grid(points, parameters, [count_u, count_v], degree)?;
    if !(smoothing.is_finite() && smoothing >= 0.0) {
        return Err(Error::invalid(format!(
            "the smoothing weight must be finite and ≥ 0, got {smoothing}"
        )));
    }
    let controls: Vec<Affine> = (0..count_u * count_v).map(Affine::unknown).collect();
    let mut equations = NormalEquations::new(controls.len());
    let segments = [
        if closed_u { count_u } else { count_u - degree },
        count_v - degree,
    ];
    let mut row: Vec<(f64, &Affine)> = Vec::with_capacity(36);
    for (q, &p) in points.iter().zip(parameters) {
        row.clear();
        row.extend(
            basis_row(p, segments, count_u, degree)
                .into_iter()
                .map(|(f, b)| (b, &controls[f])),
        );
        equations.add_row(&row, *q, 1.0);
    }
    let weight = smoothing * equations.mean_diagonal();
    for differences in second_differences([count_u, count_v], closed_u) {
        row.clear();
        row.extend(differences.into_iter().map(|(f, c)| (c, &controls[f])));
        equations.add_row(&row, [0.0; 3], weight);
    }
    let control = equations.solve().ok_or_else(|| {
        Error::invalid(format!(
            "the surface least-squares system for {count_u} × {count_v} control points over \
             {} points is singular: use fewer control points or more smoothing",
            points.len()
        ))
    })?;
    Ok(open_along_v(closed_u, degree, [count_u, count_v], control))
}

/// Checks a grid of `count_u × count_v` control points of `degree` for a fit to `points` at
/// `parameters`.
///
/// # Errors
/// [`Error::InvalidInput`] for a degree outside 2 to 5, counts below [`MIN_CONTROL_POINTS`]
/// or not above the degree, a grid above [`MAX_SURFACE_CONTROL_POINTS`], mismatched lengths
/// or non-finite parameters.
pub(crate) fn check_grid(
    points: &[[f64; 3]],
    parameters: &[[f64; 2]],
    [count_u, count_v]: [usize; 2],
    degree: usize,
) -> Result<()> {
    super::spline::check_degree(degree)?;
    if count_u < MIN_CONTROL_POINTS.max(degree + 1)
        || count_v < MIN_CONTROL_POINTS.max(degree + 1)
        || count_u.saturating_mul(count_v) > MAX_SURFACE_CONTROL_POINTS
    {
        return Err(Error::invalid(format!(
            "a fitted surface needs {MIN_CONTROL_POINTS} or more control points per direction \
             and at most {MAX_SURFACE_CONTROL_POINTS} in all, got {count_u} × {count_v}"
        )));
    }
    if points.len() != parameters.len() {
        return Err(Error::invalid(format!(
            "{} points but {} parameter pairs",
            points.len(),
            parameters.len()
        )));
    }
    if let Some(i) = parameters
        .iter()
        .position(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return Err(Error::invalid(format!(
            "the parameters {:?} of point {i} are not finite",
            parameters[i]
        )));
    }
    Ok(())
}

/// The (control index, weight) pairs of S(u, v) for `parameter`, on a grid `count_u` wide
/// with `segments` = [along u, along v] (u wraps around when it has as many segments as
/// control points).
pub(crate) fn basis_row(
    parameter: [f64; 2],
    segments: [usize; 2],
    count_u: usize,
    degree: usize,
) -> Vec<(usize, f64)> {
    let basis = |u: f64| {
        if degree == 3 {
            let c = cubic_basis(u);
            [c[0], c[1], c[2], c[3], 0.0, 0.0]
        } else {
            uniform_basis(degree, u)
        }
    };
    let (i, lu) = locate(parameter[0], segments[0]);
    let (j, lv) = locate(parameter[1], segments[1]);
    let (bu, bv) = (basis(lu), basis(lv));
    let mut row = Vec::with_capacity((degree + 1) * (degree + 1));
    for b in 0..=degree {
        for a in 0..=degree {
            row.push(((j + b) * count_u + (i + a) % count_u, bu[a] * bv[b]));
        }
    }
    row
}

/// The second differences of a `count_u × count_v` control grid along u (around, when
/// `closed_u`) and along v, as (control index, coefficient) rows.
pub(crate) fn second_differences(
    [count_u, count_v]: [usize; 2],
    closed_u: bool,
) -> Vec<[(usize, f64); 3]> {
    let at = |i: usize, j: usize| j * count_u + i;
    let mut rows = Vec::with_capacity(2 * count_u * count_v);
    for j in 0..count_v {
        for i in 0..count_u {
            if closed_u {
                let (before, after) = ((i + count_u - 1) % count_u, (i + 1) % count_u);
                rows.push([(at(before, j), 1.0), (at(i, j), -2.0), (at(after, j), 1.0)]);
            } else if i > 0 && i + 1 < count_u {
                rows.push([(at(i - 1, j), 1.0), (at(i, j), -2.0), (at(i + 1, j), 1.0)]);
            }
            if j > 0 && j + 1 < count_v {
                rows.push([(at(i, j - 1), 1.0), (at(i, j), -2.0), (at(i, j + 1), 1.0)]);
            }
        }
    }
    rows
}

/// The fitted surfaces' shape: open along v, open or closed around u, of `degree` both ways.
pub(crate) fn open_along_v(
    closed_u: bool,
    degree: usize,
    [count_u, count_v]: [usize; 2],
    control: Vec<[f64; 3]>,
) -> BSplineSurface {
    BSplineSurface {
        closed_u,
        closed_v: false,
        degree_u: degree,
        degree_v: degree,
        count_u,
        count_v,
        control,
    }
}

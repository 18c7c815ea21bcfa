//! Surfaces from scattered 3-D points, the paper's planned extension: a 2-D Kohonen map
//! ([`train_map`]) orders the points in two directions, each point gets map coordinates
//! (u, v), and a uniform cubic [`BSplineSurface`] is fitted to them in least squares.
//!
//! Beyond the paper, the map starts from the patch unrolled into the plane ([`unroll`]):
//! already ordered, it only settles onto the points, where a random start folds a long or
//! rolled sheet over itself. [`SurfaceOptions::shaped_for`] gives the map and the control
//! grid the patch's proportions. Measured with defaults (residual RMS as a share of the
//! bounding diagonal, 2 seeds): an S-sheet of length 3π and width 2, 500–8 000 points,
//! 0.06–0.18 % (a random 12 × 12 start: 1.6–1.7 % at 2 000); a Swiss roll of two turns,
//! 2 000 points, 0.09–0.11 % (1.7–2.3 %); at 500 and 8 000 points the roll still folds on
//! some seeds (0.05–1.5 %, against 2.3–2.8 %).
//!
//! With [`SurfaceOptions::interpolate`] the surface passes through every point instead
//! ([`interpolate_surface`], the paper's interpolating surface).
//!
//! The converged grid itself can also serve directly as a control grid
//! ([`control_grid_surface`]), as the paper suggests; it sits inside the point cloud (the
//! map's border neurons are pulled inwards) and the uniform B-spline shrinks it further, so
//! the fitted surface is the default.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::grid::NeuronGrid;
use super::grid_map::{KohonenMap, KohonenMapOptions, MapReport, train_map, train_map_from};
use super::points::CurvePoints;
use super::spline::{BSplineSurface, MIN_CONTROL_POINTS};
use super::surface_boundary::{BOUNDARY_NEIGHBOURS, CLOSED_BELOW, largest_boundary};
use super::surface_extent::{Unrolled, patch_aspect, unroll};
use super::surface_fit::fit_surface_of_degree;
use super::surface_interpolate::{
    CONTROL_PER_POINT, interpolate_surface, interpolation_grid, swing,
};
use super::surface_stray::stray_distance;
use super::surface_tube::tube_parameters;
use crate::geometry::vector::{distance, dot, sub};

/// Neighbourhood radius, in neurons, at the start of training from an unrolled map: the
/// map is already ordered, so training only settles it onto the points (Kohonen's
/// convergence phase). Measured on a Swiss roll, a 540° helicoid and an S-sheet (500–8 000
/// points): 1.25 and 1.75 neurons each break one of them, and 3 or more fold the roll's
/// layers together as a random start does.
pub const SETTLING_RADIUS: f64 = 1.5;
/// Learning rate at the start of training from an unrolled map (see [`SETTLING_RADIUS`]).
pub const SETTLING_RATE: f64 = 0.05;

/// Settings of [`fit_surface`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurfaceOptions {
    /// The map.
    pub map: KohonenMapOptions,
    /// Control points along u of the fitted surface (8).
    pub control_u: usize,
    /// Control points along v (8).
    pub control_v: usize,
    /// Weight of the second-difference penalty, relative to the data term (1e-4).
    pub smoothing: f64,
    /// Parameter corrections: after a fit, move every (uⱼ, vⱼ) to the nearest surface
    /// point (Gauss–Newton, clamped to [0, 1]²) and fit again; this many times (3).
    pub parameter_corrections: usize,
    /// Whether the points are fitted as a tube, closed around u, with parameters from its two
    /// edges ([`tube_parameters`]) instead of a map ([`TubeMode::Auto`]).
    pub tube: TubeMode,
    /// Start the map from the patch unrolled into the plane ([`unroll`]) instead of random
    /// weights (true).
    pub unroll: bool,
    /// The surface's degree in both directions, 2 to 5 (3).
    pub degree: usize,
    /// Pass through every point: after the least-squares fit has settled the parameters, the
    /// least-bending surface through the points at them ([`interpolate_surface`]) on a grid of
    /// about [`CONTROL_PER_POINT`] control points per point replaces it (false).
    pub interpolate: bool,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        SurfaceOptions {
            map: KohonenMapOptions::default(),
            control_u: 8,
            control_v: 8,
            smoothing: 1e-4,
            parameter_corrections: 3,
            tube: TubeMode::Auto,
            unroll: true,
            degree: 3,
            interpolate: false,
        }
    }
}

impl SurfaceOptions {
    /// The defaults with the map and the control grid shaped like the patch: their sides in
    /// the ratio of its [`patch_aspect`], the short side along u, with as many neurons (144)
    /// and control points (64) in all as the square defaults. Square when the aspect can't
    /// be measured.
    pub fn shaped_for(points: &[[f64; 3]]) -> Self {
        Self::shaped(patch_aspect(points).unwrap_or(1.0))
    }

    /// The defaults with the map and the control grid shaped for a patch of `aspect` (length
    /// over width, ≥ 1; see [`SurfaceOptions::shaped_for`]).
    pub fn shaped(aspect: f64) -> Self {
        let defaults = SurfaceOptions::default();
        let map = defaults.map.columns * defaults.map.rows;
        let control = defaults.control_u * defaults.control_v;
        let [columns, rows] = shaped_grid(aspect, map);
        let [control_u, control_v] = shaped_grid(aspect, control);
        SurfaceOptions {
            map: KohonenMapOptions {
                columns,
                rows,
                ..defaults.map
            },
            control_u,
            control_v,
            ..defaults
        }
    }
}

/// Whether [`fit_surface`] fits the points as a tube (an open cylinder, a pipe: two separate
/// edges), closed around u, or as one patch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TubeMode {
    /// A tube when [`tube_parameters`] finds two separate edges and the surface closed
    /// around them fits the points about as well as one patch or better (residual RMS at most
    /// [`TUBE_PREFERENCE`] times the patch's). A patch fitted to a tube is slit along it and
    /// overlaps itself there, which its residual hardly shows; a patch whose boundary merely
    /// breaks in two at its corners fits far worse when closed around.
    #[default]
    Auto,
    /// Always a tube; points without two separate edges are refused.
    Tube,
    /// Always one patch.
    Patch,
}

/// How much larger a tube's residual RMS may be than one patch's for [`TubeMode::Auto`] to
/// take the tube. Measured on point sets with two edges found (2 500 points each, seeds
/// 21–24 of the tube test): a tube's residual is 0.07–0.67 times its patch's (cones, vases,
/// bent pipes, noisy cylinders), while half cylinders and discs fit 8–10 times better as a
/// patch. A C shape (three quarters of a cylinder) closed around has 0.55–15 times its
/// patch's residual: the residual cannot see the surface bridging its opening, which
/// [`TUBE_STRAY`] does.
pub const TUBE_PREFERENCE: f64 = 2.0;

/// Fewest control points around a tube that [`TubeMode::Auto`] fits (a closed uniform cubic
/// of 8 control points fitted to a circle in least squares stays within 0.06 % of its radius).
pub const TUBE_AROUND: usize = 8;

/// Most parameter corrections of a tube's fit: after `parameter_corrections`, it goes on
/// while each round lowers the residual RMS by 1 % or more.
pub const TUBE_CORRECTIONS: usize = 20;

/// The farthest a tube's surface may get from the points ([`TubeCheck::stray`], in median
/// point spacings) for [`TubeMode::Auto`] to take the tube.
pub const TUBE_STRAY: f64 = 6.0;

/// Where [`TubeCheck::stray`] is measured: all the way around, over the middle half along
/// the tube (its ends may flare a little beyond the edges, but an opening runs along it).
pub const TUBE_MIDDLE: [[f64; 2]; 2] = [[0.0, 1.0], [0.25, 0.75]];

/// How far, in the least-squares fit's largest residuals, the surface through the points may
/// swing away from that fit between them ([`InterpolationReport::swing`]) before
/// [`SurfaceOptions::interpolate`] refuses it as folded. Measured on patches and tubes of
/// 300–400 points, some 10:1 uneven: 0.3–1.4; a patch folded over a cylinder 2.6; a wavy sheet
/// with noise of 3 % of its height 4.3.
pub const INTERPOLATION_SWING: f64 = 2.5;

/// Rounds of projection onto a stiff surface that a tube's parameters go through before its
/// fit (see `settle_tube`). Measured: 1 round gets most of the gain, 6 nearly all of it.
pub const TUBE_SETTLING: usize = 6;

/// What [`TubeMode::Auto`] compared, when the points had two separate edges.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TubeCheck {
    /// Residual RMS of the surface closed around the tube.
    pub tube_rms: f64,
    /// How far the middle half of the tube's surface ([`TUBE_MIDDLE`]) gets from the points,
    /// in median point spacings ([`stray_distance`]): farther than [`TUBE_STRAY`], the points
    /// are open around and the tube bridges the opening.
    pub stray: f64,
    /// Residual RMS of one patch; `None` when the patch could not be fitted.
    pub patch_rms: Option<f64>,
}

/// Sides `[short, long]` of a grid of about `budget` points whose ratio is near `aspect`
/// (≥ 1), the short side at least 4.
pub fn shaped_grid(aspect: f64, budget: usize) -> [usize; 2] {
    let aspect = if aspect.is_finite() {
        aspect.max(1.0)
    } else {
        1.0
    };
    let short = ((budget as f64 / aspect).sqrt().round() as usize).max(4);
    let long = ((budget as f64 / short as f64).round() as usize).max(short);
    [short, long]
}

/// What [`fit_surface`] computed.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceFit {
    /// The trained map; `None` for a tube, whose parameters come from its edges
    /// ([`tube_parameters`]).
    pub map: Option<KohonenMap>,
    /// How its training went.
    pub map_report: Option<MapReport>,
    /// The fitted surface: open in v; in u open, or closed around a tube.
    pub surface: BSplineSurface,
    /// Each point's (u, v) ∈ [0, 1]²: from the map or the tube's edges, then corrected by
    /// projection.
    pub parameters: Vec<[f64; 2]>,
    /// √(mean |S(uⱼ, vⱼ) − Qⱼ|²).
    pub rms_residual: f64,
    /// max |S(uⱼ, vⱼ) − Qⱼ|.
    pub max_residual: f64,
    /// With [`TubeMode::Auto`], what decided between a tube and a patch when the points had
    /// two separate edges.
    pub tube_check: Option<TubeCheck>,
    /// With [`SurfaceOptions::interpolate`], how the surface through the points was found.
    pub interpolation: Option<InterpolationReport>,
}

/// How [`SurfaceOptions::interpolate`] went.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct InterpolationReport {
    /// Residual RMS of the least-squares fit whose parameters the interpolation kept.
    pub approximation_rms: f64,
    /// Rounds of the iterated penalty ([`interpolate_surface`]).
    pub rounds: usize,
    /// Whether every point is met within [`super::INTERPOLATION_TOLERANCE`] of the bounding
    /// diagonal; when not, `max_residual` says by how much the worst point is missed.
    pub exact: bool,
    /// The largest distance of the surface through the points from the least-squares fit,
    /// over the parameters the points cover ([`super::swing`]).
    pub swing: f64,
}

/// Refuses points that form a closed surface (no boundary, [`largest_boundary`]): one open
/// patch would fold over it.
fn check_open(points: &[[f64; 3]]) -> Result<()> {
    let n = points.len();
    if n < 4 * BOUNDARY_NEIGHBOURS {
        return Ok(());
    }
    let boundary = largest_boundary(points);
    if (boundary as f64) < CLOSED_BELOW * (n as f64).sqrt() {
        return Err(Error::invalid(format!(
            "the {n} points form a closed surface (no boundary: at most {boundary} points lie \
             on an edge together); a spline surface is one open patch and would fold over it. \
             Cut the shape open, or fit it as an implicit or Cao En surface \
             (`neurosurf implicit fit`, `neurosurf caoen fit-mesh`)"
        )));
    }
    Ok(())
}

/// Trains a map on `points`, parametrizes them with [`map_parameters`], fits the surface,
/// and refines the parameters by projection (`parameter_corrections` times). When the points
/// are a tube (see [`TubeMode`]), they have two separate edges ([`tube_parameters`]): the map
/// is skipped, their parameters come from the edges, and the surface closes around u.
///
/// # Errors
/// As [`train_map`] and the least-squares fit (bad control counts or smoothing, a singular
/// system), for points that form a closed surface (unless they are a tube), and with
/// [`TubeMode::Tube`] for points that are not a tube.
pub fn fit_surface(points: &CurvePoints, options: &SurfaceOptions) -> Result<SurfaceFit> {
    fit_unrolled_surface(points, options, None)
}

/// [`fit_surface`] with the patch already unrolled ([`unroll`], for instance to measure its
/// aspect first), so that it is not unrolled twice; `None` unrolls it here when
/// `options.unroll`.
///
/// # Errors
/// As [`fit_surface`].
pub fn fit_unrolled_surface(
    points: &CurvePoints,
    options: &SurfaceOptions,
    unrolled: Option<&Unrolled>,
) -> Result<SurfaceFit> {
    let (u, v) = (options.control_u, options.control_v);
    let limit = neurosurf_core::curve::DEFAULT_SURFACE_POINTS;
    if u.saturating_mul(v) > limit {
        return Err(Error::invalid(format!(
            "--control {u},{v} asks for {} control points, but the core holds at most {limit}; \
             give U·V ≤ {limit} (for example --control 32,32)",
            u.saturating_mul(v)
        )));
    }
    let most = (limit as f64 / CONTROL_PER_POINT) as usize;
    if options.interpolate && points.len() > most {
        return Err(Error::invalid(format!(
            "--interpolate through {} points takes about {:.0} control points \
             ({CONTROL_PER_POINT} per point), but the core holds at most {limit}: give at most \
             {most} points, or fit without --interpolate",
            points.len(),
            CONTROL_PER_POINT * points.len() as f64
        )));
    }
    let fit = fit_approximating(points, options, unrolled)?;
    if options.interpolate {
        interpolate_fit(points, options, fit)
    } else {
        Ok(fit)
    }
}

/// The least-squares fit of [`fit_unrolled_surface`]: a tube or a patch as
/// `options.tube` says.
fn fit_approximating(
    points: &CurvePoints,
    options: &SurfaceOptions,
    unrolled: Option<&Unrolled>,
) -> Result<SurfaceFit> {
    let patch = || {
        check_open(points.points())?;
        let (map, report) = train_surface_map(points, options, unrolled)?;
        let parameters = map_parameters(points, &map)?;
        fit_parameters(points, options, Some((map, report)), parameters)
    };
    match options.tube {
        TubeMode::Patch => patch(),
        TubeMode::Tube => {
            let parameters = tube_parameters(points.points()).ok_or_else(|| {
                Error::invalid(format!(
                    "the {} points are not a tube: they have no two separate edges, or a \
                     third one (a tube is an open cylinder or a pipe); fit them without \
                     --tube as one patch",
                    points.len()
                ))
            })?;
            fit_parameters(points, options, None, parameters)
        }
        TubeMode::Auto => {
            let Some(parameters) = tube_parameters(points.points()) else {
                return patch();
            };
            // The options were shaped for a patch, whose short side along u is the tube's
            // way around when it is one: keep enough control points for a circle there.
            // (Unless that grid would not fit in the core.)
            let limit = neurosurf_core::curve::DEFAULT_SURFACE_POINTS;
            let control_u = if TUBE_AROUND.saturating_mul(options.control_v) <= limit {
                options.control_u.max(TUBE_AROUND)
            } else {
                options.control_u
            };
            let around = SurfaceOptions {
                control_u,
                ..options.clone()
            };
            let tube = fit_parameters(points, &around, None, parameters);
            let Ok(mut tube) = tube else {
                return patch();
            };
            let patch = patch();
            let check = TubeCheck {
                tube_rms: tube.rms_residual,
                stray: stray_distance(&tube.surface, points.points(), TUBE_MIDDLE)
                    .unwrap_or(f64::INFINITY),
                patch_rms: patch.as_ref().ok().map(|fit| fit.rms_residual),
            };
            match patch {
                Ok(mut patch)
                    if check.stray > TUBE_STRAY
                        || patch.rms_residual * TUBE_PREFERENCE < tube.rms_residual =>
                {
                    patch.tube_check = Some(check);
                    Ok(patch)
                }
                _ => {
                    tube.tube_check = Some(check);
                    Ok(tube)
                }
            }
        }
    }
}

/// `fit` with its surface replaced by the least-bending one through the points at its
/// parameters, on a grid of about [`CONTROL_PER_POINT`] control points per point in the
/// proportions of its own.
fn interpolate_fit(
    points: &CurvePoints,
    options: &SurfaceOptions,
    fit: SurfaceFit,
) -> Result<SurfaceFit> {
    let shape = [fit.surface.count_u, fit.surface.count_v];
    let limit = neurosurf_core::curve::DEFAULT_SURFACE_POINTS;
    let grid = interpolation_grid(points.len(), shape, options.degree, limit);
    let through = interpolate_surface(
        points.points(),
        &fit.parameters,
        grid,
        fit.surface.closed_u,
        options.degree,
    )?;
    let n = points.len();
    if !through.exact {
        return Err(Error::invalid(format!(
            "no {} × {} surface passes through all {n} points: after {} rounds the worst is \
             still {:.3e} away. Their parameters crowd more points into some knot cells than \
             those cells have control points (the least-squares fit's residual RMS is {:.3e}); \
             fit without --interpolate",
            grid[0], grid[1], through.rounds, through.max_residual, fit.rms_residual
        )));
    }
    let swing = swing(&through.surface, &fit.surface, &fit.parameters);
    if swing > INTERPOLATION_SWING * fit.max_residual {
        return Err(Error::invalid(format!(
            "the surface through all {n} points swings {swing:.3e} away from the least-squares \
             fit between them, {:.1} times the fit's largest residual ({:.3e}): points close \
             together disagree (noise, or parameters that do not follow their positions), and a \
             surface that must pass through each folds between them. Fit without --interpolate",
            swing / fit.max_residual,
            fit.max_residual
        )));
    }
    let (rms_residual, max_residual) = residuals(&through.surface, points, &fit.parameters);
    Ok(SurfaceFit {
        surface: through.surface,
        rms_residual,
        max_residual,
        interpolation: Some(InterpolationReport {
            approximation_rms: fit.rms_residual,
            rounds: through.rounds,
            exact: through.exact,
            swing,
        }),
        ..fit
    })
}

/// √(mean |S(uⱼ, vⱼ) − Qⱼ|²) and max |S(uⱼ, vⱼ) − Qⱼ|.
fn residuals(
    surface: &BSplineSurface,
    points: &CurvePoints,
    parameters: &[[f64; 2]],
) -> (f64, f64) {
    let residuals: Vec<f64> = points
        .points()
        .iter()
        .zip(parameters)
        .map(|(&q, p)| distance(surface.point(p[0], p[1]), q))
        .collect();
    let rms = (residuals.iter().map(|r| r * r).sum::<f64>() / residuals.len() as f64).sqrt();
    (rms, residuals.iter().copied().fold(0.0, f64::max))
}

/// The fit from first parameters: from the map's (`map` given, open around u) or a tube's
/// edges (`None`, closed around u), corrected by projection.
fn fit_parameters(
    points: &CurvePoints,
    options: &SurfaceOptions,
    map: Option<(KohonenMap, MapReport)>,
    mut parameters: Vec<[f64; 2]>,
) -> Result<SurfaceFit> {
    let closed_u = map.is_none();
    let fit = |parameters: &[[f64; 2]]| {
        fit_surface_of_degree(
            points.points(),
            parameters,
            [options.control_u, options.control_v],
            closed_u,
            options.smoothing,
            options.degree,
        )
    };
    if closed_u {
        settle_tube(points, options, &mut parameters)?;
    }
    let mut surface = fit(&parameters)?;
    let mut rms = residuals(&surface, points, &parameters).0;
    // A tube's parameters come from path lengths to its edges, which an edge found only in
    // part bends; corrections then converge slowly, so a tube keeps correcting while each
    // round still lowers the residual by 1 % (measured with defaults on cylinders, cones,
    // vases and bent pipes of 500–8 000 points: residual RMS 1.3–6 times lower than after 3
    // rounds, for about 1.6 times the time).
    let most = if closed_u {
        options.parameter_corrections.max(TUBE_CORRECTIONS)
    } else {
        options.parameter_corrections
    };
    for round in 0..most {
        let mut corrected = parameters.clone();
        for (p, &q) in corrected.iter_mut().zip(points.points()) {
            *p = project(&surface, q, *p);
        }
        let refitted = fit(&corrected)?;
        let refitted_rms = residuals(&refitted, points, &corrected).0;
        if round >= options.parameter_corrections && refitted_rms > 0.99 * rms {
            break;
        }
        (surface, parameters, rms) = (refitted, corrected, refitted_rms);
    }
    let (rms_residual, max_residual) = residuals(&surface, points, &parameters);
    let (map, map_report) = map.unzip();
    Ok(SurfaceFit {
        map,
        map_report,
        surface,
        parameters,
        rms_residual,
        max_residual,
        tube_check: None,
        interpolation: None,
    })
}

/// Moves a tube's first parameters onto a stiff surface, [`TUBE_SETTLING`] times: fitted with
/// all of `options`' control points around but only the fewest along it, it can't follow the
/// parameters' errors along the tube, and projecting onto it removes them.
///
/// A tube's v comes from path lengths to its edges, which a sparse or uneven sample bends by
/// up to a third of the tube's length where an edge is found only in part; the full grid then
/// follows the bend and the corrections keep it. Measured with defaults on cylinders and cones
/// of 300–1 000 random points (some 10:1 uneven) and on the tubes of 500–8 000 points: residual
/// RMS 1.1–13 times lower (a cylinder of height 15: 6.9 % of the radius → 1.1 %), within 10 %
/// either way on vases and noisy tubes.
fn settle_tube(
    points: &CurvePoints,
    options: &SurfaceOptions,
    parameters: &mut [[f64; 2]],
) -> Result<()> {
    let along = MIN_CONTROL_POINTS.max(options.degree + 1);
    for _ in 0..TUBE_SETTLING {
        let stiff = fit_surface_of_degree(
            points.points(),
            parameters,
            [options.control_u, along],
            true,
            options.smoothing,
            options.degree,
        )?;
        for (p, &q) in parameters.iter_mut().zip(points.points()) {
            *p = project(&stiff, q, *p);
        }
    }
    Ok(())
}

/// The map of [`fit_surface`]: from the patch unrolled when it can be, else from random
/// weights.
fn train_surface_map(
    points: &CurvePoints,
    options: &SurfaceOptions,
    unrolled: Option<&Unrolled>,
) -> Result<(KohonenMap, MapReport)> {
    let here;
    let unrolled = match unrolled {
        Some(unrolled) => Some(unrolled),
        None if options.unroll => {
            here = unroll(points.points());
            here.as_ref()
        }
        None => None,
    };
    let initial = unrolled.and_then(|u| u.initial_map(options.map.columns, options.map.rows));
    match &initial {
        Some(initial) => {
            let settling = KohonenMapOptions {
                initial_radius: SETTLING_RADIUS / options.map.columns.max(options.map.rows) as f64,
                initial_rate: SETTLING_RATE,
                ..options.map.clone()
            };
            train_map_from(points, &settling, Some(initial))
        }
        None => train_map(points, &options.map),
    }
}

/// The parameters of the surface point nearest to `q`, starting from `start`: up to 8
/// Gauss–Newton steps on |S(u, v) − q|², clamped to [0, 1]² (wrapped around along a closed
/// direction).
pub(crate) fn project(surface: &BSplineSurface, q: [f64; 3], start: [f64; 2]) -> [f64; 2] {
    let mut p = start;
    for _ in 0..8 {
        let r = sub(q, surface.point(p[0], p[1]));
        let (su, sv) = surface.partials(p[0], p[1]);
        let (a, b, e) = (dot(su, su), dot(su, sv), dot(sv, sv));
        let determinant = a * e - b * b;
        if !(determinant > 0.0 && determinant.is_finite()) {
            break;
        }
        let (x, y) = (dot(r, su), dot(r, sv));
        let step = [(e * x - b * y) / determinant, (a * y - b * x) / determinant];
        let next = [
            (p[0] + step[0], surface.closed_u),
            (p[1] + step[1], surface.closed_v),
        ]
        .map(|(t, closed)| {
            if closed {
                t.rem_euclid(1.0)
            } else {
                t.clamp(0.0, 1.0)
            }
        });
        let moved = (next[0] - p[0]).abs() + (next[1] - p[1]).abs();
        p = next;
        if moved < 1e-12 {
            break;
        }
    }
    p
}

/// Map coordinates of every point, scaled to [0, 1]²: the winner (i, j) plus the offset
/// (δᵢ, δⱼ) that best explains x − w in the map's local frame (the central differences of
/// the neighbours, one-sided at the border), clamped to ±½ inside and up to 1 outwards at
/// the border; then each coordinate is mapped affinely onto [0, 1] over all points.
///
/// # Errors
/// [`Error::InvalidInput`] when the map's shape does not match its neurons or all points
/// share one coordinate.
pub fn map_parameters(points: &CurvePoints, map: &KohonenMap) -> Result<Vec<[f64; 2]>> {
    let (columns, rows) = (map.columns, map.rows);
    if columns < 2 || rows < 2 || Some(map.neurons.len()) != columns.checked_mul(rows) {
        return Err(Error::invalid(format!(
            "a {columns} × {rows} Kohonen map cannot have {} neurons",
            map.neurons.len()
        )));
    }
    let (lower, upper) = points.bounds();
    let grid = NeuronGrid::new(lower, upper, &map.neurons);
    let raw: Vec<[f64; 2]> = points
        .points()
        .iter()
        .map(|&x| {
            let (c, _) = grid.nearest(x, &map.neurons, None).unwrap_or((0, 0.0));
            let (i, j) = (c % columns, c / columns);
            let along = |before: usize, after: usize, steps: f64, column: bool| {
                let at = |column: usize, row: usize| map.neurons[row * columns + column];
                let (a, b) = if column {
                    (at(before, j), at(after, j))
                } else {
                    (at(i, before), at(i, after))
                };
                sub(b, a).map(|v| v / steps)
            };
            let frame = |k: usize, count: usize, column: bool| {
                let before = k.saturating_sub(1);
                let after = (k + 1).min(count - 1);
                along(before, after, (after - before) as f64, column)
            };
            let tu = frame(i, columns, true);
            let tv = frame(j, rows, false);
            let d = sub(x, map.neurons[c]);
            let (a, b, e) = (dot(tu, tu), dot(tu, tv), dot(tv, tv));
            let determinant = a * e - b * b;
            let (mut du, mut dv) = if determinant > 1e-12 * (a * e) && determinant > 0.0 {
                let (r, s) = (dot(d, tu), dot(d, tv));
                ((e * r - b * s) / determinant, (a * s - b * r) / determinant)
            } else {
                (0.0, 0.0)
            };
            let limits = |k: usize, count: usize| {
                (
                    if k == 0 { -1.0 } else { -0.5 },
                    if k + 1 == count { 1.0 } else { 0.5 },
                )
            };
            let (lo, hi) = limits(i, columns);
            du = du.clamp(lo, hi);
            let (lo, hi) = limits(j, rows);
            dv = dv.clamp(lo, hi);
            [i as f64 + du, j as f64 + dv]
        })
        .collect();
    let mut scaled = raw.clone();
    for k in 0..2 {
        let low = raw.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
        let high = raw.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
        if high.partial_cmp(&low) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::invalid(
                "every point got the same map coordinate: the map did not spread",
            ));
        }
        for (s, r) in scaled.iter_mut().zip(&raw) {
            s[k] = (r[k] - low) / (high - low);
        }
    }
    Ok(scaled)
}

/// The converged grid used directly as the control grid of an open surface.
///
/// # Errors
/// [`Error::InvalidInput`] when the map has fewer than 4 neurons per direction.
pub fn control_grid_surface(map: &KohonenMap) -> Result<BSplineSurface> {
    let surface = BSplineSurface {
        closed_u: false,
        closed_v: false,
        degree_u: 3,
        degree_v: 3,
        count_u: map.columns,
        count_v: map.rows,
        control: map.neurons.clone(),
    };
    surface.validate()?;
    Ok(surface)
}

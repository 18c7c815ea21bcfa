//! The whole curve pipeline in one call: scattered points → chain → order → refined order
//! → splines.

use serde::{Deserialize, Serialize};

use crate::error::Result;

use super::fit::{
    Approximation, ApproximationOptions, Ends, approximate, approximate_within, density_parameters,
    interpolate,
};
use super::kohonen::{KohonenChain, KohonenOptions, Topology, TrainingReport, train_chain};
use super::noise::{BandReport, band_parameters};
use super::ordering::{Ordering, order_points};
use super::points::CurvePoints;
use super::principal::follow_either;
use super::refine::{RefineOptions, RefineReport, refine_order};
use super::spline::BSplineCurve;

/// Settings of [`reconstruct_curve`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveOptions {
    /// The chain (its topology decides open or closed curves).
    pub kohonen: KohonenOptions,
    /// The least-squares fit.
    pub approximation: ApproximationOptions,
    /// Repair of the chain's order by local search ([`refine_order`]); `None` keeps the
    /// paper's order as it is (on by default).
    pub refine: Option<RefineOptions>,
}

impl Default for CurveOptions {
    fn default() -> Self {
        CurveOptions {
            kohonen: KohonenOptions::default(),
            approximation: ApproximationOptions::default(),
            refine: Some(RefineOptions::default()),
        }
    }
}

impl CurveOptions {
    /// Defaults with the given topology and seed.
    pub fn new(topology: Topology, seed: u64) -> Self {
        let mut options = CurveOptions::default();
        options.kohonen.topology = topology;
        options.kohonen.seed = seed;
        options
    }
}

/// Everything [`reconstruct_curve`] computed.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveReconstruction {
    /// The trained chain.
    pub chain: KohonenChain,
    /// How training went.
    pub training: TrainingReport,
    /// The order read off the chain (the paper's method).
    pub chain_ordering: Ordering,
    /// What the refinement changed, when it ran.
    pub refinement: Option<RefineReport>,
    /// The order the splines use: the refined order, or the chain's.
    pub ordering: Ordering,
    /// The least-squares spline through the ordered points.
    pub approximation: Approximation,
    /// When the noise across the curve is wider than the spacing: how the approximation
    /// was parametrized instead of by chord length.
    pub band: Option<BandReport>,
    /// The spline through every ordered point.
    pub interpolation: BSplineCurve,
}

/// Trains a chain on `points`, orders them, refines the order (if asked), and fits both
/// splines.
///
/// # Errors
/// As [`train_chain`], [`order_points`], [`refine_order`], [`approximate`] and
/// [`interpolate`].
pub fn reconstruct_curve(
    points: &CurvePoints,
    options: &CurveOptions,
) -> Result<CurveReconstruction> {
    let (chain, training) = train_chain(points, &options.kohonen)?;
    let chain_ordering = order_points(points, &chain)?;
    let (ordering, refinement) = match &options.refine {
        Some(refine) => {
            let (ordering, report) = refine_order(points, &chain_ordering, refine)?;
            (ordering, Some(report))
        }
        None => (chain_ordering.clone(), None),
    };
    let ordered = ordering.ordered_points(points);
    let closed = ordering.closed;
    let dimension = points.dimension();
    let band = band_parameters(&ordered, dimension, closed);
    let (mut ordering, mut ordered) = (ordering, ordered);
    // A band's first and last points lie anywhere across it: the fit places the ends. And
    // its order zig-zags across it, where the corner detector's arms see turns everywhere:
    // noise wider than the spacing hides corners (they are rounded).
    let mut fitting = options.approximation.clone();
    if band.is_some() {
        fitting.ends = Ends::Fitted;
        fitting.corners = false;
    }
    let within = |parameters: Vec<f64>, tolerance: f64| {
        approximate_within(&ordered, parameters, dimension, closed, tolerance, &fitting)
    };
    let tolerance = match options.approximation.control_points {
        None => options.approximation.tolerance,
        Some(_) => None,
    };
    let mut report = band.as_ref().map(|b| b.report.clone());
    let approximation = match (band, tolerance) {
        (Some(band), Some(tolerance)) => within(band.parameters, tolerance)?,
        (None, Some(tolerance)) => within(density_parameters(&ordered, closed)?, tolerance)?,
        (None, None) => approximate(&ordered, dimension, closed, &options.approximation)?,
        (Some(band), None) => {
            // The fit knows better where the band runs than the order it was fitted in.
            let followed = follow_either(
                &ordered,
                (dimension, closed),
                (band.report.noise, band.parameters),
                options.approximation.control_points,
                &fitting,
            )?;
            if let Some(report) = &mut report {
                report.rounds = followed.rounds;
                report.noise = followed.noise;
                report.spacing = followed.length / ordered.len() as f64;
                report.control_points = followed.approximation.curve.control.len();
            }
            ordering.order = followed.order.iter().map(|&i| ordering.order[i]).collect();
            ordered = followed.order.iter().map(|&i| ordered[i]).collect();
            followed.approximation
        }
    };
    let interpolation = interpolate(&ordered, dimension, closed)?;
    Ok(CurveReconstruction {
        band: report,
        chain,
        training,
        chain_ordering,
        refinement,
        ordering,
        approximation,
        interpolation,
    })
}

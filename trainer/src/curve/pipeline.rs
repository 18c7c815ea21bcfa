//! The whole curve pipeline in one call: scattered points → chain → order → refined order
//! → splines.

use serde::{Deserialize, Serialize};

use crate::error::Result;

use super::fit::{
    Approximation, ApproximationOptions, approximate, approximate_at, approximate_within,
    density_parameters, interpolate,
};
use super::kohonen::{KohonenChain, KohonenOptions, Topology, TrainingReport, train_chain};
use super::noise::{BandReport, band_parameters};
use super::ordering::{Ordering, order_points};
use super::points::CurvePoints;
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
    let within = |parameters: Vec<f64>, tolerance: f64| {
        approximate_within(
            &ordered,
            parameters,
            dimension,
            closed,
            tolerance,
            &options.approximation,
        )
    };
    let tolerance = match options.approximation.control_points {
        None => options.approximation.tolerance,
        Some(_) => None,
    };
    let approximation = match (&band, tolerance) {
        (Some(band), Some(tolerance)) => within(band.parameters.clone(), tolerance)?,
        (None, Some(tolerance)) => within(density_parameters(&ordered, closed)?, tolerance)?,
        (band, None) => match band {
            Some(band) => {
                let k = options
                    .approximation
                    .control_points
                    .unwrap_or(band.control_points);
                approximate_at(
                    &ordered,
                    band.parameters.clone(),
                    dimension,
                    closed,
                    k,
                    &options.approximation,
                )?
            }
            None => approximate(&ordered, dimension, closed, &options.approximation)?,
        },
    };
    let interpolation = interpolate(&ordered, dimension, closed)?;
    Ok(CurveReconstruction {
        band: band.map(|b| b.report),
        chain,
        training,
        chain_ordering,
        refinement,
        ordering,
        approximation,
        interpolation,
    })
}

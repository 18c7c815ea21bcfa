//! Optional repair of a recovered order by local search on the length of the ordering
//! polygon — an addition to the paper, which stops at the chain's order.
//!
//! A chain that had to bend into a spiral sometimes keeps a defect: it follows one arm,
//! jumps to the neighbouring arm for a stretch and jumps back. Each defect is two long edges
//! in the ordering polygon, and removing it shortens the polygon, so two classic tour
//! moves repair it: 2-opt (reverse a stretch; candidates from each point's k nearest
//! neighbours) and segment insertion (Or-opt: move a stretch elsewhere, possibly reversed;
//! the stretches tried are those of ≤ 3 points and those bounded by two long edges or an
//! end of an open order). Between long edges both moves are also tried directly (reverse
//! what two long edges bound; insert a stretch into another long edge): in a band thicker
//! than the spacing a defect's true neighbours lie beyond the k nearest. An open
//! order is handled as a closed tour through a dummy point at distance 0 from every point,
//! so the ends may move too. Moves are applied while they shorten the polygon by more than
//! 1e-12 of the bounding-box diagonal. Each pass costs O(n·k) for 2-opt, O(n·k + J²·(k + J))
//! for insertion with J long edges, plus O(n) per applied move.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

use super::ordering::Ordering;
use super::points::CurvePoints;
use super::tour::Tour;

/// Settings of [`refine_order`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefineOptions {
    /// Candidate neighbours per point (10).
    pub neighbours: usize,
    /// Most passes over all moves (50).
    pub max_passes: usize,
    /// An edge is long when it exceeds this multiple of the median edge (3).
    pub long_edge_factor: f64,
    /// Most long edges whose pairs bound candidate stretches (64, the longest ones).
    pub max_long_edges: usize,
}

impl Default for RefineOptions {
    fn default() -> Self {
        RefineOptions {
            neighbours: 10,
            max_passes: 50,
            long_edge_factor: 3.0,
            max_long_edges: 64,
        }
    }
}

/// What [`refine_order`] changed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RefineReport {
    /// Length of the ordering polygon before (closing edge included when closed).
    pub length_before: f64,
    /// … and after.
    pub length_after: f64,
    /// 2-opt moves applied.
    pub reversals: usize,
    /// Stretch insertions applied.
    pub insertions: usize,
    /// Passes made.
    pub passes: usize,
}

/// Shortens the ordering polygon of `ordering` by local moves (see the module docs). The
/// result starts with the same point as the input when closed. Deterministic.
///
/// # Errors
/// [`Error::InvalidInput`] when `ordering.order` is not a permutation of the points or the
/// options are unusable (no neighbours, a factor that is not finite and > 1).
pub fn refine_order(
    points: &CurvePoints,
    ordering: &Ordering,
    options: &RefineOptions,
) -> Result<(Ordering, RefineReport)> {
    let n = points.len();
    let mut seen = vec![false; n];
    if ordering.order.len() != n
        || ordering
            .order
            .iter()
            .any(|&i| i >= n || std::mem::replace(&mut seen[i], true))
    {
        return Err(Error::invalid(format!(
            "the order to refine is not a permutation of the {n} points"
        )));
    }
    if options.neighbours == 0 {
        return Err(Error::invalid(
            "refinement needs at least 1 neighbour per point",
        ));
    }
    if !(options.long_edge_factor.is_finite() && options.long_edge_factor > 1.0) {
        return Err(Error::invalid(format!(
            "the long-edge factor must be finite and > 1, got {}",
            options.long_edge_factor
        )));
    }
    let mut tour = Tour::new(points, ordering, options.neighbours);
    let length_before = tour.length();
    let epsilon = 1e-12 * points.diagonal();
    let mut report = RefineReport {
        length_before,
        length_after: length_before,
        reversals: 0,
        insertions: 0,
        passes: 0,
    };
    while report.passes < options.max_passes {
        report.passes += 1;
        let reversals = tour.two_opt_pass(epsilon);
        let insertions = tour.insertion_pass(epsilon, options);
        report.reversals += reversals;
        report.insertions += insertions;
        if reversals + insertions == 0 {
            break;
        }
    }
    report.length_after = tour.length();
    let order = tour.into_order(ordering);
    Ok((
        Ordering {
            order,
            closed: ordering.closed,
            chain_position: ordering.chain_position.clone(),
        },
        report,
    ))
}

//! The order of the input points read off a trained chain.
//!
//! Each point goes to its winner neuron c (nearest, Euclidean) and gets the chain position
//! c + τ, where τ ∈ [−½, ½] is its projection onto the chain's local direction
//! (o_{c+1} − o_{c−1}, one-sided at an open chain's ends) in units of that direction's
//! length. Sorting by (position, input index) orders the points; several points sharing a
//! winner are ordered by their projection. For a ring the order is cyclic: it starts at the
//! point nearest to neuron 0's side of the ring, and the last point neighbours the first.

use crate::error::{Error, Result};

use super::grid::NeuronGrid;
use super::kohonen::{KohonenChain, Topology};
use super::points::CurvePoints;
use crate::geometry::vector::{dot, sub};

/// The recovered order of the input points.
#[derive(Clone, Debug, PartialEq)]
pub struct Ordering {
    /// Indices of the input points along the curve.
    pub order: Vec<usize>,
    /// Whether the order is cyclic (a closed curve).
    pub closed: bool,
    /// Chain position c + τ of every input point, indexed like the input (from the chain;
    /// [`refine_order`](super::refine_order) keeps it unchanged).
    pub chain_position: Vec<f64>,
}

/// The steps of an order that are much longer than its typical step: where a wrong order
/// shows (a jump to another arm and back), or a real gap in the data.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LongSteps {
    /// Steps longer than the factor × the median step.
    pub count: usize,
    /// The longest step ÷ the median step.
    pub longest_ratio: f64,
    /// The distance from the last point back to the first ÷ the median step: near 1 on a
    /// closed curve, large on an open one whatever the order's topology.
    pub ends_ratio: f64,
}

impl Ordering {
    /// The input points in the recovered order.
    pub fn ordered_points(&self, points: &CurvePoints) -> Vec<[f64; 3]> {
        self.order.iter().map(|&i| points.points()[i]).collect()
    }

    /// The steps between consecutive points (the closing one too when closed) longer than
    /// `factor` × the median step.
    pub fn long_steps(&self, points: &CurvePoints, factor: f64) -> LongSteps {
        let ordered = self.ordered_points(points);
        let mut steps: Vec<f64> = ordered
            .windows(2)
            .map(|w| crate::geometry::vector::distance(w[0], w[1]))
            .collect();
        if self.closed
            && let (Some(&first), Some(&last)) = (ordered.first(), ordered.last())
        {
            steps.push(crate::geometry::vector::distance(last, first));
        }
        let mut sorted = steps.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        if median.is_nan() || median <= 0.0 {
            return LongSteps {
                count: 0,
                longest_ratio: 0.0,
                ends_ratio: 0.0,
            };
        }
        let ends = match (ordered.first(), ordered.last()) {
            (Some(&first), Some(&last)) => crate::geometry::vector::distance(last, first),
            _ => 0.0,
        };
        LongSteps {
            count: steps.iter().filter(|&&d| d > factor * median).count(),
            longest_ratio: sorted.last().copied().unwrap_or(0.0) / median,
            ends_ratio: ends / median,
        }
    }
}

/// Orders `points` along `chain`. O(n log n) plus n nearest-neuron queries.
///
/// # Errors
/// [`Error::InvalidInput`] when the chain has fewer than 2 neurons, a non-finite weight, or
/// a dimension other than the points'.
pub fn order_points(points: &CurvePoints, chain: &KohonenChain) -> Result<Ordering> {
    let neurons = &chain.neurons;
    let m = neurons.len();
    if m < 2 {
        return Err(Error::invalid(format!(
            "a Kohonen chain needs at least 2 neurons to order points, got {m}"
        )));
    }
    if chain.dimension != points.dimension() {
        return Err(Error::invalid(format!(
            "the chain is {}-D but the points are {}-D",
            chain.dimension,
            points.dimension()
        )));
    }
    if let Some(j) = neurons
        .iter()
        .position(|w| w.iter().any(|c| !c.is_finite()))
    {
        return Err(Error::invalid(format!(
            "neuron {j} of the chain has a non-finite weight {:?}",
            neurons[j]
        )));
    }
    let closed = chain.topology == Topology::Closed;
    let (lower, upper) = points.bounds();
    // The grid clamps neurons outside the points' box into its border cells: still exact.
    let grid = NeuronGrid::new(lower, upper, neurons);
    let chain_position: Vec<f64> = points
        .points()
        .iter()
        .map(|&x| {
            let (c, _) = grid.nearest(x, neurons, None).unwrap_or((0, 0.0));
            let (before, after) = if closed {
                ((c + m - 1) % m, (c + 1) % m)
            } else {
                (c.saturating_sub(1), (c + 1).min(m - 1))
            };
            let direction = sub(neurons[after], neurons[before]);
            let steps = (after as f64 - before as f64).rem_euclid(m as f64).max(1.0);
            let length2 = dot(direction, direction);
            let tau = if length2 > 0.0 {
                (steps * dot(sub(x, neurons[c]), direction) / length2).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            c as f64 + tau
        })
        .collect();
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        chain_position[a]
            .total_cmp(&chain_position[b])
            .then(a.cmp(&b))
    });
    Ok(Ordering {
        order,
        closed,
        chain_position,
    })
}

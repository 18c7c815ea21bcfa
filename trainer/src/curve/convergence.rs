//! The paper's two convergence tests of a chain, and the spacing that scales their
//! tolerances.

use serde::{Deserialize, Serialize};

use super::grid::NeuronGrid;
use super::points::CurvePoints;
use crate::geometry::vector::distance_to_line;

/// Both convergence tests on one chain state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Convergence {
    /// ε of the paper's test, in the data's units.
    pub epsilon: f64,
    /// The paper's test: every input point has a neuron within ε.
    pub within_epsilon: bool,
    /// The largest distance from an input point to its nearest neuron.
    pub worst_input_distance: f64,
    /// Tolerance of the strong test, in the data's units.
    pub line_tolerance: f64,
    /// The strong test: every neuron that wins no input lies within the tolerance of the
    /// line through its two chain neighbours (for an open chain's end neuron: the line
    /// through the next two).
    pub on_neighbour_lines: bool,
    /// The largest such distance (0 when every neuron wins an input).
    pub worst_line_distance: f64,
    /// Neurons that win at least one input point.
    pub winning_neurons: usize,
}

impl Convergence {
    /// Both tests passed.
    pub fn converged(&self) -> bool {
        self.within_epsilon && self.on_neighbour_lines
    }
}

/// Runs both tests; `grid` must be up to date with `neurons`. O(n + m) plus n grid queries.
pub(crate) fn check_chain(
    data: &[[f64; 3]],
    neurons: &[[f64; 3]],
    grid: &NeuronGrid,
    closed: bool,
    epsilon: f64,
    line_tolerance: f64,
) -> Convergence {
    let m = neurons.len();
    let mut wins = vec![false; m];
    let mut worst_input_distance: f64 = 0.0;
    for &x in data {
        if let Some((c, d2)) = grid.nearest(x, neurons, None) {
            wins[c] = true;
            worst_input_distance = worst_input_distance.max(d2.sqrt());
        } else {
            worst_input_distance = f64::INFINITY;
        }
    }
    let mut worst_line_distance: f64 = 0.0;
    if m >= 3 {
        for j in (0..m).filter(|&j| !wins[j]) {
            let (a, b) = if closed {
                ((j + m - 1) % m, (j + 1) % m)
            } else if j == 0 {
                (1, 2)
            } else if j == m - 1 {
                (m - 2, m - 3)
            } else {
                (j - 1, j + 1)
            };
            let d = distance_to_line(neurons[j], neurons[a], neurons[b]);
            worst_line_distance = worst_line_distance.max(d);
        }
    }
    Convergence {
        epsilon,
        within_epsilon: worst_input_distance <= epsilon,
        worst_input_distance,
        line_tolerance,
        on_neighbour_lines: worst_line_distance <= line_tolerance,
        worst_line_distance,
        winning_neurons: wins.iter().filter(|&&w| w).count(),
    }
}

/// The median distance from an input point to its nearest other input point (positive:
/// validation rejects duplicates). O(n) expected with a grid.
pub(crate) fn point_spacing(points: &CurvePoints) -> f64 {
    let (lower, upper) = points.bounds();
    let data = points.points();
    let grid = NeuronGrid::new(lower, upper, data);
    let mut nearest: Vec<f64> = data
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            grid.nearest(p, data, Some(i))
                .map_or(f64::INFINITY, |(_, d2)| d2.sqrt())
        })
        .collect();
    let middle = nearest.len() / 2;
    let (_, median, _) = nearest.select_nth_unstable_by(middle, f64::total_cmp);
    *median
}

//! The normal equations of a surface network, one set per output coordinate.
//!
//! Row k of J (output k of a point) is zero at the output-layer weights and biases of the two
//! other outputs. Multiplying full rows would spend a fifth of JᵀJ (2 × 12 network: 26 of
//! 231 columns) on those zeros; instead, row k goes to its own [`NormalEquations`] over the
//! columns [hidden parameters, output k's weights, output k's bias], and
//! [`OutputNormalEquations::add_to`] places the three sums in the full system: the hidden
//! block is their sum, output k's columns come from set k alone, and the entries between two
//! outputs' weights are exactly 0. That is (P_h + n + 1)² instead of P² per row: 0.79× for
//! 2 × 12, 0.43× for 1 × 12.

use crate::solve::{DampedSystem, NormalEquations};

/// J's rows of one part of the training set, split by output coordinate.
pub(crate) struct OutputNormalEquations {
    /// Per output k: columns [0, hidden) are the hidden layers' parameters, then output k's
    /// `last_hidden` weights and its bias.
    sets: [NormalEquations; 3],
    hidden: usize,
    last_hidden: usize,
}

impl OutputNormalEquations {
    /// Empty sums for a network with `hidden` parameters below the output layer and
    /// `last_hidden` neurons in the last hidden layer (f32 products, see
    /// [`NormalEquations::single_precision`]).
    pub(crate) fn new(hidden: usize, last_hidden: usize) -> Self {
        let columns = hidden + last_hidden + 1;
        OutputNormalEquations {
            sets: std::array::from_fn(|_| NormalEquations::single_precision(columns)),
            hidden,
            last_hidden,
        }
    }

    /// Row stride of the blocks [`Self::rows_mut`] hands out.
    pub(crate) fn stride(&self) -> usize {
        self.sets[0].stride()
    }

    /// Most points [`Self::rows_mut`] takes at once.
    pub(crate) fn max_points(&self) -> usize {
        self.sets[0].max_rows()
    }

    /// Zeroes the sums.
    pub(crate) fn clear(&mut self) {
        self.sets.iter_mut().for_each(NormalEquations::clear);
    }

    /// The next `points` rows of each output (rows with [`Self::stride`]) and their residuals.
    pub(crate) fn rows_mut(&mut self, points: usize) -> [(&mut [f64], &mut [f64]); 3] {
        self.sets.each_mut().map(|set| set.rows_mut(points))
    }

    /// Multiplies the pending rows in.
    pub(crate) fn finish(&mut self) {
        self.sets.iter_mut().for_each(NormalEquations::finish);
    }

    /// The network parameter of set `k`'s column `c` (parameters are ordered layer by layer:
    /// the output layer's 3 × `last_hidden` weights, row by row, then its 3 biases).
    fn parameter(&self, k: usize, c: usize) -> usize {
        let (h, n) = (self.hidden, self.last_hidden);
        if c < h {
            c
        } else if c < h + n {
            h + k * n + (c - h)
        } else {
            h + 3 * n + k
        }
    }

    /// Writes Σ over `parts` of JᵀJ into `system`'s matrix and −Σ Jᵀe into its right-hand
    /// side (both fully overwritten; sums in part order, so independent of thread count).
    pub(crate) fn add_to(parts: &[&OutputNormalEquations], system: &mut DampedSystem) {
        let Some(first) = parts.first() else {
            return;
        };
        let p = first.hidden + 3 * first.last_hidden + 3;
        for i in 0..p {
            system.lhs_row_mut(i).fill(0.0);
        }
        system.rhs_mut().fill(0.0);
        let columns = first.hidden + first.last_hidden + 1;
        for k in 0..3 {
            for c in 0..columns {
                let i = first.parameter(k, c);
                let row = system.lhs_row_mut(i);
                for d in c..columns {
                    // `parameter` grows with the column, so (i, j) stays on the upper triangle.
                    let j = first.parameter(k, d);
                    row[j - i] += parts.iter().map(|s| s.sets[k].gram(c, d)).sum::<f64>();
                }
                system.rhs_mut()[i] -= parts.iter().map(|s| s.sets[k].gradient(c)).sum::<f64>();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The column map follows the network's own parameter order: numbered parameters, read
    /// back from the output layer's weights and biases.
    #[test]
    fn columns_map_to_the_networks_output_parameters() {
        use crate::parametric::activation::Activation;
        use crate::parametric::network::SurfaceNetwork;
        for hidden in [vec![1], vec![4, 3], vec![2, 5, 6]] {
            let mut net = SurfaceNetwork::zeros(
                &hidden,
                Activation::TanSig,
                [0.0; 2],
                [1.0; 2],
                [0.0; 3],
                1.0,
            )
            .unwrap();
            let p = net.parameter_count();
            let numbered: Vec<f64> = (0..p).map(|j| j as f64).collect();
            net.set_parameters(&numbered).unwrap();
            let top = net.layers.last().unwrap();
            let n = top.inputs;
            let below = p - top.parameter_count();
            let layout = OutputNormalEquations::new(below, n);
            for k in 0..3 {
                for c in 0..below {
                    assert_eq!(layout.parameter(k, c), c);
                }
                for i in 0..n {
                    // weights[k·n + i]: output k's weight from hidden neuron i.
                    assert_eq!(
                        layout.parameter(k, below + i),
                        top.weights[k * n + i] as usize
                    );
                }
                assert_eq!(layout.parameter(k, below + n), top.biases[k] as usize);
            }
        }
    }

    /// Compact rows of two parts, placed by `add_to`, against JᵀJ and Jᵀe of the full rows.
    #[test]
    fn the_split_sums_equal_the_full_normal_equations() {
        let (hidden, n) = (7, 3);
        let p = hidden + 3 * n + 3;
        let mut full = vec![vec![0.0; p]; p];
        let mut gradient = vec![0.0; p];
        let mut parts = [0, 1].map(|_| OutputNormalEquations::new(hidden, n));
        for (s, part) in parts.iter_mut().enumerate() {
            let layout = OutputNormalEquations::new(hidden, n);
            for point in 0..5 {
                let blocks = part.rows_mut(1);
                for (k, (row, e)) in blocks.into_iter().enumerate() {
                    let value = |c: usize| ((s * 31 + point * 7 + k * 3 + c) % 11) as f64 - 5.0;
                    let mut expanded = vec![0.0; p];
                    for c in 0..hidden + n + 1 {
                        row[c] = value(c);
                        expanded[layout.parameter(k, c)] = value(c);
                    }
                    e[0] = (point as f64) - 2.0 + k as f64;
                    for i in 0..p {
                        gradient[i] += expanded[i] * e[0];
                        for j in 0..p {
                            full[i][j] += expanded[i] * expanded[j];
                        }
                    }
                }
            }
            part.finish();
        }
        let mut system = DampedSystem::new(p);
        OutputNormalEquations::add_to(&[&parts[0], &parts[1]], &mut system);
        for i in 0..p {
            // Integer-valued entries below 2²⁴: the f32 products are exact.
            assert_eq!(system.rhs_mut()[i], -gradient[i], "gradient {i}");
            let row = system.lhs_row_mut(i).to_vec();
            for j in i..p {
                assert_eq!(row[j - i], full[i][j], "({i}, {j})");
            }
        }
    }
}

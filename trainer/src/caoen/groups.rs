//! Key order for compact blending: the core groups [`GROUP_KEYS`] consecutive key points and
//! skips a group whose keys cannot reach a source point (`neurosurf_core::caoen`), bounding
//! every key of the group by its first key's cosine plus |x| times the group's reach. How
//! much it skips depends on that reach, so the keys are ordered here: split recursively at a
//! multiple of [`GROUP_KEYS`] along the weights' widest coordinate, and each group's key
//! nearest its mean first. The network's function is unchanged (a sum over keys, in another
//! order).

use neurosurf_core::caoen::GROUP_KEYS;

use super::network::CaoEnNetwork;

/// `network` with its key points reordered for group skipping (see the module documentation).
///
/// ```
/// use neurosurf_trainer::caoen::{CaoEnNetwork, order_for_groups};
/// let weights: Vec<Vec<f64>> = (0..20)
///     .map(|i| {
///         let a = i as f64 * 0.3;
///         vec![a.cos(), a.sin(), 0.0]
///     })
///     .collect();
/// let network = CaoEnNetwork {
///     domain: 0,
///     blending: 2,
///     normalized: false,
///     targets: weights.clone(),
///     weights,
///     sharpness: vec![2.0; 20],
/// };
/// let ordered = order_for_groups(&network);
/// let x = [0.6, 0.8, 0.0];
/// let (a, b) = (network.position(&x), ordered.position(&x));
/// assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-12));
/// ```
pub fn order_for_groups(network: &CaoEnNetwork) -> CaoEnNetwork {
    let mut order: Vec<usize> = (0..network.key_count()).collect();
    split(&network.weights, &mut order);
    let pick = |values: &[Vec<f64>]| order.iter().map(|&i| values[i].clone()).collect();
    CaoEnNetwork {
        weights: pick(&network.weights),
        targets: pick(&network.targets),
        sharpness: order.iter().map(|&i| network.sharpness[i]).collect(),
        ..network.clone()
    }
}

/// Orders `keys` (indices into `weights`) into compact groups, in place.
fn split(weights: &[Vec<f64>], keys: &mut [usize]) {
    if keys.len() <= GROUP_KEYS {
        lead_with_nearest_to_mean(weights, keys);
        return;
    }
    let m = weights[keys[0]].len();
    let spread = |h: usize| {
        let (lo, hi) = keys
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |r, &i| {
                (r.0.min(weights[i][h]), r.1.max(weights[i][h]))
            });
        hi - lo
    };
    let axis = (0..m)
        .max_by(|&a, &b| spread(a).total_cmp(&spread(b)))
        .unwrap_or(0);
    keys.sort_by(|&a, &b| {
        weights[a][axis]
            .total_cmp(&weights[b][axis])
            .then(a.cmp(&b))
    });
    // The left part: half of the groups, rounded up, all full.
    let groups = keys.len().div_ceil(GROUP_KEYS);
    let left = groups.div_ceil(2) * GROUP_KEYS;
    let (a, b) = keys.split_at_mut(left.min(keys.len()));
    split(weights, a);
    split(weights, b);
}

/// Moves the key nearest the group's mean weight to the front.
fn lead_with_nearest_to_mean(weights: &[Vec<f64>], keys: &mut [usize]) {
    let Some(&first) = keys.first() else {
        return;
    };
    let m = weights[first].len();
    let mean: Vec<f64> = (0..m)
        .map(|h| keys.iter().map(|&i| weights[i][h]).sum::<f64>() / keys.len() as f64)
        .collect();
    let distance = |i: usize| -> f64 {
        weights[i]
            .iter()
            .zip(&mean)
            .map(|(a, b)| (a - b) * (a - b))
            .sum()
    };
    if let Some(best) = (0..keys.len()).min_by(|&a, &b| {
        distance(keys[a])
            .total_cmp(&distance(keys[b]))
            .then(a.cmp(&b))
    }) {
        keys.swap(0, best);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every group's reach (largest distance from its first weight) is well below the
    /// diameter for keys spread over the sphere (measured: largest 0.96, mean 0.73; 2.0 is
    /// the sphere's diameter).
    #[test]
    fn groups_are_compact() {
        let n = 104;
        let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
        let weights: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let a = golden * i as f64;
                vec![r * a.cos(), r * a.sin(), z]
            })
            .collect();
        // Shuffle deterministically so the input order carries no locality.
        let mut shuffled: Vec<usize> = (0..n).map(|i| (i * 37) % n).collect();
        shuffled.dedup();
        let network = CaoEnNetwork {
            domain: 0,
            blending: 2,
            normalized: false,
            weights: shuffled.iter().map(|&i| weights[i].clone()).collect(),
            targets: shuffled.iter().map(|&i| weights[i].clone()).collect(),
            sharpness: vec![2.0; n],
        };
        let ordered = order_for_groups(&network);
        let mut sorted = ordered.weights.clone();
        sorted.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let mut expected = weights.clone();
        expected.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(sorted, expected, "a permutation of the keys");
        let reach = |group: &[Vec<f64>]| {
            group
                .iter()
                .map(|w| {
                    w.iter()
                        .zip(&group[0])
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(0.0, f64::max)
        };
        let worst = ordered
            .weights
            .chunks(GROUP_KEYS)
            .map(reach)
            .fold(0.0, f64::max);
        let input_worst = network
            .weights
            .chunks(GROUP_KEYS)
            .map(reach)
            .fold(0.0, f64::max);
        let mean = ordered.weights.chunks(GROUP_KEYS).map(reach).sum::<f64>()
            / n.div_ceil(GROUP_KEYS) as f64;
        // 13 groups of the unit sphere: a cap of 1/13 of its area has a chord radius of 0.55.
        assert!(
            worst < 1.0 && mean < 0.8,
            "group reach: largest {worst}, mean {mean}"
        );
        assert!(
            input_worst > 1.5,
            "the shuffled order is not grouped ({input_worst})"
        );
    }
}

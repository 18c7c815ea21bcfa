//! The 85 / 10 / 5 split of §5.2 with stratified sampling over parameter-space cells (Fig. 8).
//!
//! The parameter bounding box is cut into g × g cells (g = ⌈√(n/20)⌉, about 20 points per
//! cell); the points are ordered cell by cell, shuffled inside each cell, and dealt by a
//! repeating pattern of 20 (17 training, 2 validation at positions 4 and 14, 1 test at 9), so
//! every cell contributes to each set in proportion and no region of the surface is left out
//! of training.

use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;

/// Indices of the training, validation and test points.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Split {
    /// ≈ 85 %.
    pub training: Vec<usize>,
    /// ≈ 10 %.
    pub validation: Vec<usize>,
    /// ≈ 5 %.
    pub test: Vec<usize>,
}

/// Stratified split of `parameters` (see the module docs). Sets of fewer than 20 points still
/// get at least one validation and one test point when there are at least 3 points.
pub fn stratified_split(parameters: &[[f64; 2]], seed: u64) -> Split {
    let n = parameters.len();
    let cells = ((n as f64 / 20.0).sqrt().ceil() as usize).max(1);
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in parameters {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let cell_of = |p: &[f64; 2]| -> usize {
        let c: [usize; 2] = std::array::from_fn(|a| {
            let t = (p[a] - lo[a]) / (hi[a] - lo[a]).max(f64::MIN_POSITIVE);
            ((t * cells as f64) as usize).min(cells - 1)
        });
        c[0] * cells + c[1]
    };
    let mut buckets = vec![Vec::new(); cells * cells];
    for (i, p) in parameters.iter().enumerate() {
        buckets[cell_of(p)].push(i);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut split = Split::default();
    let mut position = 0usize;
    for bucket in buckets.iter_mut() {
        bucket.shuffle(&mut rng);
        for &i in bucket.iter() {
            match position % 20 {
                4 | 14 => split.validation.push(i),
                9 => split.test.push(i),
                _ => split.training.push(i),
            }
            position += 1;
        }
    }
    // Small sets: make sure validation and test are not empty.
    if n >= 3 {
        if split.validation.is_empty()
            && let Some(i) = split.training.pop()
        {
            split.validation.push(i);
        }
        if split.test.is_empty()
            && let Some(i) = split.training.pop()
        {
            split.test.push(i);
        }
    }
    split
}

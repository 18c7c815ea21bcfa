//! From a raw oriented point set to a trained model: features (given, decomposed or one),
//! the tree (given, inherited from the initial model, or balanced), and training.

use super::blob::DecodedImplicit;
use super::capacity::check_capacity;
use super::features::decompose;
use super::options::ImplicitOptions;
use super::train::{Progress, Trained, train_with};
use super::tree::TreeSpec;
use crate::error::{Error, Result};
use crate::points::PointSet;

/// What to train besides the points and the options.
#[derive(Clone, Debug, Default)]
pub struct FitRequest {
    /// Split unlabelled points into this many features (ignored when the points carry labels).
    pub features: Option<usize>,
    /// The module tree; by default the initial model's, else balanced over the features.
    pub tree: Option<TreeSpec>,
    /// Warm start from this model (same tree and width).
    pub init: Option<DecodedImplicit>,
    /// Leave out the sign guards: Carcenac's procedure alone (Table 5 times it).
    pub unguarded: bool,
}

/// Labels the points, chooses the tree and trains.
///
/// Points without labels form a single feature unless `request.features` asks for an
/// automatic decomposition. With a warm start the width is the initial model's.
///
/// # Errors
/// [`Error::InvalidInput`] for unusable points (see [`PointSet::validated`]), a tree that
/// does not match the features, an initial model of another shape, and every training error.
pub fn fit(
    points: PointSet,
    request: &FitRequest,
    options: &ImplicitOptions,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Trained> {
    let mut points = points.validated()?;
    if let (Some(k), None) = (request.features, &request.init) {
        check_capacity(k, options.width)?;
    }
    let mut options = options.clone();
    if points.features.is_none() {
        let labels = match request.features {
            Some(k) if k > 1 => {
                options.seam_band = true;
                decompose(&points.positions, k, options.min_points)?
            }
            Some(0) => return Err(Error::invalid("--features must be at least 1")),
            _ => vec![0; points.len()],
        };
        points.features = Some(labels);
    }
    let labels = points.features.as_deref().unwrap_or_default();
    if let Some(init) = &request.init {
        options.width = init.network.width();
    }
    let tree = match (&request.tree, &request.init) {
        (Some(tree), _) => tree.clone(),
        (None, Some(init)) => init.network.tree(),
        (None, None) => TreeSpec::balanced(&feature_centroids(&points.positions, labels))?,
    };
    let cold: Vec<usize> = request
        .init
        .as_ref()
        .and_then(|init| init.metadata.as_ref())
        .and_then(|m| m.summary.as_ref())
        .map(|s| s.cold_iterations.clone())
        .unwrap_or_default();
    let init = request.init.as_ref().map(|i| (&i.network, cold.as_slice()));
    train_with(&points, &tree, &options, init, progress, !request.unguarded)
}

/// The centroid of each feature's points (features numbered densely from 0; an empty feature
/// gets the origin and is rejected later by training).
pub fn feature_centroids(positions: &[[f64; 3]], labels: &[u32]) -> Vec<[f64; 3]> {
    let count = labels.iter().map(|&f| f as usize + 1).max().unwrap_or(0);
    let mut sums = vec![[0.0; 3]; count];
    let mut counts = vec![0usize; count];
    for (p, &f) in positions.iter().zip(labels) {
        let f = f as usize;
        counts[f] += 1;
        for k in 0..3 {
            sums[f][k] += p[k];
        }
    }
    sums.iter()
        .zip(&counts)
        .map(|(s, &c)| s.map(|v| v / c.max(1) as f64))
        .collect()
}

//! Carcenac §7's human body, trained: 17 leaf modules on their features, 16 node modules
//! blending them along [`BODY_TREE`], measured against the true posed surface.

use serde::Serialize;

use crate::error::Result;
use crate::fidelity::{Fidelity, diameter};
use crate::implicit::{ImplicitNetwork, ImplicitOptions, Progress, Trained, TreeSpec, train};
use crate::points::PointSet;
use crate::quality::{
    MEASURE_RESOLUTION, STRAY_RESOLUTION, Truth, TwoSided, grown_bounds, two_sided,
};
use crate::render::{DEFAULT_BOX_SIZE, DEFAULT_INFLATE, NetworkField};
use crate::sample::{BODY_POINTS, BODY_TREE, Body, Pose, scaled_counts};

/// Held-out points the body is measured on (spread over the features like the control points).
pub const BODY_HELD_OUT: usize = 2000;

/// The seed offset of the held-out points (so they are never the control points).
const HELD_OUT_SEED: u64 = 1_000_003;

/// The body's control points in `pose`.
///
/// # Errors
/// None expected on the built-in poses (see [`Body::sample`]).
pub fn body_points(pose: &Pose, seed: u64) -> Result<PointSet> {
    Body::new(pose).sample(&BODY_POINTS, seed)
}

/// The body's tree ([`BODY_TREE`]).
///
/// # Errors
/// None expected: the constant is parsed and checked by the sampler's tests.
pub fn body_tree() -> Result<TreeSpec> {
    BODY_TREE.parse()
}

/// Trains the body on `points` (cold, or warm from `init`: a previous frame's network and its
/// chain's cold-start iterations).
///
/// # Errors
/// Training errors (none expected on the built-in body).
pub fn train_body(
    points: &PointSet,
    options: &ImplicitOptions,
    init: Option<(&ImplicitNetwork, &[usize])>,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Trained> {
    train(points, &body_tree()?, options, init, progress)
}

/// How close a trained body is to the true surface in `pose`.
///
/// # Errors
/// None expected (sampling the built-in body).
pub fn body_fidelity(network: &ImplicitNetwork, pose: &Pose, seed: u64) -> Result<Fidelity> {
    let held_out = Body::new(pose).sample(
        &scaled_counts(BODY_HELD_OUT),
        seed.wrapping_add(HELD_OUT_SEED),
    )?;
    let d = diameter(&held_out.positions);
    Fidelity::measure(&held_out, d, |p| network.eval(p))
        .ok_or_else(|| crate::Error::invalid("the body model has a vanishing gradient"))
}

/// The body model against the true surface in `pose`, both ways (see
/// [`two_sided`](crate::quality::two_sided)): the truth is the body's signed distance meshed
/// at [`BODY_TRUTH_RESOLUTION`].
///
/// # Errors
/// None expected on the built-in poses.
pub fn body_two_sided(network: &ImplicitNetwork, pose: &Pose) -> Result<TwoSided> {
    let body = Body::new(pose);
    let sample = body.sample(&scaled_counts(BODY_HELD_OUT), HELD_OUT_SEED)?;
    let grown = grown_bounds(&Truth::from_points(&sample)?, 0.2);
    let truth =
        Truth::from_signed_distance(|p| body.signed_distance(p), grown, BODY_TRUTH_RESOLUTION)?;
    let field = NetworkField::new(network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE)?;
    two_sided(&field, &truth, MEASURE_RESOLUTION, STRAY_RESOLUTION)
}

/// Cells along the body's height when its true surface is meshed for [`body_two_sided`].
pub const BODY_TRUTH_RESOLUTION: usize = 160;

/// One module's training in the body (the paper's Fig. 9).
#[derive(Clone, Debug, Serialize)]
pub struct BodyModule {
    /// Module index (post-order).
    pub module: usize,
    /// The feature's name for a leaf, `node` otherwise.
    pub what: String,
    /// Control points it was trained on.
    pub points: usize,
    /// LM iterations.
    pub iterations: usize,
    /// Seconds.
    pub seconds: f64,
    /// Final E_s.
    pub error: f64,
}

/// The per-module story of a training (Fig. 9).
pub fn modules(trained: &Trained) -> Vec<BodyModule> {
    trained
        .summary
        .modules
        .iter()
        .map(|m| BodyModule {
            module: m.module,
            what: m.feature.map_or_else(
                || "node".to_string(),
                |f| {
                    crate::sample::BODY_FEATURES
                        .get(f as usize)
                        .map_or_else(|| format!("feature {f}"), |n| (*n).to_string())
                },
            ),
            points: m.points,
            iterations: m.lm.iterations,
            seconds: m.seconds,
            error: m.lm.error,
        })
        .collect()
}

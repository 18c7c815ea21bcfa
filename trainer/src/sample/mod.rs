//! Point samplers: analytic shapes, the posed human body and meshes.
//!
//! Every sampler draws points area-uniformly on the surface with exact outward unit normals
//! (on meshes, by default, spread evenly: see [`Spread`]), from a [`ChaCha8Rng`](rand_chacha::ChaCha8Rng) seeded with the caller's seed, so the same
//! seed always gives the same points on every platform.

mod body;
mod mesh;
mod shape;
mod spread;

pub use body::{BODY_FEATURES, BODY_POINTS, BODY_TREE, Body, Pose, scaled_counts};
pub use mesh::sample_mesh;
pub use shape::{HEAD_FEATURES, Shape, sample_shape};
pub use spread::{CANDIDATES_PER_POINT, MAX_EVEN_POINTS, Spread};

use crate::error::{Error, Result};

/// The largest point count a sampler accepts; more is almost certainly a typo and would
/// exhaust memory.
pub const MAX_SAMPLES: usize = 50_000_000;

/// Checks a requested point count.
fn check_count(count: usize) -> Result<()> {
    if count == 0 {
        return Err(Error::invalid("the point count must be at least 1"));
    }
    if count > MAX_SAMPLES {
        return Err(Error::invalid(format!(
            "{count} points requested, at most {MAX_SAMPLES} are supported"
        )));
    }
    Ok(())
}

//! How well a model reproduces a known surface, measured both ways: from the true surface to
//! the model and from the model back to the true surface, with the normals, the pieces of the
//! model's mesh, and stray surface far from the data.
//!
//! A measure taken only on points of the true surface looks excellent on a model that grows
//! sheets and blobs elsewhere; [`two_sided`] looks everywhere in the grown bounding box.

mod stray;
mod truth;
mod two_sided;

pub use stray::{
    FAR_FRACTION, STRAY_GROWTH, STRAY_RESOLUTION, StrayReport, grown_bounds, stray_surface,
};
pub use truth::{Truth, signed_distance_mesh};
pub use two_sided::{
    Distances, MEASURE_RESOLUTION, MeshCheck, TwoSided, component_labels, components, two_sided,
};

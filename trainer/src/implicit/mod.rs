//! Carcenac's modular implicit surfaces, host side: the `f64` network, the analytic Jacobian,
//! Levenberg–Marquardt, PCA-box normalization, module trees and automatic features, training,
//! and conversion to and from blobs.

mod activation;
mod blob;
mod capacity;
mod constraints;
mod features;
mod frame;
mod grid_cache;
mod guards;
mod jacobian;
mod network;
mod normalize;
mod options;
mod oracle;
pub mod overlap;
mod pipeline;
mod problem;
mod train;
mod tree;
mod value_rows;

pub use activation::{Activation, activation};
pub use blob::{DecodedImplicit, ImplicitMetadata, check_storable, from_blob, to_blob};
pub use capacity::{check_capacity, fits, model_size};
pub use features::decompose;
pub use frame::{Frame, MODEL_DIAGONAL};
pub use grid_cache::{CachedField, GridCache};
pub use guards::{
    GUARD_CLEARANCE, GUARD_RESOLUTION, PIECE_SUPPORT, guard_stray_pieces, place_guards,
};
pub use jacobian::{HiddenJet, InputJet, MAX_INPUTS, Tape, TrainedLayout, forward, jacobian_rows};
pub use network::{Guard, ImplicitNetwork};
pub use normalize::{BoxScaling, Normalization};
pub use options::ImplicitOptions;
pub use oracle::Oracle;
pub use pipeline::{FitRequest, feature_centroids, fit};
pub use problem::{ModuleData, ModuleProblem, ValueGoal};
pub use train::{ModuleReport, Outcome, Progress, Trained, TrainingSummary, train};
pub use tree::TreeSpec;

#[cfg(test)]
mod tests;

//! Carcenac's modular implicit surfaces: a binary tree of small MLP modules whose output Φ is
//! zero on the surface.
//!
//! - [`layout`](ModuleLayout): where each module's weights lie (shared with the trainer);
//! - [`ImplicitModel`]: decoding and validation of a blob;
//! - [`guard`]: sign guards, compactly supported bumps that fix Φ's sign away from the data;
//! - evaluation of Φ, ∇Φ (reverse mode) and the unit normal, for one point or in batches of
//!   [`LANES`], for the whole tree or any module's subtree ([`ModuleView`]).

mod activation;
mod batch;
mod eval;
pub mod guard;
mod layout;
mod model;
mod reverse;
mod width;

pub use activation::Activation;
pub use batch::LANES;
pub(crate) use batch::WIDE_LANES;
pub use eval::{FieldGradient, ModuleView};
pub use guard::{GUARD_CODE, GUARD_LEN, MAX_GUARDS};
pub use layout::{DenseLayout, MAX_HEIGHT, MAX_WIDTH, ModuleKind, ModuleLayout, NORMALIZATION_LEN};
pub use model::{
    DEFAULT_MODULES, DEFAULT_PARAMETERS, ImplicitModel, ImplicitPayload, MODULE_PARAMETERS,
};
pub use width::SPECIALIZED as SPECIALIZED_WIDTHS;

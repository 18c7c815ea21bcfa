//! The RBF baseline (Carcenac §9): a host-only implicit surface
//! f(x) = Σ wᵢ √(|x − cᵢ|² + c²) + a·x + b interpolating an oriented point set, fitted by one
//! dense linear solve, for comparison with the neural implicit model.
//!
//! A fair peer, as a user would set one up: Hermite-style off-surface points on both sides of
//! every control point (at ±ε along the normal, ε halved until the point's nearest control
//! point is its own, Carr et al. 2001), every length relative to the data's bounding diagonal
//! D (so units and position do not matter), and one dense Cholesky factorization by faer on
//! every core. The kernel is Carcenac's multiquadric by default (c = 0.0078·D, which is his
//! c² = 10⁻³ on the Table 5 torus), or the biharmonic φ(r) = r ([`RbfKernel::Biharmonic`]).
//! `render::RbfField` renders and meshes a model.
//!
//! ```
//! use neurosurf_trainer::PointSet;
//! use neurosurf_trainer::rbf::{RbfModel, RbfOptions, fit};
//! // Eight points on the unit sphere with outward normals.
//! let positions: Vec<[f64; 3]> = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
//!     [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.6, 0.8, 0.0], [0.0, 0.6, -0.8]]
//!     .to_vec();
//! let points = PointSet { normals: positions.clone(), positions, features: None };
//! let (model, report) = fit(&points, &RbfOptions::default())?;
//! assert!(model.field([0.0; 3]) > 0.0 && model.field([2.0, 0.0, 0.0]) < 0.0);
//! assert!(report.max_residual < 1e-9);
//! let again = RbfModel::from_blob(&model.to_blob()?, std::path::Path::new("sphere.rbf"))?;
//! assert_eq!(again, model);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod blob;
mod condition;
mod fit;
mod kernel;
mod model;
mod options;
mod solve;

pub use blob::RBF_SCALAR;
pub use fit::{DUPLICATE_TOLERANCE, RESIDUAL_TOLERANCE, RbfReport, fit};
pub use kernel::{multiquadric, multiquadric_gradient};
pub use model::{MAX_CENTERS, RbfModel};
pub use options::{
    C_RELATIVE, EPSILON_RELATIVE, MAX_HALVINGS, MAX_POINTS, MIN_POINTS, RbfKernel, RbfOptions,
};

#[cfg(test)]
mod tests;

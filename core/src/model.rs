//! One path for every model kind. [`Model`] is what code that serves, fuzzes, evaluates or
//! describes *any* blob needs from a model, and [`visit`] runs such code with the model type a
//! blob's header names. Each family implements [`Model`] beside its model; adding a kind is
//! its family folders plus one line in [`visit`]'s registry.
//!
//! ```
//! use neurosurf_core::blob::{self, ModelKind};
//! use neurosurf_core::model::{self, Model, ModelVisitor, MAX_OUTPUTS};
//! use neurosurf_core::scalar::{Scalar, ScalarKind};
//! use neurosurf_core::BlobError;
//!
//! /// The first output of any model at the origin, as `f32`.
//! struct FirstOutput<'a>(&'a [u8]);
//!
//! impl ModelVisitor for FirstOutput<'_> {
//!     type Output = Result<f32, BlobError>;
//!     fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output {
//!         let mut model = M::default();
//!         model.load_blob(self.0)?;
//!         let mut out = [S::ZERO; MAX_OUTPUTS];
//!         model.evaluate(&[S::ZERO; 3], false, &mut out);
//!         Ok(out[0].to_f32())
//!     }
//! }
//!
//! let bytes = include_bytes!("../examples/torus.nsb");
//! let (header, _) = blob::parse(bytes)?;
//! assert_eq!(header.model, ModelKind::Implicit);
//! let phi = model::visit(header.model, header.scalar, FirstOutput(bytes)).unwrap()?;
//! assert!(phi < 0.0); // the torus's hole is outside
//! # Ok::<(), BlobError>(())
//! ```

use crate::BlobError;
use crate::blob::ModelKind;
use crate::caoen::{CaoEnModel, MAX_SOURCE_DIMENSION, MAX_TARGET_DIMENSION};
use crate::curve::{BSplineCurve, BSplineSurface};
use crate::implicit::ImplicitModel;
use crate::parametric::SurfaceNetworkModel;
use crate::scalar::{Q16, Scalar, ScalarKind};

/// The most numbers an input point has over all kinds (a Cao En hypersphere's source point).
pub const MAX_INPUTS: usize = MAX_SOURCE_DIMENSION;
/// The most numbers a result has over all kinds (a Cao En network's outputs and its normal).
pub const MAX_OUTPUTS: usize = MAX_TARGET_DIMENSION + 3;

/// What every model kind offers code written once for all of them.
///
/// Loading validates everything; after a successful [`Model::load_blob`], [`Model::evaluate`]
/// cannot fail or panic, on any input.
pub trait Model<S: Scalar>: Default {
    /// The blob kind this model loads.
    const KIND: ModelKind;

    /// Loads a blob of this kind (see each model's `load`).
    ///
    /// # Errors
    /// The [`BlobError`] that names what is wrong.
    fn load_blob(&mut self, blob: &[u8]) -> Result<(), BlobError>;

    /// Numbers per input point: 3 for a position x, 1 for a curve's t, 2 for (u, v), the
    /// source dimension of a Cao En network. At most [`MAX_INPUTS`].
    fn input_len(&self) -> usize;

    /// Numbers per result: the value alone, or (`full`) with its derivative. At most
    /// [`MAX_OUTPUTS`].
    ///
    /// | kind | value | `full` adds |
    /// | --- | --- | --- |
    /// | implicit | Φ | ∇Φ |
    /// | curve | C(t) | dC/dt |
    /// | spline surface, surface network | position | unit normal (0, 0, 0 where none) |
    /// | Cao En | the p outputs | unit normal (0, 0, 0 where none, and unless p = 3) |
    fn output_len(&self, full: bool) -> usize;

    /// Evaluates one point: reads the first [`Model::input_len`] numbers of `input` (missing
    /// ones read as 0) and writes the first [`Model::output_len`] numbers of `out` (as many
    /// as fit).
    fn evaluate(&self, input: &[S], full: bool, out: &mut [S]);
}

/// Code generic over the model type, run by [`visit`] with the type a blob names.
pub trait ModelVisitor {
    /// What the code returns.
    type Output;
    /// Runs the code for model type `M` in scalar `S`.
    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output;
}

/// Runs `visitor` with the model type of `kind` stored as `scalar` (`f32` or Q16.16, at the
/// core's default capacities); `None` for a kind the core does not evaluate (the RBF baseline)
/// or a scalar the core does not evaluate in.
pub fn visit<V: ModelVisitor>(
    kind: ModelKind,
    scalar: ScalarKind,
    visitor: V,
) -> Option<V::Output> {
    macro_rules! registry {
        ($($kind:ident => $model:ident,)*) => {
            match (kind, scalar) {
                $(
                    (ModelKind::$kind, ScalarKind::F32) => Some(visitor.visit::<f32, $model<f32>>()),
                    (ModelKind::$kind, ScalarKind::Q16_16) => Some(visitor.visit::<Q16, $model<Q16>>()),
                )*
                _ => None,
            }
        };
    }
    registry! {
        Implicit => ImplicitModel,
        Curve => BSplineCurve,
        SplineSurface => BSplineSurface,
        CaoEn => CaoEnModel,
        SurfaceNetwork => SurfaceNetworkModel,
    }
}

/// The first `N` numbers of `input`, missing ones 0.
pub(crate) fn point<S: Scalar, const N: usize>(input: &[S]) -> [S; N] {
    let mut out = [S::ZERO; N];
    for (slot, &v) in out.iter_mut().zip(input) {
        *slot = v;
    }
    out
}

/// Writes `values` into `out`, as many as fit.
pub(crate) fn write<S: Scalar>(out: &mut [S], values: impl IntoIterator<Item = S>) {
    for (slot, v) in out.iter_mut().zip(values) {
        *slot = v;
    }
}

/// A normal's three numbers, (0, 0, 0) where there is none.
pub(crate) fn normal_or_zero<S: Scalar>(normal: Option<[S; 3]>) -> [S; 3] {
    normal.unwrap_or([S::ZERO; 3])
}

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
use core::mem::{align_of, size_of};

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

    /// Evaluates `inputs[i]` into `out[i]` for as many points as both hold, bit for bit as
    /// [`Model::evaluate`] does one point at a time. Kinds with a batch path (several points
    /// per pass over the parameters, [`LANES`](crate::implicit::LANES) at a time) take it.
    fn evaluate_batch(&self, inputs: &[[S; MAX_INPUTS]], full: bool, out: &mut [[S; MAX_OUTPUTS]]) {
        for (input, out) in inputs.iter().zip(out.iter_mut()) {
            self.evaluate(input, full, out);
        }
    }

    /// Multiply–accumulates of one evaluation, the value alone or (`full`) with its
    /// derivative: the lower bound of its cost.
    fn mac_count(&self, full: bool) -> usize;

    /// What the model holds, in one line (for example `3 modules, width 9, tree ((0,1),2)`),
    /// for `neurosurf info` and logs.
    ///
    /// # Errors
    /// Only those of `f`.
    fn describe(&self, f: &mut dyn core::fmt::Write) -> core::fmt::Result;
}

/// Code generic over the model type, run by [`visit`] with the type a blob names.
pub trait ModelVisitor {
    /// What the code returns.
    type Output;
    /// Runs the code for model type `M` in scalar `S`.
    fn visit<S: Scalar, M: Model<S>>(self) -> Self::Output;
}

/// The registry: every kind the core evaluates and its model type. [`visit`] dispatches on
/// it, and [`MAX_MODEL_BYTES`] and [`MAX_MODEL_ALIGN`] cover every type in it.
macro_rules! registry {
    ($($kind:ident => $model:ident,)*) => {
        /// Runs `visitor` with the model type of `kind` stored as `scalar` (`f32` or Q16.16, at
        /// the core's default capacities); `None` for a kind the core does not evaluate (the
        /// RBF baseline) or a scalar the core does not evaluate in.
        pub fn visit<V: ModelVisitor>(
            kind: ModelKind,
            scalar: ScalarKind,
            visitor: V,
        ) -> Option<V::Output> {
            match (kind, scalar) {
                $(
                    (ModelKind::$kind, ScalarKind::F32) => Some(visitor.visit::<f32, $model<f32>>()),
                    (ModelKind::$kind, ScalarKind::Q16_16) => Some(visitor.visit::<Q16, $model<Q16>>()),
                )*
                _ => None,
            }
        }

        /// The largest model type [`visit`] hands out, in bytes: storage that holds any of them
        /// (a firmware's one static slot for whatever blob it is given).
        pub const MAX_MODEL_BYTES: usize = {
            let mut bytes = 0;
            $(
                bytes = max(bytes, size_of::<$model<f32>>());
                bytes = max(bytes, size_of::<$model<Q16>>());
            )*
            bytes
        };

        /// The strictest alignment among the model types [`visit`] hands out.
        pub const MAX_MODEL_ALIGN: usize = {
            let mut align = 1;
            $(
                align = max(align, align_of::<$model<f32>>());
                align = max(align, align_of::<$model<Q16>>());
            )*
            align
        };
    };
}

registry! {
    Implicit => ImplicitModel,
    Curve => BSplineCurve,
    SplineSurface => BSplineSurface,
    CaoEn => CaoEnModel,
    SurfaceNetwork => SurfaceNetworkModel,
}

const fn max(a: usize, b: usize) -> usize {
    if a > b { a } else { b }
}

/// Points a kind's batch path is given at a time by [`batch`].
pub(crate) const BATCH_CHUNK: usize = 16;

/// [`Model::evaluate_batch`] through a kind's own batch call: up to [`BATCH_CHUNK`] points at a
/// time are turned into the call's inputs by `input`, evaluated by `run`, and their results
/// written by `output`.
pub(crate) fn batch<S: Scalar, I: Copy + Default, R: Copy + Default>(
    inputs: &[[S; MAX_INPUTS]],
    out: &mut [[S; MAX_OUTPUTS]],
    input: impl Fn(&[S; MAX_INPUTS]) -> I,
    run: impl Fn(&[I], &mut [R]),
    output: impl Fn(&R, &mut [S; MAX_OUTPUTS]),
) {
    let mut xs = [I::default(); BATCH_CHUNK];
    let mut rs = [R::default(); BATCH_CHUNK];
    for (inputs, out) in inputs.chunks(BATCH_CHUNK).zip(out.chunks_mut(BATCH_CHUNK)) {
        let n = inputs.len().min(out.len());
        let (Some(xs), Some(rs)) = (xs.get_mut(..n), rs.get_mut(..n)) else {
            return;
        };
        for (x, input_point) in xs.iter_mut().zip(inputs) {
            *x = input(input_point);
        }
        run(xs, rs);
        for (r, out) in rs.iter().zip(out) {
            output(r, out);
        }
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
pub(crate) fn write<S: Scalar, const N: usize>(out: &mut [S], values: [S; N]) {
    let n = out.len().min(N);
    if let (Some(out), Some(values)) = (out.get_mut(..n), values.get(..n)) {
        out.copy_from_slice(values);
    }
}

/// Writes `values` into `out`, as many as fit (for results whose length is known at run time).
pub(crate) fn write_each<S: Scalar>(out: &mut [S], values: impl IntoIterator<Item = S>) {
    for (slot, v) in out.iter_mut().zip(values) {
        *slot = v;
    }
}

/// Two triples as one result: a position and its tangent or normal.
pub(crate) fn pair<S: Scalar>([x, y, z]: [S; 3], [u, v, w]: [S; 3]) -> [S; 6] {
    [x, y, z, u, v, w]
}

/// [`batch`] for a kind whose value is a position: `run` fills one per input (the lengths
/// agree by construction, so its length error never happens).
pub(crate) fn positions<S: Scalar, I: Copy + Default, E>(
    inputs: &[[S; MAX_INPUTS]],
    out: &mut [[S; MAX_OUTPUTS]],
    input: impl Fn(&[S; MAX_INPUTS]) -> I,
    run: impl Fn(&[I], &mut [[S; 3]]) -> Result<(), E>,
) {
    batch(
        inputs,
        out,
        input,
        |x, positions| {
            let _ = run(x, positions);
        },
        |&p: &[S; 3], out| write(out, p),
    );
}

/// `"closed"` or `"open"`.
pub(crate) fn open_or_closed(closed: bool) -> &'static str {
    if closed { "closed" } else { "open" }
}

/// A normal's three numbers, (0, 0, 0) where there is none.
pub(crate) fn normal_or_zero<S: Scalar>(normal: Option<[S; 3]>) -> [S; 3] {
    normal.unwrap_or([S::ZERO; 3])
}

//! The validated implicit model and its blob decoder.

use heapless::Vec;
use serde::{Deserialize, Serialize};

use super::guard::{GUARD_LEN, MAX_GUARDS, split_tree};
use super::layout::{MAX_HEIGHT, MAX_WIDTH, ModuleKind, ModuleLayout, NORMALIZATION_LEN};
use crate::blob::{self, ModelKind};
use crate::error::{BlobError, Quantity};
use crate::frame::{Frame, FramePayload};
use crate::scalar::{Scalar, ScalarKind};

/// The modules' share of the default parameter capacity: a 17-leaf, 16-node body model of
/// width 9 needs 7 476 (17 × 148 + 16 × 310).
pub const MODULE_PARAMETERS: usize = 8192;
/// Default parameter capacity: [`MODULE_PARAMETERS`] for the modules and room for
/// [`MAX_GUARDS`] sign guards beside them (9 472).
pub const DEFAULT_PARAMETERS: usize = MODULE_PARAMETERS + MAX_GUARDS * GUARD_LEN;
/// Default module capacity.
pub const DEFAULT_MODULES: usize = 64;

/// The postcard payload of an implicit-model blob (see [`crate::blob`] for the framing).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ImplicitPayload<'a> {
    /// Hidden width N of every module.
    pub width: u8,
    /// Where the modules' coordinates sit among the user's ([`crate::frame`]).
    #[serde(borrow)]
    pub frame: FramePayload<'a>,
    /// Module kinds in post-order ([`ModuleKind::code`]), then one
    /// [`GUARD_CODE`](super::GUARD_CODE) per sign guard.
    #[serde(borrow)]
    pub tree: &'a [u8],
    /// All parameters in [`ModuleLayout`](super::ModuleLayout) order, then
    /// [`GUARD_LEN`](super::GUARD_LEN) per guard; 4 little-endian bytes each in the blob's
    /// scalar kind.
    #[serde(borrow)]
    pub parameters: &'a [u8],
    /// Opaque to the core (the trainer stores its training summary here).
    #[serde(borrow)]
    pub metadata: &'a [u8],
}

impl<'a> ImplicitPayload<'a> {
    /// Parses and frames-checks an implicit blob without building a model.
    ///
    /// # Errors
    /// Framing errors of [`blob::parse`], [`BlobError::WrongModelKind`],
    /// [`BlobError::MalformedPayload`].
    pub fn from_blob(bytes: &'a [u8]) -> Result<(blob::BlobHeader, Self), BlobError> {
        blob::decode_kind(bytes, ModelKind::Implicit)
    }
}

/// Where one module sits: its kind, its parameters and its children.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub(crate) struct ModuleEntry {
    pub(crate) kind: ModuleKind,
    /// Offset of the module's first parameter.
    pub(crate) offset: usize,
    /// Index of the first module of this module's subtree.
    pub(crate) subtree_start: usize,
    /// Index of the left child (nodes only; the right child is `index − 1`).
    pub(crate) left: usize,
    /// Height of the subtree (leaf = 1).
    pub(crate) height: usize,
}

/// A modular implicit surface Φ (Carcenac 2004), loaded from a blob and validated.
///
/// `P` and `M` are the parameter and module capacities reserved inline (no heap): the defaults
/// take 37 KiB in `f32` and hold a 33-module body model with 256 guards. Evaluation after a
/// successful load cannot fail: it saturates in fixed point and never reads out of bounds.
///
/// ```
/// # use neurosurf_core::implicit::*;
/// # use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// # let blob = example_blob();
/// let model = ImplicitModel::<f32>::from_blob(&blob)?;
/// let fixed = ImplicitModel::<Q16>::from_blob(&blob)?; // same blob, other scalar
/// let p = [0.1, 0.2, 0.3];
/// let phi = model.field(p);
/// let phi_q = fixed.field(p.map(Q16::from_f32_saturating)).to_f32();
/// assert!((phi - phi_q).abs() < 1e-3);
/// # Ok(())
/// # }
/// # fn example_blob() -> Vec<u8> {
/// #     let layout = ModuleLayout::new(ModuleKind::Leaf, 2);
/// #     let params: Vec<f64> = (0..layout.len).map(|i| ((i * 7 % 11) as f64 - 5.0) / 10.0).collect();
/// #     let bytes: Vec<u8> = params.iter().flat_map(|&p| ScalarKind::F32.encode(p).unwrap()).collect();
/// #     let payload = ImplicitPayload {
/// #         width: 2, frame: neurosurf_core::frame::IDENTITY_PAYLOAD, tree: &[0],
/// #         parameters: &bytes, metadata: &[] };
/// #     let mut out = vec![0_u8; 1024];
/// #     let n = neurosurf_core::blob::write(
/// #         neurosurf_core::blob::ModelKind::Implicit, ScalarKind::F32, &payload, &mut out).unwrap();
/// #     out.truncate(n);
/// #     out
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct ImplicitModel<
    S: Scalar,
    const P: usize = DEFAULT_PARAMETERS,
    const M: usize = DEFAULT_MODULES,
> {
    pub(crate) width: usize,
    pub(crate) modules: Vec<ModuleEntry, M>,
    pub(crate) parameters: Vec<S, P>,
    /// Where the guards' parameters start (the modules' parameter count).
    pub(crate) guards_offset: usize,
    pub(crate) stored_as: ScalarKind,
    /// The blob's frame, as stored.
    pub(crate) frame: Frame<S>,
    /// What of the frame's scale 2ˢ the load could not fold into the normalizations (always 0
    /// for `f32`): each module scales its normalized position by 2^`input_shift`.
    pub(crate) input_shift: i8,
}

impl<S: Scalar, const P: usize, const M: usize> ImplicitModel<S, P, M> {
    /// An empty model (no modules: every evaluation gives zero), to be filled by
    /// [`ImplicitModel::load`]. `const`, so firmware can place a model in a `static` and load
    /// blobs into it in place, with no large temporary on the stack.
    pub const fn new() -> Self {
        ImplicitModel {
            width: 0,
            modules: Vec::new(),
            parameters: Vec::new(),
            guards_offset: 0,
            stored_as: S::KIND,
            frame: Frame::IDENTITY,
            input_shift: 0,
        }
    }

    /// Decodes and validates a blob, converting its parameters to `S`.
    ///
    /// # Errors
    /// Every [`BlobError`] that applies: framing ([`blob::parse`]), wrong model kind, malformed
    /// payload, invalid width or tree, parameter count disagreeing with the tree, capacities of
    /// this type exceeded, non-finite or (for fixed point) out-of-range parameters.
    pub fn from_blob(bytes: &[u8]) -> Result<Self, BlobError> {
        let mut model = Self::new();
        model.load(bytes)?;
        Ok(model)
    }

    /// Replaces this model by the one in `bytes`, in place (see [`ImplicitModel::from_blob`]).
    /// On error the model is left empty.
    ///
    /// # Errors
    /// As [`ImplicitModel::from_blob`].
    pub fn load(&mut self, bytes: &[u8]) -> Result<(), BlobError> {
        self.clear();
        let result = ImplicitPayload::from_blob(bytes)
            .and_then(|(header, payload)| self.load_payload(&payload, header.scalar));
        #[cfg(feature = "defmt")]
        if let Err(e) = &result {
            defmt::warn!("implicit blob rejected: {}", e);
        }
        result
    }

    /// Validates a decoded payload whose parameters are stored as `stored`.
    ///
    /// # Errors
    /// As [`ImplicitModel::from_blob`], minus framing.
    pub fn from_payload(
        payload: &ImplicitPayload<'_>,
        stored: ScalarKind,
    ) -> Result<Self, BlobError> {
        let mut model = Self::new();
        model.load_payload(payload, stored)?;
        Ok(model)
    }

    /// Replaces this model by a decoded payload, in place. On error the model is left empty.
    ///
    /// # Errors
    /// As [`ImplicitModel::from_payload`].
    pub fn load_payload(
        &mut self,
        payload: &ImplicitPayload<'_>,
        stored: ScalarKind,
    ) -> Result<(), BlobError> {
        self.clear();
        let result = self.fill(payload, stored);
        if result.is_err() {
            self.clear();
        }
        result
    }

    /// Makes this the empty model.
    fn clear(&mut self) {
        self.width = 0;
        self.modules.clear();
        self.parameters.clear();
        self.guards_offset = 0;
        self.stored_as = S::KIND;
        self.frame = Frame::IDENTITY;
        self.input_shift = 0;
    }

    fn fill(&mut self, payload: &ImplicitPayload<'_>, stored: ScalarKind) -> Result<(), BlobError> {
        if !matches!(stored, ScalarKind::F32 | ScalarKind::Q16_16) {
            return Err(BlobError::UnsupportedStorage {
                model: blob::ModelKind::Implicit,
                scalar: stored,
            });
        }
        let width = usize::from(payload.width);
        if width == 0 || width > MAX_WIDTH {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::Width,
                expected: MAX_WIDTH,
                found: width,
            });
        }
        let frame = Frame::from_payload(&payload.frame, stored)?;
        // The modules, then the guards: one code each, after the last module.
        let (tree, guards) = split_tree(payload.tree)?;
        if guards > MAX_GUARDS {
            return Err(BlobError::CapacityExceeded {
                what: Quantity::Guards,
                needed: guards,
                capacity: MAX_GUARDS,
            });
        }
        build_tree(&mut self.modules, tree, width)?;
        let module_parameters = self
            .modules
            .last()
            .map_or(0, |m| m.offset + ModuleLayout::new(m.kind, width).len);
        let needed = module_parameters + GUARD_LEN * guards;
        let word = stored.stored_bytes();
        let found = payload.parameters.len() / word;
        if !payload.parameters.len().is_multiple_of(word) || found != needed {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::Parameters,
                expected: needed,
                found,
            });
        }
        if needed > P {
            return Err(BlobError::CapacityExceeded {
                what: Quantity::Parameters,
                needed,
                capacity: P,
            });
        }
        for (index, chunk) in payload.parameters.chunks_exact(4).enumerate() {
            let bytes: [u8; 4] = chunk.try_into().map_err(|_| BlobError::MalformedPayload)?;
            let value = S::from_stored(bytes, stored).ok_or_else(|| {
                if stored == ScalarKind::F32 && !f32::from_le_bytes(bytes).is_finite() {
                    BlobError::NonFiniteParameter { index }
                } else {
                    BlobError::ParameterOutOfRange { index }
                }
            })?;
            self.parameters
                .push(value)
                .map_err(|_| BlobError::CapacityExceeded {
                    what: Quantity::Parameters,
                    needed,
                    capacity: P,
                })?;
        }
        // A guard's inverse radius must be positive: its support is then a ball.
        let guard_parameters = self.parameters.get(module_parameters..).unwrap_or(&[]);
        for (guard, params) in guard_parameters.chunks_exact(GUARD_LEN).enumerate() {
            if !params.get(3).is_some_and(|rho| *rho > S::ZERO) {
                return Err(BlobError::ParameterOutOfRange {
                    index: module_parameters + GUARD_LEN * guard + 3,
                });
            }
        }
        self.input_shift = fold_frame(&mut self.parameters, &self.modules, width, &frame)?;
        self.width = width;
        self.guards_offset = module_parameters;
        self.stored_as = stored;
        self.frame = frame;
        Ok(())
    }

    /// Hidden width N.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of modules (leaves and nodes).
    pub fn module_count(&self) -> usize {
        self.modules.len()
    }

    /// Number of leaf modules (features).
    pub fn leaf_count(&self) -> usize {
        self.modules
            .iter()
            .filter(|m| m.kind == ModuleKind::Leaf)
            .count()
    }

    /// Number of sign guards ([`super::guard`]).
    pub fn guard_count(&self) -> usize {
        (self.parameters.len() - self.guards_offset.min(self.parameters.len())) / GUARD_LEN
    }

    /// The guards' parameters, [`GUARD_LEN`] each.
    pub(crate) fn guard_parameters(&self) -> &[S] {
        self.parameters.get(self.guards_offset..).unwrap_or(&[])
    }

    /// Total stored parameters (guards included).
    pub fn parameter_count(&self) -> usize {
        self.parameters.len()
    }

    /// Kind of module `index` (post-order), if it exists.
    pub fn module_kind(&self, index: usize) -> Option<ModuleKind> {
        self.modules.get(index).map(|m| m.kind)
    }

    /// The children of node `index` as (left, right), `None` for leaves and bad indices.
    pub fn children(&self, index: usize) -> Option<(usize, usize)> {
        let m = self.modules.get(index)?;
        (m.kind == ModuleKind::Node).then(|| (m.left, index - 1))
    }

    /// Index of the root module.
    pub fn root(&self) -> usize {
        self.modules.len().saturating_sub(1)
    }

    /// The blob's frame, as stored. The load folds it into the modules and guards (see
    /// [`crate::frame`]), so every evaluation takes and returns the caller's units.
    pub fn frame(&self) -> &Frame<S> {
        &self.frame
    }

    /// The scalar kind the blob stored its parameters in.
    pub fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    /// Multiply–accumulates of one field (or field and gradient) evaluation of the whole model,
    /// as the core evaluates it (see [`ModuleLayout::mac_count`]): the lower bound of its
    /// instruction count.
    pub fn mac_count(&self, gradient: bool) -> usize {
        self.modules
            .iter()
            .map(|m| ModuleLayout::new(m.kind, self.width).mac_count(gradient))
            .sum()
    }
}

impl<S: Scalar, const P: usize, const M: usize> Default for ImplicitModel<S, P, M> {
    fn default() -> Self {
        Self::new()
    }
}

/// Rewrites the modules' normalizations and the guards, stored in the frame's coordinates, to
/// read the caller's points: with x_model = (x − o)·2ˢ, a module's A·(x_model − c) is
/// A·2ˢ·(x − c̃) with c̃ = o + c·2⁻ˢ, and a guard's centre and inverse radius move alike
/// (with a run-time shift, the radius stays as stored).
/// Returns the shift left to apply at run time: 0 when A·2ˢ is exact and within the parameter
/// bound (always in `f32`; in Q16.16 for s ≥ 0 when it fits), else s, with A kept as stored.
///
/// # Errors
/// [`BlobError::FrameOutOfRange`] when A·2ˢ or a guard's inverse radius ·2ˢ overflows `f32`.
fn fold_frame<S: Scalar>(
    parameters: &mut [S],
    modules: &[ModuleEntry],
    width: usize,
    frame: &Frame<S>,
) -> Result<i8, BlobError> {
    let (origin, shift) = (frame.origin(), frame.shift());
    let modules_end = modules
        .last()
        .map_or(0, |m| m.offset + ModuleLayout::new(m.kind, width).len);
    let bound = S::from_f32(S::MAX_PARAMETER).unwrap_or(S::ZERO);
    let fits = |value: S| {
        let scaled = value.times_power_of_two(shift);
        scaled.to_f32().is_finite() && scaled.abs().to_f64() <= bound.to_f64()
    };
    let is_f32 = S::KIND == ScalarKind::F32;
    let exact = is_f32 || shift >= 0;
    let axes = |m: &ModuleEntry| m.offset + 3..m.offset + NORMALIZATION_LEN;
    let mut guard_radii = parameters
        .get(modules_end..)
        .unwrap_or(&[])
        .chunks_exact(GUARD_LEN)
        .filter_map(|g| g.get(3));
    let fold = exact
        && modules.iter().all(|m| {
            parameters
                .get(axes(m))
                .is_some_and(|a| a.iter().all(|&v| fits(v)))
        })
        && guard_radii.all(|&rho| fits(rho));
    let move_center = |center: &mut [S]| {
        for (c, o) in center.iter_mut().zip(origin) {
            *c = o.add(c.times_power_of_two(shift.saturating_neg()));
        }
    };
    if is_f32 && !fold {
        // Only an overflow stops f32 (evaluation compiles no run-time shift for it).
        return Err(BlobError::FrameOutOfRange);
    }
    for m in modules {
        if let Some(center) = parameters.get_mut(m.offset..m.offset + 3) {
            move_center(center);
        }
        if fold && let Some(a) = parameters.get_mut(axes(m)) {
            for v in a {
                *v = v.times_power_of_two(shift);
            }
        }
    }
    for guard in parameters
        .get_mut(modules_end..)
        .unwrap_or(&mut [])
        .chunks_exact_mut(GUARD_LEN)
    {
        let (center, rest) = guard.split_at_mut(3);
        move_center(center);
        // With a run-time shift the radius stays in the frame's units (see `guard::inside`).
        if fold && let Some(rho) = rest.first_mut() {
            *rho = rho.times_power_of_two(shift);
        }
    }
    Ok(if fold { 0 } else { shift })
}

/// Checks a post-order tree and computes each module's offset, subtree and children.
fn build_tree<const M: usize>(
    modules: &mut Vec<ModuleEntry, M>,
    tree: &[u8],
    width: usize,
) -> Result<(), BlobError> {
    if tree.is_empty() {
        return Err(BlobError::ShapeMismatch {
            what: Quantity::Modules,
            expected: 1,
            found: 0,
        });
    }
    if tree.len() > M {
        return Err(BlobError::CapacityExceeded {
            what: Quantity::Modules,
            needed: tree.len(),
            capacity: M,
        });
    }
    modules.clear();
    // Roots of the subtrees completed so far, as module indices.
    let mut pending: Vec<usize, M> = Vec::new();
    let mut offset = 0_usize;
    for (index, &code) in tree.iter().enumerate() {
        let kind = ModuleKind::from_code(code).ok_or(BlobError::InvalidTree { module: index })?;
        let entry = match kind {
            ModuleKind::Leaf => ModuleEntry {
                kind,
                offset,
                subtree_start: index,
                left: index,
                height: 1,
            },
            ModuleKind::Node => {
                let invalid = BlobError::InvalidTree { module: index };
                let right = pending.pop().ok_or(invalid)?;
                let left = pending.pop().ok_or(invalid)?;
                let (left_entry, right_entry) = (
                    modules.get(left).ok_or(invalid)?,
                    modules.get(right).ok_or(invalid)?,
                );
                let height = 1 + left_entry.height.max(right_entry.height);
                if height > MAX_HEIGHT {
                    return Err(BlobError::CapacityExceeded {
                        what: Quantity::StackDepth,
                        needed: height,
                        capacity: MAX_HEIGHT,
                    });
                }
                ModuleEntry {
                    kind,
                    offset,
                    subtree_start: left_entry.subtree_start,
                    left,
                    height,
                }
            }
        };
        pending
            .push(index)
            .map_err(|_| BlobError::InvalidTree { module: index })?;
        modules
            .push(entry)
            .map_err(|_| BlobError::InvalidTree { module: index })?;
        offset += ModuleLayout::new(kind, width).len;
    }
    if pending.len() != 1 {
        return Err(BlobError::InvalidTree {
            module: tree.len() - 1,
        });
    }
    Ok(())
}

impl<S: Scalar, const P: usize, const M: usize> crate::model::Model<S> for ImplicitModel<S, P, M> {
    const KIND: ModelKind = ModelKind::Implicit;

    fn load_blob(&mut self, blob: &[u8]) -> Result<(), BlobError> {
        self.load(blob)
    }

    fn input_len(&self) -> usize {
        3
    }

    fn output_len(&self, full: bool) -> usize {
        if full { 4 } else { 1 }
    }

    fn evaluate(&self, input: &[S], full: bool, out: &mut [S]) {
        let x = crate::model::point(input);
        if full {
            let fg = self.field_gradient(x);
            let [gx, gy, gz] = fg.gradient;
            crate::model::write(out, [fg.value, gx, gy, gz]);
        } else {
            crate::model::write(out, [self.field(x)]);
        }
    }

    fn evaluate_batch(
        &self,
        inputs: &[[S; crate::model::MAX_INPUTS]],
        full: bool,
        out: &mut [[S; crate::model::MAX_OUTPUTS]],
    ) {
        let x = |input: &[S; crate::model::MAX_INPUTS]| crate::model::point::<S, 3>(input);
        if full {
            crate::model::batch(
                inputs,
                out,
                x,
                |x, fg| {
                    // Lengths agree by construction: nothing to report.
                    let _ = self.field_gradient_batch(x, fg);
                },
                |fg: &super::FieldGradient<S>, out| {
                    let [gx, gy, gz] = fg.gradient;
                    crate::model::write(out, [fg.value, gx, gy, gz]);
                },
            );
        } else {
            crate::model::batch(
                inputs,
                out,
                x,
                |x, phi| {
                    let _ = self.field_batch(x, phi);
                },
                |&phi: &S, out| crate::model::write(out, [phi]),
            );
        }
    }

    fn mac_count(&self, full: bool) -> usize {
        ImplicitModel::mac_count(self, full)
    }

    fn describe(&self, f: &mut dyn core::fmt::Write) -> core::fmt::Result {
        let origin = self.frame().origin().map(S::to_f32);
        write!(
            f,
            "{} module{}, width {}, {} sign guards, frame model = (x − ({}, {}, {})) · 2^{}",
            self.module_count(),
            if self.module_count() == 1 { "" } else { "s" },
            self.width(),
            self.guard_count(),
            origin[0],
            origin[1],
            origin[2],
            self.frame().shift()
        )
    }
}

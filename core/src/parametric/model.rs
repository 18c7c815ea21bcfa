//! The validated surface network: loading, accessors and cost.

use heapless::Vec;

use super::activation::Activation;
use super::payload::SurfaceNetworkPayload;
use crate::blob::{self, ModelKind};
use crate::error::{BlobError, Quantity};
use crate::frame::Frame;
use crate::scalar::{Scalar, ScalarKind};

/// Most hidden layers a surface-network blob may have (the paper's search stops at 2).
pub const MAX_HIDDEN_LAYERS: usize = 4;
/// Most neurons in a hidden layer: with every weight within ±1024 in Q16.16, a neuron's 32
/// products and its bias stay below 2⁶³ in the Q32.32 accumulator.
pub const MAX_NEURONS: usize = 32;
/// Words around the layers: c_u, c_v, g_u, g_v before them, c_x, c_y, c_z, s_p after.
pub const NORMALIZATION_WORDS: usize = 8;
/// Default parameter capacity of [`SurfaceNetworkModel`]: 1280 words (5 KiB in `f32`), enough
/// for two hidden layers of 32 neurons (1259 words); the trainer's default search ends at two
/// layers of at most 12 (231 words).
pub const DEFAULT_PARAMETERS: usize = 1280;

/// A parametric surface network (u, v) → (x, y, z), loaded from a blob and validated (see
/// [`crate::parametric`] for the formula, the payload and the accuracy).
///
/// `P` is the parameter capacity reserved inline (no heap). Evaluation after a successful load
/// cannot fail: every input, including ±∞ and NaN, gives a value.
///
/// ```
/// # use neurosurf_core::parametric::SurfaceNetworkModel;
/// # use neurosurf_core::scalar::Q16;
/// # fn demo(blob: &[u8]) -> Result<(), neurosurf_core::BlobError> {
/// let model = SurfaceNetworkModel::<f32>::from_blob(blob)?;
/// let fixed = SurfaceNetworkModel::<Q16>::from_blob(blob)?; // same blob, other scalar
/// let p: [f32; 3] = model.position([0.25, -0.5]);
/// let point = fixed.eval([Q16::from_num(0.25), Q16::from_num(-0.5)]);
/// assert!((p[0] - point.position[0].to_num::<f32>()).abs() < 1e-3);
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct SurfaceNetworkModel<S: Scalar, const P: usize = DEFAULT_PARAMETERS> {
    pub(crate) activation: Activation,
    pub(crate) hidden: Vec<u8, MAX_HIDDEN_LAYERS>,
    pub(crate) parameters: Vec<S, P>,
    pub(crate) stored_as: ScalarKind,
    /// The blob's frame, as stored.
    pub(crate) frame: Frame<S>,
    /// What of the frame's scale the load could not fold into s_p (0 for `f32`): positions
    /// and partials are scaled by 2^`output_shift` after the output layer.
    pub(crate) output_shift: i8,
}

impl<S: Scalar, const P: usize> SurfaceNetworkModel<S, P> {
    /// An empty network (no layers: every position is 0 and no normal exists), to be filled
    /// by [`SurfaceNetworkModel::load`]. `const`, so firmware can keep one in a `static`.
    pub const fn new() -> Self {
        SurfaceNetworkModel {
            activation: Activation::TanSig,
            hidden: Vec::new(),
            parameters: Vec::new(),
            stored_as: S::KIND,
            frame: Frame::IDENTITY,
            output_shift: 0,
        }
    }

    crate::blob::loader_methods!(
        SurfaceNetworkPayload,
        "surface network",
        "Framing errors ([`crate::blob::parse`]); [`BlobError::WrongModelKind`] for \
         another kind of blob; [`BlobError::MalformedPayload`]; \
         [`BlobError::UnsupportedStorage`] for `f64` storage; \
         [`BlobError::ShapeMismatch`] for an unknown activation code (`Activation`, \
         expected the largest code), no or more than [`MAX_HIDDEN_LAYERS`] hidden layers \
         (`Layers`), a layer of 0 or more than [`MAX_NEURONS`] neurons (`Width`), or a \
         parameter string that does not hold exactly the words the layers need \
         (`Parameters`, in words); [`BlobError::CapacityExceeded`] (`Parameters`) beyond \
         `P`; [`BlobError::NonFiniteParameter`] / [`BlobError::ParameterOutOfRange`] \
         (|value| > 1024 for Q16.16, or a gain g_u, g_v or scale s_p that is not positive) \
         naming the first bad word."
    );

    fn fill(
        &mut self,
        payload: &SurfaceNetworkPayload<'_>,
        stored: ScalarKind,
    ) -> Result<(), BlobError> {
        self.clear();
        blob::check_storage(ModelKind::SurfaceNetwork, stored)?;
        let activation =
            Activation::from_code(payload.activation).ok_or(BlobError::ShapeMismatch {
                what: Quantity::Activation,
                expected: usize::from(Activation::LAST_CODE),
                found: usize::from(payload.activation),
            })?;
        let layers = payload.hidden.len();
        if !(1..=MAX_HIDDEN_LAYERS).contains(&layers) {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::Layers,
                expected: if layers == 0 { 1 } else { MAX_HIDDEN_LAYERS },
                found: layers,
            });
        }
        if let Some(&bad) = payload
            .hidden
            .iter()
            .find(|&&n| n == 0 || usize::from(n) > MAX_NEURONS)
        {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::Width,
                expected: if bad == 0 { 1 } else { MAX_NEURONS },
                found: usize::from(bad),
            });
        }
        let needed = parameter_count(payload.hidden);
        let found = payload.parameters.len() / 4;
        if found != needed || !payload.parameters.len().is_multiple_of(4) {
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
        let positive = [2, 3, needed - 1];
        for (index, chunk) in payload.parameters.chunks_exact(4).enumerate() {
            let value = blob::decode_word::<S>(chunk, stored, index)?;
            if positive.contains(&index) && value <= S::ZERO {
                return Err(BlobError::ParameterOutOfRange { index });
            }
            self.parameters
                .push(value)
                .map_err(|_| BlobError::CapacityExceeded {
                    what: Quantity::Parameters,
                    needed,
                    capacity: P,
                })?;
        }
        for &n in payload.hidden {
            // At most MAX_HIDDEN_LAYERS, checked above.
            self.hidden.push(n).map_err(|_| BlobError::ShapeMismatch {
                what: Quantity::Layers,
                expected: MAX_HIDDEN_LAYERS,
                found: layers,
            })?;
        }
        // The frame: c_p moves into the user's units; f32 folds the scale into s_p exactly,
        // Q16.16 keeps it for after the output layer (folding would cost s_p its bits).
        let frame = Frame::<S>::from_payload(&payload.frame, stored)?;
        let shift = frame.shift().saturating_neg();
        let origin = frame.origin();
        if let Some(output) = self.parameters.get_mut(needed - 4..needed) {
            for (c, o) in output.iter_mut().zip(origin) {
                *c = o.add(c.times_power_of_two(shift));
            }
            if S::KIND == ScalarKind::F32
                && let Some(scale) = output.get_mut(3)
            {
                *scale = scale.times_power_of_two(shift);
                if !(*scale > S::ZERO && scale.to_f32().is_finite()) {
                    return Err(BlobError::FrameOutOfRange);
                }
            }
        }
        self.output_shift = if S::KIND == ScalarKind::F32 { 0 } else { shift };
        self.frame = frame;
        self.activation = activation;
        self.stored_as = stored;
        Ok(())
    }

    /// The blob's frame, as stored; the load applies it (see [`crate::frame`]).
    pub fn frame(&self) -> &Frame<S> {
        &self.frame
    }

    /// σ of every hidden layer.
    pub fn activation(&self) -> Activation {
        self.activation
    }

    /// Neurons of each hidden layer (empty for an empty network).
    pub fn hidden_sizes(&self) -> &[u8] {
        &self.hidden
    }

    /// Every stored word, in the layout of [`crate::parametric`].
    pub fn parameters(&self) -> &[S] {
        &self.parameters
    }

    /// The scalar kind the blob stored its words in.
    pub fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    /// Multiply–accumulates of the layers for one point: Σ nₗ·nₗ₋₁ over the hidden and output
    /// layers for the position, three times that with the partials (and so the normal). The
    /// activations (one `exp` and one quotient per sigmoid neuron) are not counted.
    ///
    /// ```
    /// # use neurosurf_core::parametric::SurfaceNetworkModel;
    /// # fn demo(model: &SurfaceNetworkModel<f32>) {
    /// // Hidden layers of 8 and 8 neurons: 2·8 + 8·8 + 8·3 = 104.
    /// assert_eq!(model.mac_count(false), 104);
    /// assert_eq!(model.mac_count(true), 312);
    /// # }
    /// ```
    pub fn mac_count(&self, partials: bool) -> usize {
        if self.hidden.is_empty() {
            return 0;
        }
        let mut inputs = 2;
        let mut macs = 0;
        for outputs in self.hidden.iter().map(|&n| usize::from(n)).chain([3]) {
            macs += inputs * outputs;
            inputs = outputs;
        }
        if partials { 3 * macs } else { macs }
    }
}

impl<S: Scalar, const P: usize> Default for SurfaceNetworkModel<S, P> {
    fn default() -> Self {
        Self::new()
    }
}

/// Words of a network with these hidden layers: the normalization and every layer's weights
/// and biases.
pub fn parameter_count(hidden: &[u8]) -> usize {
    let mut inputs = 2;
    let mut count = NORMALIZATION_WORDS;
    for outputs in hidden.iter().map(|&n| usize::from(n)).chain([3]) {
        count += outputs * (inputs + 1);
        inputs = outputs;
    }
    count
}

impl<S: Scalar, const P: usize> crate::model::Model<S> for SurfaceNetworkModel<S, P> {
    const KIND: ModelKind = ModelKind::SurfaceNetwork;

    fn load_blob(&mut self, blob: &[u8]) -> Result<(), BlobError> {
        self.load(blob)
    }

    fn input_len(&self) -> usize {
        2
    }

    fn output_len(&self, full: bool) -> usize {
        if full { 6 } else { 3 }
    }

    fn evaluate(&self, input: &[S], full: bool, out: &mut [S]) {
        let uv = crate::model::point(input);
        if full {
            let p = self.eval(uv);
            let normal = crate::model::normal_or_zero(p.normal);
            crate::model::write(out, crate::model::pair(p.position, normal));
        } else {
            crate::model::write(out, self.position(uv));
        }
    }

    fn evaluate_batch(
        &self,
        inputs: &[[S; crate::model::MAX_INPUTS]],
        full: bool,
        out: &mut [[S; crate::model::MAX_OUTPUTS]],
    ) {
        let uv = |input: &[S; crate::model::MAX_INPUTS]| crate::model::point::<S, 2>(input);
        if full {
            crate::model::batch(
                inputs,
                out,
                uv,
                |uv, points| {
                    // Lengths agree by construction: nothing to report.
                    let _ = self.eval_batch(uv, points);
                },
                |p: &super::SurfaceNetworkPoint<S>, out| {
                    let normal = crate::model::normal_or_zero(p.normal);
                    crate::model::write(out, crate::model::pair(p.position, normal));
                },
            );
        } else {
            crate::model::positions(inputs, out, uv, |uv, positions| {
                self.position_batch(uv, positions)
            });
        }
    }

    fn mac_count(&self, full: bool) -> usize {
        SurfaceNetworkModel::mac_count(self, full)
    }

    fn describe(&self, f: &mut dyn core::fmt::Write) -> core::fmt::Result {
        write!(f, "hidden layers")?;
        for (i, size) in self.hidden_sizes().iter().enumerate() {
            write!(f, "{}{size}", if i == 0 { " " } else { " × " })?;
        }
        write!(f, ", {:?}", self.activation())
    }
}

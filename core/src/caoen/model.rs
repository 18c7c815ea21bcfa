//! The validated Cao En network: loading, accessors and cost.

use heapless::Vec;

use super::blending::{Blending, Domain, MAX_SHARPNESS};
use super::payload::CaoEnPayload;
use crate::blob::{self, ModelKind};
use crate::error::{BlobError, Quantity};
use crate::scalar::{Scalar, ScalarKind};

/// Largest source dimension m (hyperspheres up to S⁷).
pub const MAX_SOURCE_DIMENSION: usize = 8;
/// Largest target dimension p (3 for shapes, 2 for screen projections, 5 for images, …).
pub const MAX_TARGET_DIMENSION: usize = 8;
/// Most key points any Cao En blob may have, whatever the capacity: with every weight, target
/// and blending value within ±1024 in Q16.16 (2²⁶ in bits), 1024 products of 2⁵² stay below
/// 2⁶² in the Q32.32 accumulator.
pub const MAX_KEY_POINTS: usize = 1024;
/// Default key-point capacity of [`CaoEnModel`]: 256 (18 KiB in `f32`), more than twice the
/// paper's 104-point teapot.
pub const DEFAULT_KEY_POINTS: usize = 256;

/// Most key points in one group of a [`Blending::Compact`] network: consecutive keys are
/// grouped in the blob's order, eight at a time, and a group that cannot reach a source point
/// is skipped whole.
pub const GROUP_KEYS: usize = 8;

/// One key point: its blending weight wᵢ (the source point), its target tᵢ (column i of V),
/// and its sharpness q (also as a whole number for power blending).
///
/// The first key of a group also carries the group's skip test (see [`Group`]); `group.span`
/// is 0 for the other keys and for networks that never skip.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Key<S> {
    pub(crate) weight: [S; MAX_SOURCE_DIMENSION],
    pub(crate) target: [S; MAX_TARGET_DIMENSION],
    pub(crate) sharpness: S,
    pub(crate) power: u8,
    pub(crate) group: Group<S>,
}

/// The skip test of a group of compact keys led by key 0 with weight w₀: every key j of the
/// group has |wⱼ − w₀| ≤ `reach`, so sⱼ = x·wⱼ ≤ x·w₀ + |x|·`reach`, and it is off its cap when
/// sⱼ ≤ 1 − 1/qⱼ. The group is skipped when x·w₀ + |x|·`reach` < `floor`, the smallest cap
/// edge minus a margin of 2⁻¹⁰ that covers every rounding of both scalars, so a skipped key
/// would have given exactly 0: skipping changes no bit of any result. Groups are only formed
/// of keys with weights within ±[`GROUP_WEIGHT_LIMIT`] and only lanes with |x| below
/// [`GROUP_NORM_LIMIT`] are tested, so nothing in the test saturates in Q16.16.
#[derive(Copy, Clone, Debug, PartialEq)]
pub(crate) struct Group<S> {
    /// Keys in the group, this one first (0: not a group leader, or never skipped).
    pub(crate) span: u8,
    pub(crate) reach: S,
    pub(crate) floor: S,
}

/// Largest weight coordinate of a key that can be grouped.
pub(crate) const GROUP_WEIGHT_LIMIT: f64 = 16.0;
/// |x| from which a lane is never skipped.
pub(crate) const GROUP_NORM_LIMIT: f32 = 64.0;

impl<S: Scalar> Group<S> {
    const NONE: Self = Group {
        span: 0,
        reach: S::ZERO,
        floor: S::ZERO,
    };

    /// Whether no key of the group reaches a lane with s₀ = x·w₀ and `norm` = |x| (false for
    /// |x| ≥ `norm_limit`, [`GROUP_NORM_LIMIT`] in the scalar, and for NaN).
    #[inline(always)]
    pub(crate) fn out_of_reach(&self, s0: S, norm: S, norm_limit: S) -> bool {
        norm < norm_limit && s0.add(norm.mul(self.reach)) < self.floor
    }
}

/// Margin of the skip test (see [`Group`]).
const SKIP_MARGIN: f64 = 1.0 / 1024.0;

/// A Cao En network y = V·k, kᵢ = Fᵢ(x·wᵢ), loaded from a blob and validated (see
/// [`crate::caoen`] for the contract, the payload and the accuracy).
///
/// `K` is the key-point capacity reserved inline (no heap). Evaluation after a successful load
/// cannot fail: every input, including ±∞ and NaN coordinates, gives a value.
///
/// ```
/// # use neurosurf_core::caoen::{CaoEnModel, CaoEnPayload};
/// # use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// # let blob = example_blob();
/// let model = CaoEnModel::<f32>::from_blob(&blob)?;
/// let fixed = CaoEnModel::<Q16>::from_blob(&blob)?; // same blob, other scalar
/// let x = [0.6, 0.0, 0.8]; // a point of the unit sphere
/// let y: [f32; 3] = model.eval(&x);
/// let z: [Q16; 3] = fixed.eval(&x.map(Q16::from_num));
/// assert!((y[2] - z[2].to_f32()).abs() < 1e-3);
/// assert_eq!((model.key_count(), model.source_dimension(), model.target_dimension()), (6, 3, 3));
/// # Ok(())
/// # }
/// # fn example_blob() -> Vec<u8> {
/// #     let axes = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
/// #     let words: Vec<u8> = axes.iter().flatten().flat_map(|&c| ScalarKind::F32.encode(c).unwrap()).collect();
/// #     let q: Vec<u8> = [2.0; 6].iter().flat_map(|&c| ScalarKind::F32.encode(c).unwrap()).collect();
/// #     let payload = CaoEnPayload { domain: 0, blending: 0, normalized: false, source_dimension: 3, target_dimension: 3, weights: &words, targets: &words, sharpness: &q, metadata: &[] };
/// #     let mut out = vec![0_u8; 512];
/// #     let n = payload.write(ScalarKind::F32, &mut out).unwrap();
/// #     out.truncate(n);
/// #     out
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct CaoEnModel<S: Scalar, const K: usize = DEFAULT_KEY_POINTS> {
    pub(crate) domain: Domain,
    pub(crate) blending: Blending,
    pub(crate) normalized: bool,
    pub(crate) source_dimension: u8,
    pub(crate) target_dimension: u8,
    pub(crate) keys: Vec<Key<S>, K>,
    pub(crate) stored_as: ScalarKind,
}

impl<S: Scalar, const K: usize> CaoEnModel<S, K> {
    /// An empty network (no key points: every output is 0), to be filled by
    /// [`CaoEnModel::load`]. `const`, so firmware can keep a model in a `static`.
    pub const fn new() -> Self {
        CaoEnModel {
            domain: Domain::Sphere,
            blending: Blending::Power,
            normalized: false,
            source_dimension: 0,
            target_dimension: 0,
            keys: Vec::new(),
            stored_as: S::KIND,
        }
    }

    crate::blob::loader_methods!(
        CaoEnPayload,
        "Cao En",
        "Framing errors ([`crate::blob::parse`]); [`BlobError::WrongModelKind`] for \
         another kind of blob; [`BlobError::MalformedPayload`]; \
         [`BlobError::UnsupportedStorage`] for `f64` storage; \
         [`BlobError::ShapeMismatch`] for an unknown domain or blending code (`Domain`, \
         `Blending`, expected the largest code), a source dimension outside 3 … \
         [`MAX_SOURCE_DIMENSION`] or other than 4 for a torus (`SourceDimension`), a \
         target dimension outside 1 … [`MAX_TARGET_DIMENSION`] (`TargetDimension`), no \
         key points (`KeyPoints`, expected 1) or word strings that disagree with n = \
         sharpness words (`Parameters`, in words); [`BlobError::CapacityExceeded`] \
         (`KeyPoints`) beyond [`MAX_KEY_POINTS`] or `K`; \
         [`BlobError::NonFiniteParameter`] / [`BlobError::ParameterOutOfRange`] (|value| \
         > 1024 for Q16.16; a sharpness outside [0, 64], or not whole for power blending) \
         naming the first bad word, counted through W, then V, then q."
    );

    fn fill(&mut self, payload: &CaoEnPayload<'_>, stored: ScalarKind) -> Result<(), BlobError> {
        self.clear();
        blob::check_storage(ModelKind::CaoEn, stored)?;
        let code_error = |what, last: u8, found: u8| BlobError::ShapeMismatch {
            what,
            expected: usize::from(last),
            found: usize::from(found),
        };
        let domain = Domain::from_code(payload.domain)
            .ok_or_else(|| code_error(Quantity::Domain, Domain::LAST_CODE, payload.domain))?;
        let blending = Blending::from_code(payload.blending)
            .ok_or_else(|| code_error(Quantity::Blending, Blending::LAST_CODE, payload.blending))?;
        let m = usize::from(payload.source_dimension);
        let valid_m = match domain {
            Domain::Torus => 4..=4,
            _ => 3..=MAX_SOURCE_DIMENSION,
        };
        if !valid_m.contains(&m) {
            return Err(dimension_error(Quantity::SourceDimension, valid_m, m));
        }
        let p = usize::from(payload.target_dimension);
        if !(1..=MAX_TARGET_DIMENSION).contains(&p) {
            return Err(dimension_error(
                Quantity::TargetDimension,
                1..=MAX_TARGET_DIMENSION,
                p,
            ));
        }
        let n = payload.sharpness.len() / 4;
        if !payload.sharpness.len().is_multiple_of(4) {
            return Err(words_error(n + 1, payload.sharpness.len()));
        }
        if n == 0 {
            return Err(BlobError::ShapeMismatch {
                what: Quantity::KeyPoints,
                expected: 1,
                found: 0,
            });
        }
        for capacity in [MAX_KEY_POINTS, K] {
            if n > capacity {
                return Err(BlobError::CapacityExceeded {
                    what: Quantity::KeyPoints,
                    needed: n,
                    capacity,
                });
            }
        }
        for (bytes, per_key) in [(payload.weights, m), (payload.targets, p)] {
            if bytes.len() != n * per_key * 4 {
                return Err(words_error(n * per_key, bytes.len()));
            }
        }
        // Words are numbered through W, then V, then q.
        let word = |bytes: &[u8], index: usize| -> Result<S, BlobError> {
            let chunk = bytes.get(4 * index..4 * index + 4).unwrap_or(&[]);
            blob::decode_word::<S>(chunk, stored, index)
        };
        for i in 0..n {
            let mut key = Key {
                weight: [S::ZERO; MAX_SOURCE_DIMENSION],
                target: [S::ZERO; MAX_TARGET_DIMENSION],
                sharpness: S::ZERO,
                power: 0,
                group: Group::NONE,
            };
            for (h, slot) in key.weight.iter_mut().take(m).enumerate() {
                *slot = word(payload.weights, i * m + h)?;
            }
            self.keys
                .push(key)
                .map_err(|_| BlobError::CapacityExceeded {
                    what: Quantity::KeyPoints,
                    needed: n,
                    capacity: K,
                })?;
        }
        for (i, key) in self.keys.iter_mut().enumerate() {
            for (g, slot) in key.target.iter_mut().take(p).enumerate() {
                *slot = word(payload.targets, i * p + g).map_err(|e| renumber(e, n * m))?;
            }
        }
        for (i, key) in self.keys.iter_mut().enumerate() {
            let index = n * (m + p) + i;
            key.sharpness = word(payload.sharpness, i).map_err(|e| renumber(e, n * (m + p)))?;
            let chunk = payload.sharpness.get(4 * i..4 * i + 4).unwrap_or(&[]);
            key.power = sharpness_check(chunk, stored, blending)
                .ok_or(BlobError::ParameterOutOfRange { index })?;
        }
        if blending == Blending::Compact {
            self.form_groups(m);
        }
        self.domain = domain;
        self.blending = blending;
        self.normalized = payload.normalized;
        self.source_dimension = payload.source_dimension;
        self.target_dimension = payload.target_dimension;
        self.stored_as = stored;
        Ok(())
    }

    /// Fills the skip test of every group of [`GROUP_KEYS`] consecutive keys (m source
    /// coordinates). Done once at load, in `f64` from the scalar's values; a group with a key
    /// of q < 1/2 (a cap that covers the sphere) or a weight beyond ±[`GROUP_WEIGHT_LIMIT`]
    /// is never skipped.
    fn form_groups(&mut self, m: usize) {
        for group in self.keys.chunks_mut(GROUP_KEYS) {
            let Some(leader) = group.first().map(|k| k.weight) else {
                continue;
            };
            let mut reach = 0.0_f64;
            let mut floor = f64::INFINITY;
            let bounded = group.iter().all(|key| {
                key.weight
                    .iter()
                    .all(|w| w.to_f64().abs() <= GROUP_WEIGHT_LIMIT)
            });
            for key in group.iter() {
                let squared: f64 = key
                    .weight
                    .iter()
                    .zip(&leader)
                    .take(m)
                    .map(|(a, b)| {
                        let d = a.to_f64() - b.to_f64();
                        d * d
                    })
                    .sum();
                reach = reach.max(crate::math::sqrt(squared));
                let q = key.sharpness.to_f64();
                floor = floor.min(if q >= 0.5 { 1.0 - 1.0 / q } else { -3.0 });
            }
            let span = group.len() as u8;
            if let Some(first) = group.first_mut() {
                first.group = if bounded && floor > -2.0 {
                    Group {
                        span,
                        reach: round_up::<S>(reach * (1.0 + SKIP_MARGIN) + SKIP_MARGIN),
                        floor: S::from_f32_saturating((floor - SKIP_MARGIN) as f32),
                    }
                } else {
                    Group::NONE
                };
            }
        }
    }

    /// What the network maps from.
    pub fn domain(&self) -> Domain {
        self.domain
    }

    /// The blending function of every key point.
    pub fn blending(&self) -> Blending {
        self.blending
    }

    /// Whether k is normalized by Σ F (the rational form).
    pub fn is_normalized(&self) -> bool {
        self.normalized
    }

    /// m (0 for an empty network).
    pub fn source_dimension(&self) -> usize {
        usize::from(self.source_dimension)
    }

    /// p (0 for an empty network).
    pub fn target_dimension(&self) -> usize {
        usize::from(self.target_dimension)
    }

    /// n, the number of key points.
    pub fn key_count(&self) -> usize {
        self.keys.len()
    }

    /// wᵢ of key point `index` (m coordinates, zeros after), if it exists.
    pub fn weight(&self, index: usize) -> Option<[S; MAX_SOURCE_DIMENSION]> {
        self.keys.get(index).map(|k| k.weight)
    }

    /// tᵢ of key point `index` (p coordinates, zeros after), if it exists.
    pub fn target(&self, index: usize) -> Option<[S; MAX_TARGET_DIMENSION]> {
        self.keys.get(index).map(|k| k.target)
    }

    /// qᵢ of key point `index`, if it exists.
    pub fn sharpness(&self, index: usize) -> Option<S> {
        self.keys.get(index).map(|k| k.sharpness)
    }

    /// The scalar kind the blob stored its words in.
    pub fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    /// Multiply–accumulates of the network's two layers for one point: n·(m + p) for the
    /// position (n more when normalized), and with the exact normal n·m·(p + 1) more (n·m
    /// more again when normalized). The blending functions are not counted: power q costs at
    /// most 2·⌈log₂ q⌉ + 2 products per key point, exponential one product and one `exp`.
    ///
    /// ```
    /// # use neurosurf_core::caoen::CaoEnModel;
    /// # fn demo(model: &CaoEnModel<f32>) {
    /// // A sphere → 3-D network with 26 key points, not normalized:
    /// assert_eq!(model.mac_count(false), 26 * 6);
    /// assert_eq!(model.mac_count(true), 26 * 6 + 26 * 3 * 4);
    /// # }
    /// ```
    pub fn mac_count(&self, normal: bool) -> usize {
        let (n, m, p) = (
            self.key_count(),
            self.source_dimension(),
            self.target_dimension(),
        );
        let extra = usize::from(self.normalized);
        let position = n * (m + p + extra);
        if normal {
            position + n * m * (p + 1 + extra)
        } else {
            position
        }
    }
}

impl<S: Scalar, const K: usize> Default for CaoEnModel<S, K> {
    fn default() -> Self {
        Self::new()
    }
}

/// `value` in the scalar, rounded up by a margin larger than its rounding (values ≤ 2048).
fn round_up<S: Scalar>(value: f64) -> S {
    S::from_f32_saturating((value + 1.0 / 32768.0) as f32)
}

/// The shape error for a dimension outside `valid` (reports the nearer end as expected).
fn dimension_error(
    what: Quantity,
    valid: core::ops::RangeInclusive<usize>,
    found: usize,
) -> BlobError {
    BlobError::ShapeMismatch {
        what,
        expected: if found < *valid.start() {
            *valid.start()
        } else {
            *valid.end()
        },
        found,
    }
}

/// Shifts the word index of a parameter error by `offset` (from one word string's numbering
/// to the whole payload's).
fn renumber(error: BlobError, offset: usize) -> BlobError {
    match error {
        BlobError::NonFiniteParameter { index } => BlobError::NonFiniteParameter {
            index: index + offset,
        },
        BlobError::ParameterOutOfRange { index } => BlobError::ParameterOutOfRange {
            index: index + offset,
        },
        other => other,
    }
}

/// The shape error of a word string that does not hold `expected` words.
fn words_error(expected: usize, bytes: usize) -> BlobError {
    BlobError::ShapeMismatch {
        what: Quantity::Parameters,
        expected,
        found: bytes / 4,
    }
}

/// The whole-number power of a valid sharpness word (0 for exponential blending), `None` when
/// q is outside [0, 64] or, for power blending, not whole. Checked on the stored value, so
/// both scalars accept the same blobs.
fn sharpness_check(word: &[u8], stored: ScalarKind, blending: Blending) -> Option<u8> {
    let q = blob::stored_value(word, stored)?;
    if !(0.0..=MAX_SHARPNESS).contains(&q) {
        return None;
    }
    match blending {
        Blending::Power => {
            let whole = q as u8;
            (f64::from(whole) == q).then_some(whole)
        }
        _ => Some(0),
    }
}

impl<S: Scalar, const K: usize> crate::model::Model<S> for CaoEnModel<S, K> {
    const KIND: ModelKind = ModelKind::CaoEn;

    fn load_blob(&mut self, blob: &[u8]) -> Result<(), BlobError> {
        self.load(blob)
    }

    fn input_len(&self) -> usize {
        self.source_dimension()
    }

    fn output_len(&self, full: bool) -> usize {
        self.target_dimension() + if full { 3 } else { 0 }
    }

    fn evaluate(&self, input: &[S], full: bool, out: &mut [S]) {
        let x: [S; MAX_SOURCE_DIMENSION] = crate::model::point(input);
        let p = self.target_dimension();
        let (outputs, normal) = if full && p == 3 {
            let point = self.eval_normal(&x);
            let mut outputs = [S::ZERO; MAX_TARGET_DIMENSION];
            crate::model::write(&mut outputs, point.position);
            (outputs, point.normal)
        } else {
            (
                self.eval::<MAX_SOURCE_DIMENSION, MAX_TARGET_DIMENSION>(&x),
                None,
            )
        };
        let normal = full.then(|| crate::model::normal_or_zero(normal));
        crate::model::write_each(
            out,
            outputs
                .into_iter()
                .take(p)
                .chain(normal.into_iter().flatten()),
        );
    }

    fn evaluate_batch(
        &self,
        inputs: &[[S; crate::model::MAX_INPUTS]],
        full: bool,
        out: &mut [[S; crate::model::MAX_OUTPUTS]],
    ) {
        let p = self.target_dimension();
        let x = |input: &[S; crate::model::MAX_INPUTS]| {
            crate::model::point::<S, MAX_SOURCE_DIMENSION>(input)
        };
        if full && p == 3 {
            crate::model::batch(
                inputs,
                out,
                x,
                |x, points| {
                    // Lengths agree by construction: nothing to report.
                    let _ = self.eval_normal_batch(x, points);
                },
                |point: &super::CaoEnPoint<S>, out| {
                    let normal = crate::model::normal_or_zero(point.normal);
                    crate::model::write(out, crate::model::pair(point.position, normal));
                },
            );
        } else {
            crate::model::batch(
                inputs,
                out,
                x,
                |x, outputs| {
                    let _ =
                        self.eval_batch::<MAX_SOURCE_DIMENSION, MAX_TARGET_DIMENSION>(x, outputs);
                },
                |outputs: &[S; MAX_TARGET_DIMENSION], out| {
                    let normal = full.then_some([S::ZERO; 3]);
                    crate::model::write_each(
                        out,
                        outputs
                            .iter()
                            .copied()
                            .take(p)
                            .chain(normal.into_iter().flatten()),
                    );
                },
            );
        }
    }

    fn mac_count(&self, full: bool) -> usize {
        CaoEnModel::mac_count(self, full)
    }

    fn describe(&self, f: &mut dyn core::fmt::Write) -> core::fmt::Result {
        write!(
            f,
            "{} key points, {:?} {}-D → {}-D, {:?} blending{}",
            self.key_count(),
            self.domain(),
            self.source_dimension(),
            self.target_dimension(),
            self.blending(),
            if self.is_normalized() {
                ", normalized"
            } else {
                ""
            }
        )
    }
}

#[cfg(test)]
#[allow(clippy::indexing_slicing)]
mod tests {
    use super::super::blending::blend;
    use super::*;
    use crate::scalar::Q16;

    /// 96 key points of a cube sphere (4 × 4 per face), each face's two 2 × 4 halves a group,
    /// `(x, y, z)` per key.
    fn cube_sphere() -> [[f64; 3]; 96] {
        let mut keys = [[0.0; 3]; 96];
        let offsets = [-0.75, -0.25, 0.25, 0.75];
        for (i, key) in keys.iter_mut().enumerate() {
            let (face, cell) = (i / 16, i % 16);
            let (axis, sign) = (face / 2, if face % 2 == 0 { 1.0 } else { -1.0 });
            let mut v = [0.0; 3];
            v[axis] = sign;
            v[(axis + 1) % 3] = offsets[cell % 4];
            v[(axis + 2) % 3] = offsets[cell / 4];
            let r = libm::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            *key = v.map(|c| c / r);
        }
        keys
    }

    /// The cube-sphere compact network (q = 3): a quarter of the groups is out of reach of a
    /// sphere point, and every key of a skipped group blends to exactly 0, in both scalars.
    fn check_skipping<S: Scalar>() {
        let mut weights = [0_u8; 96 * 3 * 4];
        for (key, chunk) in cube_sphere().iter().zip(weights.chunks_exact_mut(12)) {
            for (c, word) in key.iter().zip(chunk.chunks_exact_mut(4)) {
                word.copy_from_slice(&ScalarKind::F32.encode(*c).unwrap_or_default());
            }
        }
        let mut sharpness = [0_u8; 96 * 4];
        for word in sharpness.chunks_exact_mut(4) {
            word.copy_from_slice(&ScalarKind::F32.encode(3.0).unwrap_or_default());
        }
        let payload = CaoEnPayload {
            domain: 0,
            blending: Blending::Compact.code(),
            normalized: false,
            source_dimension: 3,
            target_dimension: 3,
            weights: &weights,
            targets: &weights,
            sharpness: &sharpness,
            metadata: &[],
        };
        let mut blob = [0_u8; 4096];
        let len = payload.write(ScalarKind::F32, &mut blob).unwrap_or(0);
        let mut model = CaoEnModel::<S, 128>::new();
        assert!(model.load(blob.get(..len).unwrap_or(&[])).is_ok());
        let limit = S::from_f32_saturating(S::MAX_PARAMETER);
        let norm_limit = S::from_f32_saturating(GROUP_NORM_LIMIT);
        let (mut groups, mut skipped) = (0, 0);
        for p in 0..100 {
            let z = 1.0 - 2.0 * (f64::from(p) + 0.5) / 100.0;
            let r = libm::sqrt(1.0 - z * z);
            let a = 2.4 * f64::from(p);
            let x =
                [r * libm::cos(a), r * libm::sin(a), z].map(|c| S::from_f32_saturating(c as f32));
            let norm = crate::scalar::dot(S::ZERO, &x, &x).sqrt();
            let cosine = |key: &Key<S>| crate::scalar::dot(S::ZERO, &x, &key.weight[..3]);
            let mut index = 0;
            while let Some(key) = model.keys.get(index) {
                assert!(key.group.span > 0, "every group of this network is tested");
                let span = usize::from(key.group.span);
                groups += 1;
                if key.group.out_of_reach(cosine(key), norm, norm_limit) {
                    skipped += 1;
                    for other in model.keys.iter().skip(index).take(span) {
                        let (k, slope) = blend::<S, true>(
                            Blending::Compact,
                            cosine(other),
                            other.sharpness,
                            other.power,
                            limit,
                        );
                        assert!(k == S::ZERO && slope == S::ZERO);
                    }
                }
                index += span;
            }
        }
        // 12 groups per point. A cap of q = 3 (48°) covers 1/6 of the sphere, and a group is
        // skipped beyond about 48° plus its own spread (≈ 45°): 298 of 1200 here.
        assert_eq!(groups, 1200);
        assert!(skipped > 240, "{skipped} of {groups} groups skipped");
    }

    #[test]
    fn out_of_reach_groups_blend_to_zero_f32() {
        check_skipping::<f32>();
    }

    #[test]
    fn out_of_reach_groups_blend_to_zero_q16() {
        check_skipping::<Q16>();
    }
}

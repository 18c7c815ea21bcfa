//! Converting between the trainer's `f64` network and the core's blob.
//!
//! The blob's parameters are the network's parameters, in the same layout, rounded to the
//! stored scalar. Its metadata (opaque to the core) is a postcard-encoded [`ImplicitMetadata`]:
//! the feature each leaf learned and, when the model was trained here, the training summary —
//! so `neurosurf info` can tell the model's story and `--init` can check it warm-starts the
//! right tree.

use neurosurf_core::blob::ModelKind;
use neurosurf_core::frame::Frame as CoreFrame;
use neurosurf_core::implicit::guard::split_tree;
use neurosurf_core::implicit::{GUARD_CODE, GUARD_LEN, ImplicitPayload, MAX_GUARDS, ModuleKind};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use std::path::Path;

use neurosurf_core::BlobError;
use serde::{Deserialize, Serialize};

use super::frame::Frame;
use super::network::{Guard, ImplicitNetwork};
use super::normalize::Normalization;
use super::train::TrainingSummary;
use crate::blob::{StoredFrame, check_q16_origin, encode};
use crate::error::{Error, Result};

/// What the trainer stores next to the parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImplicitMetadata {
    /// Feature index of each module in post-order (`None` for nodes).
    pub leaf_features: Vec<Option<u32>>,
    /// How the model was trained, when it was.
    pub summary: Option<TrainingSummary>,
}

/// An implicit blob read back into the trainer.
#[derive(Clone, Debug)]
pub struct DecodedImplicit {
    /// The network, parameters widened to `f64` exactly.
    pub network: ImplicitNetwork,
    /// The trainer's metadata, if the blob carries readable metadata.
    pub metadata: Option<ImplicitMetadata>,
    /// How the parameters were stored.
    pub stored_as: ScalarKind,
}

/// Encodes `network` as a blob storing its parameters as `scalar`.
///
/// # Errors
/// [`Error::InvalidInput`] when a parameter cannot be stored: not finite, or outside what the
/// core loads for that scalar (`±Q16::MAX_PARAMETER` for Q16.16), or a scalar the core's
/// implicit models are not stored in.
pub fn to_blob(
    network: &ImplicitNetwork,
    summary: Option<&TrainingSummary>,
    scalar: ScalarKind,
) -> Result<Vec<u8>> {
    let limit = match scalar {
        ScalarKind::F32 => f64::from(f32::MAX),
        ScalarKind::Q16_16 => f64::from(<Q16 as Scalar>::MAX_PARAMETER),
        other => {
            return Err(Error::invalid(format!(
                "implicit models are stored as f32 or q16.16, not {}",
                other.name()
            )));
        }
    };
    let (frame, stored_frame) = blob_frame(network, scalar)?;
    let network = &frame.network_to_model(network);
    let guards: Vec<f64> = network
        .guards()
        .iter()
        .flat_map(|g| g.parameters())
        .collect();
    let mut parameters = Vec::with_capacity((network.params().len() + guards.len()) * 4);
    for (index, &value) in network.params().iter().chain(&guards).enumerate() {
        let word = scalar
            .encode(value)
            .filter(|_| value.abs() <= limit)
            .ok_or_else(|| {
                let part = Part::of(network, index);
                Error::invalid(format!(
                    "parameter {index} = {value} ({}) cannot be stored as {} (limit ±{limit}){}",
                    part.describe(),
                    scalar.name(),
                    part.advice(value, limit)
                ))
            })?;
        parameters.extend_from_slice(&word);
    }
    let metadata = ImplicitMetadata {
        leaf_features: network.leaf_features().to_vec(),
        summary: summary.map(TrainingSummary::without_timings),
    };
    let metadata = postcard::to_allocvec(&metadata)
        .map_err(|e| Error::invalid(format!("cannot encode the model metadata: {e}")))?;
    if network.guards().len() > MAX_GUARDS {
        return Err(Error::invalid(format!(
            "{} sign guards; the core loads at most {MAX_GUARDS}",
            network.guards().len()
        )));
    }
    let tree: Vec<u8> = network
        .kinds()
        .iter()
        .map(|k| k.code())
        .chain(network.guards().iter().map(|_| GUARD_CODE))
        .collect();
    let width = u8::try_from(network.width())
        .map_err(|_| Error::invalid(format!("width {} does not fit", network.width())))?;
    let payload = ImplicitPayload {
        width,
        frame: stored_frame.payload(),
        tree: &tree,
        parameters: &parameters,
        metadata: &metadata,
    };
    encode(ModelKind::Implicit, scalar, &payload)
}

/// Checks, before training, that a model of `positions` can be stored as `scalar`: its frame's
/// origin (near the points' centre) must lie within what Q16.16 holds.
///
/// # Errors
/// [`Error::InvalidInput`] naming the coordinate, the limit and the way out.
pub fn check_storable(positions: &[[f64; 3]], scalar: ScalarKind) -> Result<()> {
    let Some(first) = positions.first() else {
        return Ok(());
    };
    let (lo, hi) = positions.iter().fold((*first, *first), |(lo, hi), p| {
        (
            [0, 1, 2].map(|k| lo[k].min(p[k])),
            [0, 1, 2].map(|k| hi[k].max(p[k])),
        )
    });
    check_q16_origin([0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])), scalar)
}

/// The frame a blob keeps `network` in ([`neurosurf_core::frame`]): the root module's centre
/// and the power of two nearest the root's scale (its matrix's largest row norm). The stored
/// normalizations and guards are then of order one whatever the data's units.
fn blob_frame(network: &ImplicitNetwork, scalar: ScalarKind) -> Result<(Frame, StoredFrame)> {
    let root = network
        .normalization(network.root())
        .unwrap_or(Normalization {
            center: [0.0; 3],
            matrix: [[0.0; 3]; 3],
        });
    let scale = root
        .matrix
        .iter()
        .map(|row| row.iter().map(|a| a * a).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    let stored = StoredFrame::new(root.center, scale, scalar)?;
    let frame = Frame {
        center: stored.origin,
        scale: (-f64::from(stored.shift)).exp2(),
    };
    Ok((frame, stored))
}

/// Where a blob parameter sits.
enum Part {
    /// A module's normalization in the blob's frame: its centre or its matrix (large for a
    /// feature much smaller than the whole shape).
    Normalization { module: usize, centre: bool },
    /// A module's trained weights and biases.
    Weights { module: usize },
    /// A sign guard's centre, inverse radius (large for a small guard) or amplitude.
    Guard { guard: usize, part: usize },
}

impl Part {
    /// Parameter `index` of `network`'s blob: the modules' parameters, then the guards'.
    fn of(network: &ImplicitNetwork, index: usize) -> Part {
        let mut start = 0;
        for module in 0..network.module_count() {
            let layout = network.layout(module);
            if index < start + layout.len {
                let offset = index - start;
                return if offset < layout.trainable_start {
                    // A centre (3), then a matrix (9).
                    Part::Normalization {
                        module,
                        centre: offset < 3,
                    }
                } else {
                    Part::Weights { module }
                };
            }
            start += layout.len;
        }
        Part::Guard {
            guard: (index - start) / GUARD_LEN,
            part: (index - start) % GUARD_LEN,
        }
    }

    fn describe(&self) -> String {
        match *self {
            Part::Normalization { module, centre } => format!(
                "module {module}'s normalization {}",
                if centre { "centre" } else { "matrix" }
            ),
            Part::Weights { module } => format!("module {module}'s weights"),
            Part::Guard { guard, part } => format!(
                "sign guard {guard}'s {}",
                ["centre", "centre", "centre", "inverse radius", "amplitude"][part.min(4)]
            ),
        }
    }

    /// How to make this part's `value` fit within ±`limit`. The blob's frame keeps every
    /// part of order one in any units, so what is left is a part far out of scale with the
    /// whole shape.
    fn advice(&self, value: f64, limit: f64) -> String {
        let ratio = value.abs() / limit;
        match self {
            Part::Normalization { centre: false, .. } | Part::Guard { part: 3, .. } => format!(
                ": it is {ratio:.1}× what fits, for a part much smaller than the whole shape; \
                 store the model as f32, or train with fewer features"
            ),
            Part::Normalization { centre: true, .. } | Part::Guard { part: 0..=2, .. } => {
                format!(
                    ": it is {ratio:.1}× what fits, for a part far from the shape's centre; \
                     store the model as f32"
                )
            }
            _ => format!(": it is {ratio:.1}× what fits; store the model as f32"),
        }
    }
}

/// Reads an implicit blob back into an `f64` network (parameters widened exactly). `path`
/// only names the source in errors.
///
/// # Errors
/// [`Error::Blob`] for framing, kind, storage and non-finite parameters; [`Error::Format`]
/// when the tree and parameters do not form a model.
pub fn from_blob(bytes: &[u8], path: &Path) -> Result<DecodedImplicit> {
    let rejected = |source| Error::Blob {
        path: path.to_path_buf(),
        source,
    };
    let (header, payload) = ImplicitPayload::from_blob(bytes).map_err(rejected)?;
    let stored_as = header.scalar;
    if stored_as.stored_bytes() != 4 {
        return Err(rejected(BlobError::UnsupportedStorage {
            model: ModelKind::Implicit,
            scalar: stored_as,
        }));
    }
    let (tree, guard_count) = split_tree(payload.tree).map_err(rejected)?;
    let mut kinds = Vec::with_capacity(tree.len());
    for (module, &code) in tree.iter().enumerate() {
        kinds.push(ModuleKind::from_code(code).ok_or(rejected(BlobError::InvalidTree { module }))?);
    }
    if !payload.parameters.len().is_multiple_of(4) {
        return Err(Error::format(
            path,
            format!(
                "{} parameter bytes is not a whole number of 4-byte words",
                payload.parameters.len()
            ),
        ));
    }
    let mut params = Vec::with_capacity(payload.parameters.len() / 4);
    for (index, chunk) in payload.parameters.chunks_exact(4).enumerate() {
        let word = [chunk[0], chunk[1], chunk[2], chunk[3]];
        let value = match stored_as {
            ScalarKind::F32 => f64::from(f32::from_le_bytes(word)),
            _ => f64::from(i32::from_le_bytes(word)) / 65536.0,
        };
        if !value.is_finite() {
            return Err(rejected(BlobError::NonFiniteParameter { index }));
        }
        params.push(value);
    }
    // The stored frame, exactly: a Q16.16 or f32 word is exact in f64.
    CoreFrame::<f32>::from_payload(&payload.frame, stored_as).map_err(rejected)?;
    let stored_frame = StoredFrame::read(&payload.frame, stored_as);
    let frame = Frame {
        center: stored_frame.origin,
        scale: (-f64::from(stored_frame.shift)).exp2(),
    };
    let guard_params = params.split_off(params.len().saturating_sub(GUARD_LEN * guard_count));
    let guards: Vec<Guard> = guard_params
        .chunks_exact(GUARD_LEN)
        .map(|g| Guard {
            center: [g[0], g[1], g[2]],
            inverse_radius: g[3],
            amplitude: g[4],
        })
        .collect();
    if guards.len() != guard_count || guards.iter().any(|g| g.inverse_radius <= 0.0) {
        return Err(Error::format(
            path,
            "the sign guards' parameters are missing or have a radius that is not positive",
        ));
    }
    let metadata: Option<ImplicitMetadata> = postcard::from_bytes(payload.metadata).ok();
    let leaf_features = match &metadata {
        Some(m) if m.leaf_features.len() == kinds.len() => m.leaf_features.clone(),
        _ => {
            // Foreign blob: number the leaves in post-order.
            let mut next = 0;
            kinds
                .iter()
                .map(|k| {
                    (*k == ModuleKind::Leaf).then(|| {
                        next += 1;
                        next - 1
                    })
                })
                .collect()
        }
    };
    let network =
        ImplicitNetwork::from_parts(usize::from(payload.width), kinds, leaf_features, params)
            .map_err(|e| Error::format(path, format!("not a valid implicit model: {e}")))?
            .with_guards(guards);
    let network = frame.network_to_world(&network);
    Ok(DecodedImplicit {
        network,
        metadata,
        stored_as,
    })
}

impl crate::evaluate::HostModel for DecodedImplicit {
    const KIND: ModelKind = ModelKind::Implicit;
    const OUTPUT: crate::evaluate::Output = crate::evaluate::Output::Field;

    fn from_blob(bytes: &[u8], path: &Path) -> Result<Self> {
        from_blob(bytes, path)
    }

    fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    fn parameter_count(&self) -> usize {
        self.network.params().len()
    }

    fn query_arity(&self) -> usize {
        3
    }

    fn field(&self, x: [f64; 3]) -> Option<(f64, [f64; 3])> {
        Some(self.network.eval(x))
    }
}

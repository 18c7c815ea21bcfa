//! Converting between the trainer's `f64` [`SurfaceNetwork`] and the core's surface-network
//! blobs (layout in `neurosurf_core::parametric`).
//!
//! The blob stores input gains g = 1/s (the core multiplies, never divides); reading back
//! gives s = 1/g, equal to the trained scale up to the storage rounding. The metadata (opaque
//! to the core) is a postcard-encoded [`NetworkSummary`]. Every blob written here is loaded
//! back by the core before it is returned.

use std::path::Path;

use neurosurf_core::BlobError;
use neurosurf_core::blob::{ModelKind, stored_value};
use neurosurf_core::parametric::{
    self as core_parametric, SurfaceNetworkModel, SurfaceNetworkPayload,
};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use serde::{Deserialize, Serialize};

use super::activation::Activation;
use super::fit::SurfaceFit;
use super::network::SurfaceNetwork;
use crate::blob::{StoredFrame, encode};
use crate::error::{Error, Result};

/// How a surface-network blob was made (stored as its metadata).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NetworkSummary {
    /// Points the network was fitted to.
    pub points: usize,
    /// Configurations the topology search trained.
    pub candidates: usize,
    /// RMS distance between the network and the points (the points' units).
    pub rms_error: f64,
    /// The same over the points' bounding-box diagonal.
    pub relative_rms_error: f64,
    /// Wall-clock seconds of the fit (0 in a blob: blobs store no wall time).
    pub seconds: f64,
    /// The region of the parameter plane the points cover: their boundary loop, at most
    /// [`MAX_REGION_VERTICES`] corners, counter-clockwise (empty when unknown, as in blobs
    /// written before it was stored). Outside it the network extrapolates.
    pub region: Vec<[f64; 2]>,
}

/// The summary as blobs stored it before the region.
#[derive(Deserialize)]
struct SummaryWithoutRegion {
    points: usize,
    candidates: usize,
    rms_error: f64,
    relative_rms_error: f64,
    seconds: f64,
}

/// Most corners of a stored parameter region.
pub const MAX_REGION_VERTICES: usize = 256;

impl NetworkSummary {
    /// The summary of a fit that took `seconds`, with no region.
    pub fn of(fit: &SurfaceFit, points: usize, seconds: f64) -> Self {
        NetworkSummary {
            points,
            candidates: fit.search.candidates.len(),
            rms_error: fit.rms_error,
            relative_rms_error: fit.relative_rms_error,
            seconds,
            region: Vec::new(),
        }
    }

    /// The summary stored in a blob's metadata, in either layout; `None` for other bytes.
    pub fn decode(metadata: &[u8]) -> Option<Self> {
        postcard::from_bytes(metadata).ok().or_else(|| {
            let old: SummaryWithoutRegion = postcard::from_bytes(metadata).ok()?;
            Some(NetworkSummary {
                points: old.points,
                candidates: old.candidates,
                rms_error: old.rms_error,
                relative_rms_error: old.relative_rms_error,
                seconds: old.seconds,
                region: Vec::new(),
            })
        })
    }

    /// Whether (u, v) lies in the stored region (always, when none is stored).
    pub fn covers(&self, u: f64, v: f64) -> bool {
        self.region.len() < 3 || super::planar::inside_polygon([u, v], &self.region)
    }
}

/// The region of the parameter plane that `parameters` cover: their boundary loop
/// ([`super::boundary_loop`] with the default options), every k-th corner kept when it has
/// more than [`MAX_REGION_VERTICES`].
///
/// # Errors
/// As [`super::boundary_loop`].
pub fn parameter_region(parameters: &[[f64; 2]]) -> Result<Vec<[f64; 2]>> {
    let cycle = super::boundary_loop(parameters, &super::BoundaryOptions::default())?;
    let step = cycle.len().div_ceil(MAX_REGION_VERTICES).max(1);
    Ok(cycle
        .iter()
        .step_by(step)
        .map(|&i| parameters[i as usize])
        .collect())
}

/// A surface-network blob read back into `f64`.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedNetwork {
    /// The network, words widened to `f64` exactly (scales as 1/g).
    pub network: SurfaceNetwork,
    /// The fit summary, if the blob carries a readable one.
    pub summary: Option<NetworkSummary>,
    /// How the words were stored.
    pub stored_as: ScalarKind,
}

impl Activation {
    /// The core's activation of the same formula.
    pub fn core(self) -> core_parametric::Activation {
        match self {
            Activation::LogSig => core_parametric::Activation::LogSig,
            Activation::TanSig => core_parametric::Activation::TanSig,
            Activation::RadBas => core_parametric::Activation::RadBas,
            Activation::TriBas => core_parametric::Activation::TriBas,
        }
    }
}

/// Encodes `network` as a [`ModelKind::SurfaceNetwork`] blob storing its words as `scalar`.
///
/// # Errors
/// [`Error::InvalidInput`] when a layer is wider than the core's
/// [`MAX_NEURONS`](core_parametric::MAX_NEURONS) or deeper than
/// [`MAX_HIDDEN_LAYERS`](core_parametric::MAX_HIDDEN_LAYERS), a word cannot be stored in
/// `scalar` (Q16.16: |value| ≤ 1024 for evaluation), or the core would not load the result.
pub fn network_to_blob(
    network: &SurfaceNetwork,
    summary: Option<&NetworkSummary>,
    scalar: ScalarKind,
) -> Result<Vec<u8>> {
    let sizes = network.hidden_sizes();
    if sizes.len() > core_parametric::MAX_HIDDEN_LAYERS {
        return Err(Error::invalid(format!(
            "{} hidden layers: the core evaluates at most {}",
            sizes.len(),
            core_parametric::MAX_HIDDEN_LAYERS
        )));
    }
    if let Some(n) = sizes.iter().find(|&&n| n > core_parametric::MAX_NEURONS) {
        return Err(Error::invalid(format!(
            "a hidden layer of {n} neurons: the core evaluates at most {}",
            core_parametric::MAX_NEURONS
        )));
    }
    let hidden: Vec<u8> = sizes.iter().map(|&n| n as u8).collect();
    let mut values = vec![
        network.input_center[0],
        network.input_center[1],
        1.0 / network.input_scale[0],
        1.0 / network.input_scale[1],
    ];
    values.extend(network.parameters());
    // The output in the blob's frame: origin at the output centre, 2^shift near 1 / the output
    // scale, so that c_p and s_p are of order one (c_p the origin's rounding, s_p within
    // [0.7, 1.4]) whatever the data's units.
    let frame = StoredFrame::new(network.output_center, 1.0 / network.output_scale, scalar)?;
    values.extend(frame.to_model(network.output_center));
    values.push(network.output_scale * f64::from(frame.shift).exp2());
    let mut words = Vec::with_capacity(values.len() * 4);
    let count = values.len();
    for (index, &value) in values.iter().enumerate() {
        let word = scalar.encode(value).ok_or_else(|| {
            Error::invalid(format!(
                "word {index} of the network ({value}, {}) cannot be stored as {}",
                word_role(index, count).0,
                scalar.name()
            ))
        })?;
        words.extend_from_slice(&word);
    }
    let metadata = match summary {
        None => Vec::new(),
        // No wall time: the same points, options and seed give the same bytes.
        Some(summary) => postcard::to_allocvec(&NetworkSummary {
            seconds: 0.0,
            ..summary.clone()
        })
        .map_err(|e| Error::invalid(format!("cannot encode the fit summary: {e}")))?,
    };
    let payload = SurfaceNetworkPayload {
        activation: network.activation.core().code(),
        hidden: &hidden,
        frame: frame.payload(),
        parameters: &words,
        metadata: &metadata,
    };
    let bytes = encode(ModelKind::SurfaceNetwork, scalar, &payload)?;
    let loads = match scalar {
        ScalarKind::Q16_16 => SurfaceNetworkModel::<Q16>::from_blob(&bytes).map(drop),
        _ => SurfaceNetworkModel::<f32>::from_blob(&bytes).map(drop),
    };
    loads.map_err(|e| {
        let why = match e {
            BlobError::ParameterOutOfRange { index } if index < count => {
                let (part, advice) = word_role(index, count);
                format!(
                    "word {index} ({}, {part}) is beyond ±{} in {}: {advice}",
                    values[index],
                    <Q16 as Scalar>::MAX_PARAMETER,
                    scalar.name()
                )
            }
            other => other.to_string(),
        };
        Error::invalid(format!("the core would not load this network: {why}"))
    })?;
    Ok(bytes)
}

/// What word `index` of `count` in a surface-network blob is, and how to make it fit a
/// fixed-point range: the input's centre and inverse scale (u, v), the layers, the output's
/// centre (x, y, z) and scale.
fn word_role(index: usize, count: usize) -> (&'static str, &'static str) {
    const F32: &str = "store the network as f32";
    match index {
        0 | 1 => ("the parameters' centre", F32),
        2 | 3 => ("the parameters' inverse scale", F32),
        i if i + 4 < count => (
            "a layer weight",
            "store the network as f32, or fit fewer neurons",
        ),
        i if i + 1 < count => (
            "the output centre",
            "store the network as f32, or move the points nearer the origin before fitting",
        ),
        _ => (
            "the output scale",
            "store the network as f32, or scale the points down before fitting",
        ),
    }
}

/// Reads a surface-network blob back into `f64`. `path` only names the source in errors.
///
/// # Errors
/// [`Error::Blob`] when the core rejects the blob (framing, kind, shapes, words).
pub fn network_from_blob(bytes: &[u8], path: &Path) -> Result<DecodedNetwork> {
    let rejected = |source| Error::Blob {
        path: path.to_path_buf(),
        source,
    };
    let core = SurfaceNetworkModel::<f32>::from_blob(bytes).map_err(rejected)?;
    let (header, payload) = SurfaceNetworkPayload::from_blob(bytes).map_err(rejected)?;
    let words: Vec<f64> = payload
        .parameters
        .chunks_exact(4)
        .map(|w| stored_value(w, header.scalar).unwrap_or(0.0))
        .collect();
    let activation = Activation::ALL
        .into_iter()
        .find(|a| a.core() == core.activation())
        .unwrap_or_default();
    let hidden: Vec<usize> = payload.hidden.iter().map(|&n| usize::from(n)).collect();
    let n = words.len();
    let frame = StoredFrame::read(&payload.frame, header.scalar);
    let mut network = SurfaceNetwork::zeros(
        &hidden,
        activation,
        [words[0], words[1]],
        [1.0 / words[2], 1.0 / words[3]],
        frame.to_user([words[n - 4], words[n - 3], words[n - 2]]),
        words[n - 1] * (-f64::from(frame.shift)).exp2(),
    )?;
    network.set_parameters(&words[4..n - 4])?;
    Ok(DecodedNetwork {
        network,
        summary: NetworkSummary::decode(payload.metadata),
        stored_as: header.scalar,
    })
}

impl crate::evaluate::HostModel for DecodedNetwork {
    const KIND: ModelKind = ModelKind::SurfaceNetwork;
    const OUTPUT: crate::evaluate::Output = crate::evaluate::Output::Geometry;

    fn from_blob(bytes: &[u8], path: &Path) -> Result<Self> {
        network_from_blob(bytes, path)
    }

    fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    fn parameter_count(&self) -> usize {
        self.network.parameter_count()
    }

    fn query_arity(&self) -> usize {
        2
    }

    fn geometry(&self, p: &[f64]) -> Option<crate::evaluate::Geometry> {
        let at = |k: usize| p.get(k).copied().unwrap_or(0.0);
        let point = self.network.evaluate(at(0), at(1));
        Some(crate::evaluate::geometry(point.position, point.normal()))
    }

    fn geometry_columns(&self) -> Option<Vec<String>> {
        Some(crate::evaluate::columns(&[
            "u", "v", "x", "y", "z", "nx", "ny", "nz",
        ]))
    }
}

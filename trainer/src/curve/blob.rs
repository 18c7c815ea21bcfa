//! Converting between the trainer's `f64` curves and surfaces and the core's blobs.
//!
//! The control points are stored in the blob's scalar (`f32` or Q16.16), 12 bytes a point. The
//! metadata (opaque to the core) is a postcard-encoded [`FitSummary`], so `neurosurf info` can
//! say how the model was made. Every blob written here is loaded back by the core before it is
//! returned: what the trainer writes, the core (and the microcontroller) accepts.

use std::path::Path;

use neurosurf_core::BlobError;
use neurosurf_core::blob::ModelKind;
use neurosurf_core::curve::{self as core_curve, CurvePayload, SurfacePayload};
use neurosurf_core::frame::{FramePayload, MAX_Q16_ORIGIN};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use serde::{Deserialize, Serialize};

use super::spline::{BSplineCurve, BSplineSurface};
use crate::blob::{StoredFrame, encode};
use crate::error::{Error, Result};

/// How a curve or surface blob was made (stored as its metadata).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FitSummary {
    /// `approximation`, `interpolation` or `surface`.
    pub method: String,
    /// Scattered input points.
    pub points: usize,
    /// Kohonen neurons (chain length, or map rows × columns).
    pub neurons: usize,
    /// The seed of the Kohonen training.
    pub seed: u64,
    /// Root mean square distance from the ordered input points to the fit, at their
    /// parameters.
    pub rms_residual: f64,
    /// Largest such distance.
    pub max_residual: f64,
    /// Wall-clock seconds of ordering and fitting (0 in a blob: blobs store no wall time).
    pub seconds: f64,
}

/// A curve blob read back into `f64`.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedCurve {
    /// The curve, control points widened to `f64` exactly.
    pub curve: BSplineCurve,
    /// The fit summary, if the blob carries a readable one.
    pub summary: Option<FitSummary>,
    /// How the control points were stored.
    pub stored_as: ScalarKind,
}

/// A spline-surface blob read back into `f64`.
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedSurface {
    /// The surface, control points widened to `f64` exactly.
    pub surface: BSplineSurface,
    /// The fit summary, if the blob carries a readable one.
    pub summary: Option<FitSummary>,
    /// How the control points were stored.
    pub stored_as: ScalarKind,
}

/// Encodes `curve` as a [`ModelKind::Curve`] blob storing its control points as `scalar`.
///
/// # Errors
/// [`Error::InvalidInput`] when the curve is invalid, a coordinate cannot be stored in
/// `scalar` (the core loads Q16.16 values up to ±1024), or the core would not load the result (more control
/// points than its default capacity of [`core_curve::DEFAULT_CURVE_POINTS`]).
pub fn curve_to_blob(
    curve: &BSplineCurve,
    summary: Option<&FitSummary>,
    scalar: ScalarKind,
) -> Result<Vec<u8>> {
    curve.validate()?;
    let frame = control_frame(&curve.control, scalar)?;
    let control = encode_control(&curve.control, &frame, scalar)?;
    let metadata = encode_summary(summary)?;
    let payload = CurvePayload {
        dimension: if curve.dimension == 2 { 2 } else { 3 },
        closed: curve.closed,
        // validate() checked 2..=5.
        degree: curve.degree as u8,
        frame: frame.payload(),
        control: &control,
        metadata: &metadata,
    };
    let bytes = encode(ModelKind::Curve, scalar, &payload)?;
    let loads = match scalar {
        ScalarKind::Q16_16 => core_curve::BSplineCurve::<Q16>::from_blob(&bytes).map(drop),
        _ => core_curve::BSplineCurve::<f32>::from_blob(&bytes).map(drop),
    };
    loads.map_err(|e| not_loadable("curve", e))?;
    Ok(bytes)
}

/// Encodes `surface` as a [`ModelKind::SplineSurface`] blob storing its control points as
/// `scalar`.
///
/// # Errors
/// As [`curve_to_blob`]; the core's default capacity is
/// [`core_curve::DEFAULT_SURFACE_POINTS`] control points, and each direction holds at most
/// 65 535.
pub fn surface_to_blob(
    surface: &BSplineSurface,
    summary: Option<&FitSummary>,
    scalar: ScalarKind,
) -> Result<Vec<u8>> {
    surface.validate()?;
    let count = |n: usize| {
        u16::try_from(n).map_err(|_| {
            Error::invalid(format!(
                "{n} control points in one direction is more than a blob holds (65 535)"
            ))
        })
    };
    let frame = control_frame(&surface.control, scalar)?;
    let control = encode_control(&surface.control, &frame, scalar)?;
    let metadata = encode_summary(summary)?;
    let payload = SurfacePayload {
        closed_u: surface.closed_u,
        closed_v: surface.closed_v,
        degree_u: surface.degree_u as u8,
        degree_v: surface.degree_v as u8,
        count_u: count(surface.count_u)?,
        count_v: count(surface.count_v)?,
        frame: frame.payload(),
        control: &control,
        metadata: &metadata,
    };
    let bytes = encode(ModelKind::SplineSurface, scalar, &payload)?;
    let loads = match scalar {
        ScalarKind::Q16_16 => core_curve::BSplineSurface::<Q16>::from_blob(&bytes).map(drop),
        _ => core_curve::BSplineSurface::<f32>::from_blob(&bytes).map(drop),
    };
    loads.map_err(|e| not_loadable("spline surface", e))?;
    Ok(bytes)
}

/// Reads a curve blob back into `f64`. `path` only names the source in errors.
///
/// # Errors
/// [`Error::Blob`] when the framing, kind, storage or control points are rejected (the core's
/// own validation); [`Error::Format`] when the control points do not form a curve.
pub fn curve_from_blob(bytes: &[u8], path: &Path) -> Result<DecodedCurve> {
    let rejected = |source| Error::Blob {
        path: path.to_path_buf(),
        source,
    };
    core_curve::BSplineCurve::<f32>::from_blob(bytes).map_err(rejected)?;
    let (header, payload) = CurvePayload::from_blob(bytes).map_err(rejected)?;
    let curve = BSplineCurve {
        dimension: usize::from(payload.dimension),
        closed: payload.closed,
        degree: usize::from(payload.degree),
        control: decode_control(payload.control, &payload.frame, header.scalar),
    };
    curve
        .validate()
        .map_err(|e| Error::format(path, format!("not a valid curve: {e}")))?;
    Ok(DecodedCurve {
        curve,
        summary: postcard::from_bytes(payload.metadata).ok(),
        stored_as: header.scalar,
    })
}

/// Reads a spline-surface blob back into `f64`. `path` only names the source in errors.
///
/// # Errors
/// As [`curve_from_blob`].
pub fn surface_from_blob(bytes: &[u8], path: &Path) -> Result<DecodedSurface> {
    let rejected = |source| Error::Blob {
        path: path.to_path_buf(),
        source,
    };
    core_curve::BSplineSurface::<f32>::from_blob(bytes).map_err(rejected)?;
    let (header, payload) = SurfacePayload::from_blob(bytes).map_err(rejected)?;
    let surface = BSplineSurface {
        closed_u: payload.closed_u,
        closed_v: payload.closed_v,
        degree_u: usize::from(payload.degree_u),
        degree_v: usize::from(payload.degree_v),
        count_u: usize::from(payload.count_u),
        count_v: usize::from(payload.count_v),
        control: decode_control(payload.control, &payload.frame, header.scalar),
    };
    surface
        .validate()
        .map_err(|e| Error::format(path, format!("not a valid spline surface: {e}")))?;
    Ok(DecodedSurface {
        surface,
        summary: postcard::from_bytes(payload.metadata).ok(),
        stored_as: header.scalar,
    })
}

/// The blob frame of a control net ([`neurosurf_core::frame`]): the centre of its bounding
/// box and the power of two nearest 4 over its diagonal, so that the stored points are of
/// order one whatever the data's units. A 2-D curve's has z = 0.
fn control_frame(control: &[[f64; 3]], scalar: ScalarKind) -> Result<StoredFrame> {
    let Some(first) = control.first() else {
        return StoredFrame::new([0.0; 3], 1.0, scalar);
    };
    let (lo, hi) = control.iter().fold((*first, *first), |(lo, hi), p| {
        (
            [0, 1, 2].map(|k| lo[k].min(p[k])),
            [0, 1, 2].map(|k| hi[k].max(p[k])),
        )
    });
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    StoredFrame::new(
        [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])),
        4.0 / diagonal,
        scalar,
    )
}

fn encode_control(
    control: &[[f64; 3]],
    frame: &StoredFrame,
    scalar: ScalarKind,
) -> Result<Vec<u8>> {
    // Positions are convex combinations of the control points, in the user's units: Q16.16
    // must hold those.
    if scalar == ScalarKind::Q16_16 {
        let limit = f64::from(MAX_Q16_ORIGIN);
        if let Some((index, point)) = control
            .iter()
            .enumerate()
            .find(|(_, p)| p.iter().any(|c| c.abs() > limit))
        {
            return Err(Error::invalid(format!(
                "control point {index} {point:?} has a coordinate beyond ±{limit}, what \
                 Q16.16 represents; store it as f32 (--scalar f32), or move or scale the \
                 points toward the origin before fitting"
            )));
        }
    }
    let control: Vec<[f64; 3]> = control.iter().map(|&p| frame.to_model(p)).collect();
    let control = &control[..];
    // What the core accepts of a stored parameter in this scalar (Q16.16: ±1024, so that its
    // accumulators provably cannot overflow).
    let limit = match scalar {
        ScalarKind::Q16_16 => f64::from(<Q16 as Scalar>::MAX_PARAMETER),
        _ => f64::from(<f32 as Scalar>::MAX_PARAMETER),
    };
    let largest = control.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut out = Vec::with_capacity(control.len() * 12);
    for (index, point) in control.iter().enumerate() {
        for &c in point {
            if c.is_finite() && c.abs() > limit {
                return Err(Error::invalid(format!(
                    "control point {index} {point:?} has a coordinate beyond ±{limit}, the \
                     largest {} value the core loads (the largest here is {largest:.4e}); store \
                     it as f32 (--scalar f32), or scale the points by at most {:.4e} \
                     before fitting",
                    scalar.name(),
                    limit / largest
                )));
            }
            let word = scalar.encode(c).ok_or_else(|| {
                Error::invalid(format!(
                    "control point {index} {point:?} cannot be stored as {}",
                    scalar.name()
                ))
            })?;
            out.extend_from_slice(&word);
        }
    }
    Ok(out)
}

/// The control points of a payload the core has validated (so whole 12-byte points in a
/// 4-byte scalar), widened exactly and moved from the blob's frame into the user's units.
fn decode_control(bytes: &[u8], frame: &FramePayload<'_>, scalar: ScalarKind) -> Vec<[f64; 3]> {
    let frame = StoredFrame::read(frame, scalar);
    let word = |b: &[u8]| {
        let bits = [b[0], b[1], b[2], b[3]];
        match scalar {
            ScalarKind::Q16_16 => f64::from(i32::from_le_bytes(bits)) / 65536.0,
            _ => f64::from(f32::from_le_bytes(bits)),
        }
    };
    bytes
        .chunks_exact(12)
        .map(|p| frame.to_user([word(&p[0..4]), word(&p[4..8]), word(&p[8..12])]))
        .collect()
}

fn encode_summary(summary: Option<&FitSummary>) -> Result<Vec<u8>> {
    match summary {
        None => Ok(Vec::new()),
        // No wall time: the same points, options and seed give the same bytes.
        Some(summary) => postcard::to_allocvec(&FitSummary {
            seconds: 0.0,
            ..summary.clone()
        })
        .map_err(|e| Error::invalid(format!("cannot encode the fit summary: {e}"))),
    }
}

fn not_loadable(what: &str, error: BlobError) -> Error {
    Error::invalid(format!("the core would not load this {what}: {error}"))
}

impl crate::evaluate::HostModel for DecodedCurve {
    const KIND: ModelKind = ModelKind::Curve;
    const OUTPUT: crate::evaluate::Output = crate::evaluate::Output::Geometry;

    fn from_blob(bytes: &[u8], path: &Path) -> Result<Self> {
        curve_from_blob(bytes, path)
    }

    fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    fn parameter_count(&self) -> usize {
        self.curve.control.len() * 3
    }

    fn query_arity(&self) -> usize {
        1
    }

    fn geometry(&self, p: &[f64]) -> Option<crate::evaluate::Geometry> {
        let t = p.first().copied().unwrap_or(0.0);
        Some(crate::evaluate::geometry(
            self.curve.point(t),
            self.curve.tangent(t),
        ))
    }

    fn geometry_columns(&self) -> Option<Vec<String>> {
        Some(crate::evaluate::columns(&[
            "t", "x", "y", "z", "tx", "ty", "tz",
        ]))
    }
}

impl crate::evaluate::HostModel for DecodedSurface {
    const KIND: ModelKind = ModelKind::SplineSurface;
    const OUTPUT: crate::evaluate::Output = crate::evaluate::Output::Geometry;

    fn from_blob(bytes: &[u8], path: &Path) -> Result<Self> {
        surface_from_blob(bytes, path)
    }

    fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    fn parameter_count(&self) -> usize {
        self.surface.control.len() * 3
    }

    fn query_arity(&self) -> usize {
        2
    }

    fn geometry(&self, p: &[f64]) -> Option<crate::evaluate::Geometry> {
        let at = |k: usize| p.get(k).copied().unwrap_or(0.0);
        let (u, v) = (at(0), at(1));
        Some(crate::evaluate::geometry(
            self.surface.point(u, v),
            self.surface.normal(u, v).unwrap_or([0.0; 3]),
        ))
    }

    fn geometry_columns(&self) -> Option<Vec<String>> {
        Some(crate::evaluate::columns(&[
            "u", "v", "x", "y", "z", "nx", "ny", "nz",
        ]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve() -> BSplineCurve {
        BSplineCurve {
            dimension: 2,
            closed: true,
            degree: 3,
            control: vec![
                [0.0, 0.0, 0.0],
                [1.5, 0.25, 0.0],
                [1.0, 1.0, 0.0],
                [-0.75, 0.5, 0.0],
                [-1.0, -1.0, 0.0],
            ],
        }
    }

    #[test]
    fn curves_round_trip_exactly_in_both_scalars() {
        let summary = FitSummary {
            method: "interpolation".into(),
            points: 5,
            neurons: 20,
            seed: 7,
            rms_residual: 0.0,
            max_residual: 0.0,
            seconds: 0.001,
        };
        for scalar in [ScalarKind::F32, ScalarKind::Q16_16] {
            let bytes = curve_to_blob(&curve(), Some(&summary), scalar).unwrap();
            let decoded = curve_from_blob(&bytes, Path::new("c.nsb")).unwrap();
            assert_eq!(decoded.curve, curve(), "{scalar:?}");
            // Everything but the wall time, which blobs do not store.
            let stored = FitSummary {
                seconds: 0.0,
                ..summary.clone()
            };
            assert_eq!(decoded.summary.as_ref(), Some(&stored));
            assert_eq!(decoded.stored_as, scalar);
        }
    }

    #[test]
    fn surfaces_round_trip_and_blobs_of_the_other_kind_are_refused() {
        let mut control = Vec::new();
        for v in 0..4 {
            for u in 0..5 {
                let (x, y) = (f64::from(u) * 0.5, f64::from(v) * 0.25);
                control.push([x, y, x * y]);
            }
        }
        let surface = BSplineSurface {
            closed_u: false,
            closed_v: false,
            degree_u: 3,
            degree_v: 3,
            count_u: 5,
            count_v: 4,
            control,
        };
        let bytes = surface_to_blob(&surface, None, ScalarKind::Q16_16).unwrap();
        let decoded = surface_from_blob(&bytes, Path::new("s.nsb")).unwrap();
        assert_eq!((decoded.surface, decoded.summary), (surface, None));
        let error = curve_from_blob(&bytes, Path::new("s.nsb")).unwrap_err();
        assert!(error.to_string().contains("s.nsb"), "{error}");
    }

    #[test]
    fn coordinates_outside_q16_and_over_capacity_curves_are_refused_clearly() {
        // The blob's frame keeps the stored points near the origin: far and large data
        // stores as Q16.16 while its coordinates are within what Q16.16 represents.
        for (scale, offset) in [(1.0, 1_500.0), (1e-3, 0.0), (1e3, -20_000.0)] {
            let mut moved = curve();
            for p in &mut moved.control {
                p[0] = p[0] * scale + offset;
                p[1] *= scale;
            }
            let bytes = curve_to_blob(&moved, None, ScalarKind::Q16_16).unwrap();
            let decoded = curve_from_blob(&bytes, Path::new("m.nsb")).unwrap();
            for (a, b) in decoded.curve.control.iter().zip(&moved.control) {
                for k in 0..3 {
                    assert!((a[k] - b[k]).abs() <= 1.0 / 65_536.0, "{a:?} {b:?}");
                }
            }
        }
        let mut far = curve();
        far.control[2][0] = 40_000.0;
        let error = curve_to_blob(&far, None, ScalarKind::Q16_16)
            .unwrap_err()
            .to_string();
        // The coordinate, the limit and both fixes are named.
        for part in ["control point 2", "±32767", "--scalar f32", "move or scale"] {
            assert!(error.contains(part), "{part}: {error}");
        }
        assert!(curve_to_blob(&far, None, ScalarKind::F32).is_ok());

        let long = BSplineCurve {
            dimension: 3,
            closed: false,
            degree: 3,
            control: (0..core_curve::DEFAULT_CURVE_POINTS + 1)
                .map(|i| [i as f64 * 0.01, 0.0, 0.0])
                .collect(),
        };
        let error = curve_to_blob(&long, None, ScalarKind::F32).unwrap_err();
        assert!(error.to_string().contains("would not load"), "{error}");
    }
}

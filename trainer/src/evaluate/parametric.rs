//! Evaluating curves and spline surfaces: position and direction (a curve's tangent dC/dt, a
//! surface's unit normal) at parameters, in `f64` (the trainer's reference) or through the
//! core in `f32` or Q16.16.

use neurosurf_core::curve::{BSplineCurve, BSplineSurface, CurvePoint};
use neurosurf_core::scalar::{Q16, Scalar};

use super::{LoadedModel, Precision};
use crate::error::{Error, Result};

/// Position and direction at one parameter, in `f64` whatever the precision it was computed
/// in: a curve's C(t) and dC/dt, or a surface's S(u, v) and unit normal ((0, 0, 0) where the
/// normal does not exist).
pub type Geometry = ([f64; 3], [f64; 3]);

/// The CSV columns of `neurosurf eval` for a curve (`t,x,y,z,tx,ty,tz`) or a spline surface
/// (`u,v,x,y,z,nx,ny,nz`); `None` for field models.
pub fn geometry_columns(model: &LoadedModel) -> Option<&'static [&'static str]> {
    match model {
        LoadedModel::Curve { .. } => Some(&["t", "x", "y", "z", "tx", "ty", "tz"]),
        LoadedModel::SplineSurface { .. } => Some(&["u", "v", "x", "y", "z", "nx", "ny", "nz"]),
        _ => None,
    }
}

impl LoadedModel {
    /// Position and direction of a curve (t = `parameters[i][0]`) or spline surface
    /// ((u, v) = the first two coordinates) in `precision`. Parameters are first rounded to
    /// `f32`, which is what the core receives, so every precision sees the same inputs.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for field models, and when the core cannot load the blob in
    /// that precision.
    pub fn evaluate_geometry(
        &self,
        parameters: &[[f64; 3]],
        precision: Precision,
    ) -> Result<Vec<Geometry>> {
        let rounded: Vec<[f64; 3]> = parameters
            .iter()
            .map(|p| p.map(|c| f64::from(c as f32)))
            .collect();
        match (self, precision) {
            (LoadedModel::Curve { decoded, .. }, Precision::F64) => Ok(rounded
                .iter()
                .map(|p| (decoded.curve.point(p[0]), decoded.curve.tangent(p[0])))
                .collect()),
            (LoadedModel::Curve { bytes, .. }, Precision::F32) => {
                curve_core::<f32>(bytes, &rounded)
            }
            (LoadedModel::Curve { bytes, .. }, Precision::Q16) => {
                curve_core::<Q16>(bytes, &rounded)
            }
            (LoadedModel::SplineSurface { decoded, .. }, Precision::F64) => Ok(rounded
                .iter()
                .map(|p| {
                    let s = &decoded.surface;
                    (
                        s.point(p[0], p[1]),
                        s.normal(p[0], p[1]).unwrap_or([0.0; 3]),
                    )
                })
                .collect()),
            (LoadedModel::SplineSurface { bytes, .. }, Precision::F32) => {
                surface_core::<f32>(bytes, &rounded)
            }
            (LoadedModel::SplineSurface { bytes, .. }, Precision::Q16) => {
                surface_core::<Q16>(bytes, &rounded)
            }
            _ => Err(Error::invalid(format!(
                "a {} model has a field, not a parametric geometry",
                self.kind().name()
            ))),
        }
    }
}

fn load_error(what: &str, scalar: &str, error: impl std::fmt::Display) -> Error {
    Error::invalid(format!(
        "the core cannot load this {what} in {scalar}: {error}"
    ))
}

fn to_scalar<S: Scalar>(c: f64) -> S {
    S::from_f32_saturating(c as f32)
}

/// The core's batch evaluation of a curve in `S`.
fn curve_core<S: Scalar>(bytes: &[u8], parameters: &[[f64; 3]]) -> Result<Vec<Geometry>> {
    let curve =
        BSplineCurve::<S>::from_blob(bytes).map_err(|e| load_error("curve", S::KIND.name(), e))?;
    let t: Vec<S> = parameters.iter().map(|p| to_scalar(p[0])).collect();
    let mut out = vec![CurvePoint::<S>::default(); t.len()];
    curve
        .eval_batch(&t, &mut out)
        .map_err(|e| Error::invalid(format!("batch evaluation: {e}")))?;
    Ok(out
        .iter()
        .map(|p| (p.position.map(S::to_f64), p.tangent.map(S::to_f64)))
        .collect())
}

/// The core's batch evaluation of a spline surface in `S`.
fn surface_core<S: Scalar>(bytes: &[u8], parameters: &[[f64; 3]]) -> Result<Vec<Geometry>> {
    let surface = BSplineSurface::<S>::from_blob(bytes)
        .map_err(|e| load_error("spline surface", S::KIND.name(), e))?;
    let uv: Vec<[S; 2]> = parameters
        .iter()
        .map(|p| [to_scalar(p[0]), to_scalar(p[1])])
        .collect();
    let mut positions = vec![[S::ZERO; 3]; uv.len()];
    let mut normals = vec![None; uv.len()];
    surface
        .position_batch(&uv, &mut positions)
        .and_then(|()| surface.normal_batch(&uv, &mut normals))
        .map_err(|e| Error::invalid(format!("batch evaluation: {e}")))?;
    Ok(positions
        .iter()
        .zip(&normals)
        .map(|(p, n)| (p.map(S::to_f64), n.unwrap_or([S::ZERO; 3]).map(S::to_f64)))
        .collect())
}

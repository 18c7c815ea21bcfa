//! Evaluating parametric models — curves, spline surfaces, Cao En networks and surface
//! networks: the output vector and a direction (a curve's tangent dC/dt, a surface's or Cao En
//! shape's unit normal)
//! at parameters, in `f64` (the trainer's reference) or through the core in `f32` or Q16.16.

use neurosurf_core::caoen::{CaoEnModel, CaoEnPoint, MAX_SOURCE_DIMENSION, MAX_TARGET_DIMENSION};
use neurosurf_core::curve::{BSplineCurve, BSplineSurface, CurvePoint};
use neurosurf_core::parametric::{SurfaceNetworkModel, SurfaceNetworkPoint};
use neurosurf_core::scalar::{Q16, Scalar};

use super::{LoadedModel, Precision};
use crate::error::{Error, Result};

/// The outputs and direction at one parameter, in `f64` whatever the precision it was
/// computed in: a curve's C(t) and dC/dt, a surface's S(u, v) and unit normal, a Cao En
/// network's p outputs y and unit normal ((0, 0, 0) where the normal does not exist).
#[derive(Clone, Debug, PartialEq)]
pub struct Geometry {
    /// The position (3 coordinates; z = 0 for a 2-D curve) or a Cao En network's p outputs.
    pub output: Vec<f64>,
    /// Tangent or unit normal.
    pub direction: [f64; 3],
}

impl From<(Vec<f64>, [f64; 3])> for Geometry {
    fn from((output, direction): (Vec<f64>, [f64; 3])) -> Self {
        Geometry { output, direction }
    }
}

/// The CSV columns of `neurosurf eval` for a parametric model, `None` for field models:
/// `t,x,y,z,tx,ty,tz` for a curve, `u,v,x,y,z,nx,ny,nz` for a spline surface or a surface
/// network, and for a Cao En
/// network its source coordinates `s1…sm`, its outputs (`x,y,z` when p = 3, else `y1…yp`)
/// and `nx,ny,nz`.
pub fn geometry_columns(model: &LoadedModel) -> Option<Vec<String>> {
    let names = |list: &[&str]| list.iter().map(|c| (*c).to_string()).collect();
    match model {
        LoadedModel::Curve { .. } => Some(names(&["t", "x", "y", "z", "tx", "ty", "tz"])),
        LoadedModel::SplineSurface { .. } | LoadedModel::SurfaceNetwork { .. } => {
            Some(names(&["u", "v", "x", "y", "z", "nx", "ny", "nz"]))
        }
        LoadedModel::CaoEn { decoded, .. } => {
            let (m, p) = (
                decoded.network.source_dimension(),
                decoded.network.target_dimension(),
            );
            let mut columns: Vec<String> = (1..=m).map(|i| format!("s{i}")).collect();
            if p == 3 {
                columns.extend(names(&["x", "y", "z"]));
            } else {
                columns.extend((1..=p).map(|i| format!("y{i}")));
            }
            columns.extend(names(&["nx", "ny", "nz"]));
            Some(columns)
        }
        _ => None,
    }
}

impl LoadedModel {
    /// Outputs and direction of a curve (t = `parameters[i][0]`), spline surface ((u, v) =
    /// the first two coordinates) or Cao En network (the source point: the first m
    /// coordinates) in `precision`. Parameters are first rounded to `f32`, which is what the
    /// core receives, so every precision sees the same inputs.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for field models, and when the core cannot load the blob in
    /// that precision.
    pub fn evaluate_geometry(
        &self,
        parameters: &[Vec<f64>],
        precision: Precision,
    ) -> Result<Vec<Geometry>> {
        let rounded: Vec<Vec<f64>> = parameters
            .iter()
            .map(|p| p.iter().map(|&c| f64::from(c as f32)).collect())
            .collect();
        let at = |p: &[f64], k: usize| p.get(k).copied().unwrap_or(0.0);
        match (self, precision) {
            (LoadedModel::Curve { decoded, .. }, Precision::F64) => Ok(rounded
                .iter()
                .map(|p| {
                    let t = at(p, 0);
                    geometry(decoded.curve.point(t), decoded.curve.tangent(t))
                })
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
                    let (u, v) = (at(p, 0), at(p, 1));
                    geometry(s.point(u, v), s.normal(u, v).unwrap_or([0.0; 3]))
                })
                .collect()),
            (LoadedModel::SplineSurface { bytes, .. }, Precision::F32) => {
                surface_core::<f32>(bytes, &rounded)
            }
            (LoadedModel::SplineSurface { bytes, .. }, Precision::Q16) => {
                surface_core::<Q16>(bytes, &rounded)
            }
            (LoadedModel::SurfaceNetwork { decoded, .. }, Precision::F64) => Ok(rounded
                .iter()
                .map(|p| {
                    let point = decoded.network.evaluate(at(p, 0), at(p, 1));
                    geometry(point.position, point.normal())
                })
                .collect()),
            (LoadedModel::SurfaceNetwork { bytes, .. }, Precision::F32) => {
                network_core::<f32>(bytes, &rounded)
            }
            (LoadedModel::SurfaceNetwork { bytes, .. }, Precision::Q16) => {
                network_core::<Q16>(bytes, &rounded)
            }
            (LoadedModel::CaoEn { decoded, .. }, Precision::F64) => {
                let network = &decoded.network;
                let m = network.source_dimension();
                Ok(rounded
                    .iter()
                    .map(|p| {
                        let x: Vec<f64> = (0..m).map(|k| at(p, k)).collect();
                        Geometry {
                            output: network.position(&x),
                            direction: network.normal(&x).unwrap_or([0.0; 3]),
                        }
                    })
                    .collect())
            }
            (LoadedModel::CaoEn { bytes, .. }, Precision::F32) => {
                caoen_core::<f32>(bytes, &rounded)
            }
            (LoadedModel::CaoEn { bytes, .. }, Precision::Q16) => {
                caoen_core::<Q16>(bytes, &rounded)
            }
            _ => Err(Error::invalid(format!(
                "a {} model has a field, not a parametric geometry",
                self.kind().name()
            ))),
        }
    }
}

fn geometry(position: [f64; 3], direction: [f64; 3]) -> Geometry {
    Geometry {
        output: position.to_vec(),
        direction,
    }
}

fn load_error(what: &str, scalar: &str, error: impl std::fmt::Display) -> Error {
    Error::invalid(format!(
        "the core cannot load this {what} in {scalar}: {error}"
    ))
}

/// Coordinate `k` of a parameter point in `S` (0 when missing), as the target decodes it.
fn coordinate<S: Scalar>(p: &[f64], k: usize) -> S {
    S::from_f32_saturating(p.get(k).copied().unwrap_or(0.0) as f32)
}

fn batch_error(e: impl std::fmt::Display) -> Error {
    Error::invalid(format!("batch evaluation: {e}"))
}

/// The core's batch evaluation of a curve in `S`.
fn curve_core<S: Scalar>(bytes: &[u8], parameters: &[Vec<f64>]) -> Result<Vec<Geometry>> {
    let curve =
        BSplineCurve::<S>::from_blob(bytes).map_err(|e| load_error("curve", S::KIND.name(), e))?;
    let t: Vec<S> = parameters.iter().map(|p| coordinate(p, 0)).collect();
    let mut out = vec![CurvePoint::<S>::default(); t.len()];
    curve.eval_batch(&t, &mut out).map_err(batch_error)?;
    Ok(out
        .iter()
        .map(|p| geometry(p.position.map(S::to_f64), p.tangent.map(S::to_f64)))
        .collect())
}

/// The core's batch evaluation of a spline surface in `S`.
fn surface_core<S: Scalar>(bytes: &[u8], parameters: &[Vec<f64>]) -> Result<Vec<Geometry>> {
    let surface = BSplineSurface::<S>::from_blob(bytes)
        .map_err(|e| load_error("spline surface", S::KIND.name(), e))?;
    let uv: Vec<[S; 2]> = parameters
        .iter()
        .map(|p| [coordinate(p, 0), coordinate(p, 1)])
        .collect();
    let mut positions = vec![[S::ZERO; 3]; uv.len()];
    let mut normals = vec![None; uv.len()];
    surface
        .position_batch(&uv, &mut positions)
        .and_then(|()| surface.normal_batch(&uv, &mut normals))
        .map_err(batch_error)?;
    Ok(positions
        .iter()
        .zip(&normals)
        .map(|(p, n)| geometry(p.map(S::to_f64), n.unwrap_or([S::ZERO; 3]).map(S::to_f64)))
        .collect())
}

/// The core's batch evaluation of a surface network in `S`: position and unit normal.
fn network_core<S: Scalar>(bytes: &[u8], parameters: &[Vec<f64>]) -> Result<Vec<Geometry>> {
    let network = SurfaceNetworkModel::<S>::from_blob(bytes)
        .map_err(|e| load_error("surface network", S::KIND.name(), e))?;
    let uv: Vec<[S; 2]> = parameters
        .iter()
        .map(|p| [coordinate(p, 0), coordinate(p, 1)])
        .collect();
    let mut points = vec![SurfaceNetworkPoint::<S>::default(); uv.len()];
    network.eval_batch(&uv, &mut points).map_err(batch_error)?;
    Ok(points
        .iter()
        .map(|p| {
            geometry(
                p.position.map(S::to_f64),
                p.normal.unwrap_or([S::ZERO; 3]).map(S::to_f64),
            )
        })
        .collect())
}

/// The core's batch evaluation of a Cao En network in `S`, with the widest source and
/// target the core supports (what the target's firmware runs; extra coordinates are 0).
fn caoen_core<S: Scalar>(bytes: &[u8], parameters: &[Vec<f64>]) -> Result<Vec<Geometry>> {
    let network = Box::new(
        CaoEnModel::<S>::from_blob(bytes)
            .map_err(|e| load_error("Cao En network", S::KIND.name(), e))?,
    );
    let p = network.target_dimension();
    let x: Vec<[S; MAX_SOURCE_DIMENSION]> = parameters
        .iter()
        .map(|point| std::array::from_fn(|k| coordinate(point, k)))
        .collect();
    // As the firmware does: one pass with the Jacobian for a shape (p = 3: position and
    // normal), one without for other networks (no normal).
    if p == 3 {
        let mut points = vec![CaoEnPoint::<S>::default(); x.len()];
        network
            .eval_normal_batch(&x, &mut points)
            .map_err(batch_error)?;
        return Ok(points
            .iter()
            .map(|point| Geometry {
                output: point.position.iter().map(|v| v.to_f64()).collect(),
                direction: point.normal.unwrap_or([S::ZERO; 3]).map(S::to_f64),
            })
            .collect());
    }
    let mut outputs = vec![[S::ZERO; MAX_TARGET_DIMENSION]; x.len()];
    network.eval_batch(&x, &mut outputs).map_err(batch_error)?;
    Ok(outputs
        .iter()
        .map(|y| Geometry {
            output: y.iter().take(p).map(|v| v.to_f64()).collect(),
            direction: [0.0; 3],
        })
        .collect())
}

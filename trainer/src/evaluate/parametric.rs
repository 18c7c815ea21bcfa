//! Evaluating parametric models — curves, spline surfaces, Cao En networks and surface
//! networks: the output vector and a direction (a curve's tangent dC/dt, a surface's or Cao En
//! shape's unit normal)
//! at parameters, in `f64` (the trainer's reference) or through the core in `f32` or Q16.16.

use super::through_core::core_outputs;
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
            (
                LoadedModel::Curve { bytes, .. }
                | LoadedModel::SplineSurface { bytes, .. }
                | LoadedModel::SurfaceNetwork { bytes, .. }
                | LoadedModel::CaoEn { bytes, .. },
                Precision::F32 | Precision::Q16,
            ) => Ok(core_outputs(bytes, self.kind(), precision, &rounded)?
                .into_iter()
                .map(|o| Geometry {
                    output: o.value,
                    direction: std::array::from_fn(|k| o.derivative.get(k).copied().unwrap_or(0.0)),
                })
                .collect()),
            (LoadedModel::Curve { decoded, .. }, Precision::F64) => Ok(rounded
                .iter()
                .map(|p| {
                    let t = at(p, 0);
                    geometry(decoded.curve.point(t), decoded.curve.tangent(t))
                })
                .collect()),
            (LoadedModel::SplineSurface { decoded, .. }, Precision::F64) => Ok(rounded
                .iter()
                .map(|p| {
                    let s = &decoded.surface;
                    let (u, v) = (at(p, 0), at(p, 1));
                    geometry(s.point(u, v), s.normal(u, v).unwrap_or([0.0; 3]))
                })
                .collect()),
            (LoadedModel::SurfaceNetwork { decoded, .. }, Precision::F64) => Ok(rounded
                .iter()
                .map(|p| {
                    let point = decoded.network.evaluate(at(p, 0), at(p, 1));
                    geometry(point.position, point.normal())
                })
                .collect()),
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

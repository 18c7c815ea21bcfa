//! The model frame: every implicit model is trained on its points moved and scaled so that
//! their bounding box is centred at the origin with a diagonal of [`MODEL_DIAGONAL`]. Every
//! setting (slope, γ, the error threshold, offsets and margins) therefore means the same thing
//! whatever the data's units; the frame is folded into the leaves' input normalizations after
//! training, so a blob evaluates in the data's own units.

use serde::{Deserialize, Serialize};

use super::network::{Guard, ImplicitNetwork};
use super::normalize::Normalization;
use crate::error::{Error, Result};

/// The bounding diagonal of the points in the model frame. Carcenac's Table 1 settings (slope
/// 5, error threshold 10⁻⁵) were chosen for shapes of about this size: the Table 5 torus
/// (R = 1, r = 0.4) has a diagonal of 4.04.
pub const MODEL_DIAGONAL: f64 = 4.0;

/// The smallest spread across the points' best-fitting plane, relative to their bounding
/// diagonal, that still encloses a volume.
const MIN_THICKNESS: f64 = 1e-4;

/// The standard deviations of `positions` along their two directions of least spread,
/// smallest first.
fn spreads(positions: &[[f64; 3]]) -> [f64; 2] {
    let n = positions.len() as f64;
    let mean = [0, 1, 2].map(|k| positions.iter().map(|p| p[k]).sum::<f64>() / n);
    let covariance = nalgebra::Matrix3::from_fn(|r, c| {
        positions
            .iter()
            .map(|p| (p[r] - mean[r]) * (p[c] - mean[c]))
            .sum::<f64>()
            / n
    });
    let mut values: Vec<f64> = covariance.symmetric_eigenvalues().iter().copied().collect();
    values.sort_by(f64::total_cmp);
    [values[0], values[1]].map(|v| v.max(0.0).sqrt())
}

/// World ↔ model frame: x_model = (x − center) / scale.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// The centre of the points' bounding box (world units).
    pub center: [f64; 3],
    /// World length of one model unit.
    pub scale: f64,
}

impl Frame {
    /// The identity frame.
    pub const IDENTITY: Frame = Frame {
        center: [0.0; 3],
        scale: 1.0,
    };

    /// The frame of `positions` (see the module documentation).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when there are no points, a coordinate is not finite, or all
    /// points coincide.
    pub fn of(positions: &[[f64; 3]]) -> Result<Frame> {
        let first = *positions
            .first()
            .ok_or_else(|| Error::invalid("no points to train on"))?;
        let (mut lo, mut hi) = (first, first);
        for p in positions {
            if p.iter().any(|v| !v.is_finite()) {
                return Err(Error::invalid(format!(
                    "a point has a non-finite coordinate: {p:?}"
                )));
            }
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
        let magnitude = (0..3)
            .map(|k| lo[k].abs().max(hi[k].abs()))
            .fold(0.0, f64::max);
        if !(diagonal > 1e-9 * magnitude && diagonal > 0.0 && diagonal.is_finite()) {
            return Err(Error::invalid(format!(
                "the points span no volume: their bounding box is {lo:?} … {hi:?}; give points \
                 spread over a surface"
            )));
        }
        let [thickness, width] = spreads(positions);
        if width <= MIN_THICKNESS * diagonal {
            return Err(Error::invalid(format!(
                "the points are collinear (their spread across the line is {width:.3e}, the \
                 bounding diagonal {diagonal:.3e}); an implicit surface encloses a volume: give \
                 points sampled over a closed surface"
            )));
        }
        if thickness <= MIN_THICKNESS * diagonal {
            return Err(Error::invalid(format!(
                "the points lie in a plane (their spread across it is {thickness:.3e}, the \
                 bounding diagonal {diagonal:.3e}); an implicit surface encloses a volume: give \
                 points sampled over a closed surface"
            )));
        }
        Ok(Frame {
            center: [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])),
            scale: diagonal / MODEL_DIAGONAL,
        })
    }

    /// A world point in the model frame.
    pub fn to_model(&self, x: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|k| (x[k] - self.center[k]) / self.scale)
    }

    /// A model-frame point in world units.
    pub fn to_world(&self, x: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|k| self.center[k] + x[k] * self.scale)
    }

    /// A leaf normalization that reads model-frame points, rewritten to read world points:
    /// A·(x_model − c) = (A / scale)·(x − (center + scale·c)).
    pub fn normalization_to_world(&self, n: &Normalization) -> Normalization {
        Normalization {
            center: self.to_world(n.center),
            matrix: n.matrix.map(|row| row.map(|a| a / self.scale)),
        }
    }

    /// `network` rewritten to read model-frame points: every normalization and sign guard
    /// (Φ itself is unchanged).
    pub fn network_to_model(&self, network: &ImplicitNetwork) -> ImplicitNetwork {
        self.rewrite(
            network,
            |n| self.normalization_to_model(n),
            |g| Guard {
                center: self.to_model(g.center),
                inverse_radius: g.inverse_radius * self.scale,
                amplitude: g.amplitude,
            },
        )
    }

    /// The inverse of [`Frame::network_to_model`].
    pub fn network_to_world(&self, network: &ImplicitNetwork) -> ImplicitNetwork {
        self.rewrite(
            network,
            |n| self.normalization_to_world(n),
            |g| Guard {
                center: self.to_world(g.center),
                inverse_radius: g.inverse_radius / self.scale,
                amplitude: g.amplitude,
            },
        )
    }

    fn rewrite(
        &self,
        network: &ImplicitNetwork,
        normalization: impl Fn(&Normalization) -> Normalization,
        guard: impl Fn(&Guard) -> Guard,
    ) -> ImplicitNetwork {
        let mut out = network.clone();
        for i in 0..out.module_count() {
            if let Some(n) = network.normalization(i) {
                out.set_normalization(i, &normalization(&n));
            }
        }
        out.with_guards(network.guards().iter().map(guard).collect())
    }

    /// The inverse of [`Frame::normalization_to_world`].
    pub fn normalization_to_model(&self, n: &Normalization) -> Normalization {
        Normalization {
            center: self.to_model(n.center),
            matrix: n.matrix.map(|row| row.map(|a| a * self.scale)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frame_centres_and_scales_the_bounding_box() {
        let corners = [
            [1000.0, -1000.0, 500.0],
            [1002.0, -998.0, 501.0],
            [1002.0, -1000.0, 500.0],
            [1000.0, -1000.0, 501.0],
        ];
        let frame = Frame::of(&corners).unwrap();
        assert_eq!(frame.center, [1001.0, -999.0, 500.5]);
        assert!((frame.scale - 3.0 / MODEL_DIAGONAL).abs() < 1e-12);
        let x = [1001.5, -999.25, 500.75];
        let back = frame.to_world(frame.to_model(x));
        assert!((0..3).all(|k| (back[k] - x[k]).abs() < 1e-9));
    }

    #[test]
    fn folding_keeps_what_a_leaf_reads() {
        let frame = Frame {
            center: [3.0, -2.0, 7.0],
            scale: 0.01,
        };
        let n = Normalization {
            center: [0.1, 0.2, -0.3],
            matrix: [[1.0, 2.0, 0.0], [0.0, 0.5, 1.0], [3.0, 0.0, 1.0]],
        };
        let world = frame.normalization_to_world(&n);
        let x = [3.004, -1.997, 7.002];
        let (a, b) = (n.apply(frame.to_model(x)), world.apply(x));
        assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-9), "{a:?} {b:?}");
        let back = frame.normalization_to_model(&world);
        assert!((0..3).all(|k| (back.center[k] - n.center[k]).abs() < 1e-12));
    }

    #[test]
    fn coincident_or_missing_points_are_refused() {
        assert!(Frame::of(&[]).is_err());
        assert!(Frame::of(&[[1.0, 2.0, 3.0]; 5]).is_err());
        assert!(Frame::of(&[[f64::NAN, 0.0, 0.0], [1.0, 1.0, 1.0]]).is_err());
    }

    #[test]
    fn points_in_a_plane_are_refused_by_name() {
        // A tilted plane: no bounding-box extent is zero, but the points enclose nothing.
        let plane: Vec<[f64; 3]> = (0..100)
            .map(|i| {
                let (u, v) = ((i % 10) as f64, (i / 10) as f64);
                [u, v, 0.3 * u - 0.2 * v + 5.0]
            })
            .collect();
        let message = Frame::of(&plane).unwrap_err().to_string();
        assert!(message.contains("lie in a plane"), "{message}");
        let mut slab = plane.clone();
        slab.push([4.0, 4.0, 9.0]);
        assert!(Frame::of(&slab).is_ok());
    }
}

//! The perspective approximation (paper §8). A true perspective view divides by depth for
//! every displayed point; the paper instead computes the screen coordinates of the key points
//! and lets the network interpolate them. [`perspective_network`] keeps a shape network's key
//! points and blending and refits V (one least-squares solve, as for the shape) so that at
//! every key point the outputs are its perspective screen coordinates and depth. The result
//! is an ordinary Cao En network: the core evaluates it in f32 and Q16.16, on the host and on
//! the target, at the cost of the shape itself.
//!
//! Accuracy: at the key points the solve's residual; between them [`PerspectiveFit`] reports
//! the measured screen error against the exact projection of the shape network's surface
//! over a grid of source points (an icosphere, or a 36 × 18 torus grid). Depth is affine in
//! the position, so a normalized network interpolates it exactly up to rounding.

use super::fit::fit_shape;
use super::network::{CaoEnNetwork, on_domain};
use super::texture::{check_points, position_part};
use crate::error::{Error, Result};
use crate::geometry::vector::{cross, inner};

/// A pinhole camera: the eye, the unit axes of its view, and the focal length.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct PerspectiveCamera {
    eye: [f64; 3],
    forward: [f64; 3],
    right: [f64; 3],
    up: [f64; 3],
    focal: f64,
}

impl PerspectiveCamera {
    /// A camera at `eye` looking at `look_at`, with `up` roughly up on the screen; a point at
    /// depth z and lateral offsets (a, b) appears at (focal·a/z, focal·b/z).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a non-finite coordinate, `look_at` at the eye, `up`
    /// parallel to the view, or a focal length that is not positive and finite.
    pub fn new(eye: [f64; 3], look_at: [f64; 3], up: [f64; 3], focal: f64) -> Result<Self> {
        if eye
            .iter()
            .chain(&look_at)
            .chain(&up)
            .any(|c| !c.is_finite())
        {
            return Err(Error::invalid(
                "the camera's eye, target and up must be finite",
            ));
        }
        if !(focal > 0.0 && focal.is_finite()) {
            return Err(Error::invalid(format!(
                "the focal length must be positive and finite, got {focal}"
            )));
        }
        let unit = |v: [f64; 3], what: &str| -> Result<[f64; 3]> {
            let r = inner(&v, &v).sqrt();
            if r > 1e-12 {
                Ok(v.map(|c| c / r))
            } else {
                Err(Error::invalid(what.to_string()))
            }
        };
        let forward = unit(
            [0, 1, 2].map(|k| look_at[k] - eye[k]),
            "the camera looks at its own eye: give a --look-at away from --eye",
        )?;
        let right = unit(
            cross(forward, up),
            "the camera's up is parallel to its view: give another --up",
        )?;
        Ok(PerspectiveCamera {
            eye,
            forward,
            right,
            up: cross(right, forward),
            focal,
        })
    }

    /// Screen x, y (y up) and depth of a point; `None` at or behind the eye's plane.
    pub fn project(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        let d = [0, 1, 2].map(|k| p[k] - self.eye[k]);
        let depth = inner(&d, &self.forward);
        (depth > 0.0).then(|| {
            [
                self.focal * inner(&d, &self.right) / depth,
                self.focal * inner(&d, &self.up) / depth,
                depth,
            ]
        })
    }
}

/// A perspective network and how far it is from the exact projection.
#[derive(Clone, Debug)]
pub struct PerspectiveFit {
    /// The network whose outputs are screen x, y and depth.
    pub network: CaoEnNetwork,
    /// Largest screen distance |(x, y) − exact| at the key points.
    pub max_error_at_keys: f64,
    /// Largest and RMS screen distance over the check points.
    pub max_screen_error: f64,
    /// See [`PerspectiveFit::max_screen_error`].
    pub rms_screen_error: f64,
    /// The larger side of the exact screen bounding box of the check points (to read the
    /// errors against).
    pub screen_extent: f64,
    /// Largest |depth − exact| over the check points.
    pub max_depth_error: f64,
    /// Source points checked.
    pub checked: usize,
}

/// The perspective network of a sphere or torus shape `network` (its first three outputs are
/// the position; further outputs are dropped) seen by `camera`.
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than three outputs, a surface that reaches the eye's
/// plane or behind it, or a failed solve.
pub fn perspective_network(
    network: &CaoEnNetwork,
    camera: &PerspectiveCamera,
) -> Result<PerspectiveFit> {
    if network.target_dimension() < 3 {
        return Err(Error::invalid(
            "the perspective view needs a shape network (at least three outputs)",
        ));
    }
    let shape = position_part(network);
    shape.validate()?;
    let exact = |x: &[f64]| -> Result<[f64; 3]> {
        let y = shape.position(x);
        camera.project([y[0], y[1], y[2]]).ok_or_else(|| {
            Error::invalid(format!(
                "the surface point {y:?} is not in front of the eye: move --eye farther away \
                 or look toward the surface"
            ))
        })
    };
    let keys: Vec<Vec<f64>> = shape
        .weights
        .iter()
        .map(|w| on_domain(shape.domain, w))
        .collect();
    let values = keys
        .iter()
        .map(|x| exact(x).map(|s| s.to_vec()))
        .collect::<Result<Vec<_>>>()?;
    let fitted = fit_shape(&shape, &keys, &values)?;
    fitted.validate()?;
    let screen_distance = |x: &[f64], expected: &[f64]| {
        let y = fitted.position(x);
        ((y[0] - expected[0]).powi(2) + (y[1] - expected[1]).powi(2)).sqrt()
    };
    let max_error_at_keys = keys
        .iter()
        .zip(&values)
        .map(|(x, v)| screen_distance(x, v))
        .fold(0.0, f64::max);
    let check = check_points(shape.domain)?;
    let (mut max_screen_error, mut squares, mut max_depth_error) = (0.0_f64, 0.0, 0.0_f64);
    let (mut low, mut high) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for x in &check {
        let expected = exact(x)?;
        let error = screen_distance(x, &expected);
        max_screen_error = max_screen_error.max(error);
        squares += error * error;
        max_depth_error = max_depth_error.max((fitted.position(x)[2] - expected[2]).abs());
        for k in 0..2 {
            low[k] = low[k].min(expected[k]);
            high[k] = high[k].max(expected[k]);
        }
    }
    Ok(PerspectiveFit {
        network: fitted,
        max_error_at_keys,
        max_screen_error,
        rms_screen_error: (squares / check.len().max(1) as f64).sqrt(),
        screen_extent: (high[0] - low[0]).max(high[1] - low[1]),
        max_depth_error,
        checked: check.len(),
    })
}

#[cfg(test)]
mod tests {
    use neurosurf_core::caoen::Blending;

    use super::super::support::{fibonacci, fitted};
    use super::*;

    /// An ellipsoid with 104 keys seen from 6 and from 2.5 units: at the keys the screen
    /// coordinates are exact; between them the error is small against the picture and grows
    /// as the eye comes closer (the projection bends more between keys).
    #[test]
    fn the_network_interpolates_the_perspective_view() {
        let keys = fibonacci(104);
        let targets: Vec<Vec<f64>> = keys
            .iter()
            .map(|k| vec![k[0], 1.5 * k[1], 0.7 * k[2]])
            .collect();
        let shape = fitted(&keys, &targets, Blending::Exponential, true, 12.0);
        let mut relative = Vec::new();
        for distance in [6.0, 2.5] {
            let camera =
                PerspectiveCamera::new([0.3, 0.4, distance], [0.0; 3], [0.0, 1.0, 0.0], 2.0)
                    .unwrap();
            let fit = perspective_network(&shape, &camera).unwrap();
            println!(
                "eye at {distance}: at keys {:.1e}, between max {:.2e} RMS {:.2e} of extent \
                 {:.3}, depth {:.1e}",
                fit.max_error_at_keys,
                fit.max_screen_error,
                fit.rms_screen_error,
                fit.screen_extent,
                fit.max_depth_error
            );
            assert!(fit.max_error_at_keys < 1e-9);
            assert!(fit.max_depth_error < 1e-9, "normalized: depth is affine");
            relative.push(fit.max_screen_error / fit.screen_extent);
        }
        assert!(relative[0] < 2.5e-4 && relative[1] < 1e-3, "{relative:?}");
        assert!(relative[1] > relative[0]);
    }

    #[test]
    fn cameras_and_surfaces_behind_the_eye_are_refused() {
        let up = [0.0, 1.0, 0.0];
        assert!(PerspectiveCamera::new([0.0; 3], [0.0; 3], up, 1.0).is_err());
        assert!(PerspectiveCamera::new([0.0, 0.0, 5.0], [0.0; 3], [0.0, 0.0, 1.0], 1.0).is_err());
        assert!(PerspectiveCamera::new([0.0, 0.0, 5.0], [0.0; 3], up, 0.0).is_err());
        assert!(PerspectiveCamera::new([f64::NAN, 0.0, 5.0], [0.0; 3], up, 1.0).is_err());
        let camera = PerspectiveCamera::new([0.0, 0.0, 5.0], [0.0; 3], up, 1.0).unwrap();
        assert_eq!(camera.project([0.0, 0.0, 6.0]), None);
        assert_eq!(camera.project([1.0, 0.5, 3.0]), Some([0.5, 0.25, 2.0]));
        let keys = fibonacci(20);
        let shape = fitted(&keys, &keys, Blending::Exponential, true, 8.0);
        let inside = PerspectiveCamera::new([0.0, 0.0, 0.5], [0.0; 3], up, 1.0).unwrap();
        let e = perspective_network(&shape, &inside)
            .unwrap_err()
            .to_string();
        assert!(e.contains("in front of the eye"), "{e}");
    }
}

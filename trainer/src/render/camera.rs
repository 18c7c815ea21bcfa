//! A pinhole camera: look-at, vertical field of view, image size; and the orbit view the CLI's
//! `--view azimuth,elevation[,distance]` describes.

use serde::Serialize;

use super::region::Aabb;
use crate::error::{Error, Result};
use crate::geometry::vector::{add, cross, dot, norm, scale, sub};

/// Largest image side accepted (pixels).
pub const MAX_SIDE: u32 = 16_384;

/// A pinhole camera. Pixel (0, 0) is the top-left corner; pixel centers are at +0.5.
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct Camera {
    /// Eye position.
    pub eye: [f64; 3],
    forward: [f64; 3],
    right: [f64; 3],
    up: [f64; 3],
    tan_half_fov: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// A camera at `eye` looking at `target`, `up` roughly up, with a vertical field of view
    /// of `fov_degrees`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a zero or too large image (sides 1..=[`MAX_SIDE`]), a field
    /// of view outside (0°, 170°], non-finite vectors, `eye == target`, or `up` parallel to
    /// the view direction.
    pub fn look_at(
        eye: [f64; 3],
        target: [f64; 3],
        up: [f64; 3],
        fov_degrees: f64,
        width: u32,
        height: u32,
    ) -> Result<Camera> {
        if !(1..=MAX_SIDE).contains(&width) || !(1..=MAX_SIDE).contains(&height) {
            return Err(Error::invalid(format!(
                "image size {width}×{height}: each side must be 1..={MAX_SIDE} pixels"
            )));
        }
        if !(fov_degrees > 0.0 && fov_degrees <= 170.0) {
            return Err(Error::invalid(format!(
                "field of view {fov_degrees}° is outside (0°, 170°]"
            )));
        }
        let view = sub(target, eye);
        let distance = norm(view);
        if !(distance.is_finite() && distance > 0.0 && norm(up).is_finite()) {
            return Err(Error::invalid(
                "the camera's eye and target must differ and be finite",
            ));
        }
        let forward = scale(view, 1.0 / distance);
        let right = cross(forward, up);
        let r = norm(right);
        if r.is_nan() || r <= 1e-9 * norm(up) {
            return Err(Error::invalid(
                "the camera's up vector is parallel to the view",
            ));
        }
        let right = scale(right, 1.0 / r);
        let up = cross(right, forward);
        Ok(Camera {
            eye,
            forward,
            right,
            up,
            tan_half_fov: (0.5 * fov_degrees.to_radians()).tan(),
            width,
            height,
        })
    }

    /// The camera of `view` framing `bounds` (z up).
    ///
    /// # Errors
    /// As [`Camera::look_at`], and for a non-finite view or a distance that puts the eye
    /// inside the scene.
    pub fn orbit(bounds: &Aabb, view: &View, width: u32, height: u32) -> Result<Camera> {
        // Frame the sphere of the longest half side: the boxes are loose (inflated, and as
        // long as the feature's longest side in every direction), so their corners rarely
        // hold surface.
        let radius = 0.5 * bounds.longest_side();
        if !view.azimuth.is_finite() || !view.elevation.is_finite() || !radius.is_finite() {
            return Err(Error::invalid("the view and the scene must be finite"));
        }
        let fov = view.fov;
        let aspect = f64::from(width.max(1)) / f64::from(height.max(1));
        // Fit the bounding sphere in the narrower of the two fields of view.
        let half = (0.5 * fov.to_radians()).tan().atan();
        let narrow = if aspect < 1.0 {
            (half.tan() * aspect).atan()
        } else {
            half
        };
        let distance = match view.distance {
            Some(d) if d.is_finite() && d > radius => d,
            Some(d) => {
                return Err(Error::invalid(format!(
                    "view distance {d} puts the camera inside the scene (radius {radius:.3})"
                )));
            }
            None => 1.05 * radius / narrow.sin().max(1e-6),
        };
        let (az, el) = (view.azimuth.to_radians(), view.elevation.to_radians());
        let direction = [el.cos() * az.sin(), el.cos() * az.cos(), el.sin()];
        let target = bounds.center();
        let eye = add(target, scale(direction, distance));
        let up = if el.cos().abs() < 1e-6 {
            [0.0, -az.cos(), 0.0]
        } else {
            [0.0, 0.0, 1.0]
        };
        Camera::look_at(eye, target, up, fov, width, height)
    }

    /// The unit ray through the image point (`x`, `y`) in pixels.
    pub fn ray(&self, x: f64, y: f64) -> ([f64; 3], [f64; 3]) {
        let w = f64::from(self.width);
        let h = f64::from(self.height);
        let sx = (2.0 * x / w - 1.0) * self.tan_half_fov * w / h;
        let sy = (1.0 - 2.0 * y / h) * self.tan_half_fov;
        let d = add(self.forward, add(scale(self.right, sx), scale(self.up, sy)));
        (self.eye, scale(d, 1.0 / norm(d)))
    }

    /// The view direction (unit).
    pub fn forward(&self) -> [f64; 3] {
        self.forward
    }

    /// The image's right axis (unit, world space).
    pub fn right(&self) -> [f64; 3] {
        self.right
    }

    /// The image's up axis (unit, world space).
    pub fn up(&self) -> [f64; 3] {
        self.up
    }

    /// How far along the view direction `p` lies from the eye.
    pub fn depth(&self, p: [f64; 3]) -> f64 {
        dot(sub(p, self.eye), self.forward)
    }
}

/// Where the camera stands around the scene: azimuth (degrees, 0 = looking from +y toward
/// −y, 90 = from +x), elevation (degrees above the xy plane), optional distance from the
/// scene's center (default: the scene fills the view), vertical field of view (degrees).
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct View {
    /// Degrees around z.
    pub azimuth: f64,
    /// Degrees above the xy plane.
    pub elevation: f64,
    /// Distance from the scene's center.
    pub distance: Option<f64>,
    /// Vertical field of view, degrees.
    pub fov: f64,
}

impl Default for View {
    fn default() -> Self {
        View {
            azimuth: 35.0,
            elevation: 20.0,
            distance: None,
            fov: 35.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn center_ray_looks_at_the_target() {
        let cam =
            Camera::look_at([0.0, -5.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0, 64, 32).unwrap();
        let (o, d) = cam.ray(32.0, 16.0);
        assert_eq!(o, [0.0, -5.0, 0.0]);
        assert!((d[1] - 1.0).abs() < 1e-12, "{d:?}");
        // Top of the image is +z, right is +x.
        assert!(cam.ray(32.0, 0.0).1[2] > 0.0);
        assert!(cam.ray(64.0, 16.0).1[0] > 0.0);
    }

    #[test]
    fn bad_cameras_are_named() {
        let e = Camera::look_at([0.0; 3], [0.0; 3], [0.0, 0.0, 1.0], 40.0, 8, 8).unwrap_err();
        assert!(e.to_string().contains("differ"), "{e}");
        let e =
            Camera::look_at([1.0, 0.0, 0.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0, 0, 8).unwrap_err();
        assert!(e.to_string().contains("image size"), "{e}");
        let e =
            Camera::look_at([0.0, 0.0, 1.0], [0.0; 3], [0.0, 0.0, 1.0], 40.0, 8, 8).unwrap_err();
        assert!(e.to_string().contains("parallel"), "{e}");
        let b = Aabb {
            lo: [-1.0; 3],
            hi: [1.0; 3],
        };
        let view = View {
            distance: Some(0.5),
            ..View::default()
        };
        assert!(
            Camera::orbit(&b, &view, 8, 8)
                .unwrap_err()
                .to_string()
                .contains("inside")
        );
    }
}

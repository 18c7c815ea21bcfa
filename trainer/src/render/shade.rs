//! Lambert + Phong shading from the analytic normal n = −∇Φ/|∇Φ|, in linear RGB, and the
//! conversion to 8-bit sRGB.

use crate::geometry::vector::{dot, norm, scale, sub};

/// Colours and lights of a rendering.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Shading {
    /// Surface colour (linear RGB).
    pub albedo: [f64; 3],
    /// Background colour (linear RGB).
    pub background: [f64; 3],
    /// Ambient term.
    pub ambient: f64,
    /// Specular strength.
    pub specular: f64,
    /// Phong exponent.
    pub shininess: f64,
}

impl Default for Shading {
    fn default() -> Self {
        Shading {
            albedo: [0.80, 0.58, 0.42],
            background: [0.035, 0.04, 0.05],
            ambient: 0.12,
            specular: 0.35,
            shininess: 40.0,
        }
    }
}

impl Shading {
    /// The colour of a surface point with gradient `gradient`, seen along the unit ray
    /// `direction`; the key light comes from above-left of the camera (`right`, `up` are the
    /// camera's axes), a fill light from the camera.
    pub fn shade(
        &self,
        gradient: [f64; 3],
        direction: [f64; 3],
        right: [f64; 3],
        up: [f64; 3],
    ) -> [f64; 3] {
        let length = norm(gradient);
        if !(length > 0.0 && length.is_finite()) {
            return self.albedo.map(|c| c * self.ambient);
        }
        let mut n = scale(gradient, -1.0 / length);
        if dot(n, direction) > 0.0 {
            // Seen from inside (a clipped or open surface): light the side we see.
            n = scale(n, -1.0);
        }
        let view = scale(direction, -1.0);
        let key = {
            let l = sub(
                sub(scale(up, 0.8), scale(right, 0.6)),
                scale(direction, 1.0),
            );
            scale(l, 1.0 / norm(l))
        };
        let mut diffuse = self.ambient;
        let mut specular = 0.0;
        for (light, strength) in [(key, 0.75), (view, 0.3)] {
            let lambert = dot(n, light).max(0.0);
            diffuse += strength * lambert;
            if lambert > 0.0 {
                let reflected = sub(scale(n, 2.0 * dot(n, light)), light);
                specular += strength * dot(reflected, view).max(0.0).powf(self.shininess);
            }
        }
        self.albedo.map(|c| c * diffuse + self.specular * specular)
    }
}

/// Linear [0, 1] to an 8-bit sRGB value.
pub fn to_srgb8(linear: f64) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

//! Test surfaces with known parameterizations: an open cylinder (Fig. 5), a swiss-roll patch,
//! a plane, a wavy height field, a sphere (closed: cannot be flattened) and a bent sheet.

use std::f64::consts::PI;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};

/// A known surface.
#[derive(Copy, Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SampleSurface {
    /// z = 0.1·x + 0.2·y − 0.05 over [−1, 1]²: a tilted plane.
    Plane,
    /// z = 0.25·sin(2.5x)·cos(2y) over [−1, 1]²: a wavy height field.
    Wavy,
    /// Radius 1, angle 0…1.5π, height 0…2.5: an open cylinder (a "C" in plan).
    OpenCylinder,
    /// The swiss roll r = t, t ∈ [1.5π, 3.5π], height 0…30: arc length × height.
    SwissRoll,
    /// The unit sphere: closed, no 2-D embedding without folds.
    Sphere,
}

impl SampleSurface {
    /// The surface point at true parameters (s, t).
    pub fn position(self, s: f64, t: f64) -> [f64; 3] {
        match self {
            SampleSurface::Plane => [s, t, 0.1 * s + 0.2 * t - 0.05],
            SampleSurface::Wavy => [s, t, 0.25 * (2.5 * s).sin() * (2.0 * t).cos()],
            SampleSurface::OpenCylinder => [s.cos(), s.sin(), t],
            SampleSurface::SwissRoll => {
                let a = roll_angle(s);
                [a * a.cos(), t, a * a.sin()]
            }
            SampleSurface::Sphere => {
                let z = s;
                let r = (1.0 - z * z).max(0.0).sqrt();
                [r * t.cos(), r * t.sin(), z]
            }
        }
    }

    /// The parameter box [s₀, s₁] × [t₀, t₁] (area-uniform in (s, t)).
    pub fn domain(self) -> [[f64; 2]; 2] {
        match self {
            SampleSurface::Plane | SampleSurface::Wavy => [[-1.0, 1.0], [-1.0, 1.0]],
            SampleSurface::OpenCylinder => [[0.0, 1.5 * PI], [0.0, 2.5]],
            SampleSurface::SwissRoll => {
                [[0.0, roll_arc(3.5 * PI) - roll_arc(1.5 * PI)], [0.0, 30.0]]
            }
            SampleSurface::Sphere => [[-1.0, 1.0], [0.0, 2.0 * PI]],
        }
    }

    /// For height fields z = f(x, y): f.
    pub fn height(self, x: f64, y: f64) -> Option<f64> {
        match self {
            SampleSurface::Plane | SampleSurface::Wavy => Some(self.position(x, y)[2]),
            _ => None,
        }
    }
}

/// Arc length of the spiral r = a from angle 0 to a.
fn roll_arc(a: f64) -> f64 {
    0.5 * (a * (1.0 + a * a).sqrt() + a.asinh())
}

/// The spiral angle at arc length s past angle 1.5π (Newton on [`roll_arc`]).
fn roll_angle(s: f64) -> f64 {
    let target = s + roll_arc(1.5 * PI);
    let mut a = 1.5 * PI;
    for _ in 0..50 {
        let step = (roll_arc(a) - target) / (1.0 + a * a).sqrt();
        a -= step;
        if step.abs() < 1e-13 {
            break;
        }
    }
    a
}

/// Points sampled from a known surface with their true parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceSample {
    /// Noisy 3-D points.
    pub points: Vec<[f64; 3]>,
    /// True (s, t) of each point.
    pub parameters: Vec<[f64; 2]>,
}

/// `count` points uniform in the parameter box of `surface`, each coordinate perturbed by a
/// uniform error of ±`noise` times the bounding-box diagonal (the paper's "percent uniform
/// error" is `noise` = 0.01).
///
/// # Errors
/// [`Error::InvalidInput`] for a zero count or a negative or non-finite noise.
pub fn sample_surface(
    surface: SampleSurface,
    count: usize,
    noise: f64,
    seed: u64,
) -> Result<SurfaceSample> {
    if count == 0 || !(noise >= 0.0 && noise.is_finite()) {
        return Err(Error::invalid(
            "a sample needs a positive count and a finite noise ≥ 0",
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let [[s0, s1], [t0, t1]] = surface.domain();
    let mut parameters = Vec::with_capacity(count);
    let mut points = Vec::with_capacity(count);
    for _ in 0..count {
        let s = s0 + (s1 - s0) * rng.random::<f64>();
        let t = t0 + (t1 - t0) * rng.random::<f64>();
        parameters.push([s, t]);
        points.push(surface.position(s, t));
    }
    if noise > 0.0 {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in &points {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
        }
        let diagonal = (0..3).map(|a| (hi[a] - lo[a]).powi(2)).sum::<f64>().sqrt();
        for p in points.iter_mut() {
            for c in p.iter_mut() {
                *c += noise * diagonal * (2.0 * rng.random::<f64>() - 1.0);
            }
        }
    }
    Ok(SurfaceSample { points, parameters })
}

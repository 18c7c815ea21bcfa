//! How faithfully a field Φ represents a known surface: the paper's distance in % of the
//! object's diameter and the normal-angle error, measured on points of the true surface.

use serde::{Deserialize, Serialize};

use crate::points::PointSet;

/// Distances and normal errors of a field on points of the true surface.
///
/// The distance of a surface point x to the model's surface is estimated to first order as
/// |Φ(x)| / |∇Φ(x)| (exact for a signed distance field, and accurate to O(d²) near the
/// surface for any smooth field). The normal error is the angle between the model's normal
/// −∇Φ/|∇Φ| and the true outward normal. A point where ∇Φ = 0 counts as infinitely far and
/// 180° off.
#[derive(Copy, Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fidelity {
    /// Points measured.
    pub points: usize,
    /// Diameter D the distances are relative to.
    pub diameter: f64,
    /// Median distance, % of D.
    pub median_distance_percent: f64,
    /// RMS distance, % of D.
    pub rms_distance_percent: f64,
    /// Largest distance, % of D.
    pub max_distance_percent: f64,
    /// Median normal error, degrees.
    pub median_angle_degrees: f64,
    /// Largest normal error, degrees.
    pub max_angle_degrees: f64,
}

impl Fidelity {
    /// Measures `field` (returning Φ and ∇Φ) on the points and true normals of `surface`.
    /// Returns `None` for an empty surface or a non-positive diameter.
    pub fn measure(
        surface: &PointSet,
        diameter: f64,
        field: impl Fn([f64; 3]) -> (f64, [f64; 3]),
    ) -> Option<Fidelity> {
        let samples: Vec<_> = surface.positions.iter().map(|&x| field(x)).collect();
        Self::from_samples(surface, diameter, &samples)
    }

    /// Like [`Fidelity::measure`], from Φ and ∇Φ already evaluated at each point of
    /// `surface`. Returns `None` for an empty surface, a non-positive diameter or a sample
    /// count that differs from the point count.
    pub fn from_samples(
        surface: &PointSet,
        diameter: f64,
        samples: &[(f64, [f64; 3])],
    ) -> Option<Fidelity> {
        if surface.is_empty()
            || samples.len() != surface.len()
            || diameter.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        {
            return None;
        }
        let mut distances = Vec::with_capacity(surface.len());
        let mut angles = Vec::with_capacity(surface.len());
        for (&(phi, g), &n) in samples.iter().zip(&surface.normals) {
            let len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
            if len > 0.0 && len.is_finite() && phi.is_finite() {
                distances.push(phi.abs() / len);
                let cos = -(g[0] * n[0] + g[1] * n[1] + g[2] * n[2]) / len;
                angles.push(cos.clamp(-1.0, 1.0).acos().to_degrees());
            } else {
                distances.push(f64::INFINITY);
                angles.push(180.0);
            }
        }
        let percent = 100.0 / diameter;
        let rms = (distances.iter().map(|d| d * d).sum::<f64>() / distances.len() as f64).sqrt();
        Some(Fidelity {
            points: surface.len(),
            diameter,
            median_distance_percent: median(&mut distances) * percent,
            rms_distance_percent: rms * percent,
            max_distance_percent: distances.iter().fold(0.0, |a: f64, &b| a.max(b)) * percent,
            median_angle_degrees: median(&mut angles),
            max_angle_degrees: angles.iter().fold(0.0, |a: f64, &b| a.max(b)),
        })
    }
}

/// The median (mean of the two middle values for an even count); `values` is reordered.
pub fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    let mid = values.len() / 2;
    if values.len() % 2 == 1 {
        values[mid]
    } else {
        0.5 * (values[mid - 1] + values[mid])
    }
}

/// The largest side of the axis-aligned bounding box of `positions` (0 when empty).
pub fn diameter(positions: &[[f64; 3]]) -> f64 {
    let mut low = [f64::INFINITY; 3];
    let mut high = [f64::NEG_INFINITY; 3];
    for p in positions {
        for k in 0..3 {
            low[k] = low[k].min(p[k]);
            high[k] = high[k].max(p[k]);
        }
    }
    (0..3).map(|k| high[k] - low[k]).fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere_points() -> PointSet {
        let mut set = PointSet::default();
        for i in 0..50 {
            let t = i as f64 * 0.37;
            let z = (i as f64 / 49.0) * 2.0 - 1.0;
            let r = (1.0 - z * z).sqrt();
            let n = [r * t.cos(), r * t.sin(), z];
            set.positions.push(n);
            set.normals.push(n);
        }
        set
    }

    #[test]
    fn an_exact_field_is_perfect_and_a_shifted_one_is_off_by_the_shift() {
        let surface = sphere_points();
        // Φ = 1 − |x| (positive inside, ∇Φ = −x/|x|): exact distance field of the unit sphere.
        let exact = |x: [f64; 3]| {
            let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            (1.0 - r, x.map(|c| -c / r))
        };
        let f = Fidelity::measure(&surface, 2.0, exact).unwrap();
        assert!(f.max_distance_percent < 1e-12 && f.max_angle_degrees < 1e-5);
        let shrunk = |x: [f64; 3]| {
            let (phi, g) = exact(x);
            (phi - 0.02, g)
        };
        let f = Fidelity::measure(&surface, 2.0, shrunk).unwrap();
        assert!((f.median_distance_percent - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_flipped_or_flat_field_reports_the_worst_angle() {
        let surface = sphere_points();
        let f = Fidelity::measure(&surface, 2.0, |x| (0.0, x)).unwrap();
        assert!((f.median_angle_degrees - 180.0).abs() < 1e-6);
        let f = Fidelity::measure(&surface, 2.0, |_| (1.0, [0.0; 3])).unwrap();
        assert!(f.max_distance_percent.is_infinite());
        assert!(Fidelity::measure(&PointSet::default(), 2.0, |_| (0.0, [1.0; 3])).is_none());
        assert!(Fidelity::measure(&surface, f64::NAN, |_| (0.0, [1.0; 3])).is_none());
    }

    #[test]
    fn median_and_diameter() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(&mut []).is_nan());
        assert_eq!(diameter(&[[0.0, 0.0, 0.0], [1.0, -2.0, 0.5]]), 2.0);
    }
}

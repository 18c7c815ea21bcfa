//! How far one evaluation is from a reference: field errors and normal angles.

use serde::Serialize;

use super::measured::Measured;
use crate::error::{Error, Result};

/// The deviation of candidate samples from reference samples at the same points.
///
/// The field error is |Φ − Φ_ref| (for curves and surfaces: the distance between the
/// positions, see [`Measured`]; their "normal" is the tangent or the surface normal). The normal is n = −∇Φ/|∇Φ|; the normal error is the angle
/// between the candidate's and the reference's normals. A point where either gradient is zero
/// (or not finite) has no normal: it is skipped for the angles and counted in
/// [`Deviation::normals_skipped`]. A statistic over no values is `None`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Deviation {
    /// Points compared.
    pub points: usize,
    /// Largest |Φ − Φ_ref| (NaN if any candidate value is NaN).
    pub field_max: Option<f64>,
    /// Root mean square of Φ − Φ_ref.
    pub field_rms: Option<f64>,
    /// Largest normal angle, degrees.
    pub normal_max_degrees: Option<f64>,
    /// Median normal angle, degrees (the mean of the middle two for an even count).
    pub normal_median_degrees: Option<f64>,
    /// Points whose normals were compared.
    pub normals_compared: usize,
    /// Points skipped because a gradient is zero or not finite.
    pub normals_skipped: usize,
}

impl Deviation {
    /// Measures `candidate` against `reference`, point by point.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the two lists differ in length.
    pub fn measure<T: Measured>(reference: &[T], candidate: &[T]) -> Result<Self> {
        if reference.len() != candidate.len() {
            return Err(Error::invalid(format!(
                "cannot compare {} samples with {} reference samples",
                candidate.len(),
                reference.len()
            )));
        }
        let mut field_max: Option<f64> = None;
        let mut square_sum = 0.0;
        let mut angles = Vec::with_capacity(reference.len());
        for (r, c) in reference.iter().zip(candidate) {
            let error = c.value_error(r);
            // A NaN error sticks (`f64::max` would drop it).
            field_max = Some(match field_max {
                None => error,
                Some(max) if max.is_nan() || error.is_nan() => f64::NAN,
                Some(max) => max.max(error),
            });
            square_sum += error * error;
            if let Some(angle) = normal_angle_degrees(r.direction(), c.direction()) {
                angles.push(angle);
            }
        }
        let points = reference.len();
        angles.sort_by(f64::total_cmp);
        Ok(Deviation {
            points,
            field_max,
            field_rms: (points > 0).then(|| (square_sum / points as f64).sqrt()),
            normal_max_degrees: angles.last().copied(),
            normal_median_degrees: median(&angles),
            normals_compared: angles.len(),
            normals_skipped: points - angles.len(),
        })
    }
}

/// The angle in degrees between the normals −`a`/|`a`| and −`b`/|`b`| of two gradients, or
/// `None` when either gradient is zero or not finite.
///
/// Computed as atan2(|a × b|, a · b), which stays accurate for tiny angles (where acos of the
/// cosine loses half the digits).
pub fn normal_angle_degrees(a: [f64; 3], b: [f64; 3]) -> Option<f64> {
    let usable = |v: [f64; 3]| v.iter().all(|c| c.is_finite()) && v.iter().any(|&c| c != 0.0);
    if !usable(a) || !usable(b) {
        return None;
    }
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let sine = cross.iter().map(|c| c * c).sum::<f64>().sqrt();
    let cosine: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
    Some(sine.atan2(cosine).to_degrees())
}

/// The median of sorted values.
fn median(sorted: &[f64]) -> Option<f64> {
    let n = sorted.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(sorted[n / 2]),
        _ => Some(0.5 * (sorted[n / 2 - 1] + sorted[n / 2])),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::evaluate::Sample;

    fn close(a: f64, b: f64, tolerance: f64) -> bool {
        (a - b).abs() <= tolerance
    }

    #[test]
    fn known_angles() {
        let x = [1.0, 0.0, 0.0];
        assert_eq!(normal_angle_degrees(x, [2.0, 0.0, 0.0]), Some(0.0));
        assert!(close(
            normal_angle_degrees(x, [0.0, 3.0, 0.0]).unwrap(),
            90.0,
            1e-12
        ));
        assert!(close(
            normal_angle_degrees(x, [1.0, 1.0, 0.0]).unwrap(),
            45.0,
            1e-12
        ));
        assert!(close(
            normal_angle_degrees(x, [-1.0, 0.0, 0.0]).unwrap(),
            180.0,
            1e-12
        ));
        // A micro-degree is resolved (acos would round it to 0 or to ~1e-6 ± 50 %).
        let tiny = 1e-6_f64.to_radians();
        let angle = normal_angle_degrees(x, [tiny.cos(), tiny.sin(), 0.0]).unwrap();
        assert!(close(angle, 1e-6, 1e-15), "{angle}");
    }

    #[test]
    fn zero_and_non_finite_gradients_have_no_normal() {
        assert_eq!(normal_angle_degrees([0.0; 3], [1.0, 0.0, 0.0]), None);
        assert_eq!(normal_angle_degrees([1.0, 0.0, 0.0], [0.0; 3]), None);
        assert_eq!(
            normal_angle_degrees([f64::NAN, 1.0, 0.0], [1.0, 0.0, 0.0]),
            None
        );
    }

    #[test]
    fn field_max_rms_and_angle_statistics() {
        let g = [0.0, 0.0, -5.0];
        let reference = vec![(0.0, g); 4];
        let tilted = |degrees: f64| {
            let t = degrees.to_radians();
            [0.0, -5.0 * t.sin(), -5.0 * t.cos()]
        };
        let candidate = vec![
            (3.0, tilted(1.0)),
            (-4.0, tilted(2.0)),
            (0.0, tilted(4.0)),
            (0.0, [0.0; 3]),
        ];
        let d = Deviation::measure(&reference, &candidate).unwrap();
        assert_eq!(d.points, 4);
        assert_eq!(d.field_max, Some(4.0));
        // √((9 + 16 + 0 + 0) / 4) = 2.5
        assert!(close(d.field_rms.unwrap(), 2.5, 1e-15));
        assert!(close(d.normal_max_degrees.unwrap(), 4.0, 1e-12));
        assert!(close(d.normal_median_degrees.unwrap(), 2.0, 1e-12));
        assert_eq!((d.normals_compared, d.normals_skipped), (3, 1));
    }

    #[test]
    fn even_counts_take_the_mean_of_the_middle_pair() {
        assert_eq!(median(&[1.0, 2.0, 4.0, 8.0]), Some(3.0));
        assert_eq!(median(&[]), None);
    }

    #[test]
    fn nan_field_errors_are_not_hidden() {
        let reference = vec![(0.0, [1.0, 0.0, 0.0]); 3];
        let candidate = vec![
            (1.0, [1.0, 0.0, 0.0]),
            (f64::NAN, [1.0, 0.0, 0.0]),
            (2.0, [1.0, 0.0, 0.0]),
        ];
        let d = Deviation::measure(&reference, &candidate).unwrap();
        assert!(d.field_max.unwrap().is_nan());
    }

    #[test]
    fn empty_and_mismatched_inputs() {
        let d = Deviation::measure::<Sample>(&[], &[]).unwrap();
        assert_eq!((d.points, d.field_max, d.field_rms), (0, None, None));
        assert_eq!(d.normal_median_degrees, None);
        assert!(Deviation::measure(&[(0.0, [1.0; 3])], &[]).is_err());
    }
}

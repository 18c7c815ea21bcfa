//! Curves as DXF `SPLINE` entities, the form 2-D CAD tools import.
//!
//! Each curve becomes one non-rational `SPLINE` of its degree (2 to 5) on clamped knots ([`clamped`]): it
//! starts at its first control point and ends at its last, with the parameter range [0, 1]
//! of [`BSplineCurve::point`]. A closed curve is marked closed (flag 1); its seam is
//! continuous to the second derivative, as in the model. A 2-D curve lies in z = 0 and is
//! marked planar (flag 8). The file is DXF R2000 (AC1015), the oldest version with
//! `SPLINE`, written by the [`dxf`] crate.
//!
//! Accuracy: the knots and control points are written with 17 significant digits, so de
//! Boor's algorithm on them reproduces the curve to within f64 rounding.

use dxf::entities::{Entity, EntityType, Spline};
use dxf::enums::AcadVersion;
use dxf::{Drawing, Point};

use crate::error::{Error, Result};

use super::export::{clamped, export_curve};
use super::spline::BSplineCurve;

/// DXF `SPLINE` flag: the curve closes on itself.
const CLOSED: i32 = 1;
/// DXF `SPLINE` flag: the curve lies in a plane.
const PLANAR: i32 = 8;

/// `curves` as a DXF drawing with one `SPLINE` entity each, in order.
///
/// # Errors
/// [`Error::InvalidInput`] when a curve is not valid ([`BSplineCurve::validate`]) or the
/// drawing cannot be written.
pub fn curves_dxf(curves: &[BSplineCurve]) -> Result<Vec<u8>> {
    let mut drawing = Drawing::new();
    drawing.header.version = AcadVersion::R2000;
    for curve in curves {
        let export = clamped(&export_curve(curve)?);
        let mut spline = Spline {
            degree_of_curve: export.degree as i32,
            knot_values: export.knots,
            control_points: export
                .control_points
                .iter()
                .map(|p| Point::new(p[0], p[1], p.get(2).copied().unwrap_or(0.0)))
                .collect(),
            ..Spline::default()
        };
        spline.flags =
            if curve.closed { CLOSED } else { 0 } | if curve.dimension == 2 { PLANAR } else { 0 };
        drawing.add_entity(Entity::new(EntityType::Spline(spline)));
    }
    let mut bytes = Vec::new();
    drawing
        .save(&mut bytes)
        .map_err(|e| Error::invalid(format!("the DXF drawing could not be written: {e}")))?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// de Boor's algorithm on a `SPLINE` read back from the file.
    fn evaluate(spline: &Spline, t: f64) -> [f64; 3] {
        let (knots, control) = (&spline.knot_values, &spline.control_points);
        let p = spline.degree_of_curve as usize;
        let m = control.len();
        let k = (p..m).rfind(|&k| knots[k] <= t).unwrap_or(p).min(m - 1);
        let mut d: Vec<[f64; 3]> = (0..=p)
            .map(|j| {
                let c = &control[j + k - p];
                [c.x, c.y, c.z]
            })
            .collect();
        for r in 1..=p {
            for j in (r..=p).rev() {
                let i = j + k - p;
                let alpha = (t - knots[i]) / (knots[i + p + 1 - r] - knots[i]);
                d[j] = [0, 1, 2].map(|c| (1.0 - alpha) * d[j - 1][c] + alpha * d[j][c]);
            }
        }
        d[p]
    }

    #[test]
    fn splines_read_back_reproduce_the_curves() {
        let ring = |n: usize, z: f64| -> Vec<[f64; 3]> {
            (0..n)
                .map(|i| {
                    let a = i as f64 * 0.9;
                    [1e3 + a.cos() * (2.0 + 0.1 * a), -5.0 + a.sin(), z * a]
                })
                .collect()
        };
        let curves = [
            BSplineCurve {
                dimension: 2,
                closed: true,
                degree: 3,
                control: ring(7, 0.0),
            },
            BSplineCurve {
                dimension: 3,
                closed: false,
                degree: 3,
                control: ring(12, 0.4),
            },
        ];
        let bytes = curves_dxf(&curves).unwrap();
        let drawing = Drawing::load(&mut bytes.as_slice()).unwrap();
        let splines: Vec<&Spline> = drawing
            .entities()
            .filter_map(|e| match &e.specific {
                EntityType::Spline(s) => Some(s),
                _ => None,
            })
            .collect();
        assert_eq!(splines.len(), 2);
        assert_eq!(splines[0].flags, CLOSED | PLANAR);
        assert_eq!(splines[1].flags, 0);
        for (curve, spline) in curves.iter().zip(splines) {
            assert_eq!(spline.degree_of_curve, 3);
            for i in 0..=100 {
                let t = f64::from(i) / 100.0;
                let (a, b) = (evaluate(spline, t), curve.point(t));
                assert!(
                    (0..3).all(|k| (a[k] - b[k]).abs() < 1e-9),
                    "{t}: {a:?} {b:?}"
                );
            }
        }
    }
}

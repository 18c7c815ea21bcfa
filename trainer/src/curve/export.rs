//! Curves and surfaces in the forms CAD tools read: degree, knots and control points (JSON),
//! and a curve as an SVG path of cubic Béziers in the model's coordinates.
//!
//! Both forms are exact: the uniform B-spline of degree p of [`BSplineCurve`] is the standard
//! (unclamped) B-spline of degree p on the knots kᵢ = (i − p)/segments, whose domain
//! [k_p, k_m] is the curve's parameter range [0, 1]; a closed curve repeats its first p
//! control points at the end (m = n + p). Each polynomial segment of a cubic is also a cubic
//! Bézier with points (P₀ + 4P₁ + P₂)/6, (2P₁ + P₂)/3, (P₁ + 2P₂)/3, (P₁ + 4P₂ + P₃)/6; a
//! quadratic's segments are cubic Béziers too (degree elevation), while quartic and quintic
//! segments have no exact cubic Bézier and no SVG form.

use serde::Serialize;

use crate::error::{Error, Result};

use super::spline::{BSplineCurve, BSplineSurface};

/// The default degree of curves and surfaces: cubic.
pub const DEGREE: usize = 3;

/// A curve as degree, knots and control points: evaluating the B-spline these define with de
/// Boor's algorithm at t ∈ `domain` gives [`BSplineCurve::point`]`(t)`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CurveExport {
    /// The curve's degree p, 2 to 5.
    pub degree: usize,
    /// 2 or 3: the length of each control point.
    pub dimension: usize,
    /// Whether the curve closes on itself (its control points then end with its first p
    /// again).
    pub closed: bool,
    /// The parameter range, [0, 1].
    pub domain: [f64; 2],
    /// m + p + 1 non-decreasing knots (uniform; unclamped).
    pub knots: Vec<f64>,
    /// m control points.
    pub control_points: Vec<Vec<f64>>,
}

/// A surface as degrees, knots and its control grid, row by row along u.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceExport {
    /// The degree along u, 2 to 5.
    pub degree_u: usize,
    /// The degree along v, 2 to 5.
    pub degree_v: usize,
    /// Whether the surface closes along u (each row then ends with its first p_u points).
    pub closed_u: bool,
    /// Whether it closes along v (the grid then ends with its first p_v rows).
    pub closed_v: bool,
    /// The parameter ranges of u and v, each [0, 1].
    pub domain: [[f64; 2]; 2],
    /// Knots along u.
    pub knots_u: Vec<f64>,
    /// Knots along v.
    pub knots_v: Vec<f64>,
    /// Control points per row (along u).
    pub count_u: usize,
    /// Rows (along v).
    pub count_v: usize,
    /// `control_points[v * count_u + u]`, each `[x, y, z]`.
    pub control_points: Vec<[f64; 3]>,
}

/// The uniform knots of a direction with `count` control points (before wrapping) and the
/// indices of its control points in standard form.
fn direction(count: usize, closed: bool, degree: usize) -> (Vec<f64>, Vec<usize>) {
    let (segments, indices): (usize, Vec<usize>) = if closed {
        (count, (0..count + degree).map(|i| i % count).collect())
    } else {
        (count.saturating_sub(degree), (0..count).collect())
    };
    let segments = segments.max(1) as f64;
    let knots = (0..indices.len() + degree + 1)
        .map(|i| (i as f64 - degree as f64) / segments)
        .collect();
    (knots, indices)
}

/// `curve` as degree, knots and control points.
///
/// # Errors
/// [`Error::InvalidInput`] when the curve is not valid ([`BSplineCurve::validate`]).
pub fn export_curve(curve: &BSplineCurve) -> Result<CurveExport> {
    curve.validate()?;
    let (knots, indices) = direction(curve.control.len(), curve.closed, curve.degree);
    Ok(CurveExport {
        degree: curve.degree,
        dimension: curve.dimension,
        closed: curve.closed,
        domain: [0.0, 1.0],
        knots,
        control_points: indices
            .iter()
            .map(|&i| curve.control[i][..curve.dimension].to_vec())
            .collect(),
    })
}

/// `export` with clamped knots: the same curve, parameter for parameter, on the knots
/// 0 (p + 1 times), 1/s, …, (s − 1)/s, 1 (p + 1 times) that CAD tools assume, so that it
/// starts at its first control point and ends at its last. Each end of the domain is
/// inserted as a knot (Boehm's algorithm) until it has multiplicity p, and what lies outside
/// the domain is dropped; the control point count stays m.
pub fn clamped(export: &CurveExport) -> CurveExport {
    let (mut knots, mut control) = (export.knots.clone(), export.control_points.clone());
    let [start, end] = export.domain;
    let p = export.degree;
    clamp_start(&mut knots, &mut control, start, p);
    // The end is the start of the reversed curve, on knots t ↦ −t.
    knots.reverse();
    knots.iter_mut().for_each(|k| *k = -*k);
    control.reverse();
    clamp_start(&mut knots, &mut control, -end, p);
    knots.reverse();
    knots.iter_mut().for_each(|k| *k = -*k);
    control.reverse();
    CurveExport {
        knots,
        control_points: control,
        ..export.clone()
    }
}

/// Clamps a degree-`p` B-spline at the start `a` of its domain (a knot of multiplicity 1
/// with p knots before it): inserts `a` p − 1 times, drops the p − 1 control points and
/// knots before it, and sets the first knot to `a`.
fn clamp_start(knots: &mut Vec<f64>, control: &mut Vec<Vec<f64>>, a: f64, p: usize) {
    for _ in 1..p {
        insert_knot(knots, control, a, p);
    }
    let first = knots.iter().position(|&k| k >= a).unwrap_or(0);
    let drop = first.saturating_sub(1);
    knots.drain(..drop);
    control.drain(..drop);
    knots[0] = a;
}

/// Inserts the knot `t` once into a degree-`p` B-spline (Boehm): the curve is unchanged,
/// one control point more.
fn insert_knot(knots: &mut Vec<f64>, control: &mut Vec<Vec<f64>>, t: f64, p: usize) {
    // The span k with knots[k] ≤ t < knots[k + 1].
    let k = knots.iter().rposition(|&u| u <= t).unwrap_or(p);
    let mut inserted = Vec::with_capacity(control.len() + 1);
    for i in 0..=control.len() {
        let point = if i + p <= k {
            control[i].clone()
        } else if i > k {
            control[i - 1].clone()
        } else {
            let alpha = (t - knots[i]) / (knots[i + p] - knots[i]);
            control[i - 1]
                .iter()
                .zip(&control[i])
                .map(|(a, b)| (1.0 - alpha) * a + alpha * b)
                .collect()
        };
        inserted.push(point);
    }
    *control = inserted;
    knots.insert(k + 1, t);
}

/// `surface` as degrees, knots and its control grid.
///
/// # Errors
/// [`Error::InvalidInput`] when the surface is not valid ([`BSplineSurface::validate`]).
pub fn export_surface(surface: &BSplineSurface) -> Result<SurfaceExport> {
    surface.validate()?;
    let (knots_u, columns) = direction(surface.count_u, surface.closed_u, surface.degree_u);
    let (knots_v, rows) = direction(surface.count_v, surface.closed_v, surface.degree_v);
    let control_points = rows
        .iter()
        .flat_map(|&v| {
            columns
                .iter()
                .map(move |&u| surface.control[v * surface.count_u + u])
        })
        .collect();
    Ok(SurfaceExport {
        degree_u: surface.degree_u,
        degree_v: surface.degree_v,
        closed_u: surface.closed_u,
        closed_v: surface.closed_v,
        domain: [[0.0, 1.0]; 2],
        knots_u,
        knots_v,
        count_u: columns.len(),
        count_v: rows.len(),
        control_points,
    })
}

/// The curve's polynomial segments as cubic Béziers, in order (four points each): exact for
/// degrees 2 and 3.
///
/// # Errors
/// [`Error::InvalidInput`] when the curve is not valid, or of degree 4 or 5 (whose segments
/// no cubic Bézier holds).
pub fn bezier_segments(curve: &BSplineCurve) -> Result<Vec<[[f64; 3]; 4]>> {
    curve.validate()?;
    if curve.degree > 3 {
        return Err(Error::invalid(format!(
            "an SVG path holds cubic Béziers, and a curve of degree {} has no exact one; \
             export it as JSON (--json) or DXF (--dxf) instead, or fit it with --degree 3",
            curve.degree
        )));
    }
    if curve.degree < 3 {
        // A polynomial of degree ≤ 3 on [0, 1] is the cubic Bézier C(0), C(0) + C′(0)/3,
        // C(1) − C′(1)/3, C(1) (C′ per unit of the segment's own parameter).
        let segments = curve.segments();
        let g = segments as f64;
        return Ok((0..segments)
            .map(|i| {
                let (a, b) = (i as f64 / g, (i + 1) as f64 / g);
                let (start, end) = (curve.point(a), curve.point(b));
                // Inside the segment, so that each end's tangent is this segment's.
                let (ta, tb) = (curve.tangent(a), curve.tangent(b.min(1.0)));
                [
                    start,
                    [0, 1, 2].map(|k| start[k] + ta[k] / (3.0 * g)),
                    [0, 1, 2].map(|k| end[k] - tb[k] / (3.0 * g)),
                    end,
                ]
            })
            .collect());
    }
    let n = curve.control.len();
    let mix = |a: [f64; 3], b: [f64; 3], c: [f64; 3], w: [f64; 3]| {
        [0, 1, 2].map(|k| (w[0] * a[k] + w[1] * b[k] + w[2] * c[k]) / 6.0)
    };
    Ok((0..curve.segments())
        .map(|i| {
            let p = [0, 1, 2, 3].map(|k| curve.control[(i + k) % n]);
            [
                mix(p[0], p[1], p[2], [1.0, 4.0, 1.0]),
                mix(p[1], p[2], p[2], [4.0, 2.0, 0.0]),
                mix(p[1], p[2], p[2], [2.0, 4.0, 0.0]),
                mix(p[1], p[2], p[3], [1.0, 4.0, 1.0]),
            ]
        })
        .collect())
}

/// A 2-D curve as an SVG document: one path of cubic Béziers in the model's coordinates (y
/// up, as in the data: the drawing is flipped by a transform, not the numbers), with a
/// view box around it.
///
/// # Errors
/// [`Error::InvalidInput`] for a 3-D curve (export its knots and control points instead) or
/// an invalid one.
pub fn curve_svg(curve: &BSplineCurve) -> Result<String> {
    if curve.dimension != 2 {
        return Err(Error::invalid(
            "an SVG path is 2-D, but this curve is 3-D; export it as JSON (--json) instead",
        ));
    }
    let segments = bezier_segments(curve)?;
    let mut lower = [f64::INFINITY; 2];
    let mut upper = [f64::NEG_INFINITY; 2];
    for p in segments.iter().flatten() {
        for k in 0..2 {
            lower[k] = lower[k].min(p[k]);
            upper[k] = upper[k].max(p[k]);
        }
    }
    let size = (upper[0] - lower[0])
        .max(upper[1] - lower[1])
        .max(f64::MIN_POSITIVE);
    let margin = 0.05 * size;
    let number = |v: f64| format!("{v:.9e}");
    let point = |p: [f64; 3]| format!("{},{}", number(p[0]), number(p[1]));
    let mut path = format!("M {}", point(segments[0][0]));
    for s in &segments {
        path.push_str(&format!(
            " C {} {} {}",
            point(s[1]),
            point(s[2]),
            point(s[3])
        ));
    }
    if curve.closed {
        path.push_str(" Z");
    }
    let (x, y) = (lower[0] - margin, -(upper[1] + margin));
    let (w, h) = (
        upper[0] - lower[0] + 2.0 * margin,
        upper[1] - lower[1] + 2.0 * margin,
    );
    Ok(format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"{} {} {} {}\">\n\
         <path transform=\"scale(1,-1)\" fill=\"none\" stroke=\"black\" \
         stroke-width=\"{}\" d=\"{path}\"/>\n</svg>\n",
        number(x),
        number(y),
        number(w),
        number(h),
        number(size / 500.0)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// de Boor's algorithm on standard knots (the reference a CAD tool applies), for the
    /// surfaces' cubic rows and the curves' degree.
    fn de_boor(knots: &[f64], control: &[Vec<f64>], t: f64) -> Vec<f64> {
        crate::curve::tests::de_boor(knots, control, DEGREE, t)
    }

    fn cubic_bezier(b: &[[f64; 3]; 4], u: f64) -> [f64; 3] {
        let v = 1.0 - u;
        let w = [v * v * v, 3.0 * u * v * v, 3.0 * u * u * v, u * u * u];
        [0, 1, 2].map(|k| (0..4).map(|j| w[j] * b[j][k]).sum())
    }

    fn curves() -> Vec<BSplineCurve> {
        let control = |n: usize, z: bool| -> Vec<[f64; 3]> {
            (0..n)
                .map(|i| {
                    let a = i as f64 * 0.7;
                    [
                        a.cos() * (1.0 + 0.1 * a),
                        a.sin(),
                        if z { 0.3 * a } else { 0.0 },
                    ]
                })
                .collect()
        };
        vec![
            BSplineCurve {
                dimension: 2,
                closed: false,
                degree: 3,
                control: control(9, false),
            },
            BSplineCurve {
                dimension: 2,
                closed: true,
                degree: 3,
                control: control(6, false),
            },
            BSplineCurve {
                dimension: 3,
                closed: false,
                degree: 3,
                control: control(4, true),
            },
            BSplineCurve {
                dimension: 3,
                closed: true,
                degree: 3,
                control: control(11, true),
            },
        ]
    }

    /// de Boor on `e` gives `curve` at 201 parameters, to 10⁻¹².
    fn assert_reproduces(curve: &BSplineCurve, e: &CurveExport) {
        for i in 0..=200 {
            let t = f64::from(i) / 200.0;
            let reference = curve.point(t);
            let exported = de_boor(&e.knots, &e.control_points, t);
            for k in 0..curve.dimension {
                assert!(
                    (exported[k] - reference[k]).abs() < 1e-12,
                    "{t}: {exported:?} against {reference:?}"
                );
            }
        }
    }

    #[test]
    fn knots_and_control_points_reproduce_the_curve() {
        for curve in curves() {
            let e = export_curve(&curve).unwrap();
            assert_eq!(e.knots.len(), e.control_points.len() + DEGREE + 1);
            assert_eq!(e.knots[DEGREE], 0.0);
            assert!((e.knots[e.control_points.len()] - 1.0).abs() < 1e-15);
            assert_reproduces(&curve, &e);
        }
    }

    #[test]
    fn clamped_knots_reproduce_the_curve_and_start_and_end_at_control_points() {
        for curve in curves() {
            let e = clamped(&export_curve(&curve).unwrap());
            let m = e.control_points.len();
            assert_eq!(
                m,
                curve.control.len() + if curve.closed { DEGREE } else { 0 }
            );
            assert_eq!(e.knots.len(), m + DEGREE + 1);
            assert_eq!(e.knots[..=DEGREE], [0.0; DEGREE + 1]);
            assert!(e.knots[m..].iter().all(|&k| (k - 1.0).abs() < 1e-15));
            let (a, b) = (curve.point(0.0), curve.point(1.0));
            for k in 0..curve.dimension {
                assert!((e.control_points[0][k] - a[k]).abs() < 1e-12);
                assert!((e.control_points[m - 1][k] - b[k]).abs() < 1e-12);
            }
            assert_reproduces(&curve, &e);
        }
    }

    #[test]
    fn bezier_segments_reproduce_the_curve() {
        for curve in curves() {
            let segments = bezier_segments(&curve).unwrap();
            assert_eq!(segments.len(), curve.segments());
            for (i, s) in segments.iter().enumerate() {
                for j in 0..=10 {
                    let u = f64::from(j) / 10.0;
                    let t = (i as f64 + u) / segments.len() as f64;
                    let (a, b) = (cubic_bezier(s, u), curve.point(t));
                    assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-12), "{t}");
                }
            }
        }
        let svg = curve_svg(&curves()[1]).unwrap();
        assert_eq!(svg.matches(" C ").count(), 6);
        assert!(svg.contains(" Z\""));
        let error = curve_svg(&curves()[2]).unwrap_err().to_string();
        assert!(error.contains("3-D") && error.contains("--json"), "{error}");
    }

    #[test]
    fn a_surface_exports_its_grid_with_wrapped_directions() {
        let (count_u, count_v) = (5, 4);
        let control = (0..count_u * count_v)
            .map(|i| [(i % count_u) as f64, (i / count_u) as f64, (i as f64).sin()])
            .collect();
        let surface = BSplineSurface {
            closed_u: true,
            closed_v: false,
            degree_u: 3,
            degree_v: 3,
            count_u,
            count_v,
            control,
        };
        let e = export_surface(&surface).unwrap();
        assert_eq!((e.count_u, e.count_v), (count_u + 3, count_v));
        assert_eq!(e.knots_u.len(), e.count_u + 4);
        assert_eq!(e.knots_v.len(), e.count_v + 4);
        assert_eq!(e.control_points.len(), e.count_u * e.count_v);
        // Each row wraps: its last three points are its first three.
        for v in 0..count_v {
            let row = &e.control_points[v * e.count_u..(v + 1) * e.count_u];
            assert_eq!(row[count_u..], row[..3]);
        }
        // A row along u is the closed curve of that row.
        let row: Vec<[f64; 3]> = surface.control[..count_u].to_vec();
        let curve = BSplineCurve {
            dimension: 3,
            closed: true,
            degree: 3,
            control: row,
        };
        let points: Vec<Vec<f64>> = e.control_points[..e.count_u]
            .iter()
            .map(|p| p.to_vec())
            .collect();
        let a = de_boor(&e.knots_u, &points, 0.37);
        let b = curve.point(0.37);
        assert!((0..3).all(|k| (a[k] - b[k]).abs() < 1e-12));
    }
}

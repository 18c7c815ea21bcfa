//! Curves and surfaces of every degree the core accepts (2 to 5): `f32` and Q16.16 against an independent
//! `f64` reference (the Cox–de Boor recursion over the whole integer knot vector, not the
//! core's per-segment triangle), tangents against the reference's, batches against single
//! calls, exact constants, version 3 blobs read as cubic, and the degree's validation.

mod curve_support;

use curve_support::{
    CurveDraws, F32_EPS, LSB, Rng, encode_points, f64s_f32, f64s_q16, max_abs_diff, q16,
};
use neurosurf_core::Quantity;
use neurosurf_core::blob::{self, BlobError};
use neurosurf_core::curve::{
    BSplineCurve, BSplineSurface, CurvePayload, MAX_DEGREE, MIN_DEGREE, SurfacePayload,
};
use neurosurf_core::scalar::{Q16, ScalarKind};

/// A curve blob of `degree` in `kind`.
fn blob_of_degree(kind: ScalarKind, closed: bool, degree: u8, points: &[[f64; 3]]) -> Vec<u8> {
    let control = encode_points(points, kind);
    let payload = CurvePayload {
        dimension: 3,
        closed,
        degree,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        control: &control,
        metadata: b"degree test",
    };
    let mut out = vec![0_u8; 128 + control.len()];
    let len = payload.write(kind, &mut out).unwrap();
    out.truncate(len);
    out
}

/// N_{j,p}(x) on the integer knots (knot k at x = k), by the textbook recursion.
fn cox_de_boor(j: i64, p: usize, x: f64) -> f64 {
    let j_f = j as f64;
    if p == 0 {
        return if (j_f..j_f + 1.0).contains(&x) {
            1.0
        } else {
            0.0
        };
    }
    let p_f = p as f64;
    (x - j_f) / p_f * cox_de_boor(j, p - 1, x)
        + (j_f + p_f + 1.0 - x) / p_f * cox_de_boor(j + 1, p - 1, x)
}

/// The reference C(t) and dC/dt of a uniform B-spline of degree `p`: segment i covers
/// x ∈ [i + p, i + p + 1) of the knot line, where control point P_{i+k} multiplies
/// N_{i+k, p}; the tangent is segments · Σ N_{j,p−1}·(P_j − P_{j−1}).
fn reference(points: &[[f64; 3]], closed: bool, p: usize, t: f64) -> ([f64; 3], [f64; 3]) {
    let n = points.len();
    let segments = if closed { n } else { n - p };
    let s = t.clamp(0.0, 1.0) * segments as f64;
    let i = (s.floor() as usize).min(segments - 1);
    let u = s - i as f64;
    let x = (i + p) as f64 + u;
    let point = |k: usize| points[(i + k) % n];
    let mut position = [0.0; 3];
    let mut tangent = [0.0; 3];
    for k in 0..=p {
        let j = (i + k) as i64;
        let w = cox_de_boor(j, p, x);
        for axis in 0..3 {
            position[axis] += w * point(k)[axis];
        }
        if k > 0 {
            let w = cox_de_boor(j, p - 1, x) * segments as f64;
            for axis in 0..3 {
                tangent[axis] += w * (point(k)[axis] - point(k - 1)[axis]);
            }
        }
    }
    (position, tangent)
}

/// The largest coordinate difference between a segment's points and its anchor, and their
/// largest magnitude: the scales of the error bounds.
fn scales(points: &[[f64; 3]]) -> (f64, f64) {
    let magnitude = points.iter().flatten().fold(0.0_f64, |m, c| m.max(c.abs()));
    (2.0 * magnitude, magnitude)
}

#[test]
fn every_degree_matches_the_reference_in_both_scalars() {
    let mut rng = Rng::new(2024);
    let mut worst = [[0.0_f64; 4]; MAX_DEGREE + 1];
    for degree in MIN_DEGREE..=MAX_DEGREE {
        for round in 0..60 {
            let closed = round % 2 == 1;
            let n = degree + 1 + rng.below(12);
            let points = rng.points(n, 40.0, false);
            let (delta, magnitude) = scales(&points);
            let blob_f = blob_of_degree(ScalarKind::F32, closed, degree as u8, &points);
            let blob_q = blob_of_degree(ScalarKind::Q16_16, closed, degree as u8, &points);
            let f = BSplineCurve::<f32>::from_blob(&blob_f).unwrap();
            let q = BSplineCurve::<Q16>::from_blob(&blob_q).unwrap();
            assert_eq!((f.degree(), q.degree()), (degree, degree));
            let segments = if closed { n } else { n - degree };
            assert_eq!(f.segments(), segments);
            let mut ts: Vec<f64> = (0..40).map(|_| rng.parameter()).collect();
            ts.extend([0.0, 1.0]);
            for &t in &ts {
                let (position, tangent) = reference(&points, closed, degree, t);
                let pf = f.eval(t as f32);
                let pq = q.eval(q16(t));
                let g = segments as f64;
                let errors = [
                    max_abs_diff(f64s_f32(pf.position), position)
                        / (F32_EPS * (magnitude + delta) * (1.0 + g)),
                    max_abs_diff(f64s_f32(pf.tangent), tangent) / (F32_EPS * g * delta),
                    max_abs_diff(f64s_q16(pq.position), position) / (LSB * (delta + 1.0)),
                    max_abs_diff(f64s_q16(pq.tangent), tangent) / (LSB * (delta + 1.0)),
                ];
                for (w, e) in worst[degree].iter_mut().zip(errors) {
                    *w = w.max(e);
                }
            }
        }
    }
    // Bounds in units of the scales above (measured worst over degrees 2–5 in brackets):
    // f32 position within 2·ε·(M + Δ)·(1 + g) (0.54; the rounding of s = t·g counts g
    // times), tangent within 4·ε·g·Δ (2.1); Q16.16 position within 5 LSB·(Δ + 1) (2.7),
    // tangent within 16 LSB·(Δ + 1) whatever g (8.8).
    let bounds = [2.0, 4.0, 5.0, 16.0];
    for degree in MIN_DEGREE..=MAX_DEGREE {
        for ((what, e), bound) in ["f32 position", "f32 tangent", "q16 position", "q16 tangent"]
            .iter()
            .zip(worst[degree])
            .zip(bounds)
        {
            assert!(
                e < bound,
                "degree {degree}: {what} error {e:.2} units (bound {bound})"
            );
        }
    }
}

#[test]
fn constants_are_exact_and_batches_equal_single_calls() {
    let mut rng = Rng::new(7);
    for degree in MIN_DEGREE..=MAX_DEGREE {
        for closed in [false, true] {
            let constant = vec![[3.25, -7.5, 0.125]; degree + 3];
            let f = BSplineCurve::<f32>::from_blob(&blob_of_degree(
                ScalarKind::F32,
                closed,
                degree as u8,
                &constant,
            ))
            .unwrap();
            let q = BSplineCurve::<Q16>::from_blob(&blob_of_degree(
                ScalarKind::Q16_16,
                closed,
                degree as u8,
                &constant,
            ))
            .unwrap();
            let ts: Vec<f64> = (0..37).map(|_| rng.parameter()).collect();
            for &t in &ts {
                let pf = f.eval(t as f32);
                assert_eq!(pf.position, [3.25, -7.5, 0.125]);
                assert_eq!(pf.tangent, [0.0; 3]);
                let pq = q.eval(q16(t));
                assert_eq!(f64s_q16(pq.position), [3.25, -7.5, 0.125]);
                assert_eq!(f64s_q16(pq.tangent), [0.0; 3]);
            }
            let points = rng.points(degree + 6, 10.0, false);
            let f = BSplineCurve::<f32>::from_blob(&blob_of_degree(
                ScalarKind::F32,
                closed,
                degree as u8,
                &points,
            ))
            .unwrap();
            let tf: Vec<f32> = ts.iter().map(|&t| t as f32).collect();
            let mut batch = vec![Default::default(); tf.len()];
            f.eval_batch(&tf, &mut batch).unwrap();
            let mut positions = vec![[0.0; 3]; tf.len()];
            f.position_batch(&tf, &mut positions).unwrap();
            for ((&t, point), position) in tf.iter().zip(&batch).zip(&positions) {
                assert_eq!(*point, f.eval(t));
                assert_eq!(*position, f.position(t));
            }
        }
    }
}

#[test]
fn degrees_outside_two_to_five_and_too_few_points_are_refused() {
    let points = vec![[0.0, 1.0, 2.0]; 8];
    for (degree, expected) in [(0_u8, 2_usize), (1, 2), (6, 5), (255, 5)] {
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let blob = blob_of_degree(kind, false, degree, &points);
            let wanted = BlobError::ShapeMismatch {
                what: Quantity::Degree,
                expected,
                found: usize::from(degree),
            };
            assert_eq!(BSplineCurve::<f32>::from_blob(&blob).unwrap_err(), wanted);
            assert_eq!(BSplineCurve::<Q16>::from_blob(&blob).unwrap_err(), wanted);
            assert!(wanted.to_string().contains("spline degree"), "{wanted}");
        }
    }
    for degree in MIN_DEGREE..=MAX_DEGREE {
        let few = vec![[0.0; 3]; degree];
        let blob = blob_of_degree(ScalarKind::F32, true, degree as u8, &few);
        assert_eq!(
            BSplineCurve::<f32>::from_blob(&blob).unwrap_err(),
            BlobError::ShapeMismatch {
                what: Quantity::ControlPoints,
                expected: degree + 1,
                found: degree,
            }
        );
        let enough = vec![[0.0; 3]; degree + 1];
        let blob = blob_of_degree(ScalarKind::F32, false, degree as u8, &enough);
        assert_eq!(BSplineCurve::<f32>::from_blob(&blob).unwrap().segments(), 1);
    }
}

/// A version 3 blob (no degree in the payload) loads as a cubic, with the bits of the same
/// curve written today.
#[test]
fn version_3_blobs_read_as_cubic() {
    let mut rng = Rng::new(3);
    let points = rng.points(9, 5.0, false);
    for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
        let current = blob_of_degree(kind, false, 3, &points);
        let (_, payload) = blob::parse(&current).unwrap();
        // The version 3 layout is the current one without the degree byte after `closed`.
        assert_eq!(payload[2], 3);
        let mut old_payload = payload[..2].to_vec();
        old_payload.extend_from_slice(&payload[3..]);
        let old = curve_support::frame_version(3, 3, kind.code(), &old_payload);
        let (header, decoded) = CurvePayload::from_blob(&old).unwrap();
        assert_eq!((header.version, decoded.degree), (3, 3));
        let a = BSplineCurve::<Q16>::from_blob(&old).unwrap();
        let b = BSplineCurve::<Q16>::from_blob(&current).unwrap();
        let c = BSplineCurve::<f32>::from_blob(&old).unwrap();
        let d = BSplineCurve::<f32>::from_blob(&current).unwrap();
        for _ in 0..50 {
            let t = rng.parameter();
            assert_eq!(a.eval(q16(t)), b.eval(q16(t)));
            assert_eq!(c.eval(t as f32), d.eval(t as f32));
        }
        // The old layout framed as version 4 is malformed, not misread.
        let misframed = curve_support::frame_version(4, 3, kind.code(), &old_payload);
        assert_eq!(
            BSplineCurve::<f32>::from_blob(&misframed).unwrap_err(),
            BlobError::MalformedPayload
        );
    }
}

/// A surface blob of `degrees` [u, v] in `kind`, `counts` [u, v] control points, rows of
/// constant v.
fn surface_of_degrees(
    kind: ScalarKind,
    closed: [bool; 2],
    degrees: [u8; 2],
    counts: [u16; 2],
    points: &[[f64; 3]],
) -> Vec<u8> {
    let control = encode_points(points, kind);
    let payload = SurfacePayload {
        closed_u: closed[0],
        closed_v: closed[1],
        degree_u: degrees[0],
        degree_v: degrees[1],
        count_u: counts[0],
        count_v: counts[1],
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        control: &control,
        metadata: &[],
    };
    let mut out = vec![0_u8; 128 + control.len()];
    let len = payload.write(kind, &mut out).unwrap();
    out.truncate(len);
    out
}

/// The reference basis weights of one direction: (first control index, [N_k], [h·N_k′]).
fn direction_weights(count: usize, closed: bool, p: usize, t: f64) -> (usize, Vec<f64>, Vec<f64>) {
    let segments = if closed { count } else { count - p };
    let s = t.clamp(0.0, 1.0) * segments as f64;
    let i = (s.floor() as usize).min(segments - 1);
    let x = (i + p) as f64 + (s - i as f64);
    let values = (0..=p).map(|k| cox_de_boor((i + k) as i64, p, x)).collect();
    let slopes = (0..=p)
        .map(|k| {
            // N′_{j,p} = N_{j,p−1} − N_{j+1,p−1} on unit knot spacing.
            let j = (i + k) as i64;
            (cox_de_boor(j, p - 1, x) - cox_de_boor(j + 1, p - 1, x)) * segments as f64
        })
        .collect();
    (i, values, slopes)
}

#[test]
fn surfaces_of_every_degree_match_the_reference_in_both_scalars() {
    let mut rng = Rng::new(77);
    let mut worst = [0.0_f64; 4];
    for (pu, pv) in [(2, 2), (2, 5), (4, 3), (5, 4), (3, 2)] {
        for closed in [[false, false], [true, false], [false, true]] {
            let counts = [pu + 1 + rng.below(4), pv + 1 + rng.below(4)];
            let points = rng.points(counts[0] * counts[1], 20.0, false);
            let (delta, magnitude) = scales(&points);
            let degrees = [pu as u8, pv as u8];
            let counts16 = counts.map(|c| c as u16);
            let f = BSplineSurface::<f32>::from_blob(&surface_of_degrees(
                ScalarKind::F32,
                closed,
                degrees,
                counts16,
                &points,
            ))
            .unwrap();
            let q = BSplineSurface::<Q16>::from_blob(&surface_of_degrees(
                ScalarKind::Q16_16,
                closed,
                degrees,
                counts16,
                &points,
            ))
            .unwrap();
            assert_eq!(f.degrees(), [pu, pv]);
            let mut uvs: Vec<[f64; 2]> = (0..30)
                .map(|_| [rng.parameter(), rng.parameter()])
                .collect();
            uvs.extend([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
            for &[u, v] in &uvs {
                let (iu, bu, su) = direction_weights(counts[0], closed[0], pu, u);
                let (iv, bv, sv) = direction_weights(counts[1], closed[1], pv, v);
                let mut want = [[0.0; 3]; 3];
                for j in 0..=pv {
                    for k in 0..=pu {
                        let point =
                            points[((iv + j) % counts[1]) * counts[0] + (iu + k) % counts[0]];
                        for axis in 0..3 {
                            want[0][axis] += bv[j] * bu[k] * point[axis];
                            want[1][axis] += bv[j] * su[k] * point[axis];
                            want[2][axis] += sv[j] * bu[k] * point[axis];
                        }
                    }
                }
                let g = counts[0].max(counts[1]) as f64;
                let pf = f.eval([u as f32, v as f32]);
                let pq = q.eval([q16(u), q16(v)]);
                let errors = [
                    max_abs_diff(f64s_f32(pf.position), want[0])
                        / (F32_EPS * (magnitude + delta) * (1.0 + g)),
                    max_abs_diff(f64s_f32(pf.du), want[1])
                        .max(max_abs_diff(f64s_f32(pf.dv), want[2]))
                        / (F32_EPS * g * delta * (1.0 + g)),
                    max_abs_diff(f64s_q16(pq.position), want[0]) / (LSB * (delta + 1.0)),
                    max_abs_diff(f64s_q16(pq.du), want[1])
                        .max(max_abs_diff(f64s_q16(pq.dv), want[2]))
                        / (LSB * g * (delta + 1.0)),
                ];
                for (w, e) in worst.iter_mut().zip(errors) {
                    *w = w.max(e);
                }
                // Batches give the single calls' bits; the normal is the partials' direction.
                let mut batch = [Default::default(); 1];
                f.eval_batch(&[[u as f32, v as f32]], &mut batch).unwrap();
                assert_eq!(batch[0], pf);
                let mut normals = [None; 1];
                f.normal_batch(&[[u as f32, v as f32]], &mut normals)
                    .unwrap();
                assert_eq!(normals[0], f.normal([u as f32, v as f32]));
                if let Some(n) = f.normal([u as f32, v as f32]) {
                    let cross = curve_support::cross(want[1], want[2]);
                    let length = curve_support::norm(cross);
                    if length > 1e-3 * curve_support::norm(want[1]) * curve_support::norm(want[2]) {
                        let angle = curve_support::angle(f64s_f32(n), cross);
                        assert!(angle < 1e-3, "normal off by {angle} rad");
                    }
                }
            }
        }
    }
    // Bounds in units of the scales above (measured worst in brackets): f32 position
    // within 2·ε·(M + Δ)·(1 + g) (0.20), partials within ε·g·Δ·(1 + g) (0.19); Q16.16
    // position within 8 LSB·(Δ + 1) (3.0), partials within 8 LSB·g·(Δ + 1) (1.0).
    let bounds = [2.0, 1.0, 8.0, 8.0];
    for ((what, e), bound) in [
        "f32 position",
        "f32 partials",
        "q16 position",
        "q16 partials",
    ]
    .iter()
    .zip(worst)
    .zip(bounds)
    {
        assert!(e < bound, "{what} error {e:.2} units (bound {bound})");
    }
}

/// A constant net gives its constant and zero partials in every degree, in both scalars; a
/// degree outside 2 to 5 is refused by name.
#[test]
fn surface_constants_are_exact_and_bad_degrees_are_refused() {
    let points = vec![[1.5, -2.25, 3.0]; 36];
    for degrees in [[2_u8, 5], [5, 2], [4, 4]] {
        let blob = surface_of_degrees(ScalarKind::Q16_16, [true, false], degrees, [6, 6], &points);
        let f = BSplineSurface::<f32>::from_blob(&blob).unwrap();
        let q = BSplineSurface::<Q16>::from_blob(&blob).unwrap();
        for uv in [[0.0, 0.0], [0.3, 0.7], [1.0, 0.5]] {
            let p = f.eval(uv);
            assert_eq!(
                (p.position, p.du, p.dv),
                ([1.5, -2.25, 3.0], [0.0; 3], [0.0; 3])
            );
            assert_eq!(f.normal(uv), None);
            let p = q.eval(uv.map(|c: f32| q16(f64::from(c))));
            assert_eq!(f64s_q16(p.position), [1.5, -2.25, 3.0]);
            assert_eq!((f64s_q16(p.du), f64s_q16(p.dv)), ([0.0; 3], [0.0; 3]));
        }
    }
    for (degrees, found) in [([1_u8, 3], 1_usize), ([3, 6], 6)] {
        let blob = surface_of_degrees(ScalarKind::F32, [false, false], degrees, [6, 6], &points);
        assert_eq!(
            BSplineSurface::<f32>::from_blob(&blob).unwrap_err(),
            BlobError::ShapeMismatch {
                what: Quantity::Degree,
                expected: found.clamp(MIN_DEGREE, MAX_DEGREE),
                found,
            }
        );
    }
}

//! B-spline curves in `f32` and Q16.16 against an independent `f64` reference
//! (`curve_support`), and the properties of the basis: partition of unity, C² joints, phantom
//! ends, clamping, batches bit-identical to single points.

mod curve_support;

use curve_support::{
    CurveDraws, F32_EPS, LSB, RefCurve, Rng, curve_blob, f64s_f32, f64s_q16, max_abs_diff, q16,
    span_scales,
};
use neurosurf_core::curve::{BSplineCurve, CurvePoint, LANES};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

// Named tolerances. Δ is the largest coordinate difference between a segment's control points
// and its second one (the core's anchor), M the largest coordinate magnitude of the segment,
// g the number of segments, ε = 2⁻²⁴, LSB = 2⁻¹⁶. Measured maxima are printed by
// `accuracy_against_the_f64_reference` (run with `--nocapture`) and quoted in the docs.

/// f32 position: |C̃ − C| ≤ F32_POSITION·ε·(M + Δ) when s = t·g is exact (every t on the
/// Q16.16 grid with g < 256).
const F32_POSITION: f64 = 2.5;
/// f32 position, any t: the rounding of s = t·g adds up to F32_PARAMETER·ε·g·Δ.
const F32_PARAMETER: f64 = 2.0;
/// f32 tangent: |T̃ − T| ≤ F32_TANGENT·ε·g·Δ (plus the parameter rounding's g·|C''|·ε·g/g).
const F32_TANGENT: f64 = 3.0;
/// Q16.16 position: |C̃ − C| ≤ Q16_POSITION·LSB·Δ + ½ LSB. (The a-priori bound from the
/// weights' errors, 2 + 2.5 + 2 LSB, is 6.5.)
const Q16_POSITION: f64 = 3.0;
/// Q16.16 tangent: |T̃ − T| ≤ Q16_TANGENT·LSB·Δ + ½ LSB, independent of g (a-priori bound
/// 1 + 2.5 + 1 LSB).
const Q16_TANGENT: f64 = 4.5;

fn load_f32(blob: &[u8]) -> BSplineCurve<f32> {
    BSplineCurve::from_blob(blob).unwrap()
}

fn load_q16(blob: &[u8]) -> BSplineCurve<Q16> {
    BSplineCurve::from_blob(blob).unwrap()
}

/// A random curve: open or closed, 2-D or 3-D, 4 … 43 points, coordinates in [−scale, scale].
fn random_curve(rng: &mut Rng, scale: f64) -> (RefCurve, u8) {
    let closed = rng.below(2) == 0;
    let dimension = 2 + rng.below(2) as u8;
    let n = 4 + rng.below(40);
    let points = rng.points(n, scale, dimension == 2);
    (RefCurve::new(closed, points), dimension)
}

/// Parameters that exercise a curve: random grid values, every joint (rounded to the grid),
/// one LSB on either side of them, and the ends.
fn parameters(rng: &mut Rng, segments: usize) -> Vec<f64> {
    let mut t: Vec<f64> = (0..40).map(|_| rng.parameter()).collect();
    for k in 0..=segments {
        let joint = curve_support::to_grid(k as f64 / segments as f64);
        t.extend([joint, (joint - LSB).max(0.0), (joint + LSB).min(1.0)]);
    }
    t.extend([0.0, 1.0, LSB, 1.0 - LSB]);
    t
}

#[derive(Default, Debug)]
struct Worst {
    f32_position: f64,
    f32_position_any_t: f64,
    f32_tangent: f64,
    q16_position: f64,
    q16_tangent: f64,
}

#[test]
fn accuracy_against_the_f64_reference() {
    let mut rng = Rng::new(0xB5_C0DE);
    let mut worst = Worst::default();
    let mut evaluations = 0;
    for case in 0..200 {
        // Mostly unit-sized curves, some large ones (Q16.16 errors scale with Δ).
        let scale = if case % 5 == 4 { 500.0 } else { 1.0 };
        let (reference, dimension) = random_curve(&mut rng, scale);
        let g = reference.segments();
        let storage = if case % 2 == 0 {
            ScalarKind::F32
        } else {
            ScalarKind::Q16_16
        };
        let blob = curve_blob(
            storage,
            dimension,
            reference.direction.closed,
            &reference.points,
        );
        let f = load_f32(&blob);
        let q = load_q16(&blob);
        assert_eq!((f.segments(), q.segments()), (g, g));

        let mut check = |t: f64, f32_t: f32, grid: bool| {
            let exact = reference.eval(f64::from(f32_t));
            let (i, _) = reference.direction.locate(f64::from(f32_t));
            let span = reference.span(i);
            let (delta, magnitude) = span_scales(&span, span[1]);
            let fp = f.eval(f32_t);
            let pos_err = max_abs_diff(f64s_f32(fp.position), exact[0]);
            let tan_err = max_abs_diff(f64s_f32(fp.tangent), exact[1]);
            if grid {
                let bound = F32_EPS * (magnitude + delta);
                worst.f32_position = worst.f32_position.max(pos_err / bound);
                assert!(
                    pos_err <= F32_POSITION * bound,
                    "f32 position at t = {t}: error {pos_err:e}, Δ = {delta}, M = {magnitude}"
                );
                let bound = F32_EPS * g as f64 * delta;
                worst.f32_tangent = worst.f32_tangent.max(tan_err / bound);
                assert!(
                    tan_err <= F32_TANGENT * bound,
                    "f32 tangent at t = {t}: {tan_err:e}"
                );

                let qp = q.eval(q16(t));
                let pos_err = max_abs_diff(f64s_q16(qp.position), exact[0]);
                let tan_err = max_abs_diff(f64s_q16(qp.tangent), exact[1]);
                worst.q16_position = worst
                    .q16_position
                    .max((pos_err - LSB / 2.0) / (LSB * delta));
                worst.q16_tangent = worst.q16_tangent.max((tan_err - LSB / 2.0) / (LSB * delta));
                assert!(
                    pos_err <= Q16_POSITION * LSB * delta + LSB / 2.0,
                    "Q16 position at t = {t}: error {:.2} LSB, Δ = {delta}",
                    pos_err / LSB
                );
                assert!(
                    tan_err <= Q16_TANGENT * LSB * delta + LSB / 2.0,
                    "Q16 tangent at t = {t}: error {:.2} LSB, Δ = {delta}",
                    tan_err / LSB
                );
                if dimension == 2 {
                    assert_eq!((qp.position[2], qp.tangent[2]), (Q16::ZERO, Q16::ZERO));
                    assert_eq!((fp.position[2], fp.tangent[2]), (0.0, 0.0));
                }
            } else {
                let bound = F32_EPS
                    * (F32_POSITION * (magnitude + delta) + F32_PARAMETER * g as f64 * delta);
                worst.f32_position_any_t = worst.f32_position_any_t.max(pos_err / bound);
                assert!(pos_err <= bound, "f32 position at t = {t}: {pos_err:e}");
                // The tangent moves with the rounded parameter by |C''|·δs/g ≤ 4·g·Δ·ε·s/g.
                let bound = F32_EPS * g as f64 * delta * (F32_TANGENT + 4.0 * g as f64);
                assert!(tan_err <= bound, "f32 tangent at t = {t}: {tan_err:e}");
            }
            evaluations += 1;
        };
        for t in parameters(&mut rng, g) {
            check(t, t as f32, true);
        }
        // Arbitrary f32 parameters: s = t·g rounds.
        for _ in 0..40 {
            let t = rng.unit() as f32;
            check(f64::from(t), t, false);
        }
    }
    println!("{evaluations} evaluations; worst error / bound: {worst:?}");
}

#[test]
fn a_constant_polygon_is_reproduced_exactly() {
    let mut rng = Rng::new(7);
    for case in 0..50 {
        let c = rng.points(1, 1000.0, case % 3 == 0)[0];
        let n = 4 + rng.below(12);
        let closed = case % 2 == 0;
        let dimension = if case % 3 == 0 { 2 } else { 3 };
        for storage in [ScalarKind::F32, ScalarKind::Q16_16] {
            let blob = curve_blob(storage, dimension, closed, &vec![c; n]);
            let (f, q) = (load_f32(&blob), load_q16(&blob));
            // The constant as stored (f32 storage rounds coordinates beyond 2⁸ in magnitude).
            let (cf, cq) = (f.control_point(0).unwrap(), q.control_point(0).unwrap());
            for _ in 0..20 {
                let t = rng.parameter();
                let fp = f.eval(t as f32);
                assert_eq!(fp.position, cf, "f32 at t = {t}");
                assert_eq!(fp.tangent, [0.0; 3]);
                let qp = q.eval(q16(t));
                assert_eq!(qp.position, cq, "Q16 at t = {t}");
                assert_eq!(qp.tangent, [Q16::ZERO; 3]);
            }
        }
    }
}

/// Equally spaced collinear control points reproduce the line at constant speed (linear
/// precision of the cubic B-spline).
#[test]
fn a_uniform_line_is_reproduced() {
    let (a, b) = ([0.25, -0.5, 0.125], [0.0625, 0.03125, -0.015625]);
    let points: Vec<[f64; 3]> = (0..9)
        .map(|k| std::array::from_fn(|i| a[i] + k as f64 * b[i]))
        .collect();
    let blob = curve_blob(ScalarKind::Q16_16, 3, false, &points);
    let (f, q) = (load_f32(&blob), load_q16(&blob));
    let mut rng = Rng::new(3);
    for _ in 0..200 {
        let t = rng.parameter();
        // C(t) = P₁ + 6t·b (open, 6 segments), C′ = 6b.
        let exact: [f64; 3] = std::array::from_fn(|i| a[i] + (1.0 + 6.0 * t) * b[i]);
        let fp = f.eval(t as f32);
        assert!(max_abs_diff(f64s_f32(fp.position), exact) < 4.0 * F32_EPS);
        assert!(max_abs_diff(f64s_f32(fp.tangent), b.map(|x| 6.0 * x)) < 8.0 * F32_EPS);
        let qp = q.eval(q16(t));
        assert!(max_abs_diff(f64s_q16(qp.position), exact) <= 1.0 * LSB);
        assert!(max_abs_diff(f64s_q16(qp.tangent), b.map(|x| 6.0 * x)) <= 1.0 * LSB);
    }
}

/// At every joint the segments on either side agree in position, first and second derivative.
///
/// The left limit (segment k − 1 at u = 1) is the end of the open curve P₀ … P₍ₖ₊₂₎, the right
/// one (segment k at u = 0) the start of P₍ₖ₎ … P₍ₙ₋₁₎: both exact parameters. dC/du is the
/// tangent divided by the sub-curve's segment count; d²C/du² is estimated by one-sided
/// differences over δu = 2⁻⁶ on each side and compared with the exact value at the joint
/// (the one-sided estimates are off by at most max|C'''|·δu/2 ≤ 4Δ·δu).
#[test]
fn joints_are_c2_continuous() {
    let mut rng = Rng::new(0x_C2);
    for case in 0..20 {
        let n = 6 + rng.below(20);
        let points = rng.points(n, 1.0, case % 2 == 0);
        let whole = RefCurve::new(false, points.clone());
        let delta = 2.0; // coordinates in [−1, 1]
        for k in 1..n - 3 {
            let left_points = &points[..k + 3];
            let right_points = &points[k..];
            let (gl, gr) = (k, n - k - 3);
            let exact = whole.eval_segment(k, 0.0);
            let exact_du = exact[1].map(|x| x / (n - 3) as f64);
            let exact_du2 = exact[2].map(|x| x / ((n - 3) * (n - 3)) as f64);
            let left = curve_blob(ScalarKind::Q16_16, 3, false, left_points);
            let right = curve_blob(ScalarKind::Q16_16, 3, false, right_points);
            let du = 1.0 / 64.0;
            // Grid parameters near u = 1 − δu on the left and u = δu on the right, and the u
            // they give exactly (s = t·g is exact in both scalars for g < 256).
            let tl = curve_support::to_grid(1.0 - du / gl as f64);
            let ul = tl * gl as f64 - (gl - 1) as f64;
            let tr = curve_support::to_grid(du / gr as f64);
            let ur = tr * gr as f64;
            let (fl, fr) = (load_f32(&left), load_f32(&right));
            let (ql, qr) = (load_q16(&left), load_q16(&right));
            // [left end, left inside, right start, right inside], tolerances of position and
            // dC/du (the tangent's divided by g ≥ 1).
            let sides: [([CurvePoint<f64>; 4], f64, f64); 2] = [
                (
                    [
                        widen_f32(fl.eval(1.0)),
                        widen_f32(fl.eval(tl as f32)),
                        widen_f32(fr.eval(0.0)),
                        widen_f32(fr.eval(tr as f32)),
                    ],
                    F32_POSITION * F32_EPS * (1.0 + delta),
                    F32_TANGENT * F32_EPS * delta,
                ),
                (
                    [
                        widen_q16(ql.eval(Q16::ONE)),
                        widen_q16(ql.eval(q16(tl))),
                        widen_q16(qr.eval(Q16::ZERO)),
                        widen_q16(qr.eval(q16(tr))),
                    ],
                    (Q16_POSITION * delta + 0.5) * LSB,
                    (Q16_TANGENT * delta + 0.5) * LSB,
                ),
            ];
            for ([l1, l0, r0, r1], position_tolerance, tangent_tolerance) in sides {
                // Position: both limits equal the exact joint, hence each other.
                assert!(max_abs_diff(l1.position, exact[0]) <= position_tolerance);
                assert!(max_abs_diff(r0.position, exact[0]) <= position_tolerance);
                assert!(max_abs_diff(l1.position, r0.position) <= 2.0 * position_tolerance);
                // dC/du.
                let left_du = l1.tangent.map(|x| x / gl as f64);
                let right_du = r0.tangent.map(|x| x / gr as f64);
                assert!(
                    max_abs_diff(left_du, exact_du) <= tangent_tolerance,
                    "case {case} joint {k}"
                );
                assert!(max_abs_diff(right_du, exact_du) <= tangent_tolerance);
                // d²C/du² from each side.
                let left_du2: [f64; 3] =
                    std::array::from_fn(|i| (left_du[i] - l0.tangent[i] / gl as f64) / (1.0 - ul));
                let right_du2: [f64; 3] =
                    std::array::from_fn(|i| (r1.tangent[i] / gr as f64 - right_du[i]) / ur);
                let tolerance = 4.0 * delta * du + 2.0 * tangent_tolerance / du;
                assert!(
                    max_abs_diff(left_du2, exact_du2) <= tolerance,
                    "left C'' at joint {k}: {left_du2:?} vs {exact_du2:?}"
                );
                assert!(
                    max_abs_diff(right_du2, exact_du2) <= tolerance,
                    "right C'' at joint {k}: {right_du2:?} vs {exact_du2:?}"
                );
            }
        }
    }
}

fn widen_f32(p: CurvePoint<f32>) -> CurvePoint<f64> {
    CurvePoint {
        position: f64s_f32(p.position),
        tangent: f64s_f32(p.tangent),
    }
}

fn widen_q16(p: CurvePoint<Q16>) -> CurvePoint<f64> {
    CurvePoint {
        position: f64s_q16(p.position),
        tangent: f64s_q16(p.tangent),
    }
}

/// With phantom end points P₋₁ = 2P₀ − P₁ and P₍ₘ₊₁₎ = 2Pₘ − P₍ₘ₋₁₎ an open curve starts at P₀
/// and ends at Pₘ, with end tangents g·(P₁ − P₀) and g·(Pₘ − P₍ₘ₋₁₎).
#[test]
fn phantom_ends_make_an_open_curve_interpolate_its_ends() {
    let mut rng = Rng::new(11);
    for case in 0..50 {
        let n = 2 + rng.below(20);
        let data = rng.points(n, 100.0, case % 2 == 0);
        let m = data.len() - 1;
        let phantom = |a: [f64; 3], b: [f64; 3]| std::array::from_fn(|i| 2.0 * a[i] - b[i]);
        let mut points = vec![phantom(data[0], data[1])];
        points.extend_from_slice(&data);
        points.push(phantom(data[m], data[m - 1]));
        let g = (points.len() - 3) as f64;
        let start_tangent: [f64; 3] = std::array::from_fn(|i| g * (data[1][i] - data[0][i]));
        let end_tangent: [f64; 3] = std::array::from_fn(|i| g * (data[m][i] - data[m - 1][i]));
        let dimension = if case % 2 == 0 { 2 } else { 3 };
        for storage in [ScalarKind::F32, ScalarKind::Q16_16] {
            let blob = curve_blob(storage, dimension, false, &points);
            // Q16.16: exact (the two equal weights of ±(P₁ − P₀) cancel in the accumulator).
            let q = load_q16(&blob);
            assert_eq!(q.position(Q16::ZERO), data[0].map(q16));
            assert_eq!(q.position(Q16::ONE), data[m].map(q16));
            let scale = 200.0 * g;
            assert!(
                max_abs_diff(f64s_q16(q.tangent(Q16::ZERO)), start_tangent)
                    <= 4.0 * LSB * scale / g
            );
            assert!(
                max_abs_diff(f64s_q16(q.tangent(Q16::ONE)), end_tangent) <= 4.0 * LSB * scale / g
            );
            // f32: within an ulp or two of the data point.
            let f = load_f32(&blob);
            assert!(max_abs_diff(f64s_f32(f.position(0.0)), data[0]) <= 2.0 * F32_EPS * 400.0);
            assert!(max_abs_diff(f64s_f32(f.position(1.0)), data[m]) <= 2.0 * F32_EPS * 400.0);
            assert!(max_abs_diff(f64s_f32(f.tangent(0.0)), start_tangent) <= 8.0 * F32_EPS * scale);
            assert!(max_abs_diff(f64s_f32(f.tangent(1.0)), end_tangent) <= 8.0 * F32_EPS * scale);
        }
    }
}

/// A closed curve has no ends: t = 0 and t = 1 are the same point with the same tangent.
#[test]
fn closed_curves_close() {
    let mut rng = Rng::new(12);
    for _ in 0..50 {
        let n = 4 + rng.below(20);
        let points = rng.points(n, 1.0, false);
        let blob = curve_blob(ScalarKind::Q16_16, 3, true, &points);
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        let g = points.len() as f64;
        let (a, b) = (f.eval(0.0), f.eval(1.0));
        assert!(max_abs_diff(f64s_f32(a.position), f64s_f32(b.position)) <= 8.0 * F32_EPS);
        assert!(max_abs_diff(f64s_f32(a.tangent), f64s_f32(b.tangent)) <= 8.0 * F32_EPS * g * 2.0);
        let (a, b) = (q.eval(Q16::ZERO), q.eval(Q16::ONE));
        assert!(
            max_abs_diff(f64s_q16(a.position), f64s_q16(b.position))
                <= 2.0 * (Q16_POSITION * 2.0 + 0.5) * LSB
        );
        assert!(
            max_abs_diff(f64s_q16(a.tangent), f64s_q16(b.tangent))
                <= 2.0 * (Q16_TANGENT * 2.0 + 0.5) * LSB
        );
    }
}

#[test]
fn parameters_outside_the_range_clamp_and_nan_is_zero() {
    let mut rng = Rng::new(13);
    let points = rng.points(9, 1.0, false);
    for closed in [false, true] {
        let blob = curve_blob(ScalarKind::F32, 3, closed, &points);
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        let (start, end) = (f.eval(0.0), f.eval(1.0));
        for t in [-0.0, -1.0e-30, -1.0, -1.0e30, f32::NEG_INFINITY, f32::MIN] {
            assert_eq!(f.eval(t), start, "t = {t}");
        }
        for t in [1.0 + f32::EPSILON, 2.0, 1.0e30, f32::INFINITY, f32::MAX] {
            assert_eq!(f.eval(t), end, "t = {t}");
        }
        let nan = f.eval(f32::NAN);
        assert_eq!(nan, start);
        assert!(
            nan.position
                .iter()
                .chain(&nan.tangent)
                .all(|c| c.is_finite())
        );
        // Subnormal and tiny parameters stay in the first segment.
        let tiny = f.eval(f32::from_bits(1));
        assert!(max_abs_diff(f64s_f32(tiny.position), f64s_f32(start.position)) <= 4.0 * F32_EPS);

        let (start, end) = (q.eval(Q16::ZERO), q.eval(Q16::ONE));
        for t in [Q16::MIN, -Q16::ONE, Q16::from_bits(-1)] {
            assert_eq!(q.eval(t), start);
        }
        for t in [Q16::MAX, Q16::from_bits(65537), Q16::from_num(1000)] {
            assert_eq!(q.eval(t), end);
        }
    }
}

#[test]
fn batches_equal_single_points_bit_for_bit() {
    let mut rng = Rng::new(14);
    for case in 0..20 {
        let (reference, dimension) =
            random_curve(&mut rng, if case % 2 == 0 { 1.0 } else { 300.0 });
        let blob = curve_blob(
            ScalarKind::F32,
            dimension,
            reference.direction.closed,
            &reference.points,
        );
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        for len in [0, 1, LANES - 1, LANES, LANES + 1, 3 * LANES + 5] {
            let mut t: Vec<f32> = (0..len).map(|_| rng.unit() as f32 * 1.2 - 0.1).collect();
            if len > 2 {
                t[0] = f32::NAN;
                t[1] = f32::INFINITY;
            }
            let mut points = vec![CurvePoint::default(); len];
            let mut positions = vec![[0.0_f32; 3]; len];
            f.eval_batch(&t, &mut points).unwrap();
            f.position_batch(&t, &mut positions).unwrap();
            for i in 0..len {
                let single = f.eval(t[i]);
                let bits = |v: [f32; 3]| v.map(f32::to_bits);
                assert_eq!(bits(points[i].position), bits(single.position));
                assert_eq!(bits(points[i].tangent), bits(single.tangent));
                assert_eq!(bits(positions[i]), bits(f.position(t[i])));
                assert_eq!(bits(positions[i]), bits(single.position));
            }
            let tq: Vec<Q16> = t.iter().map(|&x| Q16::from_f32_saturating(x)).collect();
            let mut points = vec![CurvePoint::default(); len];
            let mut positions = vec![[Q16::ZERO; 3]; len];
            q.eval_batch(&tq, &mut points).unwrap();
            q.position_batch(&tq, &mut positions).unwrap();
            for i in 0..len {
                assert_eq!(points[i], q.eval(tq[i]));
                assert_eq!(positions[i], q.position(tq[i]));
                assert_eq!(q.tangent(tq[i]), points[i].tangent);
            }
        }
        // Mismatched lengths write nothing.
        let mut out = [[1.0_f32; 3]; 3];
        let e = f.position_batch(&[0.5; 4], &mut out).unwrap_err();
        assert_eq!((e.inputs, e.outputs), (4, 3));
        assert_eq!(out, [[1.0; 3]; 3]);
        assert!(
            f.eval_batch(&[0.5; 2], &mut [CurvePoint::default(); 3])
                .is_err()
        );
    }
}

#[test]
fn accessors_and_the_empty_curve() {
    let mut rng = Rng::new(15);
    let points = rng.points(7, 2.0, true);
    for (closed, storage) in [(false, ScalarKind::F32), (true, ScalarKind::Q16_16)] {
        let blob = curve_blob(storage, 2, closed, &points);
        let f = load_f32(&blob);
        let q = load_q16(&blob);
        assert_eq!(f.dimension(), 2);
        assert_eq!(f.is_closed(), closed);
        assert_eq!(f.control_count(), 7);
        assert_eq!(f.segments(), if closed { 7 } else { 4 });
        assert_eq!(f.stored_as(), storage);
        assert_eq!(q.stored_as(), storage);
        assert_eq!(f.control_point(3), Some(points[3].map(|x| x as f32)));
        assert_eq!(q.control_point(6), Some(points[6].map(q16)));
        assert_eq!(f.control_point(7), None);
        assert_eq!((f.mac_count(false), f.mac_count(true)), (20, 34));
        assert_eq!(q.mac_count(true), 34);
    }
    // The empty curve (new(), default(), or after a failed load) evaluates to zero.
    let empty = BSplineCurve::<Q16>::new();
    assert_eq!(empty.eval(Q16::from_num(0.5)), CurvePoint::default());
    assert_eq!(
        (empty.segments(), empty.control_count(), empty.dimension()),
        (0, 0, 0)
    );
    let empty = BSplineCurve::<f32, 4>::default();
    assert_eq!(empty.eval(f32::NAN), CurvePoint::default());
    let mut out = [[1.0_f32; 3]; 9];
    empty.position_batch(&[0.5; 9], &mut out).unwrap();
    assert_eq!(out, [[0.0; 3]; 9]);
}

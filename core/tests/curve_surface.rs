//! B-spline tensor-product surfaces in `f32` and Q16.16 against the independent `f64`
//! reference (`curve_support`): position, partials, normal; partition of unity, planar nets,
//! continuity across patch joints, closed directions, clamping, batches.

mod curve_support;

use curve_support::{
    CurveDraws, F32_EPS, LSB, RefSurface, Rng, angle, cross, f64s_f32, f64s_q16, max_abs_diff,
    norm, q16, span_scales, surface_blob,
};
use neurosurf_core::curve::{BSplineSurface, LANES, SurfacePoint};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

// Named tolerances. Δ is the largest coordinate difference between the 16 control points of
// the evaluated patch and its anchor P₁₁, M their largest coordinate magnitude, g the segment
// count of a direction, ε = 2⁻²⁴, LSB = 2⁻¹⁶. Every parameter here is on the Q16.16 grid,
// so s = t·g is exact in f32 too. Measured maxima are printed by
// `accuracy_against_the_f64_reference` (`--nocapture`) and quoted in the docs.

/// f32 position: |S̃ − S| ≤ F32_POSITION·ε·(M + Δ).
const F32_POSITION: f64 = 3.0;
/// f32 partials: |∂̃ − ∂| ≤ F32_PARTIAL·ε·g·Δ.
const F32_PARTIAL: f64 = 5.0;
/// f32 normal: angle ≤ F32_NORMAL·ε·(Δ/|S_u| + Δ/|S_v| + 1)/sin θ, with S_u, S_v the partials
/// of the local parameters and θ the angle between them.
const F32_NORMAL: f64 = 4.0;
/// Q16.16 position: |S̃ − S| ≤ Q16_POSITION·LSB·Δ + ½ LSB.
const Q16_POSITION: f64 = 6.0;
/// Q16.16 partials: |∂̃ − ∂| ≤ Q16_PARTIAL·LSB·g·Δ + ½ LSB. Unlike a curve's tangent this grows
/// with g: the tensor weights g·Bⱼ′(v)·Bₖ(u) carry the rounding of Bₖ(u) times g.
const Q16_PARTIAL: f64 = 5.0;
/// Q16.16 normal: angle ≤ Q16_NORMAL·LSB·(Δ/|S_u| + Δ/|S_v| + 1)/sin θ.
const Q16_NORMAL: f64 = 5.0;

fn load_f32(blob: &[u8]) -> BSplineSurface<f32> {
    BSplineSurface::from_blob(blob).unwrap()
}

fn load_q16(blob: &[u8]) -> BSplineSurface<Q16> {
    BSplineSurface::from_blob(blob).unwrap()
}

fn random_surface(rng: &mut Rng, scale: f64) -> RefSurface {
    let closed = [rng.below(2) == 0, rng.below(2) == 0];
    let counts = [4 + rng.below(9), 4 + rng.below(9)];
    RefSurface::random(rng, closed, counts, scale)
}

/// Random grid parameters plus joints (and one LSB either side) and corners.
fn parameters(rng: &mut Rng, segments: [usize; 2]) -> Vec<[f64; 2]> {
    let mut uv: Vec<[f64; 2]> = (0..60)
        .map(|_| [rng.parameter(), rng.parameter()])
        .collect();
    for k in 0..=segments[0] {
        let joint = curve_support::to_grid(k as f64 / segments[0] as f64);
        for u in [joint, (joint - LSB).max(0.0), (joint + LSB).min(1.0)] {
            uv.push([u, rng.parameter()]);
        }
    }
    for k in 0..=segments[1] {
        let joint = curve_support::to_grid(k as f64 / segments[1] as f64);
        uv.push([rng.parameter(), joint]);
    }
    uv.extend([[0.0, 0.0], [1.0, 1.0], [0.0, 1.0], [1.0, 0.0]]);
    uv
}

fn uv_q16([u, v]: [f64; 2]) -> [Q16; 2] {
    [q16(u), q16(v)]
}

fn uv_f32([u, v]: [f64; 2]) -> [f32; 2] {
    [u as f32, v as f32]
}

#[derive(Default, Debug)]
struct Worst {
    f32_position: f64,
    f32_partial: f64,
    f32_normal: f64,
    f32_normal_angle: f64,
    q16_position: f64,
    q16_partial: f64,
    q16_normal: f64,
    q16_normal_angle: f64,
}

#[test]
fn accuracy_against_the_f64_reference() {
    let mut rng = Rng::new(0x0050_FACE);
    let mut worst = Worst::default();
    let mut normals_checked = 0;
    for case in 0..120 {
        let scale = if case % 4 == 3 { 300.0 } else { 1.0 };
        let reference = random_surface(&mut rng, scale);
        let storage = if case % 2 == 0 {
            ScalarKind::F32
        } else {
            ScalarKind::Q16_16
        };
        let blob = surface_blob(storage, &reference);
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        let [gu, gv] = reference.segments();
        assert_eq!(f.segments(), [gu, gv]);
        for uv in parameters(&mut rng, [gu, gv]) {
            let [u, v] = uv;
            let exact = reference.eval(u, v);
            let (patch, anchor) = reference.patch(u, v);
            let (delta, magnitude) = span_scales(&patch, anchor);
            let g = [gu as f64, gv as f64];

            let fp = f.eval(uv_f32(uv));
            let err = max_abs_diff(f64s_f32(fp.position), exact[0]);
            let bound = F32_EPS * (magnitude + delta);
            worst.f32_position = worst.f32_position.max(err / bound);
            assert!(
                err <= F32_POSITION * bound,
                "f32 position at {uv:?}: {err:e}"
            );
            for (d, (got, g)) in [fp.du, fp.dv].into_iter().zip(g).enumerate() {
                let err = max_abs_diff(f64s_f32(got), exact[1 + d]);
                let bound = F32_EPS * g * delta;
                worst.f32_partial = worst.f32_partial.max(err / bound);
                assert!(err <= F32_PARTIAL * bound, "f32 ∂{d} at {uv:?}: {err:e}");
            }

            let qp = q.eval(uv_q16(uv));
            let err = max_abs_diff(f64s_q16(qp.position), exact[0]);
            worst.q16_position = worst.q16_position.max((err - LSB / 2.0) / (LSB * delta));
            assert!(
                err <= Q16_POSITION * LSB * delta + LSB / 2.0,
                "Q16 position at {uv:?}: {:.2} LSB, Δ = {delta}",
                err / LSB
            );
            for (d, (got, g)) in [qp.du, qp.dv].into_iter().zip(g).enumerate() {
                let err = max_abs_diff(f64s_q16(got), exact[1 + d]);
                worst.q16_partial = worst.q16_partial.max((err - LSB / 2.0) / (LSB * g * delta));
                assert!(
                    err <= Q16_PARTIAL * LSB * g * delta + LSB / 2.0,
                    "Q16 ∂{d} at {uv:?}: {:.2} LSB, Δ = {delta}",
                    err / LSB
                );
            }

            // Normals, with a bound from the conditioning of the cross product.
            let (su, sv) = (exact[1].map(|x| x / g[0]), exact[2].map(|x| x / g[1]));
            let n = cross(su, sv);
            let sin = norm(n) / (norm(su) * norm(sv));
            let conditioning = (delta / norm(su) + delta / norm(sv) + 1.0) / sin;
            if sin < 1e-3 || !conditioning.is_finite() {
                continue;
            }
            normals_checked += 1;
            let fn_ = f.normal(uv_f32(uv)).expect("f32 normal");
            let a = angle(f64s_f32(fn_), n);
            worst.f32_normal = worst.f32_normal.max(a / (F32_EPS * conditioning));
            if conditioning < 10.0 {
                worst.f32_normal_angle = worst.f32_normal_angle.max(a);
            }
            assert!(
                a <= F32_NORMAL * F32_EPS * conditioning,
                "f32 normal at {uv:?}: {a:e} rad"
            );
            assert!((norm(f64s_f32(fn_)) - 1.0).abs() < 4.0 * F32_EPS);
            let bound = Q16_NORMAL * LSB * conditioning;
            if bound < 0.5 {
                let qn = q.normal(uv_q16(uv)).expect("Q16 normal");
                let a = angle(f64s_q16(qn), n);
                worst.q16_normal = worst.q16_normal.max(a / (LSB * conditioning));
                if conditioning < 10.0 {
                    worst.q16_normal_angle = worst.q16_normal_angle.max(a);
                }
                assert!(
                    a <= bound,
                    "Q16 normal at {uv:?}: {a:e} rad, bound {bound:e}"
                );
                assert!((norm(f64s_q16(qn)) - 1.0).abs() < 4.0 * LSB);
            }
        }
    }
    println!("{normals_checked} normals; worst error / bound: {worst:?}");
    assert!(normals_checked > 5000);
}

#[test]
fn a_constant_net_is_reproduced_exactly() {
    let mut rng = Rng::new(21);
    for case in 0..30 {
        let c = rng.points(1, 1000.0, false)[0];
        let counts = [4 + rng.below(5), 4 + rng.below(5)];
        let reference = RefSurface::new(
            [case % 2 == 0, case % 3 == 0],
            counts,
            vec![c; counts[0] * counts[1]],
        );
        for storage in [ScalarKind::F32, ScalarKind::Q16_16] {
            let blob = surface_blob(storage, &reference);
            let (f, q) = (load_f32(&blob), load_q16(&blob));
            let (cf, cq) = (
                f.control_point(0, 0).unwrap(),
                q.control_point(0, 0).unwrap(),
            );
            for _ in 0..20 {
                let uv = [rng.parameter(), rng.parameter()];
                let fp = f.eval(uv_f32(uv));
                assert_eq!(
                    fp,
                    SurfacePoint {
                        position: cf,
                        du: [0.0; 3],
                        dv: [0.0; 3]
                    }
                );
                assert_eq!(f.position(uv_f32(uv)), cf);
                assert_eq!(f.normal(uv_f32(uv)), None);
                let qp = q.eval(uv_q16(uv));
                let zero = [Q16::ZERO; 3];
                assert_eq!(
                    qp,
                    SurfacePoint {
                        position: cq,
                        du: zero,
                        dv: zero
                    }
                );
                assert_eq!(q.normal(uv_q16(uv)), None);
            }
        }
    }
}

/// A net in the plane z = 0 has the normal ±(0, 0, 1) exactly, in both scalars (the partials'
/// z components are exactly zero).
#[test]
fn a_planar_net_has_an_exact_normal() {
    let mut rng = Rng::new(22);
    for case in 0..30 {
        let counts = [4 + rng.below(6), 4 + rng.below(6)];
        let mut points = Vec::new();
        for v in 0..counts[1] {
            for u in 0..counts[0] {
                // A jittered grid, so the partials are far from parallel.
                points.push([
                    u as f64 + rng.grid(-0.2, 0.2),
                    v as f64 + rng.grid(-0.2, 0.2),
                    0.0,
                ]);
            }
        }
        let reference = RefSurface::new([false, case % 2 == 0], counts, points);
        let blob = surface_blob(ScalarKind::Q16_16, &reference);
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        for _ in 0..50 {
            let uv = [rng.parameter(), rng.parameter()];
            let exact = reference.eval(uv[0], uv[1]);
            let sign = cross(exact[1], exact[2])[2].signum();
            assert_eq!(f.normal(uv_f32(uv)), Some([0.0, 0.0, sign as f32]));
            assert_eq!(
                q.normal(uv_q16(uv)),
                Some([Q16::ZERO, Q16::ZERO, q16(sign)])
            );
        }
    }
}

/// Position and partials are continuous across patch joints: one LSB either side of a joint
/// they differ by no more than the derivative allows plus twice the evaluation error.
#[test]
fn joints_are_continuous() {
    let mut rng = Rng::new(23);
    for _ in 0..20 {
        let reference = random_surface(&mut rng, 1.0);
        let blob = surface_blob(ScalarKind::Q16_16, &reference);
        let q = load_q16(&blob);
        let [gu, gv] = reference.segments();
        let delta = 2.0;
        // Bounds of the first and second derivatives over the net (coordinates in [−1, 1]).
        let (d1, d2) = (
            delta * gu.max(gv) as f64,
            4.0 * delta * (gu.max(gv) as f64).powi(2),
        );
        let g = gu.max(gv) as f64;
        let position = 2.0 * LSB * d1 + 2.0 * (Q16_POSITION * delta + 0.5) * LSB;
        let partial = 2.0 * LSB * d2 + 2.0 * (Q16_PARTIAL * g * delta + 0.5) * LSB;
        for k in 1..gu {
            let joint = curve_support::to_grid(k as f64 / gu as f64);
            let v = rng.parameter();
            let (a, b) = (
                q.eval(uv_q16([joint - LSB, v])),
                q.eval(uv_q16([joint + LSB, v])),
            );
            assert!(max_abs_diff(f64s_q16(a.position), f64s_q16(b.position)) <= position);
            assert!(max_abs_diff(f64s_q16(a.du), f64s_q16(b.du)) <= partial);
            assert!(max_abs_diff(f64s_q16(a.dv), f64s_q16(b.dv)) <= partial);
        }
        for k in 1..gv {
            let joint = curve_support::to_grid(k as f64 / gv as f64);
            let u = rng.parameter();
            let (a, b) = (
                q.eval(uv_q16([u, joint - LSB])),
                q.eval(uv_q16([u, joint + LSB])),
            );
            assert!(max_abs_diff(f64s_q16(a.position), f64s_q16(b.position)) <= position);
            assert!(max_abs_diff(f64s_q16(a.du), f64s_q16(b.du)) <= partial);
            assert!(max_abs_diff(f64s_q16(a.dv), f64s_q16(b.dv)) <= partial);
        }
    }
}

/// A closed direction has no seam: parameter 0 and 1 give the same point and partials.
#[test]
fn closed_directions_have_no_seam() {
    let mut rng = Rng::new(24);
    for _ in 0..30 {
        let counts = [4 + rng.below(8), 4 + rng.below(8)];
        let reference = RefSurface::random(&mut rng, [true, true], counts, 1.0);
        let blob = surface_blob(ScalarKind::F32, &reference);
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        let delta = 2.0;
        for _ in 0..10 {
            let w = rng.parameter();
            for (a, b) in [([0.0, w], [1.0, w]), ([w, 0.0], [w, 1.0])] {
                let (fa, fb) = (f.eval(uv_f32(a)), f.eval(uv_f32(b)));
                let tolerance = 2.0 * F32_POSITION * F32_EPS * 2.0 * delta;
                assert!(max_abs_diff(f64s_f32(fa.position), f64s_f32(fb.position)) <= tolerance);
                let (qa, qb) = (q.eval(uv_q16(a)), q.eval(uv_q16(b)));
                let tolerance = 2.0 * (Q16_POSITION * delta + 0.5) * LSB;
                assert!(max_abs_diff(f64s_q16(qa.position), f64s_q16(qb.position)) <= tolerance);
                let g = counts[0].max(counts[1]) as f64;
                let tolerance = 2.0 * (Q16_PARTIAL * g * delta + 0.5) * LSB;
                assert!(max_abs_diff(f64s_q16(qa.du), f64s_q16(qb.du)) <= tolerance);
                assert!(max_abs_diff(f64s_q16(qa.dv), f64s_q16(qb.dv)) <= tolerance);
            }
        }
    }
}

#[test]
fn parameters_outside_the_range_clamp_and_nan_is_zero() {
    let mut rng = Rng::new(25);
    let reference = random_surface(&mut rng, 1.0);
    let blob = surface_blob(ScalarKind::F32, &reference);
    let (f, q) = (load_f32(&blob), load_q16(&blob));
    let w = rng.parameter() as f32;
    for (input, clamped) in [
        ([f32::NAN, w], [0.0, w]),
        ([w, f32::NAN], [w, 0.0]),
        ([f32::NAN; 2], [0.0; 2]),
        ([-1.0, f32::INFINITY], [0.0, 1.0]),
        ([f32::NEG_INFINITY, f32::MAX], [0.0, 1.0]),
        ([2.0, -0.0], [1.0, 0.0]),
    ] {
        let got = f.eval(input);
        assert_eq!(got, f.eval(clamped), "{input:?}");
        assert!(
            got.position
                .iter()
                .chain(&got.du)
                .chain(&got.dv)
                .all(|c| c.is_finite())
        );
        assert_eq!(f.normal(input), f.normal(clamped));
    }
    for (input, clamped) in [
        ([Q16::MIN, Q16::MAX], [Q16::ZERO, Q16::ONE]),
        (
            [Q16::from_num(-3), Q16::from_bits(65537)],
            [Q16::ZERO, Q16::ONE],
        ),
    ] {
        assert_eq!(q.eval(input), q.eval(clamped));
        assert_eq!(q.normal(input), q.normal(clamped));
    }
}

#[test]
fn batches_equal_single_points_bit_for_bit() {
    let mut rng = Rng::new(26);
    for case in 0..10 {
        let reference = random_surface(&mut rng, if case % 2 == 0 { 1.0 } else { 200.0 });
        let blob = surface_blob(ScalarKind::Q16_16, &reference);
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        for len in [0, 1, LANES - 1, LANES, LANES + 1, 2 * LANES + 3] {
            let mut uv: Vec<[f32; 2]> = (0..len)
                .map(|_| [rng.unit() as f32 * 1.2 - 0.1, rng.unit() as f32 * 1.2 - 0.1])
                .collect();
            if len > 1 {
                uv[0] = [f32::NAN, 0.5];
            }
            let mut points = vec![SurfacePoint::default(); len];
            let mut positions = vec![[0.0_f32; 3]; len];
            let mut normals = vec![None; len];
            f.eval_batch(&uv, &mut points).unwrap();
            f.position_batch(&uv, &mut positions).unwrap();
            f.normal_batch(&uv, &mut normals).unwrap();
            let bits = |v: [f32; 3]| v.map(f32::to_bits);
            for i in 0..len {
                let single = f.eval(uv[i]);
                assert_eq!(bits(points[i].position), bits(single.position));
                assert_eq!(bits(points[i].du), bits(single.du));
                assert_eq!(bits(points[i].dv), bits(single.dv));
                assert_eq!(bits(positions[i]), bits(f.position(uv[i])));
                assert_eq!(bits(positions[i]), bits(single.position));
                assert_eq!(normals[i].map(bits), f.normal(uv[i]).map(bits));
            }
            let uvq: Vec<[Q16; 2]> = uv.iter().map(|p| p.map(Q16::from_f32_saturating)).collect();
            let mut points = vec![SurfacePoint::default(); len];
            let mut positions = vec![[Q16::ZERO; 3]; len];
            let mut normals = vec![None; len];
            q.eval_batch(&uvq, &mut points).unwrap();
            q.position_batch(&uvq, &mut positions).unwrap();
            q.normal_batch(&uvq, &mut normals).unwrap();
            for i in 0..len {
                assert_eq!(points[i], q.eval(uvq[i]));
                assert_eq!(positions[i], q.position(uvq[i]));
                assert_eq!(normals[i], q.normal(uvq[i]));
            }
        }
        let e = q
            .normal_batch(&[[Q16::ZERO; 2]; 2], &mut [None; 3])
            .unwrap_err();
        assert_eq!((e.inputs, e.outputs), (2, 3));
        assert!(
            q.eval_batch(&[[Q16::ZERO; 2]; 3], &mut [SurfacePoint::default(); 2])
                .is_err()
        );
        assert!(q.position_batch(&[[Q16::ZERO; 2]; 1], &mut []).is_err());
    }
}

#[test]
fn accessors_and_the_empty_surface() {
    let mut rng = Rng::new(27);
    let reference = RefSurface::random(&mut rng, [true, false], [5, 6], 1.0);
    for storage in [ScalarKind::F32, ScalarKind::Q16_16] {
        let blob = surface_blob(storage, &reference);
        let (f, q) = (load_f32(&blob), load_q16(&blob));
        assert_eq!(f.counts(), [5, 6]);
        assert_eq!(f.is_closed(), [true, false]);
        assert_eq!(f.segments(), [5, 3]);
        assert_eq!((f.stored_as(), q.stored_as()), (storage, storage));
        assert_eq!(
            f.control_point(2, 3),
            Some(reference.point(2, 3).map(|x| x as f32))
        );
        assert_eq!(q.control_point(4, 5), Some(reference.point(4, 5).map(q16)));
        assert_eq!(q.control_point(5, 0), None);
        assert_eq!(q.control_point(0, 6), None);
        assert_eq!(q.control_point(0, usize::MAX), None);
        assert_eq!(q.control_point(usize::MAX, 1), None);
        assert_eq!(
            (f.mac_count(false), f.mac_count(true), f.normal_mac_count()),
            (82, 212, 185)
        );
    }
    let empty = BSplineSurface::<Q16>::new();
    assert_eq!(empty.eval([Q16::ONE; 2]), SurfacePoint::default());
    assert_eq!(empty.normal([Q16::ONE; 2]), None);
    assert_eq!((empty.counts(), empty.segments()), ([0, 0], [0, 0]));
    let empty = BSplineSurface::<f32, 16>::default();
    assert_eq!(empty.position([f32::NAN, 0.5]), [0.0; 3]);
}

//! Golden outputs of the B-spline evaluators: a fixed Q16.16 curve and surface and their
//! outputs at fixed parameters, committed under `core/tests/golden/curve_*` and compared BIT
//! FOR BIT in Q16.16 (integer-exact arithmetic: any difference is a behaviour change of the
//! basis, the segment location, the accumulation or the loader), within 1 ulp in `f32`.
//!
//! Files:
//! - `curve_q16.nsb`: an open 3-D curve, 12 seeded control points in [−2, 2]³ on the Q16.16
//!   grid, stored as Q16.16;
//! - `curve_q16_params.bin`: the parameters t, one i32 (Q16.16 bits) each;
//! - `curve_q16_expected.bin`: C(t) and dC/dt per parameter, 6 × i32 (Q16.16 bits);
//! - `curve_f32_expected.bin`: the same blob in `f32` at the same parameters, 6 × f32;
//! - `curve_q16_degree2.nsb`, `curve_q16_degree5.nsb`: the same control points as a
//!   quadratic and a quintic curve, and `curve_q16_degree{2,5}_expected.bin` their outputs
//!   at the same parameters (6 × i32), from the any-degree recurrence;
//! - `curve_surface_q16.nsb`: a 6 × 5 net closed in u, open in v, coordinates in [−2, 2];
//! - `curve_surface_q16_params.bin`: [u, v] per point, 2 × i32;
//! - `curve_surface_q16_expected.bin`: S, ∂S/∂u, ∂S/∂v and the unit normal per point,
//!   12 × i32 (a missing normal is three `i32::MIN`);
//! - `curve_surface_f32_expected.bin`: the same in `f32` (a missing normal is three NaN).
//!
//! To regenerate after an INTENDED change, run
//!
//! ```text
//! NEUROSURF_BLESS=1 cargo test -p neurosurf-core --test curve_golden
//! ```
//!
//! review the diff, and commit the files. Without `NEUROSURF_BLESS=1` nothing is written.

mod curve_support;
mod golden_support;

use curve_support::{
    CurveDraws, LSB, RefCurve, RefSurface, Rng, angle, curve_blob, curve_blob_of_degree,
    encode_points, surface_blob,
};
use golden_support::{assert_bits, assert_ulps, f32_words, golden_dir, q16_words, read, to_bytes};
use neurosurf_core::curve::{BSplineCurve, BSplineSurface};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

const SEED: u64 = 0x00B5_1998;

fn golden_curve() -> RefCurve {
    RefCurve::new(false, Rng::new(SEED).points(12, 2.0, false))
}

fn golden_surface() -> RefSurface {
    RefSurface::random(&mut Rng::new(SEED ^ 1), [true, false], [6, 5], 2.0)
}

/// Random grid parameters, every joint and its neighbours, the ends, and values outside.
fn curve_parameters() -> Vec<Q16> {
    let mut rng = Rng::new(SEED ^ 2);
    let mut t: Vec<Q16> = (0..40).map(|_| Q16::from_num(rng.parameter())).collect();
    for k in 0..=9 {
        let joint = Q16::from_num(curve_support::to_grid(k as f64 / 9.0));
        t.extend([joint, joint - Q16::DELTA, joint + Q16::DELTA]);
    }
    t.extend([Q16::ZERO, Q16::ONE, Q16::DELTA, Q16::ONE - Q16::DELTA]);
    t.extend([Q16::MIN, Q16::MAX, -Q16::ONE, Q16::from_num(2)]);
    t
}

fn surface_parameters() -> Vec<[Q16; 2]> {
    let mut rng = Rng::new(SEED ^ 3);
    let mut uv: Vec<[Q16; 2]> = (0..48)
        .map(|_| {
            [
                Q16::from_num(rng.parameter()),
                Q16::from_num(rng.parameter()),
            ]
        })
        .collect();
    for corner in [[0, 0], [0, 1], [1, 0], [1, 1]] {
        uv.push(corner.map(Q16::from_num));
    }
    uv.extend([
        [Q16::from_num(1.0 / 6.0), Q16::from_num(0.5)],
        [Q16::from_num(0.5), Q16::from_num(1.0 / 3.0)],
        [Q16::MIN, Q16::MAX],
        [Q16::from_num(-3), Q16::from_num(0.25)],
    ]);
    uv
}

/// C and dC/dt, 6 words per parameter.
fn evaluate_curve<S: Scalar>(blob: &[u8], t: &[S]) -> Vec<S> {
    let curve = BSplineCurve::<S>::from_blob(blob).unwrap();
    t.iter()
        .flat_map(|&t| {
            let p = curve.eval(t);
            p.position.into_iter().chain(p.tangent)
        })
        .collect()
}

/// S, ∂S/∂u, ∂S/∂v, normal (or `none` three times), 12 words per point.
fn evaluate_surface<S: Scalar>(blob: &[u8], uv: &[[S; 2]], none: S) -> Vec<S> {
    let surface = BSplineSurface::<S>::from_blob(blob).unwrap();
    uv.iter()
        .flat_map(|&uv| {
            let p = surface.eval(uv);
            let n = surface.normal(uv).unwrap_or([none; 3]);
            p.position.into_iter().chain(p.du).chain(p.dv).chain(n)
        })
        .collect()
}

fn bless() {
    let dir = golden_dir();
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes).unwrap();

    let blob = curve_blob(ScalarKind::Q16_16, 3, false, &golden_curve().points);
    let t = curve_parameters();
    write("curve_q16.nsb", &blob);
    write(
        "curve_q16_params.bin",
        &to_bytes(t.iter().map(|t| t.to_le_bytes())),
    );
    let q = evaluate_curve(&blob, &t);
    write(
        "curve_q16_expected.bin",
        &to_bytes(q.iter().map(|v| v.to_le_bytes())),
    );
    let f = evaluate_curve(
        &blob,
        &t.iter().map(|t| t.to_num::<f32>()).collect::<Vec<_>>(),
    );
    write(
        "curve_f32_expected.bin",
        &to_bytes(f.iter().map(|v| v.to_le_bytes())),
    );

    for degree in OTHER_DEGREES {
        let blob = degree_blob(degree);
        write(&format!("curve_q16_degree{degree}.nsb"), &blob);
        let q = evaluate_curve(&blob, &t);
        write(
            &format!("curve_q16_degree{degree}_expected.bin"),
            &to_bytes(q.iter().map(|v| v.to_le_bytes())),
        );
    }

    let blob = surface_blob(ScalarKind::Q16_16, &golden_surface());
    let uv = surface_parameters();
    write("curve_surface_q16.nsb", &blob);
    write(
        "curve_surface_q16_params.bin",
        &to_bytes(uv.iter().flatten().map(|x| x.to_le_bytes())),
    );
    let q = evaluate_surface(&blob, &uv, Q16::MIN);
    write(
        "curve_surface_q16_expected.bin",
        &to_bytes(q.iter().map(|v| v.to_le_bytes())),
    );
    let uv32: Vec<[f32; 2]> = uv.iter().map(|p| p.map(|x| x.to_num())).collect();
    let f = evaluate_surface(&blob, &uv32, f32::NAN);
    write(
        "curve_surface_f32_expected.bin",
        &to_bytes(f.iter().map(|v| v.to_le_bytes())),
    );
    println!(
        "blessed {} curve and {} surface golden points in {}",
        t.len(),
        uv.len(),
        dir.display()
    );
}

/// The degrees with golden files of their own besides the cubic.
const OTHER_DEGREES: [u8; 2] = [2, 5];

/// The golden curve's control points as an open 3-D curve of `degree`, stored as Q16.16.
fn degree_blob(degree: u8) -> Vec<u8> {
    let control = encode_points(&golden_curve().points, ScalarKind::Q16_16);
    curve_blob_of_degree(ScalarKind::Q16_16, 3, false, degree, &control)
}

/// The quadratic and quintic curves give their committed outputs bit for bit, and their
/// committed blobs are what the generator writes today.
#[test]
fn q16_curves_of_other_degrees_match_bit_for_bit() {
    bless_if_asked();
    let (_, t) = curve_golden();
    for degree in OTHER_DEGREES {
        let blob = read(&format!("curve_q16_degree{degree}.nsb"));
        assert_eq!(blob, degree_blob(degree));
        let expected = q16_words(&read(&format!("curve_q16_degree{degree}_expected.bin")));
        assert_bits(
            &format!("degree {degree} curve"),
            6,
            &evaluate_curve(&blob, &t),
            &expected,
        );
    }
}

fn curve_golden() -> (Vec<u8>, Vec<Q16>) {
    (
        read("curve_q16.nsb"),
        q16_words(&read("curve_q16_params.bin")),
    )
}

fn surface_golden() -> (Vec<u8>, Vec<[Q16; 2]>) {
    let params = q16_words(&read("curve_surface_q16_params.bin"));
    (
        read("curve_surface_q16.nsb"),
        params.chunks_exact(2).map(|c| [c[0], c[1]]).collect(),
    )
}

fn bless_if_asked() {
    golden_support::bless_if_asked(bless);
}

#[test]
fn q16_curve_matches_bit_for_bit() {
    bless_if_asked();
    let (blob, t) = curve_golden();
    let expected = q16_words(&read("curve_q16_expected.bin"));
    assert_bits("curve", 6, &evaluate_curve(&blob, &t), &expected);
}

#[test]
fn q16_surface_matches_bit_for_bit() {
    bless_if_asked();
    let (blob, uv) = surface_golden();
    let expected = q16_words(&read("curve_surface_q16_expected.bin"));
    assert_bits(
        "surface",
        12,
        &evaluate_surface(&blob, &uv, Q16::MIN),
        &expected,
    );
}

#[test]
fn f32_outputs_match_within_one_ulp() {
    bless_if_asked();
    let (blob, t) = curve_golden();
    let t: Vec<f32> = t.iter().map(|t| t.to_num()).collect();
    assert_ulps(
        "curve",
        &evaluate_curve(&blob, &t),
        &f32_words(&read("curve_f32_expected.bin")),
    );
    let (blob, uv) = surface_golden();
    let uv: Vec<[f32; 2]> = uv.iter().map(|p| p.map(|x| x.to_num())).collect();
    assert_ulps(
        "surface",
        &evaluate_surface(&blob, &uv, f32::NAN),
        &f32_words(&read("curve_surface_f32_expected.bin")),
    );
}

/// The committed blobs and parameters are what the generators produce today.
#[test]
fn golden_inputs_are_reproducible() {
    bless_if_asked();
    let (blob, t) = curve_golden();
    assert_eq!(
        blob,
        curve_blob(ScalarKind::Q16_16, 3, false, &golden_curve().points)
    );
    assert_eq!(t, curve_parameters());
    let (blob, uv) = surface_golden();
    assert_eq!(blob, surface_blob(ScalarKind::Q16_16, &golden_surface()));
    assert_eq!(uv, surface_parameters());
}

/// The golden outputs are right, not merely stable: they agree with the f64 reference within
/// the tolerances of `curve.rs` and `curve_surface.rs` (Δ ≤ 4 here).
#[test]
fn golden_outputs_agree_with_the_reference() {
    bless_if_asked();
    let (_, t) = curve_golden();
    let reference = golden_curve();
    let expected = q16_words(&read("curve_q16_expected.bin"));
    for (i, t) in t.iter().enumerate() {
        let exact = reference.eval(t.to_num::<f64>());
        for k in 0..6 {
            let got = expected[6 * i + k].to_num::<f64>();
            let tolerance = if k < 3 {
                3.0 * 4.0 + 0.5
            } else {
                4.5 * 4.0 + 0.5
            } * LSB;
            assert!(
                (got - exact[k / 3][k % 3]).abs() <= tolerance,
                "curve point {i} word {k}"
            );
        }
    }
    let (_, uv) = surface_golden();
    let reference = golden_surface();
    let g = reference.segments();
    let expected = q16_words(&read("curve_surface_q16_expected.bin"));
    let mut normals = 0;
    for (i, [u, v]) in uv.iter().enumerate() {
        let exact = reference.eval(u.to_num(), v.to_num());
        for k in 0..9 {
            let got = expected[12 * i + k].to_num::<f64>();
            let tolerance = match k / 3 {
                0 => 6.0 * 4.0 + 0.5,
                d => 5.0 * g[d - 1] as f64 * 4.0 + 0.5,
            } * LSB;
            assert!(
                (got - exact[k / 3][k % 3]).abs() <= tolerance,
                "surface point {i} word {k}"
            );
        }
        let n: [f64; 3] = std::array::from_fn(|k| expected[12 * i + 9 + k].to_num());
        if n[0] != f64::from(i16::MIN) {
            let exact_normal = curve_support::cross(exact[1], exact[2]);
            assert!(angle(n, exact_normal) < 1e-3, "surface normal {i}");
            normals += 1;
        }
    }
    assert!(normals >= 50);
}

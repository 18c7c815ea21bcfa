//! Golden outputs: a fixed Q16.16 model and its Φ, ∇Φ at fixed query points, committed under
//! `core/tests/golden/` and compared BIT FOR BIT (Q16.16 arithmetic is integer-exact, so any
//! difference is a behaviour change of the evaluator, the activation table or the loader).
//!
//! Files:
//! - `implicit_q16.nsb`: the model blob (tree ((0,1),2), width 9, seeded weights in
//!   [−0.5, 0.5] on the Q16.16 grid, stored as Q16.16);
//! - `implicit_q16_points.bin`: the query points, 3 × i32 little endian (Q16.16 bits) each;
//! - `implicit_q16_expected.bin`: Φ, ∂Φ/∂x, ∂Φ/∂y, ∂Φ/∂z per point, 4 × i32 little endian
//!   (Q16.16 bits);
//! - `implicit_f32_expected.bin`: the same blob evaluated in `f32` at the same points (rounded
//!   to `f32`), 4 × f32 little endian; compared within 1 ulp.
//!
//! To regenerate after an INTENDED change, run
//!
//! ```text
//! NEUROSURF_BLESS=1 cargo test -p neurosurf-core --test golden
//! ```
//!
//! review the diff of the outputs, and commit the files. Without `NEUROSURF_BLESS=1` the test
//! never writes anything and fails on the first differing bit.

mod common;

use std::path::PathBuf;
use std::sync::Once;

use common::{LEFT_COMB, Reference, Rng, model_blob, random_parameters};
use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

const WIDTH: usize = 9;
const SEED: u64 = 0x00C0_FFEE_2004;
const RANDOM_POINTS: usize = 48;

fn golden_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("golden")
}

fn blessing() -> bool {
    std::env::var_os("NEUROSURF_BLESS").is_some_and(|v| v == "1")
}

/// The golden model's parameters (deterministic).
fn golden_parameters() -> Vec<f64> {
    random_parameters(&mut Rng::new(SEED), LEFT_COMB, WIDTH, 0.5)
}

fn golden_blob() -> Vec<u8> {
    model_blob(ScalarKind::Q16_16, WIDTH, LEFT_COMB, &golden_parameters())
}

/// The query points: random points of the box, its corners and center, points far outside,
/// the ends of the Q16.16 range and single-LSB coordinates.
fn golden_points() -> Vec<[Q16; 3]> {
    let mut rng = Rng::new(SEED ^ 0xFFFF);
    let mut points: Vec<[Q16; 3]> = (0..RANDOM_POINTS)
        .map(|_| common::q16_point(rng.point()))
        .collect();
    for corner in 0..8 {
        points.push(std::array::from_fn(|k| {
            if corner >> k & 1 == 1 {
                Q16::ONE
            } else {
                -Q16::ONE
            }
        }));
    }
    points.push([Q16::ZERO; 3]);
    points.push([Q16::from_bits(1), Q16::from_bits(-1), Q16::ZERO]);
    points.push([Q16::from_num(7.5), Q16::from_num(-3), Q16::from_num(0.5)]);
    points.push([Q16::from_num(-100), Q16::from_num(250), Q16::from_num(1000)]);
    points.push([Q16::MAX, Q16::MIN, Q16::ZERO]);
    points.push([Q16::MIN, Q16::MIN, Q16::MIN]);
    points.push([Q16::MAX, Q16::MAX, Q16::MAX]);
    points.push([Q16::from_num(0.125), Q16::MAX, Q16::from_num(-0.25)]);
    points
}

fn words_to_bytes(words: impl IntoIterator<Item = [u8; 4]>) -> Vec<u8> {
    words.into_iter().flatten().collect()
}

fn bytes_to_i32(bytes: &[u8]) -> Vec<i32> {
    assert_eq!(bytes.len() % 4, 0, "not a whole number of 4-byte words");
    bytes
        .chunks_exact(4)
        .map(|c| i32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

fn encode_points(points: &[[Q16; 3]]) -> Vec<u8> {
    words_to_bytes(points.iter().flatten().map(|q| q.to_bits().to_le_bytes()))
}

fn decode_points(bytes: &[u8]) -> Vec<[Q16; 3]> {
    bytes_to_i32(bytes)
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]].map(Q16::from_bits))
        .collect()
}

/// Φ and ∇Φ of the Q16.16 model, as Q16.16 bits, 4 per point.
fn evaluate_q16(blob: &[u8], points: &[[Q16; 3]]) -> Vec<i32> {
    let model: ImplicitModel<Q16> = ImplicitModel::from_blob(blob).unwrap();
    points
        .iter()
        .flat_map(|&p| {
            let fg = model.field_gradient(p);
            [fg.value, fg.gradient[0], fg.gradient[1], fg.gradient[2]].map(Q16::to_bits)
        })
        .collect()
}

/// Φ and ∇Φ of the same blob loaded in `f32`, at the points rounded to `f32`.
fn evaluate_f32(blob: &[u8], points: &[[Q16; 3]]) -> Vec<f32> {
    let model: ImplicitModel<f32> = ImplicitModel::from_blob(blob).unwrap();
    points
        .iter()
        .flat_map(|&p| {
            let fg = model.field_gradient(p.map(Q16::to_num::<f32>));
            [fg.value, fg.gradient[0], fg.gradient[1], fg.gradient[2]]
        })
        .collect()
}

fn read(name: &str) -> Vec<u8> {
    let path = golden_dir().join(name);
    std::fs::read(&path).unwrap_or_else(|e| {
        panic!(
            "cannot read golden file {}: {e} (generate it with NEUROSURF_BLESS=1)",
            path.display()
        )
    })
}

/// Writes the golden files when blessing (once per test process, before any test reads them);
/// a no-op otherwise.
fn bless_if_asked() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if blessing() {
            bless();
        }
    });
}

fn bless() {
    let blob = golden_blob();
    let points = golden_points();
    let dir = golden_dir();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("implicit_q16.nsb"), &blob).unwrap();
    std::fs::write(dir.join("implicit_q16_points.bin"), encode_points(&points)).unwrap();
    let q16 = evaluate_q16(&blob, &points);
    std::fs::write(
        dir.join("implicit_q16_expected.bin"),
        words_to_bytes(q16.iter().map(|v| v.to_le_bytes())),
    )
    .unwrap();
    let f32s = evaluate_f32(&blob, &points);
    std::fs::write(
        dir.join("implicit_f32_expected.bin"),
        words_to_bytes(f32s.iter().map(|v| v.to_le_bytes())),
    )
    .unwrap();
    println!(
        "blessed {} golden points in {}",
        points.len(),
        dir.display()
    );
}

const NAMES: [&str; 4] = ["Φ", "∂Φ/∂x", "∂Φ/∂y", "∂Φ/∂z"];

#[test]
fn q16_outputs_match_bit_for_bit() {
    bless_if_asked();
    let blob = read("implicit_q16.nsb");
    let points = decode_points(&read("implicit_q16_points.bin"));
    let expected = bytes_to_i32(&read("implicit_q16_expected.bin"));
    assert!(!points.is_empty());
    assert_eq!(
        expected.len(),
        4 * points.len(),
        "expected file does not match the points"
    );
    let actual = evaluate_q16(&blob, &points);
    let differing: Vec<usize> = (0..expected.len())
        .filter(|&i| actual[i] != expected[i])
        .collect();
    if let Some(&first) = differing.first() {
        let (point, output) = (first / 4, first % 4);
        panic!(
            "{} of {} golden Q16.16 words differ; first: {} at point {point} {:?}: got {:#010x} \
             ({}), expected {:#010x} ({}). Bless with NEUROSURF_BLESS=1 only if the change is \
             intended.",
            differing.len(),
            expected.len(),
            NAMES[output],
            points[point],
            actual[first],
            Q16::from_bits(actual[first]),
            expected[first],
            Q16::from_bits(expected[first]),
        );
    }
}

#[test]
fn f32_outputs_match_within_one_ulp() {
    bless_if_asked();
    let blob = read("implicit_q16.nsb");
    let points = decode_points(&read("implicit_q16_points.bin"));
    let expected: Vec<f32> = bytes_to_i32(&read("implicit_f32_expected.bin"))
        .into_iter()
        .map(|b| f32::from_bits(b as u32))
        .collect();
    assert_eq!(expected.len(), 4 * points.len());
    let actual = evaluate_f32(&blob, &points);
    for (i, (&a, &e)) in actual.iter().zip(&expected).enumerate() {
        // Distance in units in the last place, over the ordered integer line of f32 (so that
        // +0 and −0 are 0 apart and 1 ulp spans a sign change at 0 consistently).
        let ordered = |x: f32| {
            let b = x.to_bits() as i32;
            if b < 0 { i32::MIN - b } else { b }
        };
        assert!(a.is_finite() && e.is_finite());
        let ulps = (i64::from(ordered(a)) - i64::from(ordered(e))).abs();
        assert!(
            ulps <= 1,
            "{} at point {} {:?}: got {a:e}, expected {e:e} ({ulps} ulp apart)",
            NAMES[i % 4],
            i / 4,
            points[i / 4]
        );
    }
}

/// The committed blob is what the generator and `blob::write` produce today, byte for byte
/// (a failure here means the encoder or the test-model generator changed, not the evaluator).
#[test]
fn golden_blob_is_reproducible() {
    bless_if_asked();
    assert_eq!(read("implicit_q16.nsb"), golden_blob());
    assert_eq!(
        decode_points(&read("implicit_q16_points.bin")),
        golden_points()
    );
}

/// The golden outputs are right, not merely stable: they agree with the f64 reference at the
/// points inside the box (within the width-9 tolerances of `eval.rs`).
#[test]
fn golden_outputs_agree_with_the_reference() {
    bless_if_asked();
    let reference = Reference::new(WIDTH, LEFT_COMB, &golden_parameters());
    let points = decode_points(&read("implicit_q16_points.bin"));
    let expected = bytes_to_i32(&read("implicit_q16_expected.bin"));
    let expected_f32 = bytes_to_i32(&read("implicit_f32_expected.bin"));
    let mut checked = 0;
    for (i, p) in points.iter().enumerate() {
        let x = p.map(Q16::to_f64);
        if x.iter().any(|c| c.abs() > 1.0) {
            continue;
        }
        checked += 1;
        let (value, gradient) = reference.eval(x);
        let exact = [value, gradient[0], gradient[1], gradient[2]];
        for k in 0..4 {
            let q = Q16::from_bits(expected[4 * i + k]).to_f64();
            let f = f64::from(f32::from_bits(expected_f32[4 * i + k] as u32));
            let tolerance = if k == 0 { 13.0 } else { 32.0 } * common::LSB;
            assert!(
                (q - exact[k]).abs() <= tolerance,
                "Q16 {} at {x:?}",
                NAMES[k]
            );
            assert!((f - exact[k]).abs() <= 1.0e-5, "f32 {} at {x:?}", NAMES[k]);
        }
    }
    assert!(checked >= RANDOM_POINTS);
}

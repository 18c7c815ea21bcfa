//! Golden-file helpers shared by the evaluators' golden tests: where the files live, blessing
//! on request (`NEUROSURF_BLESS=1`), word (de)serialization, and the two comparisons — Q16.16
//! bit for bit, `f32` within one ulp.
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::Once;

use neurosurf_core::scalar::Q16;

pub fn golden_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("golden")
}

pub fn blessing() -> bool {
    std::env::var_os("NEUROSURF_BLESS").is_some_and(|v| v == "1")
}

pub fn to_bytes(words: impl IntoIterator<Item = [u8; 4]>) -> Vec<u8> {
    words.into_iter().flatten().collect()
}

pub fn words(bytes: &[u8]) -> Vec<[u8; 4]> {
    assert_eq!(bytes.len() % 4, 0, "not a whole number of words");
    bytes
        .chunks_exact(4)
        .map(|c| c.try_into().unwrap())
        .collect()
}

pub fn q16_words(bytes: &[u8]) -> Vec<Q16> {
    words(bytes)
        .into_iter()
        .map(|w| Q16::from_bits(i32::from_le_bytes(w)))
        .collect()
}

pub fn f32_words(bytes: &[u8]) -> Vec<f32> {
    words(bytes).into_iter().map(f32::from_le_bytes).collect()
}

pub fn read(name: &str) -> Vec<u8> {
    let path = golden_dir().join(name);
    std::fs::read(&path).unwrap_or_else(|e| {
        panic!(
            "cannot read golden file {}: {e} (generate it with NEUROSURF_BLESS=1)",
            path.display()
        )
    })
}

/// Runs `bless` once per test binary when `NEUROSURF_BLESS=1`.
pub fn bless_if_asked(bless: fn()) {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        if blessing() {
            bless();
        }
    });
}

/// Compares bit for bit and names the first difference.
pub fn assert_bits(what: &str, per_point: usize, actual: &[Q16], expected: &[Q16]) {
    assert_eq!(
        actual.len(),
        expected.len(),
        "{what}: expected file does not match the parameters"
    );
    let differing: Vec<usize> = (0..expected.len())
        .filter(|&i| actual[i] != expected[i])
        .collect();
    if let Some(&first) = differing.first() {
        panic!(
            "{what}: {} of {} golden Q16.16 words differ; first: word {} of point {}: got {:#010x} \
             ({}), expected {:#010x} ({}). Bless with NEUROSURF_BLESS=1 only if the change is \
             intended.",
            differing.len(),
            expected.len(),
            first % per_point,
            first / per_point,
            actual[first].to_bits(),
            actual[first],
            expected[first].to_bits(),
            expected[first],
        );
    }
}

/// Distance in ulps over the ordered integer line of f32; NaN only matches NaN.
pub fn assert_ulps(what: &str, actual: &[f32], expected: &[f32]) {
    assert_eq!(actual.len(), expected.len());
    let ordered = |x: f32| {
        let b = x.to_bits() as i32;
        if b < 0 { i32::MIN - b } else { b }
    };
    for (i, (&a, &e)) in actual.iter().zip(expected).enumerate() {
        if e.is_nan() || a.is_nan() {
            assert!(
                a.is_nan() && e.is_nan(),
                "{what} word {i}: got {a}, expected {e}"
            );
            continue;
        }
        let ulps = (i64::from(ordered(a)) - i64::from(ordered(e))).abs();
        assert!(
            ulps <= 1,
            "{what} word {i}: got {a:e}, expected {e:e} ({ulps} ulp apart)"
        );
    }
}

//! One fuzz harness for every model kind: [`run`] takes any bytes, loads them as whatever
//! model kind their header names, in `f32` and in Q16.16 (through [`neurosurf_core::model`],
//! so a new kind is fuzzed once it is registered there), and evaluates every loaded model at
//! special and input-derived points, value and derivative. The core has no `unsafe`, so a
//! panic (an arithmetic overflow in debug builds, an index out of bounds) is the failure.
//!
//! The bytes are tried twice: as they are (the framing and CRC checks), and with the header's
//! payload length and the CRC repaired, so that mutations reach the payload decoders and the
//! model validation instead of stopping at the CRC.
//!
//! [`readers::read`] does the same for the trainer's file readers.
//!
//! `fuzz/libfuzzer/` drives them coverage-guided (see its README); the workspace test
//! `fuzz/tests/corpus.rs` runs it over the committed corpus `fuzz/corpus/` and seeded
//! mutations of it.

#[cfg(feature = "readers")]
pub mod readers;

use neurosurf_core::blob::{self, HEADER_LEN, TRAILER_LEN};
use neurosurf_core::model::{self, MAX_INPUTS, MAX_OUTPUTS, Model, ModelVisitor};
use neurosurf_core::scalar::{Scalar, ScalarKind};

/// The files of a corpus folder of this crate (`corpus`, `corpus-readers`), by name.
///
/// # Panics
/// When the folder or a file cannot be read.
pub fn corpus(folder: &str) -> Vec<(String, Vec<u8>)> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(folder);
    let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    let mut files: Vec<(String, Vec<u8>)> = entries
        .map(|entry| {
            let path = entry.expect("a corpus entry").path();
            let name = path
                .file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            (name, bytes)
        })
        .collect();
    files.sort();
    files
}

/// What the harness did with one input.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub struct Verdict {
    /// The framing accepted the bytes as they are.
    pub framed: bool,
    /// Models loaded, over both tries and both scalars.
    pub loaded: u8,
}

/// Loads `data` as a blob of any kind (as it is, and repaired) and evaluates what loads.
pub fn run(data: &[u8]) -> Verdict {
    let mut verdict = Verdict {
        framed: blob::parse(data).is_ok(),
        loaded: exercise(data),
    };
    if let Some(repaired) = repaired(data) {
        verdict.loaded += exercise(&repaired);
    }
    verdict
}

/// `data` with the header's payload length and the CRC made consistent with its length, if it
/// is long enough to have both.
pub fn repaired(data: &[u8]) -> Option<Vec<u8>> {
    let payload_len = data.len().checked_sub(HEADER_LEN + TRAILER_LEN)?;
    let mut bytes = data.to_vec();
    bytes[8..12].copy_from_slice(&u32::try_from(payload_len).ok()?.to_le_bytes());
    let body = HEADER_LEN + payload_len;
    let crc = blob::crc32(&bytes[..body]);
    bytes[body..].copy_from_slice(&crc.to_le_bytes());
    Some(bytes)
}

/// Loads `data` in both scalars; returns how many loads succeeded.
fn exercise(data: &[u8]) -> u8 {
    let Ok((header, _)) = blob::parse(data) else {
        return 0;
    };
    let mut loaded = 0;
    for scalar in [ScalarKind::F32, ScalarKind::Q16_16] {
        let run = Exercise {
            data,
            inputs: inputs_from(data),
        };
        if model::visit(header.model, scalar, run) == Some(true) {
            loaded += 1;
        }
    }
    loaded
}

/// Special inputs beside the ones the data's own bytes spell.
const SPECIAL: [f32; 12] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    0.5,
    1.0e-30,
    1024.0,
    -32768.0,
    3.0e38,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NAN,
];

/// Up to 4 input points made of the last bytes of `data`, read as `f32`.
fn inputs_from(data: &[u8]) -> Vec<[f32; MAX_INPUTS]> {
    data.rchunks_exact(4 * MAX_INPUTS)
        .take(4)
        .map(|chunk| {
            let mut point = [0.0; MAX_INPUTS];
            for (v, b) in point.iter_mut().zip(chunk.chunks_exact(4)) {
                *v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            }
            point
        })
        .collect()
}

/// Loads and evaluates one model type; `true` when it loaded.
struct Exercise<'a> {
    data: &'a [u8],
    inputs: Vec<[f32; MAX_INPUTS]>,
}

impl ModelVisitor for Exercise<'_> {
    type Output = bool;

    fn visit<S: Scalar, M: Model<S>>(self) -> bool {
        let mut model = Box::<M>::default();
        if model.load_blob(self.data).is_err() {
            return false;
        }
        assert!(model.input_len() <= MAX_INPUTS, "{:?} inputs", M::KIND);
        for full in [false, true] {
            assert!(
                model.output_len(full) <= MAX_OUTPUTS,
                "{:?} outputs",
                M::KIND
            );
        }
        let special = SPECIAL.iter().map(|&v| [v; MAX_INPUTS]);
        let mixed = SPECIAL
            .iter()
            .map(|&v| core::array::from_fn(|k| if k % 2 == 0 { v } else { 0.25 }));
        let inputs: Vec<[S; MAX_INPUTS]> = special
            .chain(mixed)
            .chain(self.inputs)
            .map(|point| point.map(S::from_f32_saturating))
            .collect();
        for full in [false, true] {
            let mut single = vec![[S::ZERO; MAX_OUTPUTS]; inputs.len()];
            for (input, out) in inputs.iter().zip(&mut single) {
                model.evaluate(input, full, out);
            }
            // A short output buffer takes what fits.
            if let Some(input) = inputs.first() {
                model.evaluate(input, full, &mut [S::ZERO; 1]);
            }
            // The batch path gives the single path's bits, and a short `out` what fits.
            let mut batch = vec![[S::ZERO; MAX_OUTPUTS]; inputs.len()];
            model.evaluate_batch(&inputs, full, &mut batch);
            let n = model.output_len(full);
            for (i, (b, s)) in batch.iter().zip(&single).enumerate() {
                // Equal words, any NaN equal to any NaN (payloads are not results).
                let same = b[..n].iter().zip(&s[..n]).all(|(x, y)| {
                    let (x, y) = (x.to_f32(), y.to_f32());
                    x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan())
                });
                assert!(
                    same,
                    "{:?}: batch and single differ at point {i} (full: {full})",
                    M::KIND
                );
            }
            model.evaluate_batch(&inputs, full, &mut batch[..inputs.len() / 2]);
        }
        true
    }
}

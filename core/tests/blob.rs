//! The blob container and the implicit model loader, through the public API only: a round
//! trip, one crafted input for every [`BlobError`] variant, and a seeded fuzz run (random byte
//! strings, mutations, truncations and extensions of valid blobs, structurally random payloads)
//! that must never panic and must keep the loaders mutually consistent.

mod common;

use common::{
    BALANCED_4, LEFT_COMB, PAIR, Reference, Rng, SINGLE_LEAF, TREES, encode_parameters, f32_point,
    fix_crc, frame, implicit_blob, model_blob, q16_point, random_parameters,
};
use neurosurf_core::Quantity;
use neurosurf_core::blob::{
    self, BlobError, FORMAT_VERSION, HEADER_LEN, MAGIC, ModelKind, TRAILER_LEN,
};
use neurosurf_core::implicit::{
    DEFAULT_MODULES, DEFAULT_PARAMETERS, FieldGradient, ImplicitModel, ImplicitPayload, MAX_HEIGHT,
    MAX_WIDTH, ModuleKind, ModuleLayout, NORMALIZATION_LEN,
};
use neurosurf_core::scalar::{ACTIVATION_AMPLITUDE, Q16, Scalar, ScalarKind};

/// Postcard's encoding of an `ImplicitPayload`, by hand: the width byte, the identity frame
/// (a byte string of 12 zero bytes, then the shift byte 0), then three byte strings, each a
/// LEB128 varint length and the bytes.
fn postcard_payload(width: u8, tree: &[u8], parameters: &[u8], metadata: &[u8]) -> Vec<u8> {
    fn varint(out: &mut Vec<u8>, mut n: usize) {
        loop {
            let byte = (n & 0x7F) as u8;
            n >>= 7;
            if n == 0 {
                out.push(byte);
                return;
            }
            out.push(byte | 0x80);
        }
    }
    let mut out = vec![width, 12];
    out.extend_from_slice(&[0; 12]);
    out.push(0);
    for bytes in [tree, parameters, metadata] {
        varint(&mut out, bytes.len());
        out.extend_from_slice(bytes);
    }
    out
}

/// A valid implicit blob and its parts.
struct Sample {
    width: usize,
    tree: &'static [u8],
    params: Vec<f64>,
}

impl Sample {
    fn new(seed: u64, width: usize, tree: &'static [u8]) -> Self {
        let mut rng = Rng::new(seed);
        let params = random_parameters(&mut rng, tree, width, 0.5);
        Sample {
            width,
            tree,
            params,
        }
    }

    fn blob(&self, kind: ScalarKind) -> Vec<u8> {
        model_blob(kind, self.width, self.tree, &self.params)
    }

    fn stored(&self, kind: ScalarKind) -> Vec<u8> {
        encode_parameters(&self.params, kind)
    }
}

// ---------------------------------------------------------------------------------------------
// Round trip

#[test]
fn round_trip_in_both_storage_kinds_and_both_scalars() {
    for (i, tree) in TREES.iter().enumerate() {
        let sample = Sample::new(40 + i as u64, 9, tree);
        let reference = Reference::new(sample.width, tree, &sample.params);
        let mut models_f32 = Vec::new();
        let mut models_q16 = Vec::new();
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let stored = sample.stored(kind);
            let metadata = b"trained by the test";
            let blob = implicit_blob(kind, 9, tree, &stored, metadata);

            // Framing: header fields, payload bytes, length, CRC.
            let expected_payload = postcard_payload(9, tree, &stored, metadata);
            assert_eq!(
                blob.len(),
                HEADER_LEN + expected_payload.len() + TRAILER_LEN
            );
            assert_eq!(blob[..4], MAGIC);
            let (header, payload) = blob::parse(&blob).unwrap();
            assert_eq!(header.version, FORMAT_VERSION);
            assert_eq!(header.model, ModelKind::Implicit);
            assert_eq!(header.scalar, kind);
            assert_eq!(payload, &expected_payload[..]);
            // The hand-made framing agrees with blob::write byte for byte.
            assert_eq!(
                frame(FORMAT_VERSION, 1, kind.code(), &expected_payload),
                blob
            );
            let crc = u32::from_le_bytes(blob[blob.len() - 4..].try_into().unwrap());
            assert_eq!(crc, blob::crc32(&blob[..blob.len() - 4]));

            // The payload decodes to what was written.
            let (header2, decoded) = ImplicitPayload::from_blob(&blob).unwrap();
            assert_eq!(header2, header);
            assert_eq!(
                decoded,
                ImplicitPayload {
                    width: 9,
                    frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
                    tree,
                    parameters: &stored,
                    metadata,
                }
            );

            // Both scalars load it, with the right structure.
            let f: ImplicitModel<f32> = ImplicitModel::from_blob(&blob).unwrap();
            let q: ImplicitModel<Q16> = ImplicitModel::from_blob(&blob).unwrap();
            for (width, modules, leaves, params, stored_as, root) in [
                (
                    f.width(),
                    f.module_count(),
                    f.leaf_count(),
                    f.parameter_count(),
                    f.stored_as(),
                    f.root(),
                ),
                (
                    q.width(),
                    q.module_count(),
                    q.leaf_count(),
                    q.parameter_count(),
                    q.stored_as(),
                    q.root(),
                ),
            ] {
                assert_eq!(width, 9);
                assert_eq!(modules, tree.len());
                assert_eq!(leaves, tree.iter().filter(|&&c| c == 0).count());
                assert_eq!(params, sample.params.len());
                assert_eq!(stored_as, kind);
                assert_eq!(root, tree.len() - 1);
            }
            for (m, &code) in tree.iter().enumerate() {
                assert_eq!(f.module_kind(m), ModuleKind::from_code(code));
                assert_eq!(q.module_kind(m), ModuleKind::from_code(code));
                assert_eq!(f.children(m), q.children(m));
            }
            assert_eq!(f.module_kind(tree.len()), None);
            assert_eq!(f.children(tree.len()), None);
            let expected_macs: usize = tree
                .iter()
                .map(|&c| ModuleLayout::new(common::kind(c), 9).mac_count(true))
                .sum();
            assert_eq!(f.mac_count(true), expected_macs);
            assert_eq!(q.mac_count(true), expected_macs);

            // The decoded parameters are the written ones: the field matches the reference.
            let mut rng = Rng::new(1);
            for _ in 0..10 {
                let p = rng.point();
                let (value, _) = reference.eval(p);
                assert!((f64::from(f.field(f32_point(p))) - value).abs() < 1e-5);
                assert!((q.field(q16_point(p)).to_f64() - value).abs() < 1e-3);
            }
            models_f32.push(f);
            models_q16.push(q);
        }
        // Grid parameters are exact in both storage kinds: loading either gives bit-identical
        // evaluations, in either scalar.
        let mut rng = Rng::new(2);
        for _ in 0..20 {
            let p = rng.point();
            assert_eq!(
                format!("{:?}", models_f32[0].field_gradient(f32_point(p))),
                format!("{:?}", models_f32[1].field_gradient(f32_point(p)))
            );
            assert_eq!(
                models_q16[0].field_gradient(q16_point(p)),
                models_q16[1].field_gradient(q16_point(p))
            );
        }
    }
}

#[test]
fn metadata_is_opaque() {
    let sample = Sample::new(3, 4, PAIR);
    let stored = sample.stored(ScalarKind::Q16_16);
    let plain = implicit_blob(ScalarKind::Q16_16, 4, PAIR, &stored, &[]);
    let big_metadata = vec![0xA5_u8; 1000];
    let annotated = implicit_blob(ScalarKind::Q16_16, 4, PAIR, &stored, &big_metadata);
    assert_ne!(plain, annotated);
    let a: ImplicitModel<Q16> = ImplicitModel::from_blob(&plain).unwrap();
    let b: ImplicitModel<Q16> = ImplicitModel::from_blob(&annotated).unwrap();
    let p = [Q16::from_num(0.25), Q16::from_num(-0.5), Q16::ZERO];
    assert_eq!(a.field_gradient(p), b.field_gradient(p));
}

/// `load` replaces a model in place (how firmware fills a `static`), and a rejected blob
/// leaves it empty rather than half-loaded.
#[test]
fn load_in_place_replaces_the_model_and_a_failure_leaves_it_empty() {
    let first = Sample::new(3, 4, PAIR);
    let second = Sample::new(5, 2, SINGLE_LEAF);
    let mut model = ImplicitModel::<Q16>::new();
    let p = [Q16::from_num(0.25), Q16::from_num(-0.5), Q16::ZERO];
    assert_eq!(model.module_count(), 0);
    assert_eq!(model.field(p), Q16::ZERO);
    model.load(&first.blob(ScalarKind::Q16_16)).unwrap();
    let direct = ImplicitModel::<Q16>::from_blob(&first.blob(ScalarKind::Q16_16)).unwrap();
    assert_eq!(model.field_gradient(p), direct.field_gradient(p));
    model.load(&second.blob(ScalarKind::F32)).unwrap();
    let direct = ImplicitModel::<Q16>::from_blob(&second.blob(ScalarKind::F32)).unwrap();
    assert_eq!((model.module_count(), model.width()), (1, 2));
    assert_eq!(model.field_gradient(p), direct.field_gradient(p));
    let mut broken = first.blob(ScalarKind::Q16_16);
    let last = broken.len() - 1;
    broken[last] ^= 1;
    assert!(model.load(&broken).is_err());
    assert_eq!((model.module_count(), model.parameter_count()), (0, 0));
    assert_eq!(model.field(p), Q16::ZERO);
}

/// A 16-high tree (the most the evaluator's recursion allows) loads and evaluates correctly.
#[test]
fn tallest_tree_loads_and_evaluates() {
    let tree = comb(MAX_HEIGHT);
    let tree: &'static [u8] = Box::leak(tree.into_boxed_slice());
    let sample = Sample::new(8, 2, tree);
    let reference = Reference::new(2, tree, &sample.params);
    let f: ImplicitModel<f32> = ImplicitModel::from_blob(&sample.blob(ScalarKind::F32)).unwrap();
    let q: ImplicitModel<Q16> = ImplicitModel::from_blob(&sample.blob(ScalarKind::Q16_16)).unwrap();
    let mut rng = Rng::new(4);
    for _ in 0..10 {
        let p = rng.point();
        let (value, gradient) = reference.eval(p);
        let fg = f.field_gradient(f32_point(p));
        assert!((f64::from(fg.value) - value).abs() < 1e-5);
        for k in 0..3 {
            assert!((f64::from(fg.gradient[k]) - gradient[k]).abs() < 1e-5);
        }
        assert!((q.field(q16_point(p)).to_f64() - value).abs() < 1e-3);
    }
}

/// Post-order codes of a left comb with `height` levels: (((0,1),2),…).
fn comb(height: usize) -> Vec<u8> {
    let mut tree = vec![0];
    for _ in 1..height {
        tree.extend_from_slice(&[0, 1]);
    }
    tree
}

// ---------------------------------------------------------------------------------------------
// Every BlobError variant

fn load_f32(bytes: &[u8]) -> Result<ImplicitModel<f32>, BlobError> {
    ImplicitModel::from_blob(bytes)
}

fn load_q16(bytes: &[u8]) -> Result<ImplicitModel<Q16>, BlobError> {
    ImplicitModel::from_blob(bytes)
}

/// Both scalars reject `bytes` with the same error, which `check` accepts.
fn rejected(bytes: &[u8], check: impl Fn(&BlobError) -> bool) -> BlobError {
    let e = load_f32(bytes).unwrap_err();
    assert_eq!(load_q16(bytes).unwrap_err(), e);
    assert!(check(&e), "unexpected error {e:?}");
    assert!(!format!("{e}").is_empty());
    e
}

#[test]
fn truncated() {
    let blob = Sample::new(1, 3, PAIR).blob(ScalarKind::F32);
    for len in 0..blob.len() {
        let needed = match len {
            0..4 => 4,
            4..12 => HEADER_LEN,
            _ => blob.len(),
        };
        let e = blob::parse(&blob[..len]).unwrap_err();
        assert!(
            matches!(e, BlobError::Truncated { needed: n, available } if n == needed && available == len),
            "prefix {len}: {e:?}"
        );
        rejected(&blob[..len], |e| matches!(e, BlobError::Truncated { .. }));
    }
    // A declared payload length near u32::MAX does not overflow.
    let mut huge = blob.clone();
    huge[8..12].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(
        blob::parse(&huge),
        Err(BlobError::Truncated { available, .. }) if available == blob.len()
    ));
}

#[test]
fn bad_magic() {
    let mut blob = Sample::new(1, 3, PAIR).blob(ScalarKind::F32);
    blob[3] = b'G';
    rejected(
        &blob,
        |e| matches!(e, BlobError::BadMagic { found } if found == b"NSRG"),
    );
    // Checked before anything else, even the length.
    rejected(
        b"not a blob",
        |e| matches!(e, BlobError::BadMagic { found } if found == b"not "),
    );
}

#[test]
fn unsupported_version() {
    // Version 4: curves and surfaces carry their degree; version 3 is still read.
    assert_eq!(FORMAT_VERSION, 4);
    assert_eq!(neurosurf_core::blob::OLDEST_READABLE_VERSION, 3);
    let blob = Sample::new(1, 3, PAIR).blob(ScalarKind::F32);
    for version in [0_u16, 1, 2, 5, u16::MAX] {
        let mut bad = blob.clone();
        bad[4..6].copy_from_slice(&version.to_le_bytes());
        // Checked before the CRC: with or without a consistent checksum.
        let unsupported = |e: &BlobError| {
            matches!(e, BlobError::UnsupportedVersion { found, supported }
                if *found == version && *supported == FORMAT_VERSION)
        };
        rejected(&bad, unsupported);
        fix_crc(&mut bad);
        rejected(&bad, unsupported);
    }
}

/// The parameter count of `tree` at `width` in format version 1, whose nodes had no
/// normalization and an a′ layer of 2N inputs.
fn version_1_parameter_count(tree: &[u8], width: usize) -> usize {
    let node = (2 * width + 1) * width + (width + 1) * width + width + 1;
    tree.iter()
        .map(|&c| match common::kind(c) {
            ModuleKind::Leaf => ModuleLayout::new(ModuleKind::Leaf, width).len,
            ModuleKind::Node => node,
        })
        .sum()
}

/// A blob of format version 1 — framed by hand as that version's writer did, with its node
/// layout — gets the named version error, from the core and from the simulated target's
/// core alike (see the simulator tests); the same parameters framed as the current version do
/// not match the tree.
#[test]
fn version_1_blobs_are_rejected_by_their_version() {
    let width = 3;
    let old = version_1_parameter_count(PAIR, width);
    let new = common::parameter_count(PAIR, width);
    assert_eq!(new - old, NORMALIZATION_LEN + 3 * width);
    let stored = encode_parameters(&vec![0.25; old], ScalarKind::F32);
    let payload = postcard_payload(3, PAIR, &stored, b"");
    let version_1 = frame(
        1,
        ModelKind::Implicit.code(),
        ScalarKind::F32.code(),
        &payload,
    );
    for bytes in [
        &version_1[..],
        &frame(1, 1, ScalarKind::Q16_16.code(), &payload)[..],
    ] {
        let e = rejected(bytes, |e| {
            *e == BlobError::UnsupportedVersion {
                found: 1,
                supported: FORMAT_VERSION,
            }
        });
        assert_eq!(
            e.to_string(),
            "blob format version 1 is not supported (this core reads versions 3..=4)"
        );
        assert_eq!(ImplicitPayload::from_blob(bytes).unwrap_err(), e);
    }
    let current = frame(FORMAT_VERSION, 1, ScalarKind::F32.code(), &payload);
    rejected(&current, |e| {
        *e == BlobError::ShapeMismatch {
            what: Quantity::Parameters,
            expected: new,
            found: old,
        }
    });
}

#[test]
fn trailing_bytes() {
    let blob = Sample::new(1, 3, PAIR).blob(ScalarKind::Q16_16);
    for extra in [1_usize, 3, 4, 100] {
        let mut long = blob.clone();
        long.extend(std::iter::repeat_n(0_u8, extra));
        rejected(
            &long,
            |e| matches!(e, BlobError::TrailingBytes { count } if *count == extra),
        );
    }
}

#[test]
fn crc_mismatch() {
    let blob = Sample::new(1, 3, PAIR).blob(ScalarKind::Q16_16);
    let stored_crc = u32::from_le_bytes(blob[blob.len() - 4..].try_into().unwrap());
    // Every single-bit error outside magic, version and length is caught by the CRC (including
    // in the kind bytes: the CRC is checked before them, and in the CRC itself).
    for byte in (6..8).chain(HEADER_LEN..blob.len()) {
        for bit in 0..8 {
            let mut bad = blob.clone();
            bad[byte] ^= 1 << bit;
            let body = &bad[..bad.len() - 4];
            let stored = u32::from_le_bytes(bad[bad.len() - 4..].try_into().unwrap());
            let e = blob::parse(&bad).unwrap_err();
            assert_eq!(
                e,
                BlobError::CrcMismatch {
                    stored,
                    computed: blob::crc32(body)
                },
                "bit {bit} of byte {byte}"
            );
            if byte < blob.len() - 4 {
                assert_eq!(stored, stored_crc);
            }
        }
    }
    let mut bad = blob.clone();
    bad[20] = bad[20].wrapping_add(1);
    rejected(&bad, |e| matches!(e, BlobError::CrcMismatch { .. }));
    // A bit error in the length field shows up as a length mismatch instead.
    for byte in 8..HEADER_LEN {
        for bit in 0..8 {
            let mut bad = blob.clone();
            bad[byte] ^= 1 << bit;
            assert!(matches!(
                blob::parse(&bad),
                Err(BlobError::Truncated { .. } | BlobError::TrailingBytes { .. })
            ));
        }
    }
}

#[test]
fn unknown_model_kind() {
    let blob = Sample::new(1, 3, PAIR).blob(ScalarKind::F32);
    for code in [0_u8, 7, 255] {
        let mut bad = blob.clone();
        bad[6] = code;
        // Without a matching CRC the corruption is reported as such.
        assert!(matches!(
            blob::parse(&bad),
            Err(BlobError::CrcMismatch { .. })
        ));
        fix_crc(&mut bad);
        assert_eq!(
            blob::parse(&bad).unwrap_err(),
            BlobError::UnknownModelKind { code }
        );
        rejected(&bad, |e| *e == BlobError::UnknownModelKind { code });
    }
}

#[test]
fn unknown_scalar_kind() {
    let blob = Sample::new(1, 3, PAIR).blob(ScalarKind::F32);
    for code in [0_u8, 4, 255] {
        let mut bad = blob.clone();
        bad[7] = code;
        fix_crc(&mut bad);
        assert_eq!(
            blob::parse(&bad).unwrap_err(),
            BlobError::UnknownScalarKind { code }
        );
        rejected(&bad, |e| *e == BlobError::UnknownScalarKind { code });
    }
}

#[test]
fn unsupported_storage() {
    // A well-framed implicit blob that claims f64 parameters: blob::parse accepts the framing,
    // the implicit loader refuses the storage kind.
    let sample = Sample::new(1, 3, PAIR);
    let stored = sample.stored(ScalarKind::F32);
    let payload = postcard_payload(3, PAIR, &stored, &[]);
    let blob = frame(FORMAT_VERSION, 1, ScalarKind::F64.code(), &payload);
    assert_eq!(blob::parse(&blob).unwrap().0.scalar, ScalarKind::F64);
    let expected = BlobError::UnsupportedStorage {
        model: ModelKind::Implicit,
        scalar: ScalarKind::F64,
    };
    rejected(&blob, |e| *e == expected);
    let (_, decoded) = ImplicitPayload::from_blob(&blob).unwrap();
    assert_eq!(
        ImplicitModel::<f32>::from_payload(&decoded, ScalarKind::F64).unwrap_err(),
        expected
    );
}

#[test]
fn wrong_model_kind() {
    let sample = Sample::new(1, 3, PAIR);
    let payload = postcard_payload(3, PAIR, &sample.stored(ScalarKind::F32), &[]);
    let blob = frame(FORMAT_VERSION, ModelKind::Rbf.code(), 1, &payload);
    assert_eq!(blob::parse(&blob).unwrap().0.model, ModelKind::Rbf);
    let expected = BlobError::WrongModelKind {
        expected: ModelKind::Implicit,
        found: ModelKind::Rbf,
    };
    rejected(&blob, |e| *e == expected);
    assert_eq!(ImplicitPayload::from_blob(&blob).unwrap_err(), expected);
}

#[test]
fn malformed_payload() {
    let sample = Sample::new(1, 3, PAIR);
    let good = postcard_payload(3, PAIR, &sample.stored(ScalarKind::F32), b"meta");
    let mut cases: Vec<Vec<u8>> = vec![
        // Empty.
        vec![],
        // Only the width.
        vec![3],
        // Ends inside the parameters.
        good[..good.len() - 10].to_vec(),
        // One byte too many: the payload must be consumed exactly.
        [&good[..], &[0]].concat(),
        // A tree length beyond the payload.
        vec![3, 100, 0, 0],
        // A varint longer than any usize / u32 length.
        vec![
            3, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x01,
        ],
    ];
    // The parameter byte string ends before its declared length (payload cut short).
    let mut short = good.clone();
    short.truncate(6);
    cases.push(short);
    for payload in &cases {
        let blob = frame(FORMAT_VERSION, 1, 1, payload);
        assert!(blob::parse(&blob).is_ok());
        rejected(&blob, |e| *e == BlobError::MalformedPayload);
        assert_eq!(
            ImplicitPayload::from_blob(&blob).unwrap_err(),
            BlobError::MalformedPayload
        );
    }
    // blob::write reports a payload that fails to serialize the same way.
    struct Unserializable;
    impl serde::Serialize for Unserializable {
        fn serialize<S: serde::Serializer>(&self, _: S) -> Result<S::Ok, S::Error> {
            Err(serde::ser::Error::custom("refuses"))
        }
    }
    let mut out = [0_u8; 64];
    assert_eq!(
        blob::write(
            ModelKind::Implicit,
            ScalarKind::F32,
            &Unserializable,
            &mut out
        ),
        Err(BlobError::MalformedPayload)
    );
}

/// A blob with the given width byte, tree and number of stored f32 words (all 0.25).
fn shaped(width: u8, tree: &[u8], words: usize) -> Vec<u8> {
    let stored = encode_parameters(&vec![0.25; words], ScalarKind::F32);
    implicit_blob(ScalarKind::F32, width, tree, &stored, &[])
}

#[test]
fn shape_mismatch() {
    let needed = common::parameter_count(PAIR, 3);
    for width in [0_u8, 17, 255] {
        rejected(&shaped(width, PAIR, needed), |e| {
            *e == BlobError::ShapeMismatch {
                what: Quantity::Width,
                expected: MAX_WIDTH,
                found: usize::from(width),
            }
        });
    }
    rejected(&shaped(3, &[], needed), |e| {
        *e == BlobError::ShapeMismatch {
            what: Quantity::Modules,
            expected: 1,
            found: 0,
        }
    });
    for words in [0, needed - 1, needed + 1] {
        rejected(&shaped(3, PAIR, words), |e| {
            *e == BlobError::ShapeMismatch {
                what: Quantity::Parameters,
                expected: needed,
                found: words,
            }
        });
    }
    // A parameter byte string that is not a whole number of words.
    let mut stored = encode_parameters(&vec![0.25; needed], ScalarKind::F32);
    stored.pop();
    rejected(
        &implicit_blob(ScalarKind::F32, 3, PAIR, &stored, &[]),
        |e| {
            matches!(e, BlobError::ShapeMismatch { what: Quantity::Parameters, expected, .. }
                if *expected == needed)
        },
    );
    // The largest width loads.
    let max = u8::try_from(MAX_WIDTH).unwrap();
    assert!(load_f32(&shaped(max, PAIR, common::parameter_count(PAIR, MAX_WIDTH))).is_ok());
}

#[test]
fn capacity_exceeded() {
    // Modules: more than the default 64, and more than a small model type holds.
    let many = vec![0_u8; DEFAULT_MODULES + 1];
    rejected(&shaped(1, &many, 0), |e| {
        *e == BlobError::CapacityExceeded {
            what: Quantity::Modules,
            needed: DEFAULT_MODULES + 1,
            capacity: DEFAULT_MODULES,
        }
    });
    let pair = shaped(3, PAIR, common::parameter_count(PAIR, 3));
    assert_eq!(
        ImplicitModel::<f32, DEFAULT_PARAMETERS, 2>::from_blob(&pair).unwrap_err(),
        BlobError::CapacityExceeded {
            what: Quantity::Modules,
            needed: 3,
            capacity: 2,
        }
    );
    assert!(ImplicitModel::<f32, DEFAULT_PARAMETERS, 3>::from_blob(&pair).is_ok());

    // Parameters: a width-16 pair needs more than 1000.
    let needed = common::parameter_count(PAIR, 16);
    let wide = shaped(16, PAIR, needed);
    assert_eq!(
        ImplicitModel::<Q16, 1000, 4>::from_blob(&wide).unwrap_err(),
        BlobError::CapacityExceeded {
            what: Quantity::Parameters,
            needed,
            capacity: 1000,
        }
    );
    // Two leaves of 365 and a node of 877 (12 + 16·35 + 16 + 16·16 + 16 + 16 + 1).
    assert_eq!(needed, 1607);
    assert!(ImplicitModel::<Q16, 1607, 4>::from_blob(&wide).is_ok());
    // More parameters than the default capacity (a width-16 tree of 31 modules needs 18 995
    // words; the blob carries them all, so the count matches and the capacity check fires).
    let big_tree = [PAIR, PAIR, &[1], PAIR, PAIR, &[1], &[1]].concat();
    let big_tree = [&big_tree[..], &big_tree[..], &[1]].concat();
    let needed = common::parameter_count(&big_tree, 16);
    assert_eq!(needed, 18_995);
    assert!(needed > DEFAULT_PARAMETERS);
    rejected(&shaped(16, &big_tree, needed), |e| {
        *e == BlobError::CapacityExceeded {
            what: Quantity::Parameters,
            needed,
            capacity: DEFAULT_PARAMETERS,
        }
    });

    // Stack depth: a comb one level taller than MAX_HEIGHT.
    let tall = comb(MAX_HEIGHT + 1);
    rejected(&shaped(2, &tall, common::parameter_count(&tall, 2)), |e| {
        *e == BlobError::CapacityExceeded {
            what: Quantity::StackDepth,
            needed: MAX_HEIGHT + 1,
            capacity: MAX_HEIGHT,
        }
    });
}

#[test]
fn invalid_tree() {
    for (tree, module) in [
        (&[2_u8][..], 0),
        (&[1], 0),
        (&[0, 1], 1),
        (&[0, 0], 1),
        (&[0, 0, 0, 1], 3),
        (&[0, 0, 1, 1], 3),
        (&[0, 0, 7, 1], 2),
        (&[0, 0, 1, 255], 3),
    ] {
        // The tree is checked before the parameter count, so any count will do.
        rejected(&shaped(2, tree, 3), |e| {
            *e == BlobError::InvalidTree { module }
        });
    }
}

#[test]
fn non_finite_parameter() {
    let sample = Sample::new(1, 3, PAIR);
    for (index, value) in [(0, f32::NAN), (17, f32::INFINITY), (90, f32::NEG_INFINITY)] {
        let mut stored = sample.stored(ScalarKind::F32);
        stored[4 * index..4 * index + 4].copy_from_slice(&value.to_le_bytes());
        let blob = implicit_blob(ScalarKind::F32, 3, PAIR, &stored, &[]);
        rejected(&blob, |e| *e == BlobError::NonFiniteParameter { index });
    }
    // A NaN with a payload (not the canonical bit pattern) too.
    let mut stored = sample.stored(ScalarKind::F32);
    stored[..4].copy_from_slice(&0x7FC0_1234_u32.to_le_bytes());
    rejected(
        &implicit_blob(ScalarKind::F32, 3, PAIR, &stored, &[]),
        |e| *e == BlobError::NonFiniteParameter { index: 0 },
    );
}

#[test]
fn parameter_out_of_range() {
    // Only Q16.16 evaluation bounds parameters (|p| ≤ 1024, so accumulators cannot overflow);
    // f32 takes any finite value.
    let sample = Sample::new(1, 3, PAIR);
    let limit = f64::from(<Q16 as Scalar>::MAX_PARAMETER);
    for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
        for (index, value, ok) in [
            (5, limit, true),
            (5, -limit, true),
            // The next f32 above 1024 (also on the Q16.16 grid).
            (5, limit + 1.0 / 8192.0, false),
            (33, -limit - 1.0, false),
            (40, 30000.0, false),
        ] {
            let mut params = sample.params.clone();
            params[index] = value;
            let blob = model_blob(kind, 3, PAIR, &params);
            assert!(load_f32(&blob).is_ok(), "f32 takes {value}");
            match load_q16(&blob) {
                Ok(_) => assert!(ok, "{value} accepted"),
                Err(e) => {
                    assert!(!ok, "{value} rejected");
                    assert_eq!(e, BlobError::ParameterOutOfRange { index });
                }
            }
        }
    }
    // One Q16.16 LSB beyond the limit, stored as Q16.16.
    let mut params = sample.params.clone();
    params[7] = limit + 1.0 / 65536.0;
    let blob = model_blob(ScalarKind::Q16_16, 3, PAIR, &params);
    assert_eq!(
        load_q16(&blob).unwrap_err(),
        BlobError::ParameterOutOfRange { index: 7 }
    );
    // The extremes of either storage kind.
    let mut stored = sample.stored(ScalarKind::Q16_16);
    stored[..4].copy_from_slice(&i32::MIN.to_le_bytes());
    let blob = implicit_blob(ScalarKind::Q16_16, 3, PAIR, &stored, &[]);
    assert_eq!(
        load_q16(&blob).unwrap_err(),
        BlobError::ParameterOutOfRange { index: 0 }
    );
    assert!(load_f32(&blob).is_ok());
    let mut stored = sample.stored(ScalarKind::F32);
    stored[..4].copy_from_slice(&f32::MAX.to_le_bytes());
    let blob = implicit_blob(ScalarKind::F32, 3, PAIR, &stored, &[]);
    assert_eq!(
        load_q16(&blob).unwrap_err(),
        BlobError::ParameterOutOfRange { index: 0 }
    );
    assert!(load_f32(&blob).is_ok());
}

/// Every module stores its normalization c, A first (format version 2): a node's twelve words
/// are checked exactly as a leaf's — finite in `f32` storage, within ±`MAX_PARAMETER` for
/// Q16.16 — with the same errors naming the word's index in the whole parameter array; and
/// what is not checked for a leaf (a singular A) is not checked for a node either.
#[test]
fn node_normalization_is_validated_like_a_leafs() {
    let width = 3;
    let sample = Sample::new(1, width, PAIR);
    let offsets = common::offsets(PAIR, width);
    let limit = f64::from(<Q16 as Scalar>::MAX_PARAMETER);
    let mut outcomes: Vec<Vec<String>> = Vec::new();
    for (module, &code) in PAIR.iter().enumerate() {
        let layout = ModuleLayout::new(common::kind(code), width);
        assert_eq!(layout.trainable_start, NORMALIZATION_LEN);
        let mut module_outcomes = Vec::new();
        for word in 0..NORMALIZATION_LEN {
            let index = offsets[module] + word;
            for value in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                let mut stored = sample.stored(ScalarKind::F32);
                stored[4 * index..4 * index + 4].copy_from_slice(&value.to_le_bytes());
                let blob = implicit_blob(ScalarKind::F32, 3, PAIR, &stored, &[]);
                rejected(&blob, |e| *e == BlobError::NonFiniteParameter { index });
                module_outcomes.push(format!("{word} {value}: not finite"));
            }
            for (value, ok) in [
                (limit, true),
                (-limit, true),
                (limit + 1.0 / 8192.0, false),
                (-limit - 1.0, false),
            ] {
                let mut params = sample.params.clone();
                params[index] = value;
                for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
                    let blob = model_blob(kind, width, PAIR, &params);
                    assert!(load_f32(&blob).is_ok(), "f32 takes {value}");
                    let outcome = match load_q16(&blob) {
                        Ok(_) => {
                            assert!(ok, "module {module} word {word}: {value} accepted");
                            "ok".to_string()
                        }
                        Err(e) => {
                            assert!(!ok, "module {module} word {word}: {value} rejected");
                            assert_eq!(e, BlobError::ParameterOutOfRange { index });
                            "out of range".to_string()
                        }
                    };
                    module_outcomes.push(format!("{word} {value} {kind:?}: {outcome}"));
                }
            }
        }
        // A singular (here: zero) A is accepted and evaluates: the node then ignores its
        // position, a leaf its input.
        let mut params = sample.params.clone();
        for a in &mut params[offsets[module] + 3..offsets[module] + NORMALIZATION_LEN] {
            *a = 0.0;
        }
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let blob = model_blob(kind, width, PAIR, &params);
            let (f, q) = (load_f32(&blob).unwrap(), load_q16(&blob).unwrap());
            let fg = f.field_gradient([0.5, -0.25, 0.125]);
            assert!(fg.value.is_finite() && fg.gradient.iter().all(|g| g.is_finite()));
            let _ = q.field_gradient([Q16::from_num(0.5); 3]);
        }
        outcomes.push(module_outcomes);
    }
    // Leaf 0, leaf 1 and the node: the same outcome for the same word of the normalization.
    assert_eq!(outcomes[0], outcomes[1]);
    assert_eq!(outcomes[0], outcomes[2]);
}

#[test]
fn buffer_too_small() {
    let sample = Sample::new(1, 3, SINGLE_LEAF);
    let stored = sample.stored(ScalarKind::F32);
    let payload = ImplicitPayload {
        width: 3,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        tree: SINGLE_LEAF,
        parameters: &stored,
        metadata: b"m",
    };
    let mut big = vec![0_u8; 4096];
    let needed = blob::write(ModelKind::Implicit, ScalarKind::F32, &payload, &mut big).unwrap();
    for capacity in 0..needed {
        let mut out = vec![0_u8; capacity];
        assert_eq!(
            blob::write(ModelKind::Implicit, ScalarKind::F32, &payload, &mut out),
            Err(BlobError::BufferTooSmall { needed, capacity })
        );
    }
    let mut exact = vec![0_u8; needed];
    assert_eq!(
        blob::write(ModelKind::Implicit, ScalarKind::F32, &payload, &mut exact),
        Ok(needed)
    );
    assert_eq!(exact[..], big[..needed]);
}

// ---------------------------------------------------------------------------------------------
// Fuzzing

#[derive(Default, Debug)]
struct Stats {
    inputs: usize,
    framed: usize,
    accepted_f32: usize,
    accepted_q16: usize,
}

/// Feeds `bytes` to every decoder; checks that they agree with each other and that accepted
/// models evaluate.
fn feed(bytes: &[u8], stats: &mut Stats, rng: &mut Rng) {
    stats.inputs += 1;
    let parsed = blob::parse(bytes);
    let payload = ImplicitPayload::from_blob(bytes);
    let f = load_f32(bytes);
    let q = load_q16(bytes);
    let small = ImplicitModel::<Q16, 300, 4>::from_blob(bytes);
    match parsed {
        Err(e) => {
            // Framing errors are reported identically by every loader.
            assert_eq!(payload.as_ref().unwrap_err(), &e);
            assert_eq!(f.as_ref().unwrap_err(), &e);
            assert_eq!(q.as_ref().unwrap_err(), &e);
            assert_eq!(small.as_ref().unwrap_err(), &e);
        }
        Ok((header, _)) => {
            stats.framed += 1;
            if header.model != ModelKind::Implicit {
                assert!(matches!(payload, Err(BlobError::WrongModelKind { .. })));
            }
        }
    }
    if let Err(e) = &payload {
        assert_eq!(f.as_ref().unwrap_err(), e);
        assert_eq!(q.as_ref().unwrap_err(), e);
    }
    // Q16.16 is the stricter loader: whatever it accepts, f32 accepts with the same shape.
    if let Ok(q) = &q {
        let f = f.as_ref().expect("f32 accepts what Q16.16 accepts");
        assert_eq!(
            (
                q.width(),
                q.module_count(),
                q.parameter_count(),
                q.stored_as()
            ),
            (
                f.width(),
                f.module_count(),
                f.parameter_count(),
                f.stored_as()
            )
        );
    }
    // A smaller capacity only adds capacity errors.
    match (&q, &small) {
        (Ok(_), Err(e)) => assert!(matches!(e, BlobError::CapacityExceeded { .. }), "{e:?}"),
        (Err(a), Err(b)) if a != b => {
            assert!(
                matches!(b, BlobError::CapacityExceeded { .. }),
                "{a:?} vs {b:?}"
            );
        }
        (Err(_), Ok(_)) => panic!("a smaller model type accepted what the default refused"),
        _ => {}
    }
    if let Ok(f) = &f {
        stats.accepted_f32 += 1;
        let field_ok = |phi: f32| phi.is_nan() || f64::from(phi).abs() <= ACTIVATION_AMPLITUDE;
        exercise(f, rng.point().map(|x| x as f32 * 4.0), field_ok);
        exercise(f, [f32::MAX, f32::NEG_INFINITY, f32::NAN], field_ok);
    }
    if let Ok(q) = &q {
        stats.accepted_q16 += 1;
        exercise(q, q16_point(rng.point().map(|x| x * 4.0)), |phi: Q16| {
            phi.to_f64().abs() < ACTIVATION_AMPLITUDE
        });
        exercise(q, [Q16::MAX, Q16::MIN, Q16::ZERO], |phi: Q16| {
            phi.to_f64().abs() < ACTIVATION_AMPLITUDE
        });
    }
}

/// Evaluates every module of an accepted model at `p`, in single and batch form.
fn exercise<S: Scalar>(model: &ImplicitModel<S>, p: [S; 3], field_ok: impl Fn(S) -> bool) {
    let fg = model.field_gradient(p);
    assert!(field_ok(fg.value), "Φ = {:?}", fg.value);
    let _ = model.normal(p);
    let _ = fg.normal();
    let points = [p; 9];
    let mut out = [FieldGradient::default(); 9];
    model.field_gradient_batch(&points, &mut out).unwrap();
    assert_eq!(format!("{:?}", out[8]), format!("{fg:?}"));
    for i in 0..model.module_count() {
        let view = model.module(i).unwrap();
        assert!(field_ok(view.field(p)));
    }
}

/// Valid blobs of several shapes, in both storage kinds.
fn seeds() -> Vec<Vec<u8>> {
    let mut blobs = Vec::new();
    for (i, (tree, width)) in [
        (SINGLE_LEAF, 1),
        (SINGLE_LEAF, 3),
        (PAIR, 2),
        (LEFT_COMB, 2),
        (BALANCED_4, 1),
        (PAIR, 4),
    ]
    .into_iter()
    .enumerate()
    {
        let sample = Sample::new(100 + i as u64, width, tree);
        blobs.push(sample.blob(ScalarKind::F32));
        blobs.push(sample.blob(ScalarKind::Q16_16));
    }
    blobs
}

#[test]
fn fuzz_random_bytes() {
    let mut rng = Rng::new(0xF022);
    let mut stats = Stats::default();
    for i in 0..24_000 {
        let len = rng.below(if i % 10 == 0 { 2000 } else { 200 });
        let mut bytes: Vec<u8> = (0..len).map(|_| rng.byte()).collect();
        // Steer a share of the inputs past the first checks.
        match i % 4 {
            1 if len >= 4 => bytes[..4].copy_from_slice(&MAGIC),
            2 if len >= HEADER_LEN + TRAILER_LEN => {
                bytes[..4].copy_from_slice(&MAGIC);
                bytes[4..6].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
                let payload_len = u32::try_from(len - HEADER_LEN - TRAILER_LEN).unwrap();
                bytes[8..12].copy_from_slice(&payload_len.to_le_bytes());
            }
            3 => bytes = frame(FORMAT_VERSION, rng.byte() % 4, rng.byte() % 5, &bytes),
            _ => {}
        }
        feed(&bytes, &mut stats, &mut rng);
    }
    println!("random bytes: {stats:?}");
    assert!(stats.framed >= 1_500, "{stats:?}");
}

#[test]
fn fuzz_mutated_blobs() {
    let seeds = seeds();
    let mut rng = Rng::new(0xB10B);
    let mut stats = Stats::default();
    let mut detected = 0;
    for i in 0..24_000 {
        let original = &seeds[i % seeds.len()];
        let mut bytes = original.clone();
        let mutation = rng.below(6);
        match mutation {
            // Truncation: always Truncated.
            0 => {
                bytes.truncate(rng.below(original.len()));
                assert!(matches!(
                    blob::parse(&bytes),
                    Err(BlobError::Truncated { .. })
                ));
            }
            // Extension: always TrailingBytes.
            1 => {
                let extra = 1 + rng.below(40);
                bytes.extend((0..extra).map(|_| rng.byte()));
                assert_eq!(
                    blob::parse(&bytes).unwrap_err(),
                    BlobError::TrailingBytes { count: extra }
                );
            }
            // Byte changes the CRC must catch (or an earlier header check).
            2 | 3 => {
                let count = if mutation == 2 { 1 } else { 1 + rng.below(8) };
                for _ in 0..count {
                    let at = rng.below(bytes.len());
                    bytes[at] ^= 1 + rng.below(255) as u8;
                }
                assert!(blob::parse(&bytes).is_err(), "corruption not detected");
                detected += 1;
            }
            // The same with a recomputed CRC: the payload decoder and the model validation
            // see the corruption (and may accept it).
            4 => {
                for _ in 0..1 + rng.below(4) {
                    let at = rng.below(bytes.len() - 4);
                    // Favour the payload's structural bytes near its start.
                    let at = if rng.below(2) == 0 { at % 24 } else { at };
                    bytes[at] = rng.byte();
                }
                fix_crc(&mut bytes);
            }
            // Truncation or extension of the payload with header length and CRC fixed up.
            _ => {
                let payload = &original[HEADER_LEN..original.len() - TRAILER_LEN];
                let mut payload = payload.to_vec();
                if rng.below(2) == 0 {
                    payload.truncate(rng.below(payload.len()));
                } else {
                    payload.extend((0..1 + rng.below(9)).map(|_| rng.byte()));
                }
                bytes = frame(FORMAT_VERSION, original[6], original[7], &payload);
            }
        }
        feed(&bytes, &mut stats, &mut rng);
    }
    println!("mutations: {stats:?}, corruptions detected by framing: {detected}");
    assert!(stats.accepted_f32 >= 200, "{stats:?}");
    assert!(stats.accepted_q16 >= 100, "{stats:?}");
}

/// A random valid post-order tree with `leaves` leaves.
fn random_tree(rng: &mut Rng, leaves: usize) -> Vec<u8> {
    if leaves == 1 {
        return vec![0];
    }
    let left = 1 + rng.below(leaves - 1);
    let mut tree = random_tree(rng, left);
    tree.extend(random_tree(rng, leaves - left));
    tree.push(1);
    tree
}

/// Payloads built field by field with random widths, trees, parameter counts and values:
/// the model validation, not the framing, decides.
#[test]
fn fuzz_structured_payloads() {
    let mut rng = Rng::new(0x5EED);
    let mut stats = Stats::default();
    let special = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::MAX,
        1024.0,
        1024.001,
        -1024.0,
        0.0,
        -0.0,
        1.0e-40,
    ];
    for _ in 0..20_000 {
        let width = match rng.below(4) {
            0 => rng.byte(),
            _ => 1 + rng.below(4) as u8,
        };
        let tree: Vec<u8> = match rng.below(3) {
            0 => TREES[rng.below(TREES.len())].to_vec(),
            1 => {
                let leaves = 1 + rng.below(6);
                random_tree(&mut rng, leaves)
            }
            _ => (0..rng.below(12))
                .map(|_| match rng.below(20) {
                    0 => rng.byte(),
                    n if n < 10 => 0,
                    _ => 1,
                })
                .collect(),
        };
        let expected_words: usize = tree
            .iter()
            .map(|&c| match ModuleKind::from_code(c) {
                Some(kind) if (1..=16).contains(&width) => {
                    ModuleLayout::new(kind, usize::from(width)).len
                }
                _ => 3,
            })
            .sum();
        let words = match rng.below(5) {
            0 => rng.below(expected_words + 3),
            _ => expected_words,
        };
        let storage = if rng.below(2) == 0 {
            ScalarKind::F32
        } else {
            ScalarKind::Q16_16
        };
        let mut stored = Vec::with_capacity(4 * words);
        for _ in 0..words {
            let bytes = match (rng.below(50), storage) {
                (0, ScalarKind::F32) => special[rng.below(special.len())].to_le_bytes(),
                (0, _) => (rng.next_u64() as u32).to_le_bytes(),
                (_, kind) => kind.encode(rng.unit() * 4.0 - 2.0).unwrap(),
            };
            stored.extend_from_slice(&bytes);
        }
        if rng.below(20) == 0 {
            stored.push(rng.byte());
        }
        let payload = postcard_payload(width, &tree, &stored, &[]);
        let scalar = if rng.below(30) == 0 {
            ScalarKind::F64.code()
        } else {
            storage.code()
        };
        let blob = frame(FORMAT_VERSION, 1, scalar, &payload);
        feed(&blob, &mut stats, &mut rng);
    }
    println!("structured payloads: {stats:?}");
    assert!(stats.accepted_q16 >= 1_000, "{stats:?}");
}

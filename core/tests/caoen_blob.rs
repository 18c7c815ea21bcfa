//! Cao En blobs through the public API: round trips, one crafted input for every error the
//! loader reports (corrupt, truncated, NaN, out of range, bad shapes), in-place loading, and a
//! seeded mutation fuzz that must never panic.

mod caoen_support;

use caoen_support::{RefNet, Rng, fix_crc, random_network, raw_blob, unit_vector};
use neurosurf_core::Quantity;
use neurosurf_core::blob::{BlobError, ModelKind};
use neurosurf_core::caoen::{
    Blending, CaoEnModel, CaoEnPayload, DEFAULT_KEY_POINTS, Domain, MAX_KEY_POINTS,
};
use neurosurf_core::scalar::{Q16, ScalarKind};

type F = CaoEnModel<f32>;
type Q = CaoEnModel<Q16>;

/// Both loaders reject `bytes` with `expected`.
fn rejected(bytes: &[u8], expected: BlobError) {
    let e = F::from_blob(bytes).unwrap_err();
    assert_eq!(e, expected);
    assert_eq!(Q::from_blob(bytes).unwrap_err(), expected);
    assert!(!e.to_string().is_empty());
}

fn sample(rng: &mut Rng) -> RefNet {
    random_network(rng, 5, (3, 3), 0, false, 2.0)
}

fn words(values: &[f64], kind: ScalarKind) -> Vec<u8> {
    values
        .iter()
        .flat_map(|&v| kind.encode(v).unwrap())
        .collect()
}

#[test]
fn round_trip_in_both_storage_kinds() {
    let mut rng = Rng::new(30);
    for (domain, m) in [(0_u8, 3_usize), (0, 5), (1, 4)] {
        let mut net = random_network(&mut rng, 7, (m, 2), 1, true, 3.0);
        net.domain = domain;
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let blob = net.blob(kind);
            let (header, payload) = CaoEnPayload::from_blob(&blob).unwrap();
            assert_eq!((header.model, header.scalar), (ModelKind::CaoEn, kind));
            assert_eq!(payload.metadata, b"test cao en");
            let f = F::from_blob(&blob).unwrap();
            let q = Q::from_payload(&payload, kind).unwrap();
            assert_eq!(
                (f.key_count(), f.source_dimension(), f.target_dimension()),
                (7, m, 2)
            );
            assert_eq!(
                (q.domain(), q.blending(), q.is_normalized()),
                (
                    Domain::from_code(domain).unwrap(),
                    Blending::Exponential,
                    true
                )
            );
            assert_eq!(f.stored_as(), kind);
            for i in 0..7 {
                let w = f.weight(i).unwrap();
                assert_eq!(
                    w[..m].iter().map(|&c| f64::from(c)).collect::<Vec<_>>(),
                    net.weights[i]
                );
                assert_eq!(q.target(i).unwrap()[1].to_num::<f64>(), net.targets[i][1]);
                assert_eq!(f64::from(f.sharpness(i).unwrap()), net.sharpness[i]);
            }
            assert_eq!(f.weight(7), None);
            assert_eq!(f.mac_count(false), 7 * (m + 2 + 1));
        }
    }
}

#[test]
fn corrupt_and_truncated_blobs() {
    let mut rng = Rng::new(31);
    let blob = sample(&mut rng).blob(ScalarKind::F32);
    let mut bad = blob.clone();
    bad[20] ^= 0x40;
    assert!(matches!(
        F::from_blob(&bad),
        Err(BlobError::CrcMismatch { .. })
    ));
    assert!(matches!(
        Q::from_blob(&bad),
        Err(BlobError::CrcMismatch { .. })
    ));
    for len in [0, 3, 11, 12, blob.len() - 1] {
        assert!(matches!(
            F::from_blob(&blob[..len]),
            Err(BlobError::Truncated { .. })
        ));
    }
    // A payload cut short but framed with a correct CRC does not decode.
    let (_, payload) = neurosurf_core::blob::parse(&blob).unwrap();
    let cut = caoen_support::frame(
        neurosurf_core::blob::FORMAT_VERSION,
        ModelKind::CaoEn.code(),
        1,
        &payload[..payload.len() - 3],
    );
    rejected(&cut, BlobError::MalformedPayload);
    // Another model kind's blob.
    let mut other = blob.clone();
    other[6] = ModelKind::Curve.code();
    fix_crc(&mut other);
    rejected(
        &other,
        BlobError::WrongModelKind {
            expected: ModelKind::CaoEn,
            found: ModelKind::Curve,
        },
    );
    // f64 storage.
    let mut wide = blob.clone();
    wide[7] = ScalarKind::F64.code();
    fix_crc(&mut wide);
    rejected(
        &wide,
        BlobError::UnsupportedStorage {
            model: ModelKind::CaoEn,
            scalar: ScalarKind::F64,
        },
    );
}

#[test]
fn shape_errors() {
    let kind = ScalarKind::F32;
    let w3 = words(&[0.0, 0.0, 1.0, 1.0, 0.0, 0.0], kind);
    let t3 = words(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0], kind);
    let q = words(&[2.0, 2.0], kind);
    let shape = |what, expected, found| BlobError::ShapeMismatch {
        what,
        expected,
        found,
    };
    rejected(
        &raw_blob(kind, [2, 0, 0, 3, 3], [&w3, &t3, &q]),
        shape(Quantity::Domain, 1, 2),
    );
    rejected(
        &raw_blob(kind, [0, 7, 0, 3, 3], [&w3, &t3, &q]),
        shape(Quantity::Blending, 2, 7),
    );
    rejected(
        &raw_blob(kind, [0, 3, 0, 3, 3], [&w3, &t3, &q]),
        shape(Quantity::Blending, 2, 3),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 2, 3], [&w3, &t3, &q]),
        shape(Quantity::SourceDimension, 3, 2),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 9, 3], [&w3, &t3, &q]),
        shape(Quantity::SourceDimension, 8, 9),
    );
    rejected(
        &raw_blob(kind, [1, 0, 0, 3, 3], [&w3, &t3, &q]),
        shape(Quantity::SourceDimension, 4, 3),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 3, 0], [&w3, &t3, &q]),
        shape(Quantity::TargetDimension, 1, 0),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 3, 9], [&w3, &t3, &q]),
        shape(Quantity::TargetDimension, 8, 9),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 3, 3], [&w3, &t3, &[]]),
        shape(Quantity::KeyPoints, 1, 0),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 3, 3], [&w3, &t3, &q[..7]]),
        shape(Quantity::Parameters, 2, 1),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 3, 3], [&w3[..20], &t3, &q]),
        shape(Quantity::Parameters, 6, 5),
    );
    rejected(
        &raw_blob(kind, [0, 0, 0, 3, 2], [&w3, &t3, &q]),
        shape(Quantity::Parameters, 4, 6),
    );
}

#[test]
fn capacity_errors() {
    let kind = ScalarKind::Q16_16;
    for n in [DEFAULT_KEY_POINTS + 1, MAX_KEY_POINTS + 1] {
        let w = words(&vec![0.5; 3 * n], kind);
        let q = words(&vec![1.0; n], kind);
        let blob = raw_blob(kind, [0, 0, 0, 3, 3], [&w, &w, &q]);
        let capacity = if n > MAX_KEY_POINTS {
            MAX_KEY_POINTS
        } else {
            DEFAULT_KEY_POINTS
        };
        rejected(
            &blob,
            BlobError::CapacityExceeded {
                what: Quantity::KeyPoints,
                needed: n,
                capacity,
            },
        );
        if n <= MAX_KEY_POINTS {
            assert_eq!(
                CaoEnModel::<f32, MAX_KEY_POINTS>::from_blob(&blob)
                    .unwrap()
                    .key_count(),
                n
            );
        }
    }
}

/// NaN and infinite f32 words, Q16.16 range, and sharpness out of range or not whole, each
/// named by its word index (through W, then V, then q).
#[test]
fn parameter_errors() {
    let kind = ScalarKind::F32;
    let raw = |values: &[f32]| -> Vec<u8> { values.iter().flat_map(|v| v.to_le_bytes()).collect() };
    let w = raw(&[0.0, 0.0, 1.0, 1.0, 0.0, 0.0]);
    let t = raw(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    let q = raw(&[2.0, 2.0]);
    let blob = |fields, w: &[u8], t: &[u8], q: &[u8]| raw_blob(kind, fields, [w, t, q]);
    let mut nan = w.clone();
    nan[16..20].copy_from_slice(&f32::NAN.to_le_bytes());
    rejected(
        &blob([0, 0, 0, 3, 3], &nan, &t, &q),
        BlobError::NonFiniteParameter { index: 4 },
    );
    let mut inf = t.clone();
    inf[4..8].copy_from_slice(&f32::INFINITY.to_le_bytes());
    rejected(
        &blob([0, 0, 0, 3, 3], &w, &inf, &q),
        BlobError::NonFiniteParameter { index: 7 },
    );
    let mut nan_q = q.clone();
    nan_q[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    rejected(
        &blob([0, 0, 0, 3, 3], &w, &t, &nan_q),
        BlobError::NonFiniteParameter { index: 13 },
    );
    // Beyond Q16.16's ±1024: only the fixed-point loader rejects it.
    let mut big = t.clone();
    big[20..24].copy_from_slice(&2000.0_f32.to_le_bytes());
    let b = blob([0, 0, 0, 3, 3], &w, &big, &q);
    assert!(F::from_blob(&b).is_ok());
    assert_eq!(
        Q::from_blob(&b).unwrap_err(),
        BlobError::ParameterOutOfRange { index: 11 }
    );
    // Sharpness: above 64, negative, or fractional for power blending (fine for exponential).
    for (bad, blending, ok) in [
        (65.0, 1, false),
        (-1.0, 1, false),
        (2.5, 0, false),
        (2.5, 1, true),
        (64.0, 0, true),
        (0.0, 0, true),
    ] {
        let q = raw(&[2.0, bad]);
        let b = blob([0, blending, 0, 3, 3], &w, &t, &q);
        if ok {
            assert!(
                F::from_blob(&b).is_ok() && Q::from_blob(&b).is_ok(),
                "{bad}"
            );
        } else {
            rejected(&b, BlobError::ParameterOutOfRange { index: 13 });
        }
    }
    // Q16.16 storage: a fractional power is caught on the stored bits too.
    let qk = ScalarKind::Q16_16;
    let b = raw_blob(
        qk,
        [0, 0, 0, 3, 3],
        [
            &words(&[0.0, 0.0, 1.0, 1.0, 0.0, 0.0], qk),
            &words(&[1.0; 6], qk),
            &words(&[2.0, 1.0 + 1.0 / 65536.0], qk),
        ],
    );
    rejected(&b, BlobError::ParameterOutOfRange { index: 13 });
}

/// `load` replaces a model in place; a rejected blob leaves it empty.
#[test]
fn load_in_place_and_failures_leave_the_model_empty() {
    let mut rng = Rng::new(32);
    let blob = sample(&mut rng).blob(ScalarKind::Q16_16);
    let mut model = Q::new();
    model.load(&blob).unwrap();
    assert_eq!(model.key_count(), 5);
    assert!(model.load(&blob[..blob.len() - 1]).is_err());
    assert_eq!((model.key_count(), model.target_dimension()), (0, 0));
    let y: [Q16; 3] = model.eval(&[Q16::ONE, Q16::ZERO, Q16::ZERO]);
    assert_eq!(y, [Q16::ZERO; 3]);
}

/// Random single-byte mutations of valid blobs (CRC recomputed so the payload decoder and
/// validation are reached) and random bytes: never a panic; what loads evaluates.
#[test]
fn fuzz_mutated_blobs() {
    let mut rng = Rng::new(33);
    let seeds: Vec<Vec<u8>> = (0..6)
        .map(|i| {
            let net = random_network(
                &mut rng,
                3 + i,
                (3 + i % 2, 1 + i % 3),
                (i % 2) as u8,
                i >= 3,
                2.0,
            );
            net.blob([ScalarKind::F32, ScalarKind::Q16_16][i % 2])
        })
        .collect();
    let (mut accepted, mut total) = (0, 0);
    for round in 0..3000 {
        let mut bytes = seeds[round % seeds.len()].clone();
        for _ in 0..1 + rng.below(3) {
            let at = rng.below(bytes.len());
            bytes[at] = rng.byte();
        }
        if round % 2 == 0 {
            fix_crc(&mut bytes);
        }
        if round % 97 == 0 {
            bytes.truncate(rng.below(bytes.len()));
        }
        total += 1;
        let x = unit_vector(&mut rng, 4);
        if let Ok(model) = F::from_blob(&bytes) {
            accepted += 1;
            let xf = caoen_support::f32s::<4>(&x);
            let _: [f32; 3] = model.eval(&xf);
            let _ = model.eval_normal(&xf);
        }
        if let Ok(model) = Q::from_blob(&bytes) {
            let xq = caoen_support::q16s::<4>(&x);
            let _: [Q16; 5] = model.eval(&xq);
            let _ = model.eval_normal(&xq);
        }
    }
    println!("{accepted} of {total} mutated blobs load");
    assert!(accepted > 100 && accepted < total);
}

//! Curve and surface blobs through the public API: round trips in both storage kinds and both
//! scalars, one crafted input for every error the loaders report, in-place loading, and a
//! seeded fuzz run (random bytes, mutations of valid blobs, structurally random payloads) that
//! must never panic and must keep the loaders consistent with each other.

mod curve_support;

use curve_support::{
    CurveDraws, RefSurface, Rng, curve_blob, curve_blob_raw, encode_points, fix_crc, frame, q16,
    surface_blob, surface_blob_raw,
};
use neurosurf_core::Quantity;
use neurosurf_core::blob::{self, BlobError, HEADER_LEN, ModelKind, TRAILER_LEN};
use neurosurf_core::curve::{
    BSplineCurve, BSplineSurface, CurvePayload, CurvePoint, DEFAULT_CURVE_POINTS,
    DEFAULT_SURFACE_POINTS, MAX_SEGMENTS, SurfacePayload, SurfacePoint,
};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

const CURVE: u8 = 3;
const SURFACE: u8 = 4;

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

/// Postcard's encoding of the identity frame: a 12-byte string of zeros, then the shift 0.
fn identity_frame(out: &mut Vec<u8>) {
    out.push(12);
    out.extend_from_slice(&[0; 12]);
    out.push(0);
}

/// Postcard's encoding of a cubic `CurvePayload`, by hand (with the identity frame).
fn curve_postcard(dimension: u8, closed: u8, control: &[u8], metadata: &[u8]) -> Vec<u8> {
    curve_postcard_of_degree(dimension, closed, Some(3), control, metadata)
}

/// Postcard's encoding of a `CurvePayload` of `degree` (`None`: the version 3 layout, which
/// has no degree), by hand (with the identity frame).
fn curve_postcard_of_degree(
    dimension: u8,
    closed: u8,
    degree: Option<u8>,
    control: &[u8],
    metadata: &[u8],
) -> Vec<u8> {
    let mut out = vec![dimension, closed];
    out.extend(degree);
    identity_frame(&mut out);
    for bytes in [control, metadata] {
        varint(&mut out, bytes.len());
        out.extend_from_slice(bytes);
    }
    out
}

/// Postcard's encoding of a `SurfacePayload`, by hand (u16 counts are varints; the identity
/// frame).
fn surface_postcard(closed: [u8; 2], counts: [u16; 2], control: &[u8], metadata: &[u8]) -> Vec<u8> {
    surface_postcard_of_degrees(closed, Some([3, 3]), counts, control, metadata)
}

/// [`surface_postcard`] with `degrees` (`None`: the version 3 layout).
fn surface_postcard_of_degrees(
    closed: [u8; 2],
    degrees: Option<[u8; 2]>,
    counts: [u16; 2],
    control: &[u8],
    metadata: &[u8],
) -> Vec<u8> {
    let mut out = closed.to_vec();
    out.extend(degrees.into_iter().flatten());
    for count in counts {
        varint(&mut out, usize::from(count));
    }
    identity_frame(&mut out);
    for bytes in [control, metadata] {
        varint(&mut out, bytes.len());
        out.extend_from_slice(bytes);
    }
    out
}

type Curve32 = BSplineCurve<f32>;
type CurveQ = BSplineCurve<Q16>;
type Surface32 = BSplineSurface<f32>;
type SurfaceQ = BSplineSurface<Q16>;

/// Both curve loaders reject `bytes` with `expected` (or, for range errors, only Q16.16).
fn curve_rejected(bytes: &[u8], expected: BlobError) {
    let e = Curve32::from_blob(bytes).unwrap_err();
    assert_eq!(e, expected);
    assert_eq!(CurveQ::from_blob(bytes).unwrap_err(), expected);
    assert!(!format!("{e}").is_empty());
}

fn surface_rejected(bytes: &[u8], expected: BlobError) {
    let e = Surface32::from_blob(bytes).unwrap_err();
    assert_eq!(e, expected);
    assert_eq!(SurfaceQ::from_blob(bytes).unwrap_err(), expected);
    assert!(!format!("{e}").is_empty());
}

// ---------------------------------------------------------------------------------------------
// Round trips

#[test]
fn curve_round_trip() {
    let mut rng = Rng::new(31);
    for (dimension, closed) in [(2_u8, false), (2, true), (3, false), (3, true)] {
        let n = 4 + rng.below(10);
        let points = rng.points(n, 10.0, dimension == 2);
        let mut loaded_f32 = Vec::new();
        let mut loaded_q16 = Vec::new();
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let control = encode_points(&points, kind);
            let blob = curve_blob_raw(kind, dimension, closed, &control);
            let expected = curve_postcard(dimension, u8::from(closed), &control, b"test curve");
            assert_eq!(blob.len(), HEADER_LEN + expected.len() + TRAILER_LEN);
            assert_eq!(blob, frame(CURVE, kind.code(), &expected));
            let (header, payload) = blob::parse(&blob).unwrap();
            assert_eq!((header.model, header.scalar), (ModelKind::Curve, kind));
            assert_eq!(payload, &expected[..]);
            let (_, decoded) = CurvePayload::from_blob(&blob).unwrap();
            assert_eq!(
                decoded,
                CurvePayload {
                    dimension,
                    closed,
                    degree: 3,
                    frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
                    control: &control,
                    metadata: b"test curve"
                }
            );
            let f = Curve32::from_blob(&blob).unwrap();
            let q = CurveQ::from_blob(&blob).unwrap();
            assert_eq!(
                (
                    f.dimension(),
                    f.is_closed(),
                    f.control_count(),
                    f.stored_as()
                ),
                (usize::from(dimension), closed, points.len(), kind)
            );
            assert_eq!(
                (
                    q.dimension(),
                    q.is_closed(),
                    q.control_count(),
                    q.stored_as()
                ),
                (usize::from(dimension), closed, points.len(), kind)
            );
            // Coordinates below 2⁸ on the Q16.16 grid are exact in both storage kinds.
            for (i, p) in points.iter().enumerate() {
                assert_eq!(f.control_point(i), Some(p.map(|x| x as f32)));
                assert_eq!(q.control_point(i), Some(p.map(q16)));
            }
            // The same models through the payload API.
            let fp = Curve32::from_payload(&decoded, kind).unwrap();
            assert_eq!(fp.eval(0.3), f.eval(0.3));
            loaded_f32.push(f);
            loaded_q16.push(q);
        }
        // Either storage kind gives bit-identical evaluations in either scalar.
        for _ in 0..20 {
            let t = rng.parameter();
            assert_eq!(loaded_f32[0].eval(t as f32), loaded_f32[1].eval(t as f32));
            assert_eq!(loaded_q16[0].eval(q16(t)), loaded_q16[1].eval(q16(t)));
        }
    }
}

#[test]
fn surface_round_trip() {
    let mut rng = Rng::new(32);
    for closed in [[false, false], [true, false], [false, true], [true, true]] {
        let counts = [4 + rng.below(5), 4 + rng.below(5)];
        let reference = RefSurface::random(&mut rng, closed, counts, 10.0);
        let counts = [reference.u.count as u16, reference.v.count as u16];
        let mut evaluations = Vec::new();
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let control = encode_points(&reference.points, kind);
            let blob = surface_blob(kind, &reference);
            let expected =
                surface_postcard(closed.map(u8::from), counts, &control, b"test surface");
            assert_eq!(blob, frame(SURFACE, kind.code(), &expected));
            let (header, decoded) = SurfacePayload::from_blob(&blob).unwrap();
            assert_eq!(
                (header.model, header.scalar),
                (ModelKind::SplineSurface, kind)
            );
            assert_eq!(
                decoded,
                SurfacePayload {
                    closed_u: closed[0],
                    closed_v: closed[1],
                    degree_u: 3,
                    degree_v: 3,
                    count_u: counts[0],
                    count_v: counts[1],
                    frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
                    control: &control,
                    metadata: b"test surface",
                }
            );
            let f = Surface32::from_blob(&blob).unwrap();
            let q = SurfaceQ::from_blob(&blob).unwrap();
            assert_eq!(f.counts(), [reference.u.count, reference.v.count]);
            assert_eq!((f.is_closed(), q.is_closed()), (closed, closed));
            assert_eq!((f.stored_as(), q.stored_as()), (kind, kind));
            for v in 0..reference.v.count {
                for u in 0..reference.u.count {
                    assert_eq!(q.control_point(u, v), Some(reference.point(u, v).map(q16)));
                }
            }
            let q2 = SurfaceQ::from_payload(&decoded, kind).unwrap();
            let uv = [Q16::from_num(0.3), Q16::from_num(0.7)];
            assert_eq!(q2.eval(uv), q.eval(uv));
            evaluations.push((
                f.eval([0.3, 0.7]),
                q.eval(uv),
                f.normal([0.3, 0.7]),
                q.normal(uv),
            ));
        }
        assert_eq!(evaluations[0], evaluations[1]);
    }
}

#[test]
fn metadata_is_opaque() {
    let mut rng = Rng::new(33);
    let points = rng.points(6, 1.0, false);
    let control = encode_points(&points, ScalarKind::Q16_16);
    let mut blobs = Vec::new();
    for metadata in [&b""[..], &[0xA5; 1000][..]] {
        let payload = CurvePayload {
            dimension: 3,
            closed: true,
            degree: 3,
            frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
            control: &control,
            metadata,
        };
        let mut out = vec![0_u8; 2000];
        let len = payload.write(ScalarKind::Q16_16, &mut out).unwrap();
        out.truncate(len);
        blobs.push(out);
    }
    assert_ne!(blobs[0], blobs[1]);
    let (a, b) = (
        CurveQ::from_blob(&blobs[0]).unwrap(),
        CurveQ::from_blob(&blobs[1]).unwrap(),
    );
    for t in [0.0, 0.3, 1.0] {
        assert_eq!(a.eval(q16(t)), b.eval(q16(t)));
    }
}

/// `load` replaces a model in place; a rejected blob leaves it empty, not half-loaded.
#[test]
fn load_in_place_and_failures_leave_the_model_empty() {
    let mut rng = Rng::new(34);
    let first = curve_blob(ScalarKind::Q16_16, 3, false, &rng.points(8, 1.0, false));
    let second = curve_blob(ScalarKind::F32, 2, true, &rng.points(5, 1.0, true));
    let mut curve = CurveQ::new();
    curve.load(&first).unwrap();
    assert_eq!(curve.control_count(), 8);
    curve.load(&second).unwrap();
    assert_eq!(
        (curve.control_count(), curve.dimension(), curve.stored_as()),
        (5, 2, ScalarKind::F32)
    );
    let direct = CurveQ::from_blob(&second).unwrap();
    assert_eq!(curve.eval(q16(0.4)), direct.eval(q16(0.4)));
    let mut broken = first.clone();
    let last = broken.len() - 1;
    broken[last] ^= 1;
    assert!(curve.load(&broken).is_err());
    assert_eq!(
        (curve.control_count(), curve.segments(), curve.dimension()),
        (0, 0, 0)
    );
    assert_eq!(curve.eval(q16(0.4)), CurvePoint::default());
    // A failure late in validation (a bad coordinate) also leaves nothing behind.
    curve.load(&first).unwrap();
    let mut points = rng.points(8, 1.0, false);
    points[7][1] = 2000.0;
    assert!(
        curve
            .load(&curve_blob(ScalarKind::F32, 3, false, &points))
            .is_err()
    );
    assert_eq!(curve.control_count(), 0);
    // The payload API too.
    let control = encode_points(&rng.points(3, 1.0, false), ScalarKind::F32);
    let payload = CurvePayload {
        dimension: 3,
        closed: true,
        degree: 3,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        control: &control,
        metadata: &[],
    };
    curve.load(&first).unwrap();
    assert!(curve.load_payload(&payload, ScalarKind::F32).is_err());
    assert_eq!(curve.control_count(), 0);

    let reference = RefSurface::random(&mut rng, [false, true], [4, 5], 1.0);
    let blob = surface_blob(ScalarKind::Q16_16, &reference);
    let mut surface = SurfaceQ::new();
    surface.load(&blob).unwrap();
    assert_eq!(surface.counts(), [4, 5]);
    assert!(surface.load(&first).is_err()); // a curve blob
    assert_eq!(surface.counts(), [0, 0]);
    assert_eq!(surface.eval([Q16::ONE; 2]), SurfacePoint::default());
}

// ---------------------------------------------------------------------------------------------
// Every error

#[test]
fn framing_errors() {
    let mut rng = Rng::new(35);
    let blob = curve_blob(ScalarKind::F32, 3, false, &rng.points(6, 1.0, false));
    for len in [0, 3, 11, blob.len() - 1] {
        let e = Curve32::from_blob(&blob[..len]).unwrap_err();
        assert!(matches!(e, BlobError::Truncated { available, .. } if available == len));
    }
    let mut long = blob.clone();
    long.push(0);
    curve_rejected(&long, BlobError::TrailingBytes { count: 1 });
    let mut bad = blob.clone();
    bad[20] ^= 4;
    assert!(matches!(
        Curve32::from_blob(&bad),
        Err(BlobError::CrcMismatch { .. })
    ));
    bad[..4].copy_from_slice(b"NSRG");
    curve_rejected(&bad, BlobError::BadMagic { found: *b"NSRG" });
    let mut bad = blob.clone();
    bad[7] = 9;
    fix_crc(&mut bad);
    curve_rejected(&bad, BlobError::UnknownScalarKind { code: 9 });
    bad[6] = 7;
    fix_crc(&mut bad);
    curve_rejected(&bad, BlobError::UnknownModelKind { code: 7 });
}

#[test]
fn wrong_model_kind() {
    let mut rng = Rng::new(36);
    let curve = curve_blob(ScalarKind::F32, 3, false, &rng.points(6, 1.0, false));
    let surface = surface_blob(
        ScalarKind::F32,
        &RefSurface::random(&mut rng, [false; 2], [4, 4], 1.0),
    );
    let found = |model| BlobError::WrongModelKind {
        expected: ModelKind::SplineSurface,
        found: model,
    };
    surface_rejected(&curve, found(ModelKind::Curve));
    curve_rejected(
        &surface,
        BlobError::WrongModelKind {
            expected: ModelKind::Curve,
            found: ModelKind::SplineSurface,
        },
    );
    // A curve payload framed as an implicit or RBF model.
    let (_, payload) = blob::parse(&curve).unwrap();
    for (code, model) in [(1, ModelKind::Implicit), (2, ModelKind::Rbf)] {
        let relabelled = frame(code, 1, payload);
        curve_rejected(
            &relabelled,
            BlobError::WrongModelKind {
                expected: ModelKind::Curve,
                found: model,
            },
        );
        surface_rejected(&relabelled, found(model));
        assert!(matches!(
            CurvePayload::from_blob(&relabelled),
            Err(BlobError::WrongModelKind { .. })
        ));
    }
    // Kind names and codes.
    assert_eq!(
        (ModelKind::Curve.code(), ModelKind::Curve.name()),
        (3, "curve")
    );
    assert_eq!(
        (
            ModelKind::SplineSurface.code(),
            ModelKind::SplineSurface.name()
        ),
        (4, "spline-surface")
    );
    assert_eq!(ModelKind::from_code(3), Some(ModelKind::Curve));
    assert_eq!(ModelKind::from_code(4), Some(ModelKind::SplineSurface));
    assert_eq!(ModelKind::from_code(7), None);
}

#[test]
fn unsupported_storage() {
    let mut rng = Rng::new(37);
    let control = encode_points(&rng.points(5, 1.0, false), ScalarKind::F32);
    let blob = frame(
        CURVE,
        ScalarKind::F64.code(),
        &curve_postcard(3, 0, &control, &[]),
    );
    curve_rejected(
        &blob,
        BlobError::UnsupportedStorage {
            model: ModelKind::Curve,
            scalar: ScalarKind::F64,
        },
    );
    let control = encode_points(&rng.points(16, 1.0, false), ScalarKind::F32);
    let blob = frame(
        SURFACE,
        ScalarKind::F64.code(),
        &surface_postcard([0, 0], [4, 4], &control, &[]),
    );
    surface_rejected(
        &blob,
        BlobError::UnsupportedStorage {
            model: ModelKind::SplineSurface,
            scalar: ScalarKind::F64,
        },
    );
}

#[test]
fn malformed_payload() {
    let mut rng = Rng::new(38);
    let control = encode_points(&rng.points(5, 1.0, false), ScalarKind::F32);
    let good = curve_postcard(3, 1, &control, b"meta");
    let cases = [
        vec![],
        vec![3],
        vec![3, 1],
        // A bool must be 0 or 1.
        curve_postcard(3, 2, &control, b""),
        good[..good.len() - 3].to_vec(),
        [&good[..], &[0]].concat(),
        vec![
            3, 0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x01,
        ],
    ];
    for payload in &cases {
        curve_rejected(&frame(CURVE, 1, payload), BlobError::MalformedPayload);
    }
    let control = encode_points(&rng.points(16, 1.0, false), ScalarKind::F32);
    let good = surface_postcard([0, 1], [4, 4], &control, &[]);
    let cases = [
        vec![],
        vec![0, 0, 4],
        surface_postcard([0, 7], [4, 4], &control, &[]),
        good[..good.len() - 1].to_vec(),
        [&good[..], &[9]].concat(),
        // A u16 count beyond 65 535.
        [&[0_u8, 0, 0xFF, 0xFF, 0x04][..], &good[3..]].concat(),
    ];
    for payload in &cases {
        surface_rejected(&frame(SURFACE, 1, payload), BlobError::MalformedPayload);
    }
}

#[test]
fn shape_mismatch() {
    let mut rng = Rng::new(39);
    let points = rng.points(6, 1.0, false);
    let control = encode_points(&points, ScalarKind::F32);
    // Dimension.
    for (dimension, expected) in [(0_u8, 2), (1, 2), (4, 3), (255, 3)] {
        curve_rejected(
            &curve_blob_raw(ScalarKind::F32, dimension, false, &control),
            BlobError::ShapeMismatch {
                what: Quantity::Dimension,
                expected,
                found: usize::from(dimension),
            },
        );
    }
    // A 2-D curve with a nonzero z (at any point, in either storage kind).
    for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
        let mut flat = rng.points(6, 1.0, true);
        flat[4][2] = 1.0 / 65536.0;
        curve_rejected(
            &curve_blob(kind, 2, true, &flat),
            BlobError::ShapeMismatch {
                what: Quantity::Dimension,
                expected: 2,
                found: 3,
            },
        );
        flat[4][2] = -0.0;
        assert!(Curve32::from_blob(&curve_blob(kind, 2, true, &flat)).is_ok());
    }
    // Not a whole number of points: the next whole point's worth of words is expected.
    for extra in [1_usize, 4, 8, 11] {
        let bytes = [&control[..], &vec![0; extra]].concat();
        curve_rejected(
            &curve_blob_raw(ScalarKind::F32, 3, false, &bytes),
            BlobError::ShapeMismatch {
                what: Quantity::Parameters,
                expected: 21,
                found: 18 + extra / 4,
            },
        );
    }
    // Too few points, open or closed.
    for n in 0..4 {
        for closed in [false, true] {
            curve_rejected(
                &curve_blob(ScalarKind::Q16_16, 3, closed, &points[..n]),
                BlobError::ShapeMismatch {
                    what: Quantity::ControlPoints,
                    expected: 4,
                    found: n,
                },
            );
        }
    }
    assert!(Curve32::from_blob(&curve_blob(ScalarKind::F32, 3, false, &points[..4])).is_ok());

    // Surfaces: too few points along u (checked first) or v.
    let net = encode_points(&rng.points(20, 1.0, false), ScalarKind::F32);
    for (counts, found) in [([3_u16, 5], 3), ([0, 0], 0), ([5, 3], 3), ([4, 1], 1)] {
        surface_rejected(
            &surface_blob_raw(
                ScalarKind::F32,
                [true, true],
                counts,
                &net[..12 * usize::from(counts[0] * counts[1])],
            ),
            BlobError::ShapeMismatch {
                what: Quantity::ControlPoints,
                expected: 4,
                found,
            },
        );
    }
    // Control points that disagree with count_u·count_v.
    for (counts, points) in [([4_u16, 5], 19), ([4, 4], 20), ([5, 4], 0)] {
        surface_rejected(
            &surface_blob_raw(ScalarKind::F32, [false, false], counts, &net[..12 * points]),
            BlobError::ShapeMismatch {
                what: Quantity::Parameters,
                expected: 3 * usize::from(counts[0] * counts[1]),
                found: 3 * points,
            },
        );
    }
    let mut ragged = net.clone();
    ragged.pop();
    surface_rejected(
        &surface_blob_raw(ScalarKind::F32, [false, false], [4, 5], &ragged),
        BlobError::ShapeMismatch {
            what: Quantity::Parameters,
            expected: 60,
            found: 59,
        },
    );
}

#[test]
fn capacity_exceeded() {
    let mut rng = Rng::new(40);
    // Points beyond the type's capacity.
    let points = rng.points(DEFAULT_CURVE_POINTS + 1, 1.0, false);
    curve_rejected(
        &curve_blob(ScalarKind::F32, 3, true, &points),
        BlobError::CapacityExceeded {
            what: Quantity::ControlPoints,
            needed: DEFAULT_CURVE_POINTS + 1,
            capacity: DEFAULT_CURVE_POINTS,
        },
    );
    assert!(
        Curve32::from_blob(&curve_blob(
            ScalarKind::F32,
            3,
            true,
            &points[..DEFAULT_CURVE_POINTS]
        ))
        .is_ok()
    );
    let small = curve_blob(ScalarKind::F32, 3, false, &points[..9]);
    assert_eq!(
        BSplineCurve::<Q16, 8>::from_blob(&small).unwrap_err(),
        BlobError::CapacityExceeded {
            what: Quantity::ControlPoints,
            needed: 9,
            capacity: 8
        }
    );
    assert!(BSplineCurve::<Q16, 9>::from_blob(&small).is_ok());

    // Segments beyond MAX_SEGMENTS, checked before the capacity.
    let zeros = vec![0_u8; 12 * (MAX_SEGMENTS + 4)];
    let segments =
        |n: usize, closed| curve_blob_raw(ScalarKind::Q16_16, 3, closed, &zeros[..12 * n]);
    curve_rejected(
        &segments(MAX_SEGMENTS + 1, true),
        BlobError::CapacityExceeded {
            what: Quantity::Segments,
            needed: MAX_SEGMENTS + 1,
            capacity: MAX_SEGMENTS,
        },
    );
    curve_rejected(
        &segments(MAX_SEGMENTS + 4, false),
        BlobError::CapacityExceeded {
            what: Quantity::Segments,
            needed: MAX_SEGMENTS + 1,
            capacity: MAX_SEGMENTS,
        },
    );
    // The largest segment counts load (given the capacity) and evaluate at the far end.
    let capacity = MAX_SEGMENTS + 3;
    let open =
        BSplineCurve::<Q16, { MAX_SEGMENTS + 3 }>::from_blob(&segments(capacity, false)).unwrap();
    assert_eq!(open.segments(), MAX_SEGMENTS);
    assert_eq!(open.eval(Q16::ONE), CurvePoint::default());
    let closed =
        BSplineCurve::<f32, { MAX_SEGMENTS + 3 }>::from_blob(&segments(MAX_SEGMENTS, true))
            .unwrap();
    assert_eq!(closed.segments(), MAX_SEGMENTS);
    assert_eq!(
        Curve32::from_blob(&segments(MAX_SEGMENTS, true)).unwrap_err(),
        BlobError::CapacityExceeded {
            what: Quantity::ControlPoints,
            needed: MAX_SEGMENTS,
            capacity: DEFAULT_CURVE_POINTS
        }
    );

    // Surfaces: segments along one direction, then total points.
    surface_rejected(
        &surface_blob_raw(ScalarKind::F32, [true, false], [40_000, 4], &[]),
        BlobError::CapacityExceeded {
            what: Quantity::Segments,
            needed: 40_000,
            capacity: MAX_SEGMENTS,
        },
    );
    surface_rejected(
        &surface_blob_raw(ScalarKind::F32, [false, false], [4, u16::MAX], &[]),
        BlobError::CapacityExceeded {
            what: Quantity::Segments,
            needed: 65_532,
            capacity: MAX_SEGMENTS,
        },
    );
    surface_rejected(
        &surface_blob_raw(ScalarKind::F32, [false, false], [33, 32], &[]),
        BlobError::CapacityExceeded {
            what: Quantity::ControlPoints,
            needed: 1056,
            capacity: DEFAULT_SURFACE_POINTS,
        },
    );
    let net = RefSurface::random(&mut rng, [false, false], [4, 5], 1.0);
    let blob = surface_blob(ScalarKind::Q16_16, &net);
    assert_eq!(
        BSplineSurface::<f32, 19>::from_blob(&blob).unwrap_err(),
        BlobError::CapacityExceeded {
            what: Quantity::ControlPoints,
            needed: 20,
            capacity: 19
        }
    );
    assert!(BSplineSurface::<f32, 20>::from_blob(&blob).is_ok());
}

#[test]
fn non_finite_parameter() {
    let mut rng = Rng::new(41);
    let points = rng.points(6, 1.0, false);
    for (index, value) in [(0, f32::NAN), (7, f32::INFINITY), (17, f32::NEG_INFINITY)] {
        let mut control = encode_points(&points, ScalarKind::F32);
        control[4 * index..4 * index + 4].copy_from_slice(&value.to_le_bytes());
        curve_rejected(
            &curve_blob_raw(ScalarKind::F32, 3, false, &control),
            BlobError::NonFiniteParameter { index },
        );
    }
    let mut control = encode_points(&rng.points(16, 1.0, false), ScalarKind::F32);
    control[4 * 47..].copy_from_slice(&0x7FC0_1234_u32.to_le_bytes());
    surface_rejected(
        &surface_blob_raw(ScalarKind::F32, [true, true], [4, 4], &control),
        BlobError::NonFiniteParameter { index: 47 },
    );
}

#[test]
fn parameter_out_of_range() {
    // Only Q16.16 evaluation bounds coordinates (|x| ≤ 1024, so accumulators cannot overflow
    // and differences cannot saturate); f32 takes any finite value.
    let mut rng = Rng::new(42);
    let limit = f64::from(<Q16 as Scalar>::MAX_PARAMETER);
    for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
        for (index, value, ok) in [
            (4, limit, true),
            (4, -limit, true),
            (4, limit + 1.0 / 8192.0, false),
            (10, -limit - 1.0, false),
            (11, 30_000.0, false),
        ] {
            let mut points = rng.points(6, 1.0, false);
            points[index / 3][index % 3] = value;
            let blob = curve_blob(kind, 3, false, &points);
            assert!(Curve32::from_blob(&blob).is_ok());
            match CurveQ::from_blob(&blob) {
                Ok(_) => assert!(ok, "{value} accepted"),
                Err(e) => {
                    assert!(!ok, "{value} rejected");
                    assert_eq!(e, BlobError::ParameterOutOfRange { index });
                }
            }
        }
    }
    // The extremes of either storage kind.
    let mut control = encode_points(&rng.points(16, 1.0, false), ScalarKind::Q16_16);
    control[8..12].copy_from_slice(&i32::MIN.to_le_bytes());
    let blob = surface_blob_raw(ScalarKind::Q16_16, [false, false], [4, 4], &control);
    assert_eq!(
        SurfaceQ::from_blob(&blob).unwrap_err(),
        BlobError::ParameterOutOfRange { index: 2 }
    );
    assert!(Surface32::from_blob(&blob).is_ok());
    let mut control = encode_points(&rng.points(16, 1.0, false), ScalarKind::F32);
    control[..4].copy_from_slice(&f32::MAX.to_le_bytes());
    let blob = surface_blob_raw(ScalarKind::F32, [false, false], [4, 4], &control);
    assert_eq!(
        SurfaceQ::from_blob(&blob).unwrap_err(),
        BlobError::ParameterOutOfRange { index: 0 }
    );
    assert!(Surface32::from_blob(&blob).is_ok());
}

#[test]
fn buffer_too_small() {
    let mut rng = Rng::new(43);
    let control = encode_points(&rng.points(4, 1.0, false), ScalarKind::F32);
    let payload = CurvePayload {
        dimension: 3,
        closed: false,
        degree: 3,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        control: &control,
        metadata: b"m",
    };
    let mut big = [0_u8; 256];
    let needed = payload.write(ScalarKind::F32, &mut big).unwrap();
    for capacity in [0, 11, needed - 1] {
        let mut out = vec![0_u8; capacity];
        assert_eq!(
            payload.write(ScalarKind::F32, &mut out),
            Err(BlobError::BufferTooSmall { needed, capacity })
        );
    }
}

// ---------------------------------------------------------------------------------------------
// Fuzzing

#[derive(Default, Debug)]
struct Stats {
    inputs: usize,
    curves_f32: usize,
    curves_q16: usize,
    surfaces_f32: usize,
    surfaces_q16: usize,
}

/// Feeds `bytes` to every loader; checks that they agree and that accepted models evaluate.
fn feed(bytes: &[u8], stats: &mut Stats, rng: &mut Rng) {
    stats.inputs += 1;
    let parsed = blob::parse(bytes);
    let (cf, cq, cs) = (
        Curve32::from_blob(bytes),
        CurveQ::from_blob(bytes),
        BSplineCurve::<Q16, 6>::from_blob(bytes),
    );
    let (sf, sq, ss) = (
        Surface32::from_blob(bytes),
        SurfaceQ::from_blob(bytes),
        BSplineSurface::<Q16, 20>::from_blob(bytes),
    );
    if let Err(e) = &parsed {
        for result in [cf.as_ref().err(), cq.as_ref().err(), cs.as_ref().err()] {
            assert_eq!(result, Some(e));
        }
        for result in [sf.as_ref().err(), sq.as_ref().err(), ss.as_ref().err()] {
            assert_eq!(result, Some(e));
        }
    }
    consistent(
        &cq.as_ref()
            .map(|c| (c.control_count(), c.segments(), c.dimension())),
        &cf.as_ref()
            .map(|c| (c.control_count(), c.segments(), c.dimension())),
        &cs.as_ref().map(|_| ()),
    );
    consistent(
        &sq.as_ref().map(|s| (s.counts(), s.segments())),
        &sf.as_ref().map(|s| (s.counts(), s.segments())),
        &ss.as_ref().map(|_| ()),
    );
    let t = rng.unit() * 1.4 - 0.2;
    if let Ok(c) = &cf {
        stats.curves_f32 += 1;
        exercise_curve(c, [t as f32, f32::NAN, f32::INFINITY, -1.0]);
    }
    if let Ok(c) = &cq {
        stats.curves_q16 += 1;
        exercise_curve(c, [q16(t), Q16::MAX, Q16::MIN, Q16::ZERO]);
        // Positions are convex combinations of the control points (in the user's units,
        // after the frame).
        let bound = (0..c.control_count())
            .filter_map(|i| c.control_point(i))
            .flatten()
            .map(|x| x.saturating_abs())
            .max()
            .unwrap_or(Q16::ZERO);
        for p in [c.position(q16(t)), c.position(Q16::ONE)] {
            assert!(
                p.iter().all(|x| x.saturating_abs() <= bound),
                "{p:?} beyond {bound}"
            );
        }
    }
    if let Ok(s) = &sf {
        stats.surfaces_f32 += 1;
        exercise_surface(
            s,
            [[t as f32, 0.5], [f32::NAN, f32::NEG_INFINITY], [2.0, 1.0]],
        );
    }
    if let Ok(s) = &sq {
        stats.surfaces_q16 += 1;
        exercise_surface(
            s,
            [
                [q16(t), Q16::ZERO],
                [Q16::MIN, Q16::MAX],
                [Q16::ONE, q16(0.5)],
            ],
        );
    }
}

/// Q16.16 is the stricter loader: what it accepts, f32 accepts with the same shape; a smaller
/// capacity only adds capacity errors.
fn consistent<T: PartialEq + std::fmt::Debug>(
    q: &Result<T, &BlobError>,
    f: &Result<T, &BlobError>,
    small: &Result<(), &BlobError>,
) {
    if let Ok(shape) = q {
        assert_eq!(f.as_ref().expect("f32 accepts what Q16.16 accepts"), shape);
    }
    if let (Err(a), Err(b)) = (q, f)
        && a != b
    {
        assert!(
            matches!(a, BlobError::ParameterOutOfRange { .. }),
            "{a:?} vs {b:?}"
        );
    }
    match (q, small) {
        (Ok(_), Err(e)) => assert!(matches!(e, BlobError::CapacityExceeded { .. }), "{e:?}"),
        (Err(a), Err(b)) if a != b => {
            assert!(
                matches!(b, BlobError::CapacityExceeded { .. }),
                "{a:?} vs {b:?}"
            );
        }
        (Err(e), Ok(())) => panic!("a smaller model type accepted what the default refused: {e:?}"),
        _ => {}
    }
}

fn exercise_curve<S: Scalar>(curve: &BSplineCurve<S>, t: [S; 4]) {
    let mut out = [CurvePoint::default(); 4];
    curve.eval_batch(&t, &mut out).unwrap();
    for (t, batch) in t.iter().zip(&out) {
        let single = curve.eval(*t);
        assert_eq!(format!("{batch:?}"), format!("{single:?}"));
        let _ = (curve.position(*t), curve.tangent(*t));
    }
}

fn exercise_surface<S: Scalar>(surface: &BSplineSurface<S>, uv: [[S; 2]; 3]) {
    let mut points = [SurfacePoint::default(); 3];
    let mut normals = [None; 3];
    surface.eval_batch(&uv, &mut points).unwrap();
    surface.normal_batch(&uv, &mut normals).unwrap();
    for ((uv, point), normal) in uv.iter().zip(&points).zip(&normals) {
        assert_eq!(format!("{point:?}"), format!("{:?}", surface.eval(*uv)));
        assert_eq!(format!("{normal:?}"), format!("{:?}", surface.normal(*uv)));
        let _ = surface.position(*uv);
    }
}

/// Valid blobs of several shapes, both model kinds, both storage kinds.
fn seeds(rng: &mut Rng) -> Vec<Vec<u8>> {
    let mut blobs = Vec::new();
    for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
        for (dimension, closed, n) in [(2, false, 4), (3, true, 4), (3, false, 6), (2, true, 9)] {
            blobs.push(curve_blob(
                kind,
                dimension,
                closed,
                &rng.points(n, 3.0, dimension == 2),
            ));
        }
        for (closed, counts) in [
            ([false, false], [4, 4]),
            ([true, false], [5, 4]),
            ([true, true], [4, 6]),
        ] {
            blobs.push(surface_blob(
                kind,
                &RefSurface::random(rng, closed, counts, 3.0),
            ));
        }
    }
    blobs
}

#[test]
fn fuzz_mutated_blobs() {
    let mut rng = Rng::new(0xF0CC);
    let seeds = seeds(&mut rng);
    let mut stats = Stats::default();
    for i in 0..30_000 {
        let original = &seeds[i % seeds.len()];
        let mut bytes = original.clone();
        match rng.below(5) {
            0 => bytes.truncate(rng.below(original.len())),
            1 => bytes.extend((0..1 + rng.below(20)).map(|_| rng.byte())),
            2 => {
                for _ in 0..1 + rng.below(4) {
                    let at = rng.below(bytes.len());
                    bytes[at] ^= 1 + rng.below(255) as u8;
                }
                assert!(blob::parse(&bytes).is_err() || bytes == *original);
            }
            // Mutations with a fixed-up CRC: the payload decoder and validation decide.
            3 => {
                for _ in 0..1 + rng.below(4) {
                    let at = rng.below(bytes.len() - 4);
                    let at = if rng.below(2) == 0 { at % 20 } else { at };
                    bytes[at] = rng.byte();
                }
                fix_crc(&mut bytes);
            }
            // Payload truncated or extended, header length and CRC fixed up.
            _ => {
                let mut payload = original[HEADER_LEN..original.len() - TRAILER_LEN].to_vec();
                if rng.below(2) == 0 {
                    payload.truncate(rng.below(payload.len()));
                } else {
                    payload.extend((0..1 + rng.below(13)).map(|_| rng.byte()));
                }
                bytes = frame(original[6], original[7], &payload);
            }
        }
        feed(&bytes, &mut stats, &mut rng);
    }
    println!("mutations: {stats:?}");
    assert!(
        stats.curves_q16 >= 300 && stats.surfaces_q16 >= 300,
        "{stats:?}"
    );
}

#[test]
fn fuzz_random_bytes() {
    let mut rng = Rng::new(0xF1CC);
    let mut stats = Stats::default();
    for _ in 0..20_000 {
        let len = rng.below(120);
        let bytes: Vec<u8> = (0..len).map(|_| rng.byte()).collect();
        feed(&bytes, &mut stats, &mut rng);
        let framed = frame(3 + rng.below(2) as u8, 1 + rng.below(3) as u8, &bytes);
        feed(&framed, &mut stats, &mut rng);
    }
    println!("random bytes: {stats:?}");
}

/// Payloads built field by field with random shapes and special values.
#[test]
fn fuzz_structured_payloads() {
    let mut rng = Rng::new(0x0005_EEDC);
    let mut stats = Stats::default();
    let special = [
        f32::NAN,
        f32::INFINITY,
        f32::MAX,
        -f32::MAX,
        1024.0,
        1024.001,
        -1024.0,
        1.0e-40,
        -0.0,
    ];
    for _ in 0..20_000 {
        let storage = if rng.below(2) == 0 {
            ScalarKind::F32
        } else {
            ScalarKind::Q16_16
        };
        let is_curve = rng.below(2) == 0;
        let counts = [3 + rng.below(5), 3 + rng.below(5)];
        let points = match rng.below(4) {
            0 => rng.below(30),
            _ if is_curve => 4 + rng.below(8),
            _ => counts[0] * counts[1],
        };
        let mut control = Vec::new();
        for word in 0..3 * points {
            let bytes = match (rng.below(40), storage) {
                (0, ScalarKind::F32) => special[rng.below(special.len())].to_le_bytes(),
                (0, _) => (rng.next_u64() as u32).to_le_bytes(),
                // Mostly z = 0, so that some 2-D curves are valid.
                _ if word % 3 == 2 && rng.below(2) == 0 => [0; 4],
                (_, kind) => kind.encode(rng.unit() * 6.0 - 3.0).unwrap(),
            };
            control.extend_from_slice(&bytes);
        }
        if rng.below(20) == 0 {
            control.push(rng.byte());
        }
        let scalar = if rng.below(30) == 0 {
            3
        } else {
            storage.code()
        };
        let payload = if is_curve {
            let dimension = if rng.below(10) == 0 {
                rng.byte()
            } else {
                2 + rng.below(2) as u8
            };
            frame(
                CURVE,
                scalar,
                &curve_postcard(dimension, rng.below(2) as u8, &control, b""),
            )
        } else {
            let closed = [rng.below(2) as u8, rng.below(2) as u8];
            let counts = counts.map(|c| c as u16);
            frame(
                SURFACE,
                scalar,
                &surface_postcard(closed, counts, &control, b""),
            )
        };
        feed(&payload, &mut stats, &mut rng);
    }
    println!("structured payloads: {stats:?}");
    assert!(
        stats.curves_q16 >= 1000 && stats.surfaces_q16 >= 500,
        "{stats:?}"
    );
}

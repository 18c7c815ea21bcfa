//! Parametric surface networks in `f32` and Q16.16 against an independent `f64` evaluation of
//! the same stored words: positions, partials (also against central differences), normals,
//! batches, and the loader's errors.

use neurosurf_core::BlobError;
use neurosurf_core::parametric::{
    Activation, F32_POSITION_ERROR, MAX_NEURONS, Q16_POSITION_ERROR, SurfaceNetworkModel,
    SurfaceNetworkPayload, parameter_count,
};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

/// Partials in `f32`: relative to their size.
const F32_PARTIAL_ERROR: f64 = 1e-5;
/// Normals in Q16.16 where both partials are at least 0.05 long (degrees).
const Q16_NORMAL_DEGREES: f64 = 0.5;

/// A small deterministic generator (xorshift64*), uniform in [lo, hi).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        lo + (hi - lo) * (bits as f64 / (1u64 << 53) as f64)
    }
}

/// σ and σ′ in f64, written from the paper's Eqs. 9–12.
fn sigma(activation: Activation, a: f64) -> (f64, f64) {
    match activation {
        Activation::LogSig => {
            let s = 1.0 / (1.0 + (-a).exp());
            (s, s * (1.0 - s))
        }
        Activation::TanSig => {
            let t = 2.0 / (1.0 + (-a).exp()) - 1.0;
            (t, 0.5 * (1.0 - t * t))
        }
        Activation::RadBas => ((-a * a).exp(), -2.0 * a * (-a * a).exp()),
        _ => {
            if a.abs() < 1.0 {
                (1.0 - a.abs(), if a == 0.0 { 0.0 } else { -a.signum() })
            } else {
                (0.0, 0.0)
            }
        }
    }
}

/// p, ∂p/∂u, ∂p/∂v in f64 from the stored words (the layout of `neurosurf_core::parametric`).
fn reference(activation: Activation, hidden: &[u8], w: &[f64], u: f64, v: f64) -> [[f64; 3]; 3] {
    let mut x = vec![(u - w[0]) * w[2], (v - w[1]) * w[3]];
    let mut du = vec![w[2], 0.0];
    let mut dv = vec![0.0, w[3]];
    let mut at = 4;
    let sizes: Vec<usize> = hidden.iter().map(|&n| n as usize).chain([3]).collect();
    for (layer, &outputs) in sizes.iter().enumerate() {
        let inputs = x.len();
        let (mut nx, mut ndu, mut ndv) =
            (vec![0.0; outputs], vec![0.0; outputs], vec![0.0; outputs]);
        for o in 0..outputs {
            let row = &w[at + o * inputs..at + (o + 1) * inputs];
            let a = w[at + outputs * inputs + o] + (0..inputs).map(|i| row[i] * x[i]).sum::<f64>();
            let au: f64 = (0..inputs).map(|i| row[i] * du[i]).sum();
            let av: f64 = (0..inputs).map(|i| row[i] * dv[i]).sum();
            let (value, slope) = if layer + 1 < sizes.len() {
                sigma(activation, a)
            } else {
                (a, 1.0)
            };
            (nx[o], ndu[o], ndv[o]) = (value, slope * au, slope * av);
        }
        at += outputs * (inputs + 1);
        (x, du, dv) = (nx, ndu, ndv);
    }
    let s = w[at + 3];
    [
        std::array::from_fn(|k| w[at + k] + s * x[k]),
        std::array::from_fn(|k| s * du[k]),
        std::array::from_fn(|k| s * dv[k]),
    ]
}

/// A random network of unit-sized output, its words as stored in `scalar` and widened back.
fn random_network(rng: &mut Rng, hidden: &[u8], scalar: ScalarKind) -> (Vec<u8>, Vec<f64>) {
    let count = parameter_count(hidden);
    let mut values: Vec<f64> = (0..count).map(|_| rng.uniform(-3.0, 3.0)).collect();
    values[..4].copy_from_slice(&[
        rng.uniform(-0.5, 0.5),
        rng.uniform(-0.5, 0.5),
        rng.uniform(0.4, 1.0),
        rng.uniform(0.4, 1.0),
    ]);
    let n = count - 4;
    values[n..].copy_from_slice(&[
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
        rng.uniform(-1.0, 1.0),
        rng.uniform(0.2, 0.5),
    ]);
    let bytes: Vec<u8> = values
        .iter()
        .flat_map(|&v| scalar.encode(v).unwrap())
        .collect();
    let stored = bytes
        .chunks_exact(4)
        .map(|c| {
            let word = [c[0], c[1], c[2], c[3]];
            match scalar {
                ScalarKind::F32 => f64::from(f32::from_le_bytes(word)),
                _ => f64::from(i32::from_le_bytes(word)) / 65536.0,
            }
        })
        .collect();
    (bytes, stored)
}

fn blob(activation: Activation, hidden: &[u8], words: &[u8], scalar: ScalarKind) -> Vec<u8> {
    let payload = SurfaceNetworkPayload {
        activation: activation.code(),
        hidden,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        parameters: words,
        metadata: b"test",
    };
    let mut out = vec![0; 64 + words.len()];
    let len = payload.write(scalar, &mut out).unwrap();
    out.truncate(len);
    out
}

fn angle_degrees(a: [f64; 3], b: [f64; 3]) -> f64 {
    let dot: f64 = (0..3).map(|k| a[k] * b[k]).sum();
    let na = (0..3).map(|k| a[k] * a[k]).sum::<f64>().sqrt();
    let nb = (0..3).map(|k| b[k] * b[k]).sum::<f64>().sqrt();
    (dot / (na * nb)).clamp(-1.0, 1.0).acos().to_degrees()
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn length(a: [f64; 3]) -> f64 {
    a.iter().map(|c| c * c).sum::<f64>().sqrt()
}

const SHAPES: [&[u8]; 5] = [&[2], &[6], &[12], &[4, 4], &[8, 12]];

#[test]
fn f32_and_q16_match_the_f64_formula() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let (mut worst_f32, mut worst_partial, mut worst_q16, mut worst_angle) =
        (0.0, 0.0, 0.0, 0.0_f64);
    for activation in [
        Activation::LogSig,
        Activation::TanSig,
        Activation::RadBas,
        Activation::TriBas,
    ] {
        for hidden in SHAPES {
            for scalar in [ScalarKind::F32, ScalarKind::Q16_16] {
                let (words, w) = random_network(&mut rng, hidden, scalar);
                let bytes = blob(activation, hidden, &words, scalar);
                let float = SurfaceNetworkModel::<f32>::from_blob(&bytes).unwrap();
                let fixed = SurfaceNetworkModel::<Q16>::from_blob(&bytes).unwrap();
                assert_eq!(float.hidden_sizes(), hidden);
                for _ in 0..200 {
                    let (u, v) = (
                        f64::from(rng.uniform(-2.0, 2.0) as f32),
                        f64::from(rng.uniform(-2.0, 2.0) as f32),
                    );
                    let [p, du, dv] = reference(activation, hidden, &w, u, v);
                    let f = float.eval([u as f32, v as f32]);
                    assert_eq!(f.position, float.position([u as f32, v as f32]));
                    for k in 0..3 {
                        worst_f32 = f64::max(worst_f32, (f64::from(f.position[k]) - p[k]).abs());
                        let size = 1.0 + length(du).max(length(dv));
                        worst_partial = f64::max(
                            worst_partial,
                            ((f64::from(f.du[k]) - du[k]).abs()
                                + (f64::from(f.dv[k]) - dv[k]).abs())
                                / size,
                        );
                    }
                    let uq = [Q16::from_num(u), Q16::from_num(v)];
                    let (uq0, vq0) = (uq[0].to_f64(), uq[1].to_f64());
                    let [pq, duq, dvq] = reference(activation, hidden, &w, uq0, vq0);
                    let q = fixed.eval(uq);
                    for k in 0..3 {
                        worst_q16 = f64::max(worst_q16, (q.position[k].to_f64() - pq[k]).abs());
                    }
                    if activation != Activation::TriBas
                        && length(duq) > 0.05
                        && length(dvq) > 0.05
                        && length(cross(duq, dvq)) > 0.05 * length(duq) * length(dvq)
                    {
                        let n = q.normal.expect("a normal where the partials span a plane");
                        let angle = angle_degrees(n.map(Q16::to_f64), cross(duq, dvq));
                        worst_angle = worst_angle.max(angle);
                    }
                }
            }
        }
    }
    eprintln!(
        "f32 position {worst_f32:.2e}, f32 partials {worst_partial:.2e}, q16 position \
         {worst_q16:.2e}, q16 normal {worst_angle:.4}°"
    );
    assert!(worst_f32 < F32_POSITION_ERROR, "{worst_f32:e}");
    assert!(worst_partial < F32_PARTIAL_ERROR, "{worst_partial:e}");
    assert!(worst_q16 < Q16_POSITION_ERROR, "{worst_q16:e}");
    assert!(worst_angle < Q16_NORMAL_DEGREES, "{worst_angle}");
}

#[test]
fn partials_match_central_differences_and_batches_match_single_points() {
    let mut rng = Rng(7);
    let hidden: &[u8] = &[6, 5];
    let (words, _) = random_network(&mut rng, hidden, ScalarKind::F32);
    let bytes = blob(Activation::TanSig, hidden, &words, ScalarKind::F32);
    let model = SurfaceNetworkModel::<f32>::from_blob(&bytes).unwrap();
    let h = 1e-2_f32;
    for i in 0..50 {
        let uv = [rng.uniform(-1.5, 1.5) as f32, rng.uniform(-1.5, 1.5) as f32];
        let point = model.eval(uv);
        let plus = model.position([uv[0] + h, uv[1]]);
        let minus = model.position([uv[0] - h, uv[1]]);
        for k in 0..3 {
            let difference = (plus[k] - minus[k]) / (2.0 * h);
            assert!((difference - point.du[k]).abs() < 1e-2, "{i} {k}");
        }
    }
    let uv: Vec<[Q16; 2]> = (0..21)
        .map(|i| [Q16::from_num(-1.0 + 0.1 * i as f64), Q16::from_num(0.3)])
        .collect();
    let fixed = SurfaceNetworkModel::<Q16>::from_blob(&bytes).unwrap();
    let mut points = vec![Default::default(); uv.len()];
    let mut positions = vec![[Q16::ZERO; 3]; uv.len()];
    fixed.eval_batch(&uv, &mut points).unwrap();
    fixed.position_batch(&uv, &mut positions).unwrap();
    for ((p, q), &uv) in points.iter().zip(&positions).zip(&uv) {
        assert_eq!(*p, fixed.eval(uv));
        assert_eq!(*q, fixed.position(uv));
    }
    assert!(fixed.eval_batch(&uv, &mut points[..3]).is_err());
    assert_eq!(model.mac_count(false), 2 * 6 + 6 * 5 + 5 * 3);
}

#[test]
fn infinite_and_nan_inputs_give_values() {
    let mut rng = Rng(11);
    for activation in [
        Activation::LogSig,
        Activation::TanSig,
        Activation::RadBas,
        Activation::TriBas,
    ] {
        let (words, _) = random_network(&mut rng, &[5], ScalarKind::Q16_16);
        let bytes = blob(activation, &[5], &words, ScalarKind::Q16_16);
        let fixed = SurfaceNetworkModel::<Q16>::from_blob(&bytes).unwrap();
        let float = SurfaceNetworkModel::<f32>::from_blob(&bytes).unwrap();
        for x in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 1e30, -32768.0] {
            let _ = fixed.eval([Q16::from_f32_saturating(x), Q16::from_f32_saturating(-x)]);
            let _ = float.eval([x, 0.5]);
        }
    }
}

#[test]
fn bad_blobs_are_named_errors() {
    let mut rng = Rng(3);
    let (words, _) = random_network(&mut rng, &[4], ScalarKind::F32);
    let load = |activation: u8, hidden: &[u8], words: &[u8]| {
        let payload = SurfaceNetworkPayload {
            activation,
            hidden,
            frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
            parameters: words,
            metadata: &[],
        };
        let mut out = vec![0; 64 + words.len()];
        let len = payload.write(ScalarKind::F32, &mut out).unwrap();
        SurfaceNetworkModel::<f32>::from_blob(&out[..len]).map(|_| ())
    };
    assert_eq!(load(1, &[4], &words), Ok(()));
    assert!(matches!(
        load(4, &[4], &words),
        Err(BlobError::ShapeMismatch {
            expected: 3,
            found: 4,
            ..
        })
    ));
    assert!(matches!(
        load(1, &[], &words),
        Err(BlobError::ShapeMismatch { found: 0, .. })
    ));
    assert!(matches!(
        load(1, &[1, 1, 1, 1, 1], &words),
        Err(BlobError::ShapeMismatch {
            expected: 4,
            found: 5,
            ..
        })
    ));
    let too_wide = [MAX_NEURONS as u8 + 1];
    assert!(matches!(
        load(1, &too_wide, &words),
        Err(BlobError::ShapeMismatch { found: 33, .. })
    ));
    assert!(matches!(
        load(1, &[5], &words),
        Err(BlobError::ShapeMismatch { .. })
    ));
    let mut bad = words.clone();
    bad[8..12].copy_from_slice(&(-1.0_f32).to_le_bytes()); // g_u
    assert_eq!(
        load(1, &[4], &bad),
        Err(BlobError::ParameterOutOfRange { index: 2 })
    );
    bad[8..12].copy_from_slice(&f32::NAN.to_le_bytes());
    assert_eq!(
        load(1, &[4], &bad),
        Err(BlobError::NonFiniteParameter { index: 2 })
    );
    let last = words.len() - 4;
    let mut flat = words.clone();
    flat[last..].copy_from_slice(&0.0_f32.to_le_bytes()); // s_p
    assert_eq!(
        load(1, &[4], &flat),
        Err(BlobError::ParameterOutOfRange { index: last / 4 })
    );
    let (big, _) = random_network(&mut rng, &[32, 32], ScalarKind::F32);
    let payload = SurfaceNetworkPayload {
        activation: 1,
        hidden: &[32, 32],
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        parameters: &big,
        metadata: &[],
    };
    let mut out = vec![0; 64 + big.len()];
    let len = payload.write(ScalarKind::F32, &mut out).unwrap();
    assert!(matches!(
        SurfaceNetworkModel::<f32, 256>::from_blob(&out[..len]),
        Err(BlobError::CapacityExceeded { capacity: 256, .. })
    ));
    assert!(SurfaceNetworkModel::<f32>::from_blob(&out[..len]).is_ok());
}

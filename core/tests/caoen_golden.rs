//! Golden outputs of the Cao En evaluator: fixed Q16.16 networks and their outputs at fixed
//! source points, committed under `core/tests/golden/caoen_*` and compared BIT FOR BIT in
//! Q16.16 (integer-exact arithmetic: any difference is a behaviour change of the blending, exp,
//! accumulation, quotient, normal or loader), within 1 ulp in `f32`.
//!
//! Files (one network per blending form, all sphere → 3-D, 26 seeded key points):
//! - `caoen_q16_{power,exponential,rational}.nsb`: the blobs, stored as Q16.16;
//! - `caoen_q16_points.bin`: the source points, 3 × i32 (Q16.16 bits) each;
//! - `caoen_q16_{…}_expected.bin`: position and normal per point, 6 × i32 (a missing normal is
//!   three `i32::MIN`);
//! - `caoen_f32_{…}_expected.bin`: the same blobs in `f32` at the same points (NaN for none).
//!
//! To regenerate after an INTENDED change, run
//!
//! ```text
//! NEUROSURF_BLESS=1 cargo test -p neurosurf-core --test caoen_golden
//! ```
//!
//! review the diff, and commit the files. Without `NEUROSURF_BLESS=1` nothing is written.

mod caoen_support;
mod golden_support;

use caoen_support::{LSB, RefNet, Rng, random_network, unit_vector};
use golden_support::{assert_bits, assert_ulps, f32_words, golden_dir, q16_words, read, to_bytes};
use neurosurf_core::caoen::CaoEnModel;
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

const SEED: u64 = 0x000C_A0E4;
const FORMS: [(&str, u8, bool); 3] = [
    ("power", 0, false),
    ("exponential", 1, false),
    ("rational", 1, true),
];

fn network(index: usize) -> RefNet {
    let (_, blending, normalized) = FORMS[index];
    random_network(
        &mut Rng::new(SEED + index as u64),
        26,
        (3, 3),
        blending,
        normalized,
        2.0,
    )
}

/// Random sphere points, the six axis points and a few off-sphere and extreme inputs.
fn points() -> Vec<[Q16; 3]> {
    let mut rng = Rng::new(SEED ^ 0xFF);
    let mut points: Vec<[Q16; 3]> = (0..60)
        .map(|_| caoen_support::q16s(&unit_vector(&mut rng, 3)))
        .collect();
    for k in 0..3 {
        for sign in [1, -1] {
            let mut p = [Q16::ZERO; 3];
            p[k] = Q16::from_num(sign);
            points.push(p);
        }
    }
    points.extend([
        [Q16::ZERO; 3],
        [Q16::MAX, Q16::MIN, Q16::ONE],
        [Q16::from_num(2); 3],
    ]);
    points
}

/// Position and normal (or `none` three times), 6 words per point.
fn evaluate<S: Scalar>(blob: &[u8], points: &[[S; 3]], none: S) -> Vec<S> {
    let model = CaoEnModel::<S>::from_blob(blob).unwrap();
    points
        .iter()
        .flat_map(|x| {
            let p = model.eval_normal(x);
            p.position.into_iter().chain(p.normal.unwrap_or([none; 3]))
        })
        .collect()
}

fn bless() {
    let dir = golden_dir();
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: String, bytes: &[u8]| std::fs::write(dir.join(name), bytes).unwrap();
    let points = points();
    write(
        "caoen_q16_points.bin".into(),
        &to_bytes(points.iter().flatten().map(|c| c.to_le_bytes())),
    );
    let points32: Vec<[f32; 3]> = points.iter().map(|p| p.map(|c| c.to_num())).collect();
    for (index, (name, _, _)) in FORMS.iter().enumerate() {
        let blob = network(index).blob(ScalarKind::Q16_16);
        write(format!("caoen_q16_{name}.nsb"), &blob);
        let q = evaluate(&blob, &points, Q16::MIN);
        write(
            format!("caoen_q16_{name}_expected.bin"),
            &to_bytes(q.iter().map(|v| v.to_le_bytes())),
        );
        let f = evaluate(&blob, &points32, f32::NAN);
        write(
            format!("caoen_f32_{name}_expected.bin"),
            &to_bytes(f.iter().map(|v| v.to_le_bytes())),
        );
    }
    println!(
        "blessed {} Cao En golden points in {}",
        points.len(),
        dir.display()
    );
}

fn bless_if_asked() {
    golden_support::bless_if_asked(bless);
}

fn golden_points() -> Vec<[Q16; 3]> {
    q16_words(&read("caoen_q16_points.bin"))
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect()
}

#[test]
fn q16_outputs_match_bit_for_bit() {
    bless_if_asked();
    let points = golden_points();
    for (name, _, _) in FORMS {
        let blob = read(&format!("caoen_q16_{name}.nsb"));
        let expected = q16_words(&read(&format!("caoen_q16_{name}_expected.bin")));
        assert_bits(name, 6, &evaluate(&blob, &points, Q16::MIN), &expected);
    }
}

#[test]
fn f32_outputs_match_within_one_ulp() {
    bless_if_asked();
    let points: Vec<[f32; 3]> = golden_points()
        .iter()
        .map(|p| p.map(|c| c.to_num()))
        .collect();
    for (name, _, _) in FORMS {
        let blob = read(&format!("caoen_q16_{name}.nsb"));
        let expected = f32_words(&read(&format!("caoen_f32_{name}_expected.bin")));
        assert_ulps(name, &evaluate(&blob, &points, f32::NAN), &expected);
    }
}

/// The committed blobs and points are what the generators produce today.
#[test]
fn golden_inputs_are_reproducible() {
    bless_if_asked();
    assert_eq!(golden_points(), points());
    for (index, (name, _, _)) in FORMS.iter().enumerate() {
        assert_eq!(
            read(&format!("caoen_q16_{name}.nsb")),
            network(index).blob(ScalarKind::Q16_16)
        );
    }
}

/// The golden positions are right, not merely stable: within 64 LSB of the f64 reference on
/// the sphere (where the rational form's Σ F ≥ 0.01).
#[test]
fn golden_outputs_agree_with_the_reference() {
    bless_if_asked();
    let points = golden_points();
    for (index, (name, _, normalized)) in FORMS.iter().enumerate() {
        let net = network(index);
        let expected = q16_words(&read(&format!("caoen_q16_{name}_expected.bin")));
        for (i, p) in points.iter().take(66).enumerate() {
            let x: Vec<f64> = p.iter().map(|c| c.to_num()).collect();
            if *normalized && net.blend_sum(&x) < 0.01 {
                continue;
            }
            let exact = net.position(&x);
            for k in 0..3 {
                let got = expected[6 * i + k].to_num::<f64>();
                assert!((got - exact[k]).abs() < 64.0 * LSB, "{name} point {i}");
            }
        }
    }
}

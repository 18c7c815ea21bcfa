//! The core on a simulated Cortex-M4F (QEMU mps2-an386), against the same core on the host:
//! trained models go through blobs to the target, and what comes back must be what the host
//! computes — bit for bit, in Q16.16 and in f32 (the issue allows 2 ulp) — while bad blobs and bad requests
//! come back as their error codes, and a hang as a time-out, never as a wrong answer.
//!
//! The toolchain comes from `firmware-sim/scripts/setup.sh` (the test command `scripts/test.sh`
//! runs it first); without it these tests fail with a message naming that script.

use std::path::Path;
use std::time::Duration;

use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::scalar::ScalarKind;
use neurosurf_firmware_sim::{Job, Mode, Op, SimError, Simulator, Status};
use neurosurf_trainer::evaluate::{LoadedModel, Precision, Sample};
use neurosurf_trainer::implicit::{
    self, FitRequest, ImplicitNetwork, ImplicitOptions, Normalization, Trained, TreeSpec,
};
use neurosurf_trainer::points::PointSet;
use neurosurf_trainer::sample::{Shape, sample_shape};

const TORUS: Shape = Shape::Torus {
    major: 1.0,
    minor: 0.4,
};

fn simulator() -> Simulator {
    Simulator::prepare().unwrap_or_else(|e| panic!("simulator not ready: {e}"))
}

fn train(points: PointSet, tree: Option<&str>) -> Trained {
    let request = FitRequest {
        tree: tree.map(|t| t.parse().unwrap()),
        ..FitRequest::default()
    };
    implicit::fit(points, &request, &ImplicitOptions::default(), &|_| {}).unwrap()
}

fn torus() -> Trained {
    train(sample_shape(&TORUS, 96, 11).unwrap(), None)
}

fn head() -> Trained {
    train(
        sample_shape(&Shape::Head, 99, 5).unwrap(),
        Some("((0,1),2)"),
    )
}

/// Query points: the held-out surface points plus a spread through the bounding box (both
/// the surface and the far field, where activations saturate).
fn queries(shape: &Shape, seed: u64) -> Vec<[f64; 3]> {
    let mut points = sample_shape(shape, 300, seed).unwrap().positions;
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1_u64 << 53) as f64 * 4.0 - 2.0
    };
    for _ in 0..100 {
        points.push([next(), next(), next()]);
    }
    points
}

fn blob(trained: &Trained, scalar: ScalarKind) -> Vec<u8> {
    implicit::to_blob(&trained.network, Some(&trained.summary), scalar).unwrap()
}

fn host(blob: &[u8], points: &[[f64; 3]], precision: Precision) -> Vec<Sample> {
    LoadedModel::from_bytes(blob.to_vec(), Path::new("m.nsb"))
        .unwrap()
        .evaluate(points, precision)
        .unwrap()
}

fn as_f32(points: &[[f64; 3]]) -> Vec<[f32; 3]> {
    points.iter().map(|p| p.map(|c| c as f32)).collect()
}

/// Distance in units in the last place between two f32 values (same sign assumed near 0).
fn ulps(a: f64, b: f64) -> u32 {
    let key = |x: f32| {
        let bits = x.to_bits() as i32;
        if bits < 0 {
            i32::MIN.wrapping_sub(bits)
        } else {
            bits
        }
    };
    key(a as f32).abs_diff(key(b as f32))
}

fn angle_degrees(a: [f64; 3], b: [f64; 3]) -> f64 {
    let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    (dot / (norm(a) * norm(b)))
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

/// Runs the Q16.16 blob `bytes` at `points` on the target, in batches and point by point, and
/// requires the host's `expected` samples bit for bit.
fn assert_q16_target_equals(bytes: &[u8], points: &[[f64; 3]], expected: &[Sample]) {
    let (sim, points_f32) = (simulator(), as_f32(points));
    for mode in [Mode::Batch, Mode::Single] {
        let job = Job {
            mode,
            ..Job::field_gradient(bytes, ScalarKind::Q16_16, &points_f32)
        };
        let samples = sim.run(&job).unwrap().samples();
        assert_eq!(sample_bits(&samples), sample_bits(expected), "{mode:?}");
    }
}

/// Every value's bits, so that +0.0 and −0.0 differ.
fn sample_bits(samples: &[(f64, [f64; 3])]) -> Vec<[u64; 4]> {
    samples
        .iter()
        .map(|(v, g)| [v.to_bits(), g[0].to_bits(), g[1].to_bits(), g[2].to_bits()])
        .collect()
}

/// Runs the torus and the head on the target in `scalar`, single points and batches, field and
/// field + gradient, and asserts that every result is the host core's, bit for bit.
fn assert_target_equals_host(scalar: ScalarKind, precision: Precision, seed: u64) {
    let sim = simulator();
    for (name, trained, shape) in [("torus", torus(), TORUS), ("head", head(), Shape::Head)] {
        let points = queries(&shape, seed);
        let bytes = blob(&trained, scalar);
        assert_runs_equal_host(&sim, name, &bytes, scalar, precision, &points);
    }
}

/// Runs the blob `bytes` at `points` on the target in `scalar` — batches and single points,
/// field + gradient and field alone — and asserts that every result is the host core's
/// (`precision`), bit for bit.
fn assert_runs_equal_host(
    sim: &Simulator,
    name: &str,
    bytes: &[u8],
    scalar: ScalarKind,
    precision: Precision,
    points: &[[f64; 3]],
) {
    let expected = host(bytes, points, precision);
    let points_f32 = as_f32(points);
    for mode in [Mode::Batch, Mode::Single] {
        let job = Job {
            mode,
            ..Job::field_gradient(bytes, scalar, &points_f32)
        };
        let run = sim.run(&job).unwrap();
        let samples = run.samples();
        let mut worst = 0;
        for (got, want) in samples.iter().zip(&expected) {
            worst = worst.max(ulps(got.0, want.0));
            for k in 0..3 {
                worst = worst.max(ulps(got.1[k], want.1[k]));
            }
        }
        eprintln!(
            "{name}, {scalar:?}, {mode:?}: worst difference target vs host: {worst} f32 ulp, \
             {:.0} instructions per field + gradient",
            run.instructions_per_point()
        );
        // Bits, not values: +0.0 and −0.0 must not pass for each other.
        assert_eq!(
            sample_bits(&samples),
            sample_bits(&expected),
            "{name}, {scalar:?}, {mode:?}"
        );
        let fields = sim
            .run(&Job {
                op: Op::Field,
                ..job
            })
            .unwrap()
            .values();
        let expected_fields: Vec<f64> = expected.iter().map(|s| s.0).collect();
        let field_bits = |values: &[f64]| values.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            field_bits(&fields),
            field_bits(&expected_fields),
            "{name}, {scalar:?}, field only, {mode:?}"
        );
    }
}

/// A network of `tree` at `width` with every parameter random (no training): each module —
/// node included — normalized by a rotation scaled per axis into [0.5, 2] around a centre in
/// [−0.3, 0.3]³, weights and biases in [−0.6, 0.6] (a node's position columns included).
fn random_network(tree: &str, width: usize, seed: u64) -> ImplicitNetwork {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move |lo: f64, hi: f64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        lo + (hi - lo) * ((state >> 11) as f64 / (1_u64 << 53) as f64)
    };
    let mut network = ImplicitNetwork::new(width, &tree.parse::<TreeSpec>().unwrap()).unwrap();
    for module in 0..network.module_count() {
        let rotation = neurosurf_tests::rotation_from_quaternion([(); 4].map(|()| next(-1.0, 1.0)));
        let normalization = Normalization {
            center: [(); 3].map(|()| next(-0.3, 0.3)),
            matrix: rotation.map(|row| {
                let scale = next(0.5, 2.0);
                row.map(|v| scale * v)
            }),
        };
        network.set_normalization(module, &normalization);
        for p in network.trained_params_mut(module) {
            *p = next(-0.6, 0.6);
        }
    }
    network
}

/// Models with nodes that no training produced — every module with its own normalization,
/// every weight random, a node's position columns included — on the target against the host,
/// bit for bit, in both scalars: field and field + gradient, single points and batches. The
/// node path is portable code (no kernel has its 2N + 3 inputs; its position goes through the
/// leaves' normalization, portable code too) and runs here at N = 9 (beside the
/// leaves' M4F kernels), at N = 4 (a width compiled as a constant) and at N = 6 (a run-time
/// width). The points spread through [−2, 2]³ and reach far outside (saturated neurons).
#[test]
fn random_models_with_nodes_on_the_target_equal_the_host_bit_for_bit() {
    let sim = simulator();
    for (tree, width, seed) in [
        ("((0,1),(2,3))", 9, 1),
        ("((0,1),2)", 4, 2),
        ("(((0,1),2),3)", 6, 3),
    ] {
        let network = random_network(tree, width, seed);
        let mut points = queries(&Shape::Head, seed + 40);
        points.truncate(150);
        points.extend([[40.0, -300.0, 7.5], [-1000.0, 1000.0, 0.0], [0.0; 3]]);
        // The premise: the nodes' positions matter. With their position weights set to zero,
        // the f64 field moves at most points.
        let mut blind = network.clone();
        for module in 0..blind.module_count() {
            if blind.children(module).is_some() {
                let layout = blind.trained_layout(module);
                let params = blind.trained_params_mut(module);
                for j in 0..width {
                    let row = layout.a_weights + j * layout.inputs;
                    params[row + 2 * width..row + 2 * width + 3].fill(0.0);
                }
            }
        }
        let moved = points
            .iter()
            .filter(|&&p| (network.eval(p).0 - blind.eval(p).0).abs() > 1e-3)
            .count();
        assert!(
            moved * 10 > points.len() * 8,
            "{tree}: moved at {moved} points"
        );
        for (scalar, precision) in [
            (ScalarKind::F32, Precision::F32),
            (ScalarKind::Q16_16, Precision::Q16),
        ] {
            let bytes = implicit::to_blob(&network, None, scalar).unwrap();
            let name = format!("random {tree} N = {width}");
            assert_runs_equal_host(&sim, &name, &bytes, scalar, precision, &points);
        }
    }
}

#[test]
fn q16_on_the_target_equals_q16_on_the_host_bit_for_bit() {
    assert_target_equals_host(ScalarKind::Q16_16, Precision::Q16, 21);
}

/// Every run ends with the firmware's kernel check: each Q16.16 kernel (3 forward layers, the
/// 9×3 transpose, the chain rule through nine neurons, 2 fused transposes) against the portable
/// loop it replaces, on 5 edge cases and 59 seeded random inputs (`neurosurf_core::kernel_check`).
/// A mismatch ends the run with `Status::KernelMismatch` and the kernel's name in the log.
/// Checked once by dropping the 9×3 transpose's rounding (`adds lo, lo, #32768`): every run then
/// fails with "transposed 9x3 differs from its portable loop in case 5".
#[test]
fn every_kernel_matches_its_portable_loop_on_the_target() {
    let trained = torus();
    let bytes = blob(&trained, ScalarKind::Q16_16);
    let points = as_f32(&queries(&TORUS, 3));
    let job = Job::field_gradient(&bytes, ScalarKind::Q16_16, &points);
    let run = simulator().run(&job).unwrap_or_else(|e| panic!("{e}"));
    let line = run
        .log
        .iter()
        .find(|line| line.contains("kernel check:"))
        .unwrap_or_else(|| panic!("no kernel check in the log:\n{}", run.log.join("\n")));
    assert!(
        line.contains(&format!("{} kernel calls match", 7 * 64)),
        "not every kernel was checked: {line}"
    );
}

/// The Q16.16 transposed kernels' out-of-line saturation, on the target against the host: a
/// torus leaf with every weight at ±1000 and zero biases, queried at its box centre (where
/// every pre-activation is 0, so every slope is a′(0) ≈ 1.144) and next to it. At the centre,
/// back through layer b the nine products of a column all share one sign
/// (W_b[j][i] = ±1000·sign(w_out[j])), so each column sums to about ±1.03·10⁷, far beyond
/// Q16.16's ±32 768, and saturates at the end its sign picks — both ends, alternating by
/// column; the first layer's transpose (about ±2.9·10⁸) then saturates at both ends too. (The
/// 1×9 output transpose multiplies by one slope and cannot.) Points that round to another Q16.16
/// value than the centre's saturate the second layer's activations instead (the forward
/// kernel's clamp to ±10, which covers the table's ends), and points 0.05–0.2 away saturate the
/// first layer's too. Checked once by breaking the transposes' saturated value (`eor … lsr` for
/// `asr`) and once by flipping the clamp's sign: this test then fails.
#[test]
fn q16_kernels_saturate_like_the_host() {
    let mut trained = torus();
    let leaf = trained.network.root();
    // A doubled, so that |x′₀| reaches about twice the Q16.16 range at these points.
    let mut normalization = trained.network.normalization(leaf).unwrap();
    normalization.matrix = normalization.matrix.map(|row| row.map(|a| 2.0 * a));
    trained.network.set_normalization(leaf, &normalization);
    let layout = trained.network.trained_layout(leaf);
    let center = trained.network.normalization(leaf).unwrap().center;
    let params = trained.network.trained_params_mut(leaf);
    let sign = |k: usize| if k % 3 == 1 { -1.0 } else { 1.0 };
    let width = layout.width;
    for j in 0..width {
        params[layout.out_weights + j] = 1000.0 * sign(j);
        for i in 0..width {
            // Columns alternate between all-positive and all-negative products.
            let column = if i % 2 == 0 { 1.0 } else { -1.0 };
            params[layout.b_weights + j * width + i] = 1000.0 * sign(j) * column;
        }
        // Row j of W_a has the sign of δ_a[j] (that of column j above), so the first layer's
        // transpose adds up without cancelling.
        let row = if j % 2 == 0 { 1.0 } else { -1.0 };
        for i in 0..layout.inputs {
            params[layout.a_weights + j * layout.inputs + i] = 1000.0 * row * sign(i);
        }
        params[layout.a_biases + j] = 0.0;
        params[layout.b_biases + j] = 0.0;
    }
    params[layout.out_bias] = 0.0;
    let bytes = blob(&trained, ScalarKind::Q16_16);
    // Sixteen points at the centre and next to it, and four farther out, where the first
    // layer's pre-activations (about 1000·x′) are beyond ±10 too: its clamp runs as well.
    let points: Vec<[f64; 3]> = (0..16)
        .map(|k| f64::from(k) * 1e-6)
        .chain((1..=4).map(|k| f64::from(k) * 0.05))
        .map(|step| [center[0] + step, center[1] - step, center[2] + 0.5 * step])
        .collect();
    let expected = host(&bytes, &points, Precision::Q16);
    // A sanity check that the centre is where the construction puts it: f64, which does not
    // saturate, has a gradient orders of magnitude larger there.
    let length = |g: [f64; 3]| g.iter().map(|c| c * c).sum::<f64>().sqrt();
    let (q16, f64) = (
        length(expected[0].1),
        length(trained.network.eval(points[0]).1),
    );
    assert!(
        f64 > 100.0 * q16 && q16 > 0.0,
        "no saturation: Q16.16 |∇Φ| {q16}, f64 {f64}"
    );
    assert_q16_target_equals(&bytes, &points, &expected);
}

/// The Q16.16 chain rule's fallback in a leaf (the fused 9×9 transpose and `times_slope`, which
/// leaves |δ| ≥ 2¹³ to the portable saturating path), on the target against the host: a torus
/// leaf whose first
/// layer has tiny weights (±0.01 by row) and equal biases (0.5), so at the box centre all nine
/// a-outputs are equal (a(0.5) ≈ 0.55, slope ≈ 1.03); layer b's rows are
/// (+1000, −1000, …, +1000, −500, −500), which cancel on equal inputs (H_b = 0, slope 1.144),
/// while the output weights of 2 make every δ_b ≈ 2.62 and the columns add nine of them to
/// about ±23 600 (columns 0–6) and −11 800 (columns 7 and 8): all nine above the fast range,
/// below saturation, so the fallback changes every δ (by the slope 1.03) and the first layer's
/// transpose carries it into ∇Φ. Checked once by dropping the fallback (the kernel's unchanged
/// δ kept), and once by widening the kernel's δ range: this test then fails.
#[test]
fn q16_slope_kernel_falls_back_like_the_host() {
    let mut trained = torus();
    let leaf = trained.network.root();
    // A doubled, so that |x′₀| reaches about twice the Q16.16 range at these points.
    let mut normalization = trained.network.normalization(leaf).unwrap();
    normalization.matrix = normalization.matrix.map(|row| row.map(|a| 2.0 * a));
    trained.network.set_normalization(leaf, &normalization);
    let layout = trained.network.trained_layout(leaf);
    let center = trained.network.normalization(leaf).unwrap().center;
    let params = trained.network.trained_params_mut(leaf);
    let width = layout.width;
    let alternate = |k: usize| if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    for j in 0..width {
        params[layout.out_weights + j] = 2.0;
        for i in 0..width {
            params[layout.b_weights + j * width + i] = if i + 2 < width {
                1000.0 * alternate(i)
            } else {
                -500.0
            };
        }
        for i in 0..layout.inputs {
            params[layout.a_weights + j * layout.inputs + i] = 0.01 * alternate(j);
        }
        params[layout.a_biases + j] = 0.5;
        params[layout.b_biases + j] = 0.0;
    }
    params[layout.out_bias] = 0.0;
    let bytes = blob(&trained, ScalarKind::Q16_16);
    let points = vec![center; 4];
    let expected = host(&bytes, &points, Precision::Q16);
    // The construction's premise: a gradient of the size the fallback's δ gives (rows of
    // 0.01 × about 24 000 per coordinate).
    let length = expected[0].1.iter().map(|c| c * c).sum::<f64>().sqrt();
    assert!(length > 100.0, "|∇Φ| {length}: the fallback is not reached");
    assert_q16_target_equals(&bytes, &points, &expected);
}

/// The same fallback in the chain-rule kernel that node modules use (`q16_times_slope_9`: their
/// 21-column transposes have no kernel), on the head ((0,1),2). The root's children end in
/// saturated layers b (biases 15, |Σ W·a| < 4), so each child's nine outputs are a(10) in
/// Q16.16 whatever the point, and the root's layer a, with rows (+1000 × 9 on the left child,
/// −1000 × 9 on the right, 0 on its own position x′), sums them to exactly 0 (H = 0, slope
/// 1.144). With the root's layer b at 0.1 and output weights of 2, every δ of the root's layer
/// a is about 2.7, and the transpose hands each child about ±24 000 per neuron: above the fast
/// range, below saturation. The children's slope there is tiny (a′(a(10)) is 2 in Q16.16
/// bits), so the fallback turns 24 000 into about 0.7, which their positive layer-b weights
/// carry down into ∇Φ. Checked by dropping the kernel's mask bit (the unchanged δ kept): this
/// test then fails.
#[test]
fn q16_node_slope_kernel_falls_back_like_the_host() {
    let mut trained = head();
    let root = trained.network.root();
    let (left, right) = trained.network.children(root).unwrap();
    for child in [left, right] {
        let layout = trained.network.trained_layout(child);
        let params = trained.network.trained_params_mut(child);
        let width = layout.width;
        for i in 0..width {
            for k in 0..width {
                params[layout.b_weights + i * width + k] = 0.01 * (i + 1) as f64 + 0.02 * k as f64;
            }
            params[layout.b_biases + i] = 15.0;
        }
    }
    let layout = trained.network.trained_layout(root);
    let params = trained.network.trained_params_mut(root);
    let width = layout.width;
    for j in 0..width {
        for i in 0..layout.inputs {
            let half = match i {
                _ if i < width => 1000.0,
                _ if i < 2 * width => -1000.0,
                // The node's normalized position: not read here.
                _ => 0.0,
            };
            params[layout.a_weights + j * layout.inputs + i] = half;
        }
        params[layout.a_biases + j] = 0.0;
        for k in 0..width {
            params[layout.b_weights + j * width + k] = 0.1;
        }
        params[layout.b_biases + j] = 0.0;
        params[layout.out_weights + j] = 2.0;
    }
    params[layout.out_bias] = 0.0;
    let bytes = blob(&trained, ScalarKind::Q16_16);
    let points: Vec<[f64; 3]> = queries(&Shape::Head, 31).into_iter().take(6).collect();
    let expected = host(&bytes, &points, Precision::Q16);
    // The construction's premise: the fallback's δ reaches ∇Φ.
    let reached = expected
        .iter()
        .any(|(_, g)| g.iter().any(|c| c.abs() > 1e-3));
    assert!(reached, "the fallback's δ does not reach ∇Φ");
    assert_q16_target_equals(&bytes, &points, &expected);
}

/// The Q16.16 input normalization x′ = A·(x − c) where it saturates, on the target against the
/// host: a torus leaf with its A doubled whose first layer reads x′₀ only, with weights
/// 10⁻⁵·(j + 1) (the rest of the leaf passes that layer to Φ), so that
/// at the ends of the Q16.16 range (|x| ≈ 32 768, where x′₀ is clamped to ±32 768) the first
/// layer's pre-activations stay within the activation's range and the clamped x′₀ shows in Φ.
#[test]
fn q16_normalization_saturates_like_the_host() {
    let mut trained = torus();
    let leaf = trained.network.root();
    // A doubled, so that |x′₀| reaches about twice the Q16.16 range at these points.
    let mut normalization = trained.network.normalization(leaf).unwrap();
    normalization.matrix = normalization.matrix.map(|row| row.map(|a| 2.0 * a));
    trained.network.set_normalization(leaf, &normalization);
    let layout = trained.network.trained_layout(leaf);
    let params = trained.network.trained_params_mut(leaf);
    for j in 0..layout.width {
        for i in 0..layout.inputs {
            params[layout.a_weights + j * layout.inputs + i] =
                if i == 0 { 1e-5 * (j + 1) as f64 } else { 0.0 };
        }
        params[layout.a_biases + j] = 0.0;
        // The second layer passes the first through (×0.5), the output sums it: the clamp
        // shows in Φ whatever the training left there.
        for k in 0..layout.width {
            params[layout.b_weights + j * layout.width + k] = if j == k { 0.5 } else { 0.0 };
        }
        params[layout.b_biases + j] = 0.0;
        params[layout.out_weights + j] = 1.0;
    }
    params[layout.out_bias] = 0.0;
    let bytes = blob(&trained, ScalarKind::Q16_16);
    let points = vec![
        [32767.0, -32768.0, 32767.0],
        [-32768.0, 32767.0, -32768.0],
        [32767.0, 32767.0, -32768.0],
        [-20000.0, 30000.0, 25000.0],
    ];
    let expected = host(&bytes, &points, Precision::Q16);
    // The construction's premise: f64, which does not clamp x′, gives another Φ there.
    let differs = points
        .iter()
        .zip(&expected)
        .any(|(&x, q16)| (trained.network.eval(x).0 - q16.0).abs() > 1e-2);
    assert!(differs, "x′ does not saturate at these points");
    assert_q16_target_equals(&bytes, &points, &expected);
}

/// The blob's frame on the target: the torus trained at ×10⁻⁴ (Q16.16 keeps the frame's
/// scale as a run-time shift: its normalization would exceed the parameter bound) and at ×100
/// (a shift that would cost the normalization bits), both moved off the origin, equal the host
/// bit for bit in both scalars. Without the frame, neither stores as Q16.16.
#[test]
fn models_in_other_units_on_the_target_equal_the_host_bit_for_bit() {
    let sim = simulator();
    for (scale, offset) in [(1e-4, [0.3, -0.2, 0.1]), (100.0, [250.0, -300.0, 40.0])] {
        let to_world = |p: [f64; 3]| [0, 1, 2].map(|k| scale * p[k] + offset[k]);
        let mut points = sample_shape(&TORUS, 96, 11).unwrap();
        points.positions = points.positions.iter().map(|&p| to_world(p)).collect();
        let trained = train(points, None);
        let queries: Vec<[f64; 3]> = queries(&TORUS, 5).into_iter().map(to_world).collect();
        for (scalar, precision) in [
            (ScalarKind::Q16_16, Precision::Q16),
            (ScalarKind::F32, Precision::F32),
        ] {
            let bytes = blob(&trained, scalar);
            let name = format!("torus ×{scale}");
            assert_runs_equal_host(&sim, &name, &bytes, scalar, precision, &queries);
        }
    }
}

/// The issue allows 2 ulp; the design gives 0 and this test holds it to that: the f32 path is
/// IEEE `+ − × ÷` in a fixed order on both machines (no fused multiply–add, no libm
/// transcendental), so the M4F's FPU rounds every step exactly like the host.
#[test]
fn f32_on_the_target_equals_the_host_bit_for_bit() {
    assert_target_equals_host(ScalarKind::F32, Precision::F32, 22);
}

#[test]
fn q16_normals_on_the_target_are_within_half_a_degree_of_f64_on_the_torus() {
    let sim = simulator();
    let trained = torus();
    let surface = sample_shape(&TORUS, 1000, 31).unwrap().positions;
    let reference = host(&blob(&trained, ScalarKind::F32), &surface, Precision::F64);
    let bytes = blob(&trained, ScalarKind::Q16_16);
    let run = sim
        .run(&Job::field_gradient(
            &bytes,
            ScalarKind::Q16_16,
            &as_f32(&surface),
        ))
        .unwrap();
    let mut angles: Vec<f64> = run
        .samples()
        .iter()
        .zip(&reference)
        .map(|(q, f)| angle_degrees(q.1, f.1))
        .collect();
    angles.sort_by(f64::total_cmp);
    let median = angles[angles.len() / 2];
    eprintln!("Q16.16 on target vs f64: median normal difference {median:.4}°");
    assert!(median <= 0.5, "median {median}°");
}

#[test]
fn corrupt_truncated_and_foreign_blobs_are_rejected_with_the_cores_error() {
    let sim = simulator();
    let good = blob(&torus(), ScalarKind::F32);
    let mut corrupt = good.clone();
    let middle = corrupt.len() / 2;
    corrupt[middle] ^= 0x40;
    let truncated = good[..good.len() - 7].to_vec();
    let foreign = b"\x89PNG\r\n\x1a\n not a model at all".to_vec();
    let empty = Vec::new();
    // Format version 1 (nodes without normalization), with a consistent CRC.
    let mut version_1 = good.clone();
    version_1[4..6].copy_from_slice(&1_u16.to_le_bytes());
    let body = version_1.len() - 4;
    let crc = neurosurf_core::blob::crc32(&version_1[..body]);
    version_1[body..].copy_from_slice(&crc.to_le_bytes());
    assert_eq!(
        ImplicitModel::<f32>::from_blob(&version_1).unwrap_err(),
        neurosurf_core::BlobError::UnsupportedVersion {
            found: 1,
            supported: neurosurf_core::blob::FORMAT_VERSION
        }
    );
    let points = [[0.5_f32, 0.0, 0.1]];
    for (name, bytes) in [
        ("corrupt", &corrupt),
        ("truncated", &truncated),
        ("foreign", &foreign),
        ("empty", &empty),
        ("version 1", &version_1),
    ] {
        let host_error = ImplicitModel::<f32>::from_blob(bytes).unwrap_err();
        match sim.run(&Job::field_gradient(bytes, ScalarKind::F32, &points)) {
            Err(SimError::BlobRejected { error }) => {
                assert_eq!(error, host_error, "{name}");
            }
            other => panic!("{name}: expected a rejection, got {other:?}"),
        }
    }
}

#[test]
fn bad_requests_panics_and_hangs_end_with_their_codes() {
    let sim = simulator();
    let good = blob(&torus(), ScalarKind::F32);
    let points = [[0.5_f32, 0.0, 0.1]];
    let code = |result: Result<_, SimError>| match result {
        Err(SimError::Firmware { code, .. }) => code,
        other => panic!("expected a firmware failure, got {other:?}"),
    };
    // f64 is a host-only scalar: the target refuses it as a bad request.
    let job = Job::field_gradient(&good, ScalarKind::F64, &points);
    assert_eq!(code(sim.run(&job)), i32::from(Status::BadRequest.code()));
    // A blob larger than the firmware's buffer.
    let huge = vec![0_u8; 64 * 1024];
    let job = Job::field_gradient(&huge, ScalarKind::F32, &points);
    assert_eq!(code(sim.run(&job)), i32::from(Status::BadRequest.code()));
    let job = Job {
        op: Op::SelfTestPanic,
        ..Job::field_gradient(&good, ScalarKind::F32, &points)
    };
    assert_eq!(code(sim.run(&job)), i32::from(Status::Panic.code()));
    let job = Job {
        op: Op::SelfTestHang,
        time_limit: Some(Duration::from_secs(2)),
        ..Job::field_gradient(&good, ScalarKind::F32, &points)
    };
    match sim.run(&job) {
        Err(SimError::Timeout { seconds, log }) => {
            assert_eq!(seconds, 2);
            assert!(
                log.iter().any(|l| l.contains("hanging on purpose")),
                "{log:?}"
            );
        }
        other => panic!("expected a time-out, got {other:?}"),
    }
}

#[test]
fn every_run_reports_its_cost_and_memory() {
    let sim = simulator();
    let bytes = blob(&torus(), ScalarKind::Q16_16);
    let points = as_f32(&queries(&TORUS, 40));
    let run = sim
        .run(&Job::field_gradient(&bytes, ScalarKind::Q16_16, &points))
        .unwrap();
    let model = ImplicitModel::<neurosurf_core::scalar::Q16>::from_blob(&bytes).unwrap();
    let per_point = run.instructions_per_point();
    // An evaluation cannot cost fewer instructions than it has multiply–accumulates.
    assert!(per_point >= model.mac_count(true) as f64, "{per_point}");
    assert_eq!(run.regions.len(), 1 + points.len().div_ceil(64));
    assert!(run.stack_bytes > 0);
    let footprint = sim.firmware().footprint;
    assert!(footprint.flash_bytes > 0 && footprint.flash_bytes < footprint.flash_budget);
    assert!(
        footprint.static_ram_bytes + u64::from(run.stack_bytes) < footprint.ram_budget,
        "{footprint:?}, stack {}",
        run.stack_bytes
    );
    assert!(
        run.log.iter().any(|l| l.contains("evaluated 400 points")),
        "{:?}",
        run.log
    );
}

//! The core's evaluation of models with nodes against the trainer's `f64` reference network
//! (`ImplicitNetwork::eval`, forward-mode tangents, written independently of the core): random
//! networks of several leaves and nodes, every module — node included — with its own
//! non-trivial normalization x′ = A·(x − c) and every weight (a node's position columns
//! included) random, written by the trainer's `to_blob`, read back by its `from_blob` (so the
//! reference sees exactly the stored parameters) and evaluated by the core in `f32` and
//! Q16.16: Φ, ∇Φ and the unit normal of the whole model and of every module's subtree, single
//! points and batches. No training is involved.

use std::path::Path;

use neurosurf_core::implicit::{FieldGradient, ImplicitModel, ModuleKind, SPECIALIZED_WIDTHS};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
use neurosurf_trainer::implicit::{self, ImplicitNetwork, Normalization, TreeSpec};

/// Trees with two to four nodes, of heights 2 to 4.
const TREES: [&str; 3] = ["((0,1),2)", "((0,1),(2,3))", "(((0,1),2),(3,4))"];
/// Widths compiled as constants (4, 9) and run at a run-time width (6, and 16 = the capacity).
const WIDTHS: [usize; 4] = [4, 6, 9, 16];
/// Weights and biases in [−WEIGHT, WEIGHT].
const WEIGHT: f64 = 0.5;
const POINTS: usize = 120;

/// `f32` against the reference, relative to max(1, |Φ|) and max(1, |∇Φ|): a few f32 roundings
/// per neuron and the activation's 3·10⁻⁷ (measured over these models, widest first: Φ
/// 1.4·10⁻⁶, ∇Φ 2.2·10⁻⁶ at N = 16).
const F32_FIELD_TOLERANCE: f64 = 3.0e-6;
const F32_GRADIENT_TOLERANCE: f64 = 5.0e-6;

/// Q16.16 against the reference, absolute, by width: (Φ, each component of ∇Φ). One rounding
/// per neuron and the activation table's 1.25·2⁻¹⁵, propagated through up to four modules of
/// three layers, and, for ∇Φ, through every module's Aᵀ (scales up to 2). Measured maxima over
/// these models and every module (in LSB = 2⁻¹⁶, Φ / ∇Φ): N = 4: 3.7 / 6.1; N = 6: 5.1 / 8.9;
/// N = 9: 6.1 / 12.9; N = 16: 12.8 / 67.3 (printed by the test); tolerances ≈ 2× that. These
/// are integer-exact, so identical on every machine.
fn q16_tolerance(width: usize) -> (f64, f64) {
    let lsb = 1.0 / 65536.0;
    match width {
        0..=4 => (8.0 * lsb, 12.0 * lsb),
        5..=6 => (10.0 * lsb, 18.0 * lsb),
        7..=9 => (12.0 * lsb, 26.0 * lsb),
        _ => (26.0 * lsb, 135.0 * lsb),
    }
}

/// xorshift64: seeded test data.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1_u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }

    /// A point of [−1.2, 1.2]³ on the Q16.16 grid (so exact in f32 and Q16.16 alike).
    fn point(&mut self) -> [f64; 3] {
        [(); 3].map(|()| (self.range(-1.2, 1.2) * 65536.0).round() / 65536.0)
    }
}

/// A rotation (from a random unit quaternion) scaled per axis into [0.5, 2].
fn normalization(rng: &mut Rng) -> Normalization {
    let rotation =
        neurosurf_tests::rotation_from_quaternion([(); 4].map(|()| rng.range(-1.0, 1.0)));
    Normalization {
        center: [(); 3].map(|()| rng.range(-0.3, 0.3)),
        matrix: rotation.map(|row| {
            let scale = rng.range(0.5, 2.0);
            row.map(|v| scale * v)
        }),
    }
}

fn random_network(tree: &str, width: usize, seed: u64) -> ImplicitNetwork {
    let tree: TreeSpec = tree.parse().unwrap();
    let mut network = ImplicitNetwork::new(width, &tree).unwrap();
    let mut rng = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1);
    for module in 0..network.module_count() {
        network.set_normalization(module, &normalization(&mut rng));
        for p in network.trained_params_mut(module) {
            *p = rng.range(-WEIGHT, WEIGHT);
        }
    }
    network
}

/// One random model: the reference as stored in each scalar, and the core's models.
struct Case {
    name: String,
    f32_reference: ImplicitNetwork,
    q16_reference: ImplicitNetwork,
    f32: Box<ImplicitModel<f32>>,
    q16: Box<ImplicitModel<Q16>>,
}

fn cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for (t, tree) in TREES.iter().enumerate() {
        for &width in &WIDTHS {
            for seed in 0..2 {
                let network =
                    random_network(tree, width, 100 * t as u64 + 10 * width as u64 + seed);
                let stored = |scalar| {
                    let bytes = implicit::to_blob(&network, None, scalar).unwrap();
                    let decoded = implicit::from_blob(&bytes, Path::new("random.nsb")).unwrap();
                    (bytes, decoded.network)
                };
                let (f32_bytes, f32_reference) = stored(ScalarKind::F32);
                let (q16_bytes, q16_reference) = stored(ScalarKind::Q16_16);
                cases.push(Case {
                    name: format!("{tree} N = {width} seed {seed}"),
                    f32_reference,
                    q16_reference,
                    f32: Box::new(ImplicitModel::from_blob(&f32_bytes).unwrap()),
                    q16: Box::new(ImplicitModel::from_blob(&q16_bytes).unwrap()),
                });
            }
        }
    }
    cases
}

fn norm(v: [f64; 3]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[test]
fn the_models_have_nodes_with_their_own_normalization_and_position_weights() {
    let cases = cases();
    assert!(WIDTHS.iter().any(|w| !SPECIALIZED_WIDTHS.contains(w)));
    for case in &cases {
        let network = &case.f32_reference;
        let nodes: Vec<usize> = (0..network.module_count())
            .filter(|&m| network.kinds()[m] == ModuleKind::Node)
            .collect();
        assert!(nodes.len() >= 2, "{}", case.name);
        for &m in &nodes {
            let n = network.normalization(m).unwrap();
            assert!(n.center.iter().any(|c| c.abs() > 1e-3), "{}", case.name);
            let layout = network.trained_layout(m);
            let width = network.width();
            assert_eq!(layout.inputs, 2 * width + 3);
            let params = network.trained_params(m);
            let position_weights = (0..width).flat_map(|j| {
                let row = layout.a_weights + j * layout.inputs;
                params[row + 2 * width..row + 2 * width + 3].iter()
            });
            assert!(position_weights.map(|w| w.abs()).sum::<f64>() > 0.1 * width as f64);
        }
        assert_eq!(case.f32.module_count(), network.module_count());
        assert_eq!(case.q16.parameter_count(), network.params().len());
    }
}

#[test]
fn f32_and_q16_match_the_trainers_reference_at_every_module() {
    let mut by_width = std::collections::BTreeMap::new();
    for case in cases() {
        let width = case.f32_reference.width();
        let (field_tolerance, gradient_tolerance) = q16_tolerance(width);
        let worst: &mut [f64; 4] = by_width.entry(width).or_default();
        let mut rng = Rng(7);
        for _ in 0..POINTS {
            let p = rng.point();
            let fp = p.map(|c| c as f32);
            let qp = p.map(Q16::from_num);
            for module in 0..case.f32_reference.module_count() {
                // f32
                let (value, gradient) = case.f32_reference.eval_module(module, p);
                let view = case.f32.module(module).unwrap();
                let fg = view.field_gradient(fp);
                assert_eq!(fg.value.to_bits(), view.field(fp).to_bits());
                let error = (f64::from(fg.value) - value).abs() / value.abs().max(1.0);
                worst[0] = worst[0].max(error);
                assert!(
                    error <= F32_FIELD_TOLERANCE,
                    "{}, module {module}: f32 Φ {} vs {value} at {p:?}",
                    case.name,
                    fg.value
                );
                let scale = norm(gradient).max(1.0);
                for k in 0..3 {
                    let error = (f64::from(fg.gradient[k]) - gradient[k]).abs() / scale;
                    worst[1] = worst[1].max(error);
                    assert!(
                        error <= F32_GRADIENT_TOLERANCE,
                        "{}, module {module}: f32 ∂{k}Φ {} vs {} at {p:?}",
                        case.name,
                        fg.gradient[k],
                        gradient[k]
                    );
                }
                // Q16.16
                let (value, gradient) = case.q16_reference.eval_module(module, p);
                let view = case.q16.module(module).unwrap();
                let qg = view.field_gradient(qp);
                assert_eq!(qg.value, view.field(qp));
                let error = (qg.value.to_f64() - value).abs();
                worst[2] = worst[2].max(error);
                assert!(
                    error <= field_tolerance,
                    "{}, module {module}: Q16 Φ {} vs {value} at {p:?}",
                    case.name,
                    qg.value
                );
                for k in 0..3 {
                    let error = (qg.gradient[k].to_f64() - gradient[k]).abs();
                    worst[3] = worst[3].max(error);
                    assert!(
                        error <= gradient_tolerance,
                        "{}, module {module}: Q16 ∂{k}Φ {} vs {} at {p:?}",
                        case.name,
                        qg.gradient[k],
                        gradient[k]
                    );
                }
            }
            // The whole model is the root's view.
            let root = case.f32_reference.root();
            assert_eq!(
                case.f32.field_gradient(fp),
                case.f32.module(root).unwrap().field_gradient(fp)
            );
        }
    }
    let lsb = 1.0 / 65536.0;
    for (width, worst) in by_width {
        println!(
            "N = {width}, core vs trainer f64: f32 Φ {:.2e}, ∇Φ {:.2e} (relative); \
             Q16 Φ {:.1} LSB, ∇Φ {:.1} LSB",
            worst[0],
            worst[1],
            worst[2] / lsb,
            worst[3] / lsb
        );
    }
}

/// The unit normal, −∇Φ/|∇Φ|, within the angle the gradient tolerances allow.
#[test]
fn normals_match_the_trainers_reference() {
    for case in cases() {
        let (_, gradient_tolerance) = q16_tolerance(case.f32_reference.width());
        let mut rng = Rng(11);
        for _ in 0..40 {
            let p = rng.point();
            let (_, gradient) = case.f32_reference.eval(p);
            let length = norm(gradient);
            if length < 1e-2 {
                continue;
            }
            let expected = gradient.map(|g| -g / length);
            let n = case.f32.normal(p.map(|c| c as f32)).unwrap();
            let (_, q_gradient) = case.q16_reference.eval(p);
            let q_length = norm(q_gradient);
            let q_expected = q_gradient.map(|g| -g / q_length);
            let qn = case.q16.normal(p.map(Q16::from_num)).unwrap();
            for k in 0..3 {
                let f32_tolerance = 4.0 * F32_GRADIENT_TOLERANCE * length.max(1.0) / length;
                assert!(
                    (f64::from(n[k]) - expected[k]).abs() <= f32_tolerance,
                    "{}",
                    case.name
                );
                let q16_tolerance = 4.0 * gradient_tolerance / q_length + 3.0 / 65536.0;
                assert!(
                    (qn[k].to_f64() - q_expected[k]).abs() <= q16_tolerance,
                    "{}",
                    case.name
                );
            }
        }
    }
}

/// Batches (eight lanes where the scalar groups them) equal single points bit for bit, for
/// the model and every module view.
#[test]
fn batches_equal_single_points_bit_for_bit() {
    fn check<S: Scalar>(model: &ImplicitModel<S>, points: &[[S; 3]]) {
        for module in 0..model.module_count() {
            let view = model.module(module).unwrap();
            let mut values = vec![S::ZERO; points.len()];
            view.field_batch(points, &mut values).unwrap();
            let mut jets = vec![FieldGradient::default(); points.len()];
            view.field_gradient_batch(points, &mut jets).unwrap();
            for (i, &p) in points.iter().enumerate() {
                assert_eq!(format!("{:?}", values[i]), format!("{:?}", view.field(p)));
                assert_eq!(
                    format!("{:?}", jets[i]),
                    format!("{:?}", view.field_gradient(p))
                );
            }
        }
    }
    for case in cases() {
        let mut rng = Rng(13);
        let points: Vec<[f64; 3]> = (0..21).map(|_| rng.point()).collect();
        check(
            &case.f32,
            &points
                .iter()
                .map(|p| p.map(|c| c as f32))
                .collect::<Vec<_>>(),
        );
        check(
            &case.q16,
            &points
                .iter()
                .map(|p| p.map(Q16::from_num))
                .collect::<Vec<_>>(),
        );
    }
}

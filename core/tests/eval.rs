//! Evaluation of implicit models against an independent `f64` reference (`common::Reference`,
//! written from the documented layout), in `f32` and Q16.16: field, gradient, normal, batches
//! and module views.
//!
//! Models are random but seeded: trees leaf, (0,1), ((0,1),2) and ((0,1),(2,3)); widths 4 and 9
//! (compiled as constants), 6 and 16 (run-time width, below and at the layer capacity); weights
//! and biases in [−0.5, 0.5], a node's position columns included; every module's (leaf's and
//! node's) normalization A = S·R (a random rotation, then scales in [0.5, 2]), centers in
//! [−0.25, 0.25]³. Every parameter and every query point
//! lies on the Q16.16 grid, so `f32`, Q16.16 and the reference see exactly the same numbers and
//! the comparison measures evaluation error only (no quantization of the model itself).

mod common;

use common::{
    BALANCED_4, LEFT_COMB, PAIR, Reference, Rng, SINGLE_LEAF, TREES, f32_point, model_blob, norm,
    q16_point, random_parameters,
};
use neurosurf_core::LengthMismatch;
use neurosurf_core::implicit::{FieldGradient, ImplicitModel, ModuleKind, ModuleLayout};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

const WIDTHS: [usize; 4] = [4, 6, 9, 16];
const WEIGHT: f64 = 0.5;
/// Random models per (tree, width).
const SEEDS: u64 = 4;
/// Query points per model.
const POINTS: usize = 200;

/// `f32` against the reference: |error| ≤ tolerance·max(1, |exact|) for Φ, and for each
/// component of ∇Φ relative to max(1, |∇Φ|). f32 has a 2⁻²⁴ ≈ 6·10⁻⁸ unit roundoff per operation
/// and the activation error 4·10⁻⁷; measured maxima over all test models: Φ 9.3·10⁻⁷, ∇Φ
/// 1.6·10⁻⁶; tolerances ≈ 2–3× that (the brief's "relative ~1e-5" is met with room to spare).
const F32_FIELD_TOLERANCE: f64 = 2.0e-6;
const F32_GRADIENT_TOLERANCE: f64 = 4.0e-6;

/// Q16.16 against the reference, absolute, by hidden width: (Φ, each component of ∇Φ).
///
/// Where the error comes from: per neuron, one rounding of the Q32.32 accumulator (±2⁻¹⁷), the
/// activation table (ε_a ≤ 1.25·2⁻¹⁵) and, for tangents, the slope (ε_s ≤ 2⁻¹⁴) and one more
/// rounding; an input error δ reaches the next layer as a′(H)·Σ|W|·δ. That worst case is
/// computed point by point by `common::Reference` (a running error analysis) and asserted as a
/// rigorous bound; it is within 3× of the measured error for single width-4 leaves but, because
/// it assumes every error aligns, grows like (1.14·N/4)^layers: up to ~5·10⁴ LSB for the
/// balanced width-16 tree, where it is only a sanity check. Errors of different neurons are in
/// fact nearly independent, so they grow like the rows' 2-norms a′·√(N/12) ≈ 0.7 (N = 4) … 1.3
/// (N = 16) per layer — slowly, and more with width than with depth. The stated tolerances are
/// the measured maxima over the test models (4 seeds × 4 trees × 1 000 points per width, every
/// module's view) with a ≈ 2× margin; Q16.16 arithmetic is integer-exact, so these numbers are
/// identical on every platform. Measured, in LSB (2⁻¹⁶) for Φ / ∇Φ: width 4: 4.6 / 7.2;
/// width 6: 5.9 / 8.4; width 9: 7.0 / 12.8; width 16: 10.8 / 79.5 (at most 0.87 of the
/// propagated bound). The nodes' position inputs (format version 2) add their own share of
/// ∇Φ, through their A (scales up to 2) and 2N + 3 inputs: the widest nodes' gradients carry
/// the most rounding (before them, width 16 measured 29.2 LSB).
fn q16_tolerance(width: usize) -> (f64, f64) {
    let lsb = common::LSB;
    match width {
        0..=4 => (10.0 * lsb, 15.0 * lsb),
        5..=9 => (14.0 * lsb, 28.0 * lsb),
        _ => (24.0 * lsb, 160.0 * lsb),
    }
}

struct Case {
    reference: Reference,
    f32: ImplicitModel<f32>,
    q16: ImplicitModel<Q16>,
}

/// Every (tree, width, seed) model, loaded from an f32 blob into `f32` and from a Q16.16 blob
/// into Q16.16.
fn cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for (t, tree) in TREES.iter().enumerate() {
        for &width in &WIDTHS {
            for seed in 0..SEEDS {
                let mut rng = Rng::new(1000 * t as u64 + 10 * width as u64 + seed);
                let params = random_parameters(&mut rng, tree, width, WEIGHT);
                let f32_blob = model_blob(ScalarKind::F32, width, tree, &params);
                let q16_blob = model_blob(ScalarKind::Q16_16, width, tree, &params);
                cases.push(Case {
                    reference: Reference::new(width, tree, &params),
                    f32: ImplicitModel::from_blob(&f32_blob).unwrap(),
                    q16: ImplicitModel::from_blob(&q16_blob).unwrap(),
                });
            }
        }
    }
    cases
}

fn to_f64<S: Scalar>(v: [S; 3]) -> [f64; 3] {
    v.map(S::to_f64)
}

#[test]
fn reference_gradient_matches_central_differences() {
    let step = 1.0e-5;
    let mut worst = 0.0_f64;
    for case in cases() {
        let r = &case.reference;
        let mut rng = Rng::new(7);
        for _ in 0..10 {
            let p = rng.point();
            for module in 0..r.tree.len() {
                let (_, gradient) = r.eval_module(module, p);
                for k in 0..3 {
                    let (mut plus, mut minus) = (p, p);
                    plus[k] += step;
                    minus[k] -= step;
                    let fd = (r.eval_module(module, plus).0 - r.eval_module(module, minus).0)
                        / (2.0 * step);
                    let error = (fd - gradient[k]).abs();
                    worst = worst.max(error);
                    // Truncation error h²/6·|Φ‴| plus rounding ε/h: both ≲ 1e-9 here.
                    assert!(
                        error <= 1.0e-8 * (1.0 + gradient[k].abs()),
                        "module {module} ∂{k}: analytic {} vs finite difference {fd}",
                        gradient[k]
                    );
                }
            }
        }
    }
    println!("reference ∇Φ vs central differences: max |error| {worst:.2e}");
}

/// The core's reverse mode against central differences of the reference's Φ (not its
/// analytic gradient), for every module view of every model, in `f32` and Q16.16: a node's
/// share of ∇Φ through its own position, like a leaf's, must come back down the transposed
/// pass. Central differences of the smooth f64 Φ are exact to ~1e-9 here (see above).
#[test]
fn reverse_mode_gradient_matches_central_differences() {
    let step = 1.0e-5;
    let mut worst = [0.0_f64; 2];
    for case in cases() {
        let r = &case.reference;
        let (_, q16_gradient_tolerance) = q16_tolerance(r.width);
        let mut rng = Rng::new(19);
        for _ in 0..10 {
            let p = rng.point();
            for module in 0..r.tree.len() {
                let fg = case
                    .f32
                    .module(module)
                    .unwrap()
                    .field_gradient(f32_point(p));
                let qg = case
                    .q16
                    .module(module)
                    .unwrap()
                    .field_gradient(q16_point(p));
                let fd: [f64; 3] = std::array::from_fn(|k| {
                    let (mut plus, mut minus) = (p, p);
                    plus[k] += step;
                    minus[k] -= step;
                    (r.eval_module(module, plus).0 - r.eval_module(module, minus).0) / (2.0 * step)
                });
                let scale = norm(fd).max(1.0);
                for k in 0..3 {
                    let error = (f64::from(fg.gradient[k]) - fd[k]).abs();
                    worst[0] = worst[0].max(error / scale);
                    assert!(
                        error <= F32_GRADIENT_TOLERANCE * scale + 1.0e-8,
                        "f32 module {module} ∂{k}Φ {} vs finite difference {} at {p:?}",
                        fg.gradient[k],
                        fd[k]
                    );
                    let error = (qg.gradient[k].to_f64() - fd[k]).abs();
                    worst[1] = worst[1].max(error);
                    assert!(
                        error <= q16_gradient_tolerance + 1.0e-8,
                        "Q16 module {module} ∂{k}Φ {} vs finite difference {} at {p:?}",
                        qg.gradient[k],
                        fd[k]
                    );
                }
            }
        }
    }
    println!(
        "core ∇Φ vs central differences: f32 {:.2e} (rel), Q16 {:.2e} ({:.1} LSB)",
        worst[0],
        worst[1],
        worst[1] / common::LSB
    );
}

/// A node's normalized position is an input that matters: with the position columns of every
/// node's a′ set to zero, the reference's Φ and ∇Φ move far beyond the tolerances at almost
/// every point, and the core follows the full model. (So the comparisons above would catch a
/// core that ignored the node's position, or the node's share of ∇Φ.)
#[test]
fn node_position_inputs_reach_the_field_and_its_gradient() {
    let mut checked = 0;
    for case in cases().iter().filter(|c| c.reference.tree.len() > 1) {
        let r = &case.reference;
        let width = r.width;
        let node = ModuleLayout::new(ModuleKind::Node, width);
        assert_eq!(node.hidden_a.inputs, 2 * width + 3);
        let mut blind = r.params.clone();
        for (&code, &offset) in r.tree.iter().zip(&common::offsets(&r.tree, width)) {
            if common::kind(code) == ModuleKind::Node {
                for row in 0..width {
                    let start = offset + node.hidden_a.weights + row * node.hidden_a.inputs;
                    blind[start + 2 * width..start + 2 * width + 3].fill(0.0);
                }
            }
        }
        let blind = Reference::new(width, &r.tree, &blind);
        let (field_tolerance, gradient_tolerance) = q16_tolerance(width);
        let mut rng = Rng::new(23);
        let (mut field_moved, mut gradient_moved) = (0, 0);
        for _ in 0..50 {
            let p = rng.point();
            let (value, gradient) = r.eval(p);
            let (blind_value, blind_gradient) = blind.eval(p);
            if (value - blind_value).abs() > 10.0 * field_tolerance {
                field_moved += 1;
            }
            if (0..3).any(|k| (gradient[k] - blind_gradient[k]).abs() > 10.0 * gradient_tolerance) {
                gradient_moved += 1;
            }
            // Both paths: the field alone (`eval.rs`) and with the gradient (`reverse.rs`).
            let fg = case.f32.field_gradient(f32_point(p));
            for phi in [fg.value, case.f32.field(f32_point(p))] {
                assert!(
                    (f64::from(phi) - value).abs() <= F32_FIELD_TOLERANCE * value.abs().max(1.0)
                );
            }
            let q = case.q16.field_gradient(q16_point(p));
            for phi in [q.value, case.q16.field(q16_point(p))] {
                assert!((phi.to_f64() - value).abs() <= field_tolerance);
            }
            for k in 0..3 {
                assert!((q.gradient[k].to_f64() - gradient[k]).abs() <= gradient_tolerance);
            }
        }
        assert!(field_moved >= 45, "Φ moved at {field_moved} of 50 points");
        assert!(
            gradient_moved >= 45,
            "∇Φ moved at {gradient_moved} of 50 points"
        );
        checked += 1;
    }
    assert_eq!(checked, 3 * WIDTHS.len() * SEEDS as usize);
}

/// The reference itself is not trivial: its fields vary and its gradients do not vanish, so
/// the comparisons below test something.
#[test]
fn reference_models_are_not_degenerate() {
    for case in cases() {
        let r = &case.reference;
        let mut rng = Rng::new(3);
        let samples: Vec<(f64, [f64; 3])> = (0..50).map(|_| r.eval(rng.point())).collect();
        let (lo, hi) = samples.iter().fold((f64::MAX, f64::MIN), |(lo, hi), s| {
            (lo.min(s.0), hi.max(s.0))
        });
        assert!(hi - lo > 1.0e-3, "field is nearly constant: {lo}..{hi}");
        assert!(samples.iter().any(|s| norm(s.1) > 1.0e-2));
    }
}

#[test]
fn f32_and_q16_match_the_reference() {
    let mut worst = [0.0_f64; 4];
    let mut bound_ratio = 0.0_f64;
    for case in cases() {
        let r = &case.reference;
        let mut rng = Rng::new(11);
        for _ in 0..POINTS {
            let p = rng.point();
            let (value, gradient, value_bound, gradient_bound) = r.eval_module_bounded(r.root(), p);

            let fg = case.f32.field_gradient(f32_point(p));
            assert_eq!(fg.value.to_bits(), case.f32.field(f32_point(p)).to_bits());
            let field_error = (f64::from(fg.value) - value).abs() / value.abs().max(1.0);
            assert!(
                field_error <= F32_FIELD_TOLERANCE,
                "f32 Φ {} vs {value} at {p:?}",
                fg.value
            );
            worst[0] = worst[0].max(field_error);
            let scale = norm(gradient).max(1.0);
            for k in 0..3 {
                let error = (f64::from(fg.gradient[k]) - gradient[k]).abs() / scale;
                assert!(
                    error <= F32_GRADIENT_TOLERANCE,
                    "f32 ∂{k}Φ {} vs {} at {p:?}",
                    fg.gradient[k],
                    gradient[k]
                );
                worst[1] = worst[1].max(error);
            }

            let (field_tolerance, gradient_tolerance) = q16_tolerance(r.width);
            let q = case.q16.field_gradient(q16_point(p));
            assert_eq!(q.value, case.q16.field(q16_point(p)));
            let error = (q.value.to_f64() - value).abs();
            assert!(
                error <= value_bound,
                "Q16 Φ error {error} beyond its propagated bound {value_bound} at {p:?}"
            );
            assert!(
                error <= field_tolerance,
                "Q16 Φ {} vs {value} at {p:?}",
                q.value
            );
            worst[2] = worst[2].max(error);
            bound_ratio = bound_ratio.max(error / value_bound);
            for k in 0..3 {
                let error = (q.gradient[k].to_f64() - gradient[k]).abs();
                assert!(
                    error <= gradient_bound[k],
                    "Q16 ∂{k}Φ error {error} beyond its propagated bound {} at {p:?}",
                    gradient_bound[k]
                );
                assert!(
                    error <= gradient_tolerance,
                    "Q16 ∂{k}Φ {} vs {} at {p:?}",
                    q.gradient[k],
                    gradient[k]
                );
                worst[3] = worst[3].max(error);
                bound_ratio = bound_ratio.max(error / gradient_bound[k]);
            }
        }
    }
    println!(
        "max errors: f32 Φ {:.2e} (rel), f32 ∇Φ {:.2e} (rel), Q16 Φ {:.2e} ({:.1} LSB), \
         Q16 ∇Φ {:.2e} ({:.1} LSB); largest error / propagated bound {bound_ratio:.3}",
        worst[0],
        worst[1],
        worst[2],
        worst[2] / common::LSB,
        worst[3],
        worst[3] / common::LSB
    );
}

/// Every module view evaluates its subtree: against the reference of that module, and bit for
/// bit like a stand-alone model made of the subtree's parameters (for a leaf: the leaf alone).
#[test]
fn module_views_evaluate_subtrees() {
    for case in cases() {
        let r = &case.reference;
        let count = r.tree.len();
        assert_eq!(case.f32.module_count(), count);
        assert!(case.f32.module(count).is_none());
        assert!(case.q16.module(count).is_none());
        assert_eq!(case.f32.view().index(), r.root());
        for module in 0..count {
            let view = case.f32.module(module).unwrap();
            let qview = case.q16.module(module).unwrap();
            assert_eq!(view.index(), module);
            let sub = r.subtree(module);
            let width = r.width;
            let f32_alone: ImplicitModel<f32> = ImplicitModel::from_blob(&model_blob(
                ScalarKind::F32,
                width,
                &sub.tree,
                &sub.params,
            ))
            .unwrap();
            let q16_alone: ImplicitModel<Q16> = ImplicitModel::from_blob(&model_blob(
                ScalarKind::Q16_16,
                width,
                &sub.tree,
                &sub.params,
            ))
            .unwrap();
            if r.tree[module] == 0 {
                assert_eq!(case.f32.module_kind(module), Some(ModuleKind::Leaf));
                assert_eq!(sub.tree, [0]);
                assert_eq!(case.f32.children(module), None);
            } else {
                let left = r.subtree_start(module - 1).checked_sub(1).unwrap();
                assert_eq!(case.f32.children(module), Some((left, module - 1)));
            }
            let (field_tolerance, gradient_tolerance) = q16_tolerance(width);
            let mut rng = Rng::new(5);
            for _ in 0..40 {
                let p = rng.point();
                let (value, gradient) = r.eval_module(module, p);
                let (fp, qp) = (f32_point(p), q16_point(p));
                let fg = view.field_gradient(fp);
                assert_eq!(fg, f32_alone.field_gradient(fp));
                assert_eq!(view.field(fp).to_bits(), f32_alone.field(fp).to_bits());
                assert!((f64::from(fg.value) - value).abs() <= F32_FIELD_TOLERANCE);
                let scale = norm(gradient).max(1.0);
                for k in 0..3 {
                    assert!(
                        (f64::from(fg.gradient[k]) - gradient[k]).abs()
                            <= F32_GRADIENT_TOLERANCE * scale
                    );
                }
                let qg = qview.field_gradient(qp);
                assert_eq!(qg, q16_alone.field_gradient(qp));
                assert_eq!(qview.field(qp), q16_alone.field(qp));
                assert!((qg.value.to_f64() - value).abs() <= field_tolerance);
                for k in 0..3 {
                    assert!((qg.gradient[k].to_f64() - gradient[k]).abs() <= gradient_tolerance);
                }
            }
        }
        // The root's view is the model.
        let p = [0.125, -0.5, 0.25];
        let root = case.f32.module(r.root()).unwrap();
        assert_eq!(root.field_gradient(p), case.f32.field_gradient(p));
    }
}

/// f64 unit vector of −g.
fn unit_normal(g: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(g);
    (n > 0.0).then(|| g.map(|x| -x / n))
}

/// Perturbing v by δ (|δᵢ| ≤ t per component) moves v/|v| by at most 2|δ|/|v| ≤ 2√3·t/|v|.
fn direction_tolerance(component_tolerance: f64, length: f64) -> f64 {
    2.0 * 3.0_f64.sqrt() * component_tolerance / length
}

#[test]
fn normal_is_the_normalized_negative_gradient() {
    let (mut worst_f32, mut worst_q16, mut worst_ref) = (0.0_f64, 0.0_f64, 0.0_f64);
    for case in cases() {
        let mut rng = Rng::new(13);
        let (_, q16_gradient_tolerance) = q16_tolerance(case.reference.width);
        for _ in 0..50 {
            let p = rng.point();
            // f32: against the normalized gradient of the same evaluation (measured 1.1·10⁻⁷:
            // a few roundings of numbers ≤ 1).
            let fg = case.f32.field_gradient(f32_point(p));
            let n = case.f32.normal(f32_point(p)).unwrap();
            assert_eq!(Some(n), fg.normal());
            let expected = unit_normal(to_f64(fg.gradient)).unwrap();
            for k in 0..3 {
                let e = (f64::from(n[k]) - expected[k]).abs();
                worst_f32 = worst_f32.max(e);
                assert!(e <= 2.5e-7, "f32 normal {n:?} vs {expected:?}");
            }
            let length: f64 = f64::from(n.iter().map(|x| x * x).sum::<f32>());
            assert!((length - 1.0).abs() <= 1.0e-6);
            // Q16.16: against the normalized Q16.16 gradient (measured 1.5 LSB: scaling by the
            // largest component, sqrt and reciprocal each round once).
            let qg = case.q16.field_gradient(q16_point(p));
            let qn = case.q16.normal(q16_point(p)).unwrap();
            assert_eq!(Some(qn), qg.normal());
            let expected = unit_normal(to_f64(qg.gradient)).unwrap();
            for k in 0..3 {
                let e = (qn[k].to_f64() - expected[k]).abs();
                worst_q16 = worst_q16.max(e);
                assert!(e <= 3.0 * common::LSB, "Q16 normal {qn:?} vs {expected:?}");
            }
            // Both against the reference normal, within what the gradient tolerances imply.
            let (_, gradient) = case.reference.eval(p);
            let reference = unit_normal(gradient).unwrap();
            let length = norm(gradient);
            let f32_tolerance =
                direction_tolerance(F32_GRADIENT_TOLERANCE * length.max(1.0), length);
            let q16_tolerance =
                direction_tolerance(q16_gradient_tolerance, length) + 3.0 * common::LSB;
            for k in 0..3 {
                let e = (qn[k].to_f64() - reference[k]).abs();
                worst_ref = worst_ref.max(e * length);
                assert!(
                    e <= q16_tolerance,
                    "Q16 normal {qn:?} vs reference {reference:?}"
                );
                assert!((f64::from(n[k]) - reference[k]).abs() <= f32_tolerance);
            }
        }
    }
    println!(
        "normal max |error|: f32 {worst_f32:.2e}, Q16 {worst_q16:.2e} ({:.1} LSB), \
         Q16 vs reference × |∇Φ| {worst_ref:.2e}",
        worst_q16 / common::LSB
    );
}

/// A model whose output weights are all zero has Φ = a(bias) everywhere and ∇Φ = 0 exactly:
/// no normal.
#[test]
fn normal_is_none_for_a_zero_gradient() {
    for tree in [SINGLE_LEAF, PAIR] {
        let width = 4;
        let mut rng = Rng::new(99);
        let mut params = random_parameters(&mut rng, tree, width, WEIGHT);
        let offsets = common::offsets(tree, width);
        let root = tree.len() - 1;
        let layout = neurosurf_core::implicit::ModuleLayout::new(common::kind(tree[root]), width);
        for w in &mut params[offsets[root] + layout.output.weights..][..width] {
            *w = 0.0;
        }
        let f32_model: ImplicitModel<f32> =
            ImplicitModel::from_blob(&model_blob(ScalarKind::F32, width, tree, &params)).unwrap();
        let q16_model: ImplicitModel<Q16> =
            ImplicitModel::from_blob(&model_blob(ScalarKind::Q16_16, width, tree, &params))
                .unwrap();
        for _ in 0..20 {
            let p = rng.point();
            let fg = f32_model.field_gradient(f32_point(p));
            assert_eq!(fg.gradient, [0.0; 3]);
            assert_eq!(f32_model.normal(f32_point(p)), None);
            assert_eq!(fg.normal(), None);
            let qg = q16_model.field_gradient(q16_point(p));
            assert_eq!(qg.gradient, [Q16::ZERO; 3]);
            assert_eq!(q16_model.normal(q16_point(p)), None);
        }
    }
    assert_eq!(FieldGradient::<f32>::default().normal(), None);
    assert_eq!(FieldGradient::<Q16>::default().normal(), None);
    // A tiny but nonzero Q16.16 gradient: from 4 LSB (2⁻¹⁴) up it has its exact direction.
    // Below that `normalize3` may report None (the reciprocal of a 1- or 2-LSB component,
    // 2³²/b in Q16.16 bits, does not fit: the documented "underflow" case) but never a wrong
    // direction.
    for bits in 1..=64 {
        for axis in 0..3 {
            let mut gradient = [Q16::ZERO; 3];
            gradient[axis] = Q16::from_bits(bits);
            let tiny = FieldGradient {
                value: Q16::ZERO,
                gradient,
            };
            let mut expected = [Q16::ZERO; 3];
            expected[axis] = -Q16::ONE;
            match tiny.normal() {
                Some(n) => assert_eq!(n, expected, "gradient {bits} LSB along {axis}"),
                None => assert!(bits < 4, "no normal for a {bits}-LSB gradient"),
            }
        }
    }
}

const BATCH_LENGTHS: [usize; 9] = [0, 1, 7, 8, 9, 31, 32, 33, 65];

fn batch_matches_single<S: Scalar>(model: &ImplicitModel<S>, points: &[[S; 3]]) {
    let views: Vec<_> = (0..model.module_count())
        .map(|i| model.module(i).unwrap())
        .collect();
    for &len in &BATCH_LENGTHS {
        let points = &points[..len];
        let mut values = vec![S::ONE; len];
        model.field_batch(points, &mut values).unwrap();
        let mut jets = vec![FieldGradient::default(); len];
        model.field_gradient_batch(points, &mut jets).unwrap();
        for (i, &p) in points.iter().enumerate() {
            // PartialEq on f32 would accept 0.0 == −0.0; compare exact representations.
            assert_eq!(format!("{:?}", values[i]), format!("{:?}", model.field(p)));
            assert_eq!(
                format!("{:?}", jets[i]),
                format!("{:?}", model.field_gradient(p)),
                "point {i} of {len}"
            );
        }
        for view in &views {
            let mut values = vec![S::ONE; len];
            view.field_batch(points, &mut values).unwrap();
            let mut jets = vec![FieldGradient::default(); len];
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
}

#[test]
fn batches_are_bit_identical_to_single_points() {
    for case in cases().iter().step_by(3) {
        let mut rng = Rng::new(17);
        let mut points: Vec<[f64; 3]> = (0..65).map(|_| rng.point()).collect();
        // Some points far outside the box (saturated neurons) in the mix, in the first and
        // in a later lane group of eight and of 32.
        points[5] = [40.0, -300.0, 7.5];
        points[20] = [-1000.0, 1000.0, 0.0];
        points[47] = [3.0e4, 0.5, -2.0e4];
        let f32_points: Vec<[f32; 3]> = points.iter().map(|&p| f32_point(p)).collect();
        let mut f32_exact: Vec<[f32; 3]> = f32_points.clone();
        // Values not on the Q16.16 grid for f32.
        f32_exact[3] = [0.1, 1.0e-30, -0.3];
        batch_matches_single(&case.f32, &f32_points);
        batch_matches_single(&case.f32, &f32_exact);
        let q16_points: Vec<[Q16; 3]> = points.iter().map(|&p| q16_point(p)).collect();
        batch_matches_single(&case.q16, &q16_points);
    }
}

#[test]
fn batches_reject_mismatched_lengths() {
    let cases = cases();
    let case = &cases[cases.len() - 1];
    let points = [[0.5_f32; 3]; 9];
    for (inputs, outputs) in [(9, 8), (8, 9), (0, 1), (1, 0), (9, 0), (3, 2)] {
        let mut values = vec![42.0_f32; outputs];
        assert_eq!(
            case.f32.field_batch(&points[..inputs], &mut values),
            Err(LengthMismatch { inputs, outputs })
        );
        assert!(values.iter().all(|&v| v == 42.0), "nothing is written");
        let sentinel = FieldGradient {
            value: 42.0_f32,
            gradient: [1.0, 2.0, 3.0],
        };
        let mut jets = vec![sentinel; outputs];
        assert_eq!(
            case.f32.field_gradient_batch(&points[..inputs], &mut jets),
            Err(LengthMismatch { inputs, outputs })
        );
        assert!(jets.iter().all(|&j| j == sentinel));
        let view = case.f32.module(0).unwrap();
        assert_eq!(
            view.field_batch(&points[..inputs], &mut values),
            Err(LengthMismatch { inputs, outputs })
        );
        assert_eq!(
            view.field_gradient_batch(&points[..inputs], &mut jets),
            Err(LengthMismatch { inputs, outputs })
        );
        let qpoints = [[Q16::ONE; 3]; 9];
        let mut qvalues = vec![Q16::ONE; outputs];
        assert_eq!(
            case.q16.field_batch(&qpoints[..inputs], &mut qvalues),
            Err(LengthMismatch { inputs, outputs })
        );
        let mut qjets = vec![FieldGradient::<Q16>::default(); outputs];
        assert_eq!(
            case.q16
                .field_gradient_batch(&qpoints[..inputs], &mut qjets),
            Err(LengthMismatch { inputs, outputs })
        );
        assert!(qvalues.iter().all(|&v| v == Q16::ONE));
    }
}

/// Inputs far outside the box, at the ends of the Q16.16 range, or not finite: evaluation
/// still returns (Q16.16 saturates; Φ is an activation, so |Φ| < 1.7159).
#[test]
fn extreme_inputs_saturate_without_panicking() {
    let amplitude = neurosurf_core::scalar::ACTIVATION_AMPLITUDE;
    let extremes = [
        Q16::MIN,
        Q16::MAX,
        Q16::ZERO,
        Q16::from_bits(-1),
        Q16::from_num(1000),
    ];
    for case in cases()
        .iter()
        .filter(|c| c.reference.tree == BALANCED_4 || c.reference.tree == LEFT_COMB)
    {
        for &x in &extremes {
            for &y in &extremes {
                for &z in &[Q16::MIN, Q16::MAX, Q16::ZERO] {
                    let fg = case.q16.field_gradient([x, y, z]);
                    assert!(fg.value.to_f64().abs() < amplitude);
                    let _ = case.q16.normal([x, y, z]);
                }
            }
        }
        for p in [
            [f32::NAN, 0.0, 0.0],
            [f32::INFINITY, f32::NEG_INFINITY, 0.0],
            [f32::MAX, f32::MIN, 1.0e-40],
        ] {
            let fg = case.f32.field_gradient(p);
            assert!(fg.value.is_nan() || f64::from(fg.value).abs() <= amplitude);
            let _ = case.f32.normal(p);
            let q = case.q16.field(p.map(Q16::from_f32_saturating));
            assert!(q.to_f64().abs() < amplitude);
        }
    }
}

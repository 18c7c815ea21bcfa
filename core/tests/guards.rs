//! Sign guards in a blob: they load in both scalars, add their bump to the whole model's Φ
//! and ∇Φ (not to a subtree's), and malformed guards are refused by name.

use neurosurf_core::BlobError;
use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::implicit::{
    GUARD_CODE, GUARD_LEN, ImplicitModel, ImplicitPayload, MAX_GUARDS, ModuleKind, ModuleLayout,
};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

const WIDTH: usize = 3;

/// A two-leaf model of width 3 with deterministic weights, then `guards` (c, ρ, a each).
fn blob(tree_tail: &[u8], guards: &[[f64; GUARD_LEN]], scalar: ScalarKind) -> Vec<u8> {
    let leaf = ModuleLayout::new(ModuleKind::Leaf, WIDTH).len;
    let node = ModuleLayout::new(ModuleKind::Node, WIDTH).len;
    let mut params: Vec<f64> = (0..2 * leaf + node)
        .map(|i| ((i * 7 % 11) as f64 - 5.0) / 10.0)
        .collect();
    params.extend(guards.iter().flatten());
    let bytes: Vec<u8> = params
        .iter()
        .flat_map(|&p| scalar.encode(p).expect("encodable"))
        .collect();
    let mut tree = vec![0, 0, 1];
    tree.extend_from_slice(tree_tail);
    let payload = ImplicitPayload {
        width: WIDTH as u8,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        tree: &tree,
        parameters: &bytes,
        metadata: &[],
    };
    let mut out = vec![0_u8; 64 * 1024];
    let n = blob::write(ModelKind::Implicit, scalar, &payload, &mut out).expect("fits");
    out.truncate(n);
    out
}

/// The guard's bump by the f64 formula.
fn bump(g: &[f64; GUARD_LEN], p: [f64; 3]) -> f64 {
    let t2: f64 = (0..3).map(|k| ((p[k] - g[k]) * g[3]).powi(2)).sum();
    if t2 >= 1.0 {
        0.0
    } else {
        g[4] * (1.0 - t2).powi(3)
    }
}

const GUARD: [f64; GUARD_LEN] = [0.5, -0.25, 0.25, 2.0, -3.0];

fn check<S: Scalar>(scalar: ScalarKind, tolerance: f64) {
    let plain = ImplicitModel::<S>::from_blob(&blob(&[], &[], scalar)).expect("plain");
    let guarded =
        ImplicitModel::<S>::from_blob(&blob(&[GUARD_CODE], &[GUARD], scalar)).expect("guarded");
    assert_eq!(guarded.guard_count(), 1);
    assert_eq!(plain.guard_count(), 0);
    for p in [
        [0.5, -0.25, 0.25],
        [0.6, -0.1, 0.3],
        [0.5, 0.2, 0.25],
        [2.0, 2.0, 2.0],
    ] {
        let x = p.map(|v: f64| S::from_f32_saturating(v as f32));
        let expected = plain.field(x).to_f64() + bump(&GUARD, p);
        assert!(
            (guarded.field(x).to_f64() - expected).abs() <= tolerance,
            "{p:?}"
        );
        let fg = guarded.field_gradient(x);
        assert_eq!(fg.value, guarded.field(x), "{p:?}");
        // A subtree (the left leaf) never carries the model's guards.
        let leaf = guarded.module(0).expect("leaf");
        assert_eq!(leaf.field(x), plain.module(0).expect("leaf").field(x));
        // The gradient against central differences of the whole field.
        let h = 1e-3;
        for k in 0..3 {
            let (mut a, mut b) = (p, p);
            a[k] += h;
            b[k] -= h;
            let f = |q: [f64; 3]| {
                plain
                    .field(q.map(|v| S::from_f32_saturating(v as f32)))
                    .to_f64()
                    + bump(&GUARD, q)
            };
            let numeric = (f(a) - f(b)) / (2.0 * h);
            assert!(
                (fg.gradient[k].to_f64() - numeric).abs()
                    <= 50.0 * tolerance + 1e-3 * numeric.abs(),
                "{p:?} axis {k}: {} against {numeric}",
                fg.gradient[k].to_f64()
            );
        }
    }
}

#[test]
fn guards_add_their_bump_in_f32_and_q16() {
    check::<f32>(ScalarKind::F32, 1e-5);
    check::<Q16>(ScalarKind::Q16_16, 2e-3);
}

#[test]
fn malformed_guards_are_refused_by_name() {
    let f32_blob = |tail: &[u8], guards: &[[f64; GUARD_LEN]]| blob(tail, guards, ScalarKind::F32);
    // A module after a guard.
    assert_eq!(
        ImplicitModel::<f32>::from_blob(&f32_blob(&[GUARD_CODE, 0], &[GUARD])).unwrap_err(),
        BlobError::InvalidTree { module: 4 }
    );
    // A radius that is not positive.
    let mut flat = GUARD;
    flat[3] = 0.0;
    assert!(matches!(
        ImplicitModel::<f32>::from_blob(&f32_blob(&[GUARD_CODE], &[flat])).unwrap_err(),
        BlobError::ParameterOutOfRange { .. }
    ));
    // A guard code without its parameters.
    assert!(matches!(
        ImplicitModel::<f32>::from_blob(&f32_blob(&[GUARD_CODE], &[])).unwrap_err(),
        BlobError::ShapeMismatch { .. }
    ));
    // More guards than the core holds.
    let codes = vec![GUARD_CODE; MAX_GUARDS + 1];
    let many = vec![GUARD; MAX_GUARDS + 1];
    let bytes = blob(&codes, &many, ScalarKind::F32);
    assert!(matches!(
        ImplicitModel::<f32>::from_blob(&bytes).unwrap_err(),
        BlobError::CapacityExceeded { .. }
    ));
}

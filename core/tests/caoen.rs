//! Cao En networks through the public API: the paper's analytic cases (W = V = the six axis
//! points, Figs. 2 and 3), `f32` and Q16.16 against the `f64` reference, exact normals against
//! finite differences, projections against dot products, and batches against single points.

mod caoen_support;

use caoen_support::{
    LSB, RefNet, Rng, angle, axis_network, dot, f32s, q16s, random_network, unit_vector,
};
use neurosurf_core::caoen::{CaoEnModel, CaoEnPoint};
use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};

fn models(net: &RefNet) -> (CaoEnModel<f32>, CaoEnModel<Q16>) {
    let blob = net.blob(ScalarKind::Q16_16);
    (
        CaoEnModel::from_blob(&blob).unwrap(),
        CaoEnModel::from_blob(&blob).unwrap(),
    )
}

fn f64s<S: Scalar, const N: usize>(v: [S; N]) -> [f64; N] {
    v.map(S::to_f64)
}

fn sphere_points(rng: &mut Rng, count: usize) -> Vec<Vec<f64>> {
    (0..count).map(|_| unit_vector(rng, 3)).collect()
}

fn l1(v: [f64; 3]) -> f64 {
    v.iter().map(|c| c.abs()).sum()
}

/// Every surface point lies behind every other point's tangent plane: the surface bounds a
/// convex solid. Returns the largest violation (y_b − y_a)·n_a over all pairs.
fn convexity_violation(points: &[([f64; 3], [f64; 3])]) -> f64 {
    let mut worst = f64::NEG_INFINITY;
    for (ya, na) in points {
        for (yb, _) in points {
            let d = [yb[0] - ya[0], yb[1] - ya[1], yb[2] - ya[2]];
            worst = worst.max(dot(&d, na));
        }
    }
    worst
}

// ---------------------------------------------------------------------------------------------
// Analytic cases (paper §4, Figs. 2 and 3)

/// Power blending, q = 1: y = x exactly (the unit sphere, the most rounded shape), in both
/// scalars, with the sphere's own normal.
#[test]
fn axis_targets_power_q1_is_the_unit_sphere() {
    let (f, q) = models(&axis_network(0, false, 1.0));
    let mut rng = Rng::new(1);
    let mut worst_normal = 0.0_f64;
    for x in sphere_points(&mut rng, 500) {
        let y: [f32; 3] = f.eval(&f32s::<3>(&x));
        assert_eq!(y, f32s::<3>(&x));
        let z: [Q16; 3] = q.eval(&q16s::<3>(&x));
        assert_eq!(z, q16s::<3>(&x));
        let n = f64s(f.normal(&f32s::<3>(&x)).unwrap());
        worst_normal = worst_normal.max(angle(n, [x[0], x[1], x[2]]));
    }
    assert!(worst_normal < 1e-6, "{worst_normal}");
}

/// Source points with zero coordinates (the six axis points and points of the three great
/// circles between them, where a key's sᵢ = x·wᵢ is exactly 0): the exact normal exists for
/// every blending, normalized or not, in both scalars and in batches, and is the reference's.
/// Power blending's F(s) = s (q = 1) has a kink there; its mean slope keeps the q = 1 sphere's
/// normal x itself, with no zero normal on the circles.
#[test]
fn points_with_zero_coordinates_have_normals_for_every_blending() {
    let mut points: Vec<Vec<f64>> = Vec::new();
    for k in 0..3 {
        for sign in [1.0, -1.0] {
            let mut x = vec![0.0; 3];
            x[k] = sign;
            points.push(x);
        }
    }
    for (a, b) in [(0, 1), (1, 2), (2, 0)] {
        for t in [0.3, 0.785, 2.0, 4.0, 5.5] {
            let mut x = vec![0.0_f64; 3];
            (x[a], x[b]) = (f64::cos(t), f64::sin(t));
            points.push(x);
        }
    }
    // (blending, q): power at its kink, and the smooth exponential and compact forms, with a
    // compact q whose caps overlap (q = 1 makes each key's cap end at the next axis, where
    // the surface has a genuine cusp).
    for (blending, q) in [(0, 1.0), (1, 1.0), (1, 4.0), (2, 0.5)] {
        for normalized in [false, true] {
            let net = axis_network(blending, normalized, q);
            let (f, fixed) = models(&net);
            let what = format!("blending {blending}, q {q}, normalized {normalized}");
            let inputs: Vec<[f32; 3]> = points.iter().map(|x| f32s(x)).collect();
            let mut batch = vec![f.eval_normal(&inputs[0]); inputs.len()];
            f.eval_normal_batch(&inputs, &mut batch).unwrap();
            for (i, x) in points.iter().enumerate() {
                let exact = net
                    .normal(x)
                    .unwrap_or_else(|| panic!("{what}: no reference normal at {x:?}"));
                let n32 = f
                    .normal(&inputs[i])
                    .unwrap_or_else(|| panic!("{what}: no f32 normal at {x:?}"));
                let nq = fixed
                    .normal(&q16s::<3>(x))
                    .unwrap_or_else(|| panic!("{what}: no Q16.16 normal at {x:?}"));
                assert!(angle(f64s(n32), exact) < 1e-5, "{what}, f32 at {x:?}");
                assert!(angle(f64s(nq), exact) < 1e-3, "{what}, Q16.16 at {x:?}");
                assert_eq!(batch[i].normal, Some(n32), "{what}, batch at {x:?}");
                if blending == 0 && !normalized {
                    assert!(angle(exact, [x[0], x[1], x[2]]) < 1e-12, "{what} at {x:?}");
                }
            }
        }
    }
}

/// Power blending, q = 2: |y|₁ = Σ xᵢ² = 1, exactly the octahedron of the targets; q ≥ 2 stays
/// within it (the convex hull of the targets) and gets spikier (smaller mean |y|₁) as q grows.
#[test]
fn axis_targets_power_q2_is_the_octahedron_and_higher_q_stays_inside() {
    let mut rng = Rng::new(2);
    let points = sphere_points(&mut rng, 400);
    let mut previous_mean = f64::INFINITY;
    for q in 2..=6 {
        let net = axis_network(0, false, f64::from(q));
        let (f, fixed) = models(&net);
        let mut mean = 0.0;
        for x in &points {
            // The grid point's |x|² (1 within 2·10⁻⁵): q = 2 gives exactly this |y|₁.
            let bound = dot(x, x);
            let exact = l1(net.position(x).try_into().unwrap());
            let y = l1(f64s(f.eval::<3, 3>(&f32s(x))));
            let z = l1(f64s(fixed.eval::<3, 3>(&q16s(x))));
            assert!(exact <= bound + 1e-12, "q {q}: {exact}");
            assert!(
                (y - exact).abs() < 1e-6 && (z - exact).abs() < 8.0 * LSB,
                "q {q}: {y} {z}"
            );
            if q == 2 {
                assert!((exact - bound).abs() < 1e-12);
            }
            mean += y / points.len() as f64;
        }
        assert!(mean < previous_mean, "q {q}: mean |y|₁ {mean}");
        previous_mean = mean;
    }
}

/// The rational (normalized) form is a convex combination of the targets: with power blending
/// every point lies on the octahedron (|y|₁ = 1) whatever q; with exponential blending it lies
/// inside and approaches the octahedron as q grows (Fig. 3).
#[test]
fn axis_targets_normalized_stay_in_the_convex_hull() {
    let mut rng = Rng::new(3);
    let points = sphere_points(&mut rng, 400);
    for q in 1..=6 {
        let (f, fixed) = models(&axis_network(0, true, f64::from(q)));
        for x in &points {
            let y = l1(f64s(f.eval::<3, 3>(&f32s(x))));
            let z = l1(f64s(fixed.eval::<3, 3>(&q16s(x))));
            assert!((y - 1.0).abs() < 1e-6, "q {q}: {y}");
            assert!((z - 1.0).abs() < 6.0 * LSB, "q {q}: {z}");
        }
    }
    let mut previous_gap = f64::INFINITY;
    for q in [1.0, 2.0, 4.0, 8.0, 16.0] {
        let net = axis_network(1, true, q);
        let (f, fixed) = models(&net);
        let mut gap = 0.0;
        for x in &points {
            let exact = l1(net.position(x).try_into().unwrap());
            let y = l1(f64s(f.eval::<3, 3>(&f32s(x))));
            let z = l1(f64s(fixed.eval::<3, 3>(&q16s(x))));
            assert!(y <= 1.0 + 1e-6 && z <= 1.0 + 6.0 * LSB);
            assert!((y - exact).abs() < 1e-6 && (z - exact).abs() < 16.0 * LSB);
            gap += (1.0 - exact) / points.len() as f64;
        }
        assert!(
            gap < previous_gap,
            "q {q}: mean distance to the octahedron {gap}"
        );
        previous_gap = gap;
    }
    assert!(previous_gap < 0.05);
}

/// Exponential blending: yₖ = 2e^{−q}·sinh(q·xₖ) exactly; for q = 1 a convex rounded shape.
#[test]
fn axis_targets_exponential_matches_the_closed_form() {
    let mut rng = Rng::new(4);
    let points = sphere_points(&mut rng, 300);
    for q in [1.0, 3.0, 16.0] {
        let (f, fixed) = models(&axis_network(1, false, q));
        let mut surface = Vec::new();
        for x in &points {
            let exact: [f64; 3] = std::array::from_fn(|k| 2.0 * (-q).exp() * (q * x[k]).sinh());
            let y = f64s(f.eval::<3, 3>(&f32s(x)));
            let z = f64s(fixed.eval::<3, 3>(&q16s(x)));
            for k in 0..3 {
                assert!((y[k] - exact[k]).abs() < 2e-6, "q {q}: {y:?} {exact:?}");
                assert!(
                    (z[k] - exact[k]).abs() < 4.0 * LSB,
                    "q {q}: {z:?} {exact:?}"
                );
            }
            if q == 1.0 {
                surface.push((y, f64s(f.normal(&f32s::<3>(x)).unwrap())));
            }
        }
        if q == 1.0 {
            let violation = convexity_violation(&surface);
            assert!(violation < 1e-6, "not convex: {violation}");
        }
    }
    // The power q = 1 sphere and the normalized power octahedron are convex too.
    let (f, _) = models(&axis_network(0, false, 1.0));
    let surface: Vec<_> = points
        .iter()
        .map(|x| {
            let y = f64s(f.eval::<3, 3>(&f32s(x)));
            (y, f64s(f.normal(&f32s::<3>(x)).unwrap()))
        })
        .collect();
    assert!(convexity_violation(&surface) < 1e-6);
}

// ---------------------------------------------------------------------------------------------
// Against the f64 reference

/// Random networks (unit weights, targets in [−2, 2]³, the three blendings, both forms, n from
/// 6 to 104) at random sphere points: position errors of f32 and Q16.16, and normal angles.
#[test]
fn random_networks_agree_with_the_reference() {
    let mut rng = Rng::new(5);
    let mut worst = [0.0_f64; 4];
    for trial in 0..36 {
        let n = [6, 26, 104][trial % 3];
        let blending = ((trial / 3) % 3) as u8;
        let normalized = (trial / 9) % 2 == 1;
        let net = random_network(&mut rng, n, (3, 3), blending, normalized, 2.0);
        let (f, fixed) = models(&net);
        // The decoded words are the reference's (all on the Q16.16 grid, below 2⁸).
        assert_eq!(f.key_count(), n);
        for x in sphere_points(&mut rng, 40) {
            let exact = net.position(&x);
            let scale = 1.0 + exact.iter().map(|c| c.abs()).fold(0.0, f64::max);
            let y = f64s(f.eval::<3, 3>(&f32s(&x)));
            let z = f64s(fixed.eval::<3, 3>(&q16s(&x)));
            // The rational form divides by Σ F, made of values rounded to 2⁻¹⁶ in Q16.16:
            // only meaningful where Σ F is well above that (see the accuracy notes).
            let q16_valid = !normalized || net.blend_sum(&x) >= 0.01;
            for k in 0..3 {
                worst[0] = worst[0].max((y[k] - exact[k]).abs() / scale);
                if q16_valid {
                    worst[1] = worst[1].max((z[k] - exact[k]).abs() / LSB);
                }
            }
            // Where the Jacobian is nearly rank 1 (a cusp of the surface) the normal's
            // direction is ill-conditioned in any precision: its error grows like 1/strength.
            let strength = net.normal_strength(&x);
            // In the rational form the Jacobian is (∂A − y ⊗ ∂B)/Σ F: as ill-conditioned as
            // the position where Σ F is tiny.
            if let Some(exact_normal) = net.normal(&x).filter(|_| strength > 1e-3 && q16_valid) {
                let n32 = f64s(f.normal(&f32s::<3>(&x)).unwrap());
                worst[2] = worst[2].max(angle(n32, exact_normal) * strength);
                // Q16.16 normals need the Jacobian well above the resolution.
                if q16_valid && net.jacobian_size(&x) > 0.05 && strength > 0.01 {
                    let nq = fixed
                        .normal(&q16s::<3>(&x))
                        .unwrap_or_else(|| panic!("no Q16 normal at {x:?}, strength {strength}"));
                    worst[3] = worst[3].max(angle(f64s(nq), exact_normal) * strength);
                }
            }
        }
    }
    println!(
        "worst: f32 position {:.2e} (relative), Q16 position {:.1} LSB, normal angle × \
         strength: f32 {:.2e} rad, Q16 {:.2e} rad",
        worst[0], worst[1], worst[2], worst[3]
    );
    assert!(worst[0] < 2e-6, "{worst:?}");
    assert!(worst[1] < 128.0, "{worst:?}");
    assert!(worst[2] < 1e-4, "{worst:?}");
    assert!(worst[3] < 1e-2, "{worst:?}");
}

/// The exact normal (cofactor form in the core, tangent frame in the reference) against
/// central finite differences of positions, on the sphere and on the torus, with orientation.
#[test]
fn exact_normals_match_finite_differences() {
    let mut rng = Rng::new(6);
    let mut worst = 0.0_f64;
    for trial in 0..12 {
        let blending = (trial % 3) as u8;
        let net = random_network(&mut rng, 26, (3, 3), blending, trial >= 6, 1.5);
        let (f, _) = models(&net);
        for x in sphere_points(&mut rng, 50) {
            let (Some(exact), Some(fd)) = (net.normal(&x), net.normal_by_differences(&x, 1e-5))
            else {
                continue;
            };
            assert!(angle(exact, fd) < 1e-3, "reference vs differences");
            let core = f64s(f.normal(&f32s::<3>(&x)).unwrap());
            worst = worst.max(angle(core, fd));
            assert!(angle(core, exact) < 1e-4, "core vs reference");
        }
    }
    // A torus: key points on a 8 × 6 grid of angles mapped to a standard torus (R = 2, r = 0.6).
    let torus = torus_network(8, 6, 4.0);
    let (f, fixed) = models(&torus);
    let mut torus_worst = 0.0_f64;
    for i in 0..40 {
        let (theta, phi) = (0.37 + i as f64 * 0.71, 0.11 + i as f64 * 1.37);
        let x = vec![theta.cos(), theta.sin(), phi.cos(), phi.sin()];
        let fd = torus.normal_by_differences(&x, 1e-5).unwrap();
        let core = f64s(f.normal(&f32s::<4>(&x)).unwrap());
        torus_worst = torus_worst.max(angle(core, fd));
        // Outward: close to the standard torus's own normal there.
        let outward = [theta.cos() * phi.cos(), theta.sin() * phi.cos(), phi.sin()];
        assert!(
            angle(core, outward) < 0.5,
            "torus normal at {i}: {core:?} {outward:?}"
        );
        let q = f64s(fixed.normal(&q16s::<4>(&x)).unwrap());
        assert!(angle(q, fd) < 0.01);
    }
    println!("worst normal angle vs differences: sphere {worst:.2e}, torus {torus_worst:.2e}");
    assert!(worst < 1e-3 && torus_worst < 1e-3);
}

/// Key points on a grid of the torus angles, targets on the standard torus of radii 2, 0.6.
pub fn torus_network(around: usize, across: usize, q: f64) -> RefNet {
    let mut weights = Vec::new();
    let mut targets = Vec::new();
    for i in 0..around {
        for j in 0..across {
            let theta = std::f64::consts::TAU * i as f64 / around as f64;
            let phi = std::f64::consts::TAU * j as f64 / across as f64;
            let w = [theta.cos(), theta.sin(), phi.cos(), phi.sin()];
            weights.push(w.iter().map(|&c| caoen_support::to_grid(c / 2.0)).collect());
            let r = 2.0 + 0.6 * phi.cos();
            targets.push(
                [r * theta.cos(), r * theta.sin(), 0.6 * phi.sin()]
                    .map(caoen_support::to_grid)
                    .to_vec(),
            );
        }
    }
    RefNet {
        domain: 1,
        blending: 1,
        normalized: true,
        sharpness: vec![q; weights.len()],
        weights,
        targets,
    }
}

/// Normals are only defined for sphere (m = 3) and torus networks with p = 3.
#[test]
fn normals_are_undefined_elsewhere() {
    let mut rng = Rng::new(7);
    let hyper = random_network(&mut rng, 10, (4, 3), 1, false, 1.0);
    let (f, _) = models(&hyper);
    let x = unit_vector(&mut rng, 4);
    assert_eq!(f.normal(&f32s::<4>(&x)), None);
    let point = f.eval_normal(&f32s::<4>(&x));
    assert_eq!(point.position, f.eval::<4, 3>(&f32s(&x)));
    let five = random_network(&mut rng, 10, (3, 5), 0, false, 1.0);
    let (f, _) = models(&five);
    assert_eq!(f.normal(&f32s::<3>(&x)), None);
    assert_eq!(CaoEnModel::<f32>::new().normal(&[1.0, 0.0, 0.0]), None);
}

// ---------------------------------------------------------------------------------------------
// Projections (§8)

/// After `project`, the outputs are y·z for each axis: exactly the f64 dot product within
/// rounding, for one axis, a view plane, and five-dimensional targets.
#[test]
fn projections_equal_dot_products() {
    let mut rng = Rng::new(8);
    for (p, normalized) in [(3, false), (3, true), (5, false)] {
        let net = random_network(&mut rng, 26, (3, p), 1, normalized, 2.0);
        let (f, fixed) = models(&net);
        let axes: Vec<Vec<f64>> = (0..2).map(|_| unit_vector(&mut rng, p)).collect();
        let (mut fz, mut qz) = (f.clone(), fixed.clone());
        let mut plane = f.clone();
        fz.project(&[f32s::<5>(&axes[0])]);
        qz.project(&[q16s::<5>(&axes[0])]);
        plane.project(&[f32s::<5>(&axes[0]), f32s::<5>(&axes[1])]);
        assert_eq!((fz.target_dimension(), plane.target_dimension()), (1, 2));
        for x in sphere_points(&mut rng, 50) {
            let y = net.position(&x);
            let exact = [dot(&y, &axes[0]), dot(&y, &axes[1])];
            let full = f64s(f.eval::<3, 5>(&f32s(&x)));
            let [single] = f64s(fz.eval::<3, 1>(&f32s(&x)));
            let screen = f64s(plane.eval::<3, 2>(&f32s(&x)));
            let [fixed_single] = f64s(qz.eval::<3, 1>(&q16s(&x)));
            assert!((single - dot(&full[..p], &axes[0])).abs() < 1e-5);
            assert!((single - exact[0]).abs() < 1e-5 && (screen[1] - exact[1]).abs() < 1e-5);
            assert_eq!(screen[0], single);
            assert!(
                (fixed_single - exact[0]).abs() < 40.0 * LSB,
                "{fixed_single} {exact:?}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Batches

fn batch_identical<S: Scalar>(model: &CaoEnModel<S>, points: &[[S; 3]]) {
    let mut out = vec![[S::ZERO; 3]; points.len()];
    model.eval_batch(points, &mut out).unwrap();
    let mut with_normals = vec![CaoEnPoint::default(); points.len()];
    model.eval_normal_batch(points, &mut with_normals).unwrap();
    for (i, x) in points.iter().enumerate() {
        let y: [S; 3] = model.eval(x);
        assert_eq!(out[i].map(|c| c.to_le_bytes()), y.map(|c| c.to_le_bytes()));
        let single = model.eval_normal(x);
        assert_eq!(with_normals[i], single, "point {i}");
        assert_eq!(single.position, y);
    }
    let mut short = vec![[S::ZERO; 3]; points.len().saturating_sub(1)];
    let e = model.eval_batch(points, &mut short).unwrap_err();
    assert_eq!((e.inputs, e.outputs), (points.len(), short.len()));
}

/// Batches of 8 lanes give the single-point bits, also for a partial last chunk.
#[test]
fn batches_are_bit_identical_to_single_points() {
    let mut rng = Rng::new(9);
    for (blending, normalized) in [
        (0, false),
        (1, false),
        (2, false),
        (0, true),
        (1, true),
        (2, true),
    ] {
        let net = random_network(&mut rng, 26, (3, 3), blending, normalized, 2.0);
        let (f, fixed) = models(&net);
        let points = sphere_points(&mut rng, 37);
        batch_identical(&f, &points.iter().map(|x| f32s(x)).collect::<Vec<_>>());
        batch_identical(&fixed, &points.iter().map(|x| q16s(x)).collect::<Vec<_>>());
    }
}

/// Non-finite inputs give values (NaN propagates in f32), never a panic.
#[test]
fn any_input_evaluates() {
    let mut rng = Rng::new(10);
    for blending in [0, 1, 2] {
        let net = random_network(&mut rng, 12, (3, 3), blending, true, 2.0);
        let (f, fixed) = models(&net);
        for x in [
            [f32::NAN, 0.0, 1.0],
            [f32::INFINITY, -f32::INFINITY, 0.0],
            [1e30, 1e30, -1e30],
            [0.0; 3],
        ] {
            let _: [f32; 3] = f.eval(&x);
            let _ = f.eval_normal(&x);
            let q = x.map(Q16::from_f32_saturating);
            let y: [Q16; 3] = fixed.eval(&q);
            let _ = fixed.eval_normal(&q);
            assert!(y.iter().all(|c| c.abs() <= Q16::MAX));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Compact blending: group skipping

/// 96 key points of a cube sphere (4 × 4 per face) in face order, so that groups of eight
/// consecutive keys are halves of faces, with compact blending (q = 3).
fn banded_compact_network(normalized: bool) -> RefNet {
    let offsets = [-0.75, -0.25, 0.25, 0.75];
    let weights: Vec<Vec<f64>> = (0..96)
        .map(|i| {
            let (face, cell) = (i / 16, i % 16);
            let (axis, sign) = (face / 2, if face % 2 == 0 { 1.0 } else { -1.0 });
            let mut v = [0.0; 3];
            v[axis] = sign;
            v[(axis + 1) % 3] = offsets[cell % 4];
            v[(axis + 2) % 3] = offsets[cell / 4];
            let r = dot(&v, &v).sqrt();
            v.iter().map(|c| caoen_support::to_grid(c / r)).collect()
        })
        .collect();
    let targets = weights
        .iter()
        .map(|w| {
            let bump = 1.0 + 0.3 * w[0] * w[1];
            w.iter().map(|c| caoen_support::to_grid(c * bump)).collect()
        })
        .collect();
    RefNet {
        domain: 0,
        blending: 2,
        normalized,
        weights,
        targets,
        sharpness: vec![3.0; 96],
    }
}

/// Skipping out-of-reach groups changes no bit: in Q16.16 every output and Jacobian entry is
/// an exact integer sum, independent of the key order, so the banded network (whose groups
/// are skipped) and the same keys in an order without locality (rarely skipped) must give
/// the same bits; both agree with the f64 reference.
#[test]
fn compact_group_skipping_changes_no_bit() {
    let mut rng = Rng::new(12);
    for normalized in [false, true] {
        let banded = banded_compact_network(normalized);
        let n = banded.weights.len();
        let order: Vec<usize> = (0..n).map(|i| (i * 41) % n).collect();
        let shuffled = RefNet {
            weights: order.iter().map(|&i| banded.weights[i].clone()).collect(),
            targets: order.iter().map(|&i| banded.targets[i].clone()).collect(),
            sharpness: order.iter().map(|&i| banded.sharpness[i]).collect(),
            ..banded.clone()
        };
        let (f, a) = models(&banded);
        let (_, b) = models(&shuffled);
        for x in sphere_points(&mut rng, 200) {
            let q = q16s::<3>(&x);
            assert_eq!(a.eval_normal(&q), b.eval_normal(&q), "at {x:?}");
            let exact = banded.position(&x);
            let y = f64s(f.eval::<3, 3>(&f32s(&x)));
            for k in 0..3 {
                assert!(
                    (y[k] - exact[k]).abs() < 1e-5,
                    "f32 at {x:?}: {y:?} {exact:?}"
                );
            }
        }
    }
}

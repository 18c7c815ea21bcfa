//! Sign guards: compactly supported bumps that set Φ's sign where the network alone is wrong,
//! away from the data.
//!
//! A small MLP is constrained near its control points only; between them and beyond them it
//! may cross zero and grow surface where there is none. The trainer finds such places on a
//! grid and adds, for each, a guard
//!
//! g(x) = a·(1 − t²)³ with t = ρ·|x − c| (0 for t ≥ 1),
//!
//! whose support (radius 1/ρ) keeps clear of the data by a margin, and whose sign is the side
//! of the surface it lies on. The model's field is the root module's output plus every guard:
//! near the surface, where no guard reaches, Φ and its normals are the network's own.
//!
//! In a blob, each guard is one trailing byte [`GUARD_CODE`] after the module tree and
//! [`GUARD_LEN`] parameters after the modules' parameters: c (3), ρ, a.

use crate::error::BlobError;
use crate::scalar::{Scalar, ScalarKind};

/// The tree byte of a guard (after every module).
pub const GUARD_CODE: u8 = 2;
/// Parameters per guard: center (3), inverse radius ρ, amplitude a.
pub const GUARD_LEN: usize = 5;
/// Most guards a model may hold.
pub const MAX_GUARDS: usize = 256;

/// Splits a blob's tree bytes into the modules and the number of guards after them.
///
/// # Errors
/// [`BlobError::InvalidTree`] for a module code after a guard, or guards without a module.
pub fn split_tree(tree: &[u8]) -> Result<(&[u8], usize), BlobError> {
    let modules = tree
        .iter()
        .position(|&code| code == GUARD_CODE)
        .unwrap_or(tree.len());
    let (modules_part, guards) = tree.split_at(modules);
    if modules == 0 && !guards.is_empty() {
        // Guards without a module to guard.
        return Err(BlobError::InvalidTree { module: 0 });
    }
    match guards.iter().position(|&code| code != GUARD_CODE) {
        Some(wrong) => Err(BlobError::InvalidTree {
            module: modules + wrong,
        }),
        None => Ok((modules_part, guards.len())),
    }
}

/// Adds every guard of `params` (a multiple of [`GUARD_LEN`]) to the values at `points`.
/// `shift` is the model's run-time shift (see `ImplicitModel::input_shift`): the guards'
/// centres are in the caller's units, their radii in the frame's.
#[inline(never)]
pub(crate) fn add_values<S: Scalar, const L: usize>(
    params: &[S],
    points: &[[S; 3]; L],
    values: &mut [S; L],
    shift: i8,
) {
    if run_time::<S>(shift) {
        add_values_shifted::<S, L, true>(params, points, values, shift);
    } else {
        add_values_shifted::<S, L, false>(params, points, values, 0);
    }
}

/// [`add_values`], with the shift compiled in or out.
#[inline(always)]
fn add_values_shifted<S: Scalar, const L: usize, const SHIFTED: bool>(
    params: &[S],
    points: &[[S; 3]; L],
    values: &mut [S; L],
    shift: i8,
) {
    for guard in params.chunks_exact(GUARD_LEN) {
        for (value, point) in values.iter_mut().zip(points) {
            if let Some((u, _)) = inside::<S, SHIFTED>(guard, point, shift) {
                let [.., a] = guard else { continue };
                *value = value.add(a.mul(u.mul(u).mul(u)));
            }
        }
    }
}

/// Adds every guard of `params` to the values and gradients (one array of lanes per axis) at
/// `points`: ∇g = −6·a·ρ·(1 − t²)²·d with d = ρ·(x − c).
#[inline(never)]
pub(crate) fn add_values_gradients<S: Scalar, const L: usize>(
    params: &[S],
    points: &[[S; 3]; L],
    values: &mut [S; L],
    gradients: &mut [[S; L]; 3],
    shift: i8,
) {
    if run_time::<S>(shift) {
        add_values_gradients_shifted::<S, L, true>(params, points, values, gradients, shift);
    } else {
        add_values_gradients_shifted::<S, L, false>(params, points, values, gradients, 0);
    }
}

/// [`add_values_gradients`], with the shift compiled in or out.
#[inline(always)]
fn add_values_gradients_shifted<S: Scalar, const L: usize, const SHIFTED: bool>(
    params: &[S],
    points: &[[S; 3]; L],
    values: &mut [S; L],
    gradients: &mut [[S; L]; 3],
    shift: i8,
) {
    let six = S::from_f32_saturating(6.0);
    for guard in params.chunks_exact(GUARD_LEN) {
        let [.., rho, a] = guard else { continue };
        let mut scale = six.mul(*a).mul(*rho).neg();
        if SHIFTED {
            scale = scale.times_power_of_two(shift);
        }
        for (lane, (value, point)) in values.iter_mut().zip(points).enumerate() {
            if let Some((u, d)) = inside::<S, SHIFTED>(guard, point, shift) {
                let u2 = u.mul(u);
                *value = value.add(a.mul(u2.mul(u)));
                let s = scale.mul(u2);
                for (axis, dk) in gradients.iter_mut().zip(d) {
                    if let Some(g) = axis.get_mut(lane) {
                        *g = g.add(s.mul(dk));
                    }
                }
            }
        }
    }
}

/// Whether a model of scalar `S` applies `shift` at run time (`f32` never does).
#[inline(always)]
fn run_time<S: Scalar>(shift: i8) -> bool {
    S::KIND != ScalarKind::F32 && shift != 0
}

/// (1 − t², ρ·(x − c)·2^`shift`) when `point` is inside the guard's support, else `None`.
#[inline(always)]
fn inside<S: Scalar, const SHIFTED: bool>(
    guard: &[S],
    point: &[S; 3],
    shift: i8,
) -> Option<(S, [S; 3])> {
    let [cx, cy, cz, rho, _] = guard else {
        return None;
    };
    let mut d = [S::ZERO; 3];
    for ((slot, &x), &c) in d.iter_mut().zip(point).zip([cx, cy, cz]) {
        let mut difference = x.sub(c);
        if SHIFTED {
            difference = difference.times_power_of_two(shift);
        }
        *slot = difference.mul(*rho);
        // Outside the bounding cube: also keeps t² within range in fixed point (a NaN
        // coordinate fails the test on t² below).
        if slot.abs() >= S::ONE {
            return None;
        }
    }
    let mut acc = S::ZERO.to_acc();
    for &dk in &d {
        acc = S::mac(acc, dk, dk);
    }
    let t2 = S::from_acc(acc);
    (t2 < S::ONE).then(|| (S::ONE.sub(t2), d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scalar::Q16;

    /// A guard at (1, 2, 3) of radius 0.5 and amplitude 2.
    const GUARD: [f32; GUARD_LEN] = [1.0, 2.0, 3.0, 2.0, 2.0];

    fn reference(p: [f64; 3]) -> (f64, [f64; 3]) {
        let d = [0, 1, 2].map(|k| 2.0 * (p[k] - f64::from(GUARD[k])));
        let t2: f64 = d.iter().map(|v| v * v).sum();
        if t2 >= 1.0 {
            return (0.0, [0.0; 3]);
        }
        let u = 1.0 - t2;
        (2.0 * u * u * u, d.map(|v| -6.0 * 2.0 * 2.0 * u * u * v))
    }

    /// The guard stored with its radius in a frame 2^`shift` times finer than the points
    /// (a model's run-time shift, Q16.16 only), checked against the same reference.
    fn check<S: Scalar>(tolerance: f64, shift: i8) {
        let mut params = GUARD.map(S::from_f32_saturating);
        params[3] = params[3].times_power_of_two(-shift);
        for p in [
            [1.0, 2.0, 3.0],
            [1.2, 2.1, 2.9],
            [1.0, 2.0, 3.45],
            [1.3, 2.3, 3.3],
            [1.6, 2.0, 3.0],
            [-400.0, 2.0, 3.0],
        ] {
            let points = [p.map(|v: f64| S::from_f32_saturating(v as f32))];
            let (mut values, mut gradients) = ([S::ZERO], [[S::ZERO]; 3]);
            add_values_gradients(&params, &points, &mut values, &mut gradients, shift);
            let mut only = [S::ZERO];
            add_values(&params, &points, &mut only, shift);
            let (v, g) = reference(p);
            assert_eq!(only, values, "{p:?}");
            assert!((values[0].to_f64() - v).abs() <= tolerance, "{p:?}");
            for k in 0..3 {
                assert!(
                    (gradients[k][0].to_f64() - g[k]).abs() <= 4.0 * tolerance,
                    "{p:?}"
                );
            }
        }
    }

    #[test]
    fn f32_and_q16_follow_the_f64_reference() {
        check::<f32>(1e-6, 0);
        check::<Q16>(2e-4, 0);
        check::<Q16>(2e-4, 2);
        // The difference x − c loses 3 bits before ρ = 16 multiplies it.
        check::<Q16>(2e-3, -3);
    }
}

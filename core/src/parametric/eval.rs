//! The forward pass: position, and with it the partials ∂p/∂u and ∂p/∂v carried through every
//! neuron (one tangent pair per neuron, forward mode: two inputs make that the cheapest
//! exact way), and the unit normal ∂p/∂u × ∂p/∂v.

use super::model::{MAX_NEURONS, SurfaceNetworkModel};
use crate::error::LengthMismatch;
use crate::lanes;
use crate::scalar::{Scalar, ScalarKind, normalize3};

/// Position, partials and unit normal at one (u, v).
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SurfaceNetworkPoint<S> {
    /// p(u, v).
    pub position: [S; 3],
    /// ∂p/∂u.
    pub du: [S; 3],
    /// ∂p/∂v.
    pub dv: [S; 3],
    /// ∂p/∂u × ∂p/∂v scaled to unit length; `None` where the partials are parallel or vanish.
    pub normal: Option<[S; 3]>,
}

/// One layer's values and, when carried, their partials.
#[derive(Copy, Clone)]
struct Jet<S> {
    value: [S; MAX_NEURONS],
    du: [S; MAX_NEURONS],
    dv: [S; MAX_NEURONS],
}

impl<S: Scalar, const P: usize> SurfaceNetworkModel<S, P> {
    /// p(u, v) (no partials: a third of the work of [`SurfaceNetworkModel::eval`]).
    ///
    /// ```
    /// # use neurosurf_core::parametric::SurfaceNetworkModel;
    /// let empty = SurfaceNetworkModel::<f32>::new();
    /// assert_eq!(empty.position([0.5, 0.5]), [0.0; 3]);
    /// ```
    pub fn position(&self, uv: [S; 2]) -> [S; 3] {
        self.forward::<false>(uv).position
    }

    /// Position, ∂p/∂u, ∂p/∂v and the unit normal at (u, v).
    ///
    /// ```
    /// # use neurosurf_core::parametric::SurfaceNetworkModel;
    /// let empty = SurfaceNetworkModel::<f32>::new();
    /// assert_eq!(empty.eval([0.5, 0.5]).normal, None);
    /// ```
    pub fn eval(&self, uv: [S; 2]) -> SurfaceNetworkPoint<S> {
        let mut point = self.forward::<true>(uv);
        // The normal from the partials in the frame's units, where Q16.16 keeps their bits.
        point.normal = unit_normal(point.du, point.dv);
        if self.runs_shift() {
            let shift = self.output_shift;
            point.du = point.du.map(|v| v.times_power_of_two(shift));
            point.dv = point.dv.map(|v| v.times_power_of_two(shift));
        }
        point
    }

    /// Whether the frame's scale is applied after the output layer (Q16.16 only; `f32` folds
    /// it into s_p at load).
    #[inline(always)]
    fn runs_shift(&self) -> bool {
        S::KIND != ScalarKind::F32 && self.output_shift != 0
    }

    /// The unit normal at (u, v) (see [`SurfaceNetworkModel::eval`]).
    pub fn normal(&self, uv: [S; 2]) -> Option<[S; 3]> {
        self.eval(uv).normal
    }

    /// [`SurfaceNetworkModel::position`] at every `uv` into `out` (same length).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn position_batch(&self, uv: &[[S; 2]], out: &mut [[S; 3]]) -> Result<(), LengthMismatch> {
        lanes::batch(uv, out, [S::ZERO; 2], |lanes| {
            lanes.map(|uv| self.position(uv))
        })
    }

    /// [`SurfaceNetworkModel::eval`] at every `uv` into `out` (same length).
    ///
    /// # Errors
    /// [`LengthMismatch`] when the slices differ in length (nothing is written).
    pub fn eval_batch(
        &self,
        uv: &[[S; 2]],
        out: &mut [SurfaceNetworkPoint<S>],
    ) -> Result<(), LengthMismatch> {
        lanes::batch(uv, out, [S::ZERO; 2], |lanes| lanes.map(|uv| self.eval(uv)))
    }

    /// The forward pass; partials only when `PARTIALS` (else zero), no normal.
    fn forward<const PARTIALS: bool>(&self, [u, v]: [S; 2]) -> SurfaceNetworkPoint<S> {
        let words = self.parameters.as_slice();
        let word = |i: usize| words.get(i).copied().unwrap_or(S::ZERO);
        let mut out = SurfaceNetworkPoint::default();
        if self.hidden.is_empty() {
            return out;
        }
        let (gain_u, gain_v) = (word(2), word(3));
        let mut jet = Jet {
            value: [S::ZERO; MAX_NEURONS],
            du: [S::ZERO; MAX_NEURONS],
            dv: [S::ZERO; MAX_NEURONS],
        };
        jet.value[0] = u.sub(word(0)).mul(gain_u);
        jet.value[1] = v.sub(word(1)).mul(gain_v);
        jet.du[0] = gain_u;
        jet.dv[1] = gain_v;
        let mut inputs = 2;
        let mut at = 4;
        let last = self.hidden.len();
        for (layer, outputs) in self
            .hidden
            .iter()
            .map(|&n| usize::from(n))
            .chain([3])
            .enumerate()
        {
            let weights = words.get(at..at + outputs * inputs).unwrap_or(&[]);
            let biases = words
                .get(at + outputs * inputs..at + outputs * (inputs + 1))
                .unwrap_or(&[]);
            at += outputs * (inputs + 1);
            let mut next = jet;
            let rows = weights.chunks_exact(inputs.max(1)).zip(biases);
            for (o, (row, &bias)) in rows.enumerate() {
                let zero = S::ZERO.to_acc();
                let (mut value, mut du, mut dv) = (bias.to_acc(), zero, zero);
                for (i, &w) in row.iter().enumerate() {
                    let (x, xu, xv) = (get(&jet.value, i), get(&jet.du, i), get(&jet.dv, i));
                    value = S::mac(value, w, x);
                    if PARTIALS {
                        du = S::mac(du, w, xu);
                        dv = S::mac(dv, w, xv);
                    }
                }
                let a = S::from_acc(value);
                let (value, slope) = if layer < last {
                    self.activation.apply::<S, PARTIALS>(a)
                } else {
                    (a, S::ONE)
                };
                set(&mut next.value, o, value);
                if PARTIALS {
                    set(&mut next.du, o, slope.mul(S::from_acc(du)));
                    set(&mut next.dv, o, slope.mul(S::from_acc(dv)));
                }
            }
            jet = next;
            inputs = outputs;
        }
        let scale = word(at + 3);
        for k in 0..3 {
            let mut scaled = get(&jet.value, k).mul(scale);
            if self.runs_shift() {
                scaled = scaled.times_power_of_two(self.output_shift);
            }
            set(&mut out.position, k, scaled.add(word(at + k)));
            if PARTIALS {
                set(&mut out.du, k, get(&jet.du, k).mul(scale));
                set(&mut out.dv, k, get(&jet.dv, k).mul(scale));
            }
        }
        out
    }
}

#[inline(always)]
fn get<S: Scalar>(values: &[S], i: usize) -> S {
    values.get(i).copied().unwrap_or(S::ZERO)
}

#[inline(always)]
fn set<S: Scalar>(values: &mut [S], i: usize, value: S) {
    if let Some(slot) = values.get_mut(i) {
        *slot = value;
    }
}

/// a × b scaled to unit length, each factor first divided by its largest component so that
/// nothing saturates in Q16.16 (the direction is unchanged); `None` when either vanishes or
/// they are parallel.
fn unit_normal<S: Scalar>(a: [S; 3], b: [S; 3]) -> Option<[S; 3]> {
    let scaled = |v: [S; 3]| -> Option<[S; 3]> {
        let largest = v.iter().fold(S::ZERO, |m, c| {
            let c = c.abs();
            if c > m { c } else { m }
        });
        let inverse = largest.recip()?;
        Some(v.map(|c| c.mul(inverse)))
    };
    let (a, b) = (scaled(a)?, scaled(b)?);
    let cross = |i: usize, j: usize| {
        let mut acc = S::ZERO.to_acc();
        acc = S::mac(acc, get(&a, i), get(&b, j));
        acc = S::mac(acc, get(&a, j).neg(), get(&b, i));
        S::from_acc(acc)
    };
    normalize3([cross(1, 2), cross(2, 0), cross(0, 1)])
}

//! The network itself: for each key point the cosine s = x·wᵢ, the blending kᵢ = Fᵢ(s), and
//! its contribution kᵢ·tᵢ to the output — and, for normals, F′ᵢ(s)·wᵢ ⊗ tᵢ to the Jacobian
//! (paper eq. 12: the same network with vᵍʲ replaced by vᵍʲ·F′ⱼ·wʰʲ).
//!
//! One pass over the key points serves [`LANES`](crate::implicit::LANES) inputs at once: each
//! key's weights are read once and applied to every lane (the paper's "parallel hardware"
//! reading of the network), and every output is one accumulation with one rounding. The
//! single-point calls are the same code with one lane, so batches give the same bits.

use super::blending::{blend, clamp};
use super::model::CaoEnModel;
use crate::scalar::Scalar;

/// The output and, when asked for, the Jacobian at one input.
#[derive(Copy, Clone, Debug)]
pub(crate) struct Jet<S, const M: usize, const P: usize> {
    /// y (its first P coordinates).
    pub(crate) position: [S; P],
    /// ∂y/∂x (rows: outputs, columns: source coordinates), up to the positive factor
    /// Σⱼ Fⱼ for normalized networks: (∂A − y ⊗ ∂B) with A = Σ Fⱼ·tⱼ, B = Σ Fⱼ.
    pub(crate) jacobian: [[S; M]; P],
}

impl<S: Scalar, const K: usize> CaoEnModel<S, K> {
    /// y = V·k at a source point x (its first M coordinates; coordinates beyond M count as 0,
    /// outputs beyond p are 0).
    ///
    /// ```
    /// # use neurosurf_core::caoen::CaoEnModel;
    /// # fn demo(model: &CaoEnModel<f32>) {
    /// let x = [0.0, 0.6, 0.8]; // on the unit sphere
    /// let y: [f32; 3] = model.eval(&x);
    /// # }
    /// ```
    pub fn eval<const M: usize, const P: usize>(&self, x: &[S; M]) -> [S; P] {
        let [jet] = self.lanes::<1, M, P, false>(core::array::from_ref(x));
        jet.position
    }

    /// `L` inputs at once (structure of arrays over the lanes).
    #[inline]
    pub(crate) fn lanes<const L: usize, const M: usize, const P: usize, const JACOBIAN: bool>(
        &self,
        x: &[[S; M]; L],
    ) -> [Jet<S, M, P>; L] {
        let limit = S::from_f32_saturating(S::MAX_PARAMETER);
        let m = self.source_dimension().min(M);
        let p = self.target_dimension().min(P);
        let zero = S::ZERO.to_acc();
        let mut outputs = [[zero; P]; L];
        let mut sums = [zero; L];
        let mut jacobians = [[[zero; M]; P]; L];
        let mut sum_gradients = [[zero; M]; L];
        for key in &self.keys {
            let mut k = [S::ZERO; L];
            let mut slope = [S::ZERO; L];
            for ((x, k), slope) in x.iter().zip(&mut k).zip(&mut slope) {
                let mut s = zero;
                for (&xh, &wh) in x.iter().zip(&key.weight).take(m) {
                    s = S::mac(s, xh, wh);
                }
                (*k, *slope) = blend::<S, JACOBIAN>(
                    self.blending,
                    S::from_acc(s),
                    key.sharpness,
                    key.power,
                    limit,
                );
            }
            for (y, &k) in outputs.iter_mut().zip(&k) {
                for (y, &t) in y.iter_mut().zip(&key.target).take(p) {
                    *y = S::mac(*y, t, k);
                }
            }
            if self.normalized {
                for (sum, &k) in sums.iter_mut().zip(&k) {
                    *sum = S::mac(*sum, k, S::ONE);
                }
            }
            if JACOBIAN {
                for ((jacobian, sum_gradient), &slope) in
                    jacobians.iter_mut().zip(&mut sum_gradients).zip(&slope)
                {
                    for (h, &wh) in key.weight.iter().enumerate().take(m) {
                        let u = clamp(slope.mul(wh), limit);
                        for (row, &t) in jacobian.iter_mut().zip(&key.target).take(p) {
                            if let Some(entry) = row.get_mut(h) {
                                *entry = S::mac(*entry, t, u);
                            }
                        }
                        if self.normalized
                            && let Some(entry) = sum_gradient.get_mut(h)
                        {
                            *entry = S::mac(*entry, u, S::ONE);
                        }
                    }
                }
            }
        }
        let mut jets = [Jet {
            position: [S::ZERO; P],
            jacobian: [[S::ZERO; M]; P],
        }; L];
        for (lane, jet) in jets.iter_mut().enumerate() {
            let (Some(y), Some(&sum)) = (outputs.get(lane), sums.get(lane)) else {
                continue;
            };
            for (position, &y) in jet.position.iter_mut().zip(y) {
                *position = if self.normalized {
                    S::quotient(y, sum)
                } else {
                    S::from_acc(y)
                };
            }
            if !JACOBIAN {
                continue;
            }
            let (Some(jacobian), Some(sum_gradient)) =
                (jacobians.get(lane), sum_gradients.get(lane))
            else {
                continue;
            };
            for ((out, row), &y) in jet.jacobian.iter_mut().zip(jacobian).zip(&jet.position) {
                for ((out, &entry), &db) in out.iter_mut().zip(row).zip(sum_gradient) {
                    *out = if self.normalized {
                        S::from_acc(entry).sub(y.mul(S::from_acc(db)))
                    } else {
                        S::from_acc(entry)
                    };
                }
            }
        }
        jets
    }
}

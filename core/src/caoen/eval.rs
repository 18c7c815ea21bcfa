//! The network itself: for each key point the cosine s = x·wᵢ, the blending kᵢ = Fᵢ(s), and
//! its contribution kᵢ·tᵢ to the output — and, for normals, F′ᵢ(s)·wᵢ ⊗ tᵢ to the Jacobian
//! (paper eq. 12: the same network with vᵍʲ replaced by vᵍʲ·F′ⱼ·wʰʲ).
//!
//! One pass over the key points serves [`LANES`](crate::implicit::LANES) inputs at once: each
//! key's weights are read once and applied to every lane (the paper's "parallel hardware"
//! reading of the network), and every output is one accumulation with one rounding. The
//! single-point calls are the same code with one lane, so batches give the same bits.

use super::blending::{Blending, blend, clamp};
use super::model::{CaoEnModel, GROUP_NORM_LIMIT};
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
    ///
    /// The common shapes (m, p) = (3, 3) (sphere → space) and (4, 3) (torus → space) get their
    /// own copy of the loop with the dimensions as constants, so that the per-key loops unroll;
    /// every other shape runs the same code with the dimensions read at run time.
    #[inline]
    pub(crate) fn lanes<const L: usize, const M: usize, const P: usize, const JACOBIAN: bool>(
        &self,
        x: &[[S; M]; L],
    ) -> [Jet<S, M, P>; L] {
        let m = self.source_dimension().min(M);
        let p = self.target_dimension().min(P);
        match (m, p) {
            (3, 3) => self.kernel::<L, M, P, JACOBIAN>(x, 3, 3),
            (4, 3) => self.kernel::<L, M, P, JACOBIAN>(x, 4, 3),
            _ => self.kernel::<L, M, P, JACOBIAN>(x, m, p),
        }
    }

    /// [`Self::lanes`] for m source and p target coordinates (m ≤ M, p ≤ P).
    #[inline(always)]
    fn kernel<const L: usize, const M: usize, const P: usize, const JACOBIAN: bool>(
        &self,
        x: &[[S; M]; L],
        m: usize,
        p: usize,
    ) -> [Jet<S, M, P>; L] {
        let limit = S::from_f32_saturating(S::MAX_PARAMETER);
        let zero = S::ZERO.to_acc();
        let mut outputs = [[zero; P]; L];
        let mut sums = [zero; L];
        let mut jacobians = [[[zero; M]; P]; L];
        let mut sum_gradients = [[zero; M]; L];
        let grouped = self.blending == Blending::Compact;
        let norm_limit = S::from_f32_saturating(GROUP_NORM_LIMIT);
        let norms = if grouped {
            x.map(|x| {
                // A coordinate at the limit or beyond (or NaN) puts |x| there too. Checked
                // first, so that the squares below stay small: Q16.16 coordinates near ±32 768
                // would overflow the accumulator and give a small norm.
                let within = |xh: S| xh < norm_limit && norm_limit.neg() < xh;
                if !x.iter().take(m).all(|&xh| within(xh)) {
                    return norm_limit;
                }
                let mut squared = zero;
                for &xh in x.iter().take(m) {
                    squared = S::mac(squared, xh, xh);
                }
                S::from_acc(squared).sqrt()
            })
        } else {
            [S::ZERO; L]
        };
        let mut index = 0;
        while let Some(key) = self.keys.get(index) {
            let mut cosines = [S::ZERO; L];
            for (x, cosine) in x.iter().zip(&mut cosines) {
                let mut s = zero;
                for (&xh, &wh) in x.iter().zip(&key.weight).take(m) {
                    s = S::mac(s, xh, wh);
                }
                *cosine = S::from_acc(s);
            }
            if grouped
                && key.group.span > 0
                && cosines
                    .iter()
                    .zip(&norms)
                    .all(|(&s0, &norm)| key.group.out_of_reach(s0, norm, norm_limit))
            {
                index += usize::from(key.group.span);
                continue;
            }
            index += 1;
            let mut k = [S::ZERO; L];
            let mut slope = [S::ZERO; L];
            for ((&s, k), slope) in cosines.iter().zip(&mut k).zip(&mut slope) {
                (*k, *slope) =
                    blend::<S, JACOBIAN>(self.blending, s, key.sharpness, key.power, limit);
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
            for (position, &y) in jet.position.iter_mut().zip(y).take(p) {
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
            for ((out, row), &y) in jet
                .jacobian
                .iter_mut()
                .zip(jacobian)
                .zip(&jet.position)
                .take(p)
            {
                for ((out, &entry), &db) in out.iter_mut().zip(row).zip(sum_gradient).take(m) {
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

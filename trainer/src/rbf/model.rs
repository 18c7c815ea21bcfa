//! The fitted RBF implicit surface f(x) = Σ wᵢ φ(|x − cᵢ|) + a·x + b, evaluated in `f64`.

use crate::error::{Error, Result};

use super::kernel::Packed;
use super::options::{MAX_POINTS, RbfKernel};

/// Most centres a model holds: three per control point at [`MAX_POINTS`].
pub const MAX_CENTERS: usize = 3 * MAX_POINTS;

/// An RBF implicit surface (Carcenac §9's baseline; host-only, never on the
/// microcontroller):
///
/// f(x) = Σᵢ wᵢ·√(|x − cᵢ|² + c²) + a·x + b,
///
/// the multiquadric for c² > 0 and the biharmonic Σ wᵢ|x − cᵢ| for c² = 0. Sign convention as
/// the implicit network: f > 0 inside, f < 0 outside, and −∇f/|∇f| is the outward normal.
/// Models from [`fit`](super::fit) hold 3n centres for n control points: the points themselves
/// first (f = 0 there), then the n outside off-surface points xᵢ + εᵢ⁺nᵢ, then the n inside
/// ones xᵢ − εᵢ⁻nᵢ. Everything is in the data's own units.
///
/// Evaluation costs O(centres) per point: the centres are kept a second time in
/// structure-of-arrays form, summed eight at a time (AVX2 + FMA where the CPU has them,
/// about 2 ns per centre and point). Its rounding error is bounded by about
/// (number of centres)·2⁻⁵³·Σ|wᵢ|φᵢ; the weights of an interpolant alternate in sign, so
/// absolute field errors are of the order of the fits' constraint residuals (10⁻¹²–10⁻¹⁰ of
/// s·D) — far below any fitting error. The last bits depend on whether the CPU has FMA.
#[derive(Clone, Debug)]
pub struct RbfModel {
    pub(super) centers: Vec<[f64; 3]>,
    pub(super) weights: Vec<f64>,
    pub(super) linear: [f64; 3],
    pub(super) constant: f64,
    pub(super) c2: f64,
    /// The centres and weights again, packed for evaluation.
    packed: Packed,
}

impl PartialEq for RbfModel {
    fn eq(&self, other: &Self) -> bool {
        // `packed` is derived from the centres and weights.
        self.centers == other.centers
            && self.weights == other.weights
            && self.linear == other.linear
            && self.constant == other.constant
            && self.c2 == other.c2
    }
}

impl RbfModel {
    /// A model from its parts; `c2 = 0` is the biharmonic kernel.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when there are no centres or more than [`MAX_CENTERS`],
    /// `weights` and `centers` differ in length, a value is not finite, or `c2 < 0`.
    pub fn new(
        centers: Vec<[f64; 3]>,
        weights: Vec<f64>,
        linear: [f64; 3],
        constant: f64,
        c2: f64,
    ) -> Result<Self> {
        if centers.is_empty() || centers.len() > MAX_CENTERS {
            return Err(Error::invalid(format!(
                "an RBF model needs 1 to {MAX_CENTERS} centres, got {}",
                centers.len()
            )));
        }
        if weights.len() != centers.len() {
            return Err(Error::invalid(format!(
                "{} RBF centres but {} weights",
                centers.len(),
                weights.len()
            )));
        }
        if !(c2.is_finite() && c2 >= 0.0) {
            return Err(Error::invalid(format!(
                "the multiquadric c² must be finite and at least 0, got {c2}"
            )));
        }
        if let Some(i) = centers
            .iter()
            .position(|c| c.iter().any(|v| !v.is_finite()))
        {
            return Err(Error::invalid(format!("RBF centre {i} is not finite")));
        }
        if let Some(i) = weights.iter().position(|w| !w.is_finite()) {
            return Err(Error::invalid(format!("RBF weight {i} is not finite")));
        }
        if !(linear.iter().all(|v| v.is_finite()) && constant.is_finite()) {
            return Err(Error::invalid("the RBF's linear term is not finite"));
        }
        Ok(Self::from_parts(centers, weights, linear, constant, c2))
    }

    /// A model from checked parts.
    pub(super) fn from_parts(
        centers: Vec<[f64; 3]>,
        weights: Vec<f64>,
        linear: [f64; 3],
        constant: f64,
        c2: f64,
    ) -> Self {
        let packed = Packed::new(&centers, &weights);
        RbfModel {
            centers,
            weights,
            linear,
            constant,
            c2,
            packed,
        }
    }

    fn polynomial(&self, p: [f64; 3]) -> f64 {
        self.constant + self.linear[0] * p[0] + self.linear[1] * p[1] + self.linear[2] * p[2]
    }

    /// The field f(p) (see the type's documentation for its accuracy).
    pub fn field(&self, p: [f64; 3]) -> f64 {
        self.polynomial(p) + self.packed.sum::<false>(p, self.c2).0
    }

    /// The field and its exact analytic gradient ∇f(p) = Σ wᵢ (p − cᵢ)/φᵢ + a, the value
    /// bit-identical to [`RbfModel::field`] (the tests check the gradient against central
    /// differences). At a biharmonic centre, where |x − cᵢ| has no gradient, that term
    /// contributes 0.
    pub fn field_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let (sum, g) = self.packed.sum::<true>(p, self.c2);
        (
            self.polynomial(p) + sum,
            [0, 1, 2].map(|k| self.linear[k] + g[k]),
        )
    }

    /// The outward unit normal −∇f/|∇f| at `p`, or `None` where the gradient vanishes
    /// (|∇f| < 10⁻³⁰⁰) and no normal is defined.
    pub fn normal(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        let (_, g) = self.field_gradient(p);
        let len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        (len > 1e-300).then(|| g.map(|v| -v / len))
    }

    /// The centres cᵢ (for a fitted model: the n control points, then the n outside and the
    /// n inside off-surface points).
    pub fn centers(&self) -> &[[f64; 3]] {
        &self.centers
    }

    /// The weights wᵢ, one per centre; they satisfy Σwᵢ = 0 and Σwᵢcᵢ = 0 for a fitted model.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The linear coefficients a.
    pub fn linear(&self) -> [f64; 3] {
        self.linear
    }

    /// The constant b.
    pub fn constant(&self) -> f64 {
        self.constant
    }

    /// The multiquadric c² (0: the biharmonic kernel).
    pub fn c2(&self) -> f64 {
        self.c2
    }

    /// The kernel: the biharmonic when c² = 0, else the multiquadric.
    pub fn kernel(&self) -> RbfKernel {
        if self.c2 == 0.0 {
            RbfKernel::Biharmonic
        } else {
            RbfKernel::Multiquadric
        }
    }

    /// The centres' axis-aligned bounding box `(lo, hi)`.
    pub fn bounds(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = self.centers[0];
        let mut hi = lo;
        for c in &self.centers {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        (lo, hi)
    }

    /// Coefficients found by the solve: one weight per centre plus the four of a·x + b
    /// (3n + 4 for n control points). The centres are data, not parameters; a blob stores
    /// 4·centres + 5 `f64` values in all.
    pub fn parameter_count(&self) -> usize {
        self.weights.len() + 4
    }
}

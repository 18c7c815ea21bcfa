//! The fitted RBF implicit surface f(x) = Σ wᵢ φ(|x − cᵢ|) + a·x + b, evaluated in `f64`.

use crate::error::{Error, Result};

use super::kernel::{multiquadric, multiquadric_gradient};
use super::options::MAX_POINTS;

/// Most centres a model holds: two per control point at [`MAX_POINTS`].
pub const MAX_CENTERS: usize = 2 * MAX_POINTS;

/// A multiquadric RBF implicit surface (Carcenac §9's baseline; host-only, never on the
/// microcontroller):
///
/// f(x) = Σᵢ wᵢ·√(|x − cᵢ|² + c²) + a·x + b.
///
/// Sign convention as the implicit network: f > 0 inside, f < 0 outside, and −∇f/|∇f| is the
/// outward normal. Models from [`fit`](super::fit) hold 2n centres for n control points:
/// the points themselves first (f = 0 there), then the off-surface points xᵢ + ε·nᵢ.
///
/// Evaluation costs O(centres) per point. Its rounding error is bounded by about
/// (number of centres)·2⁻⁵³·Σ|wᵢ|φᵢ; the weights of an interpolant alternate in sign
/// (|wᵢ| ≤ 15 but Σ|wᵢ| ≈ 10³ on the test torus), so absolute field errors are ~10⁻¹¹ in
/// practice (the fits' constraint residuals) and below 10⁻⁹ in the worst case — far below any
/// fitting error.
#[derive(Clone, Debug, PartialEq)]
pub struct RbfModel {
    pub(super) centers: Vec<[f64; 3]>,
    pub(super) weights: Vec<f64>,
    pub(super) linear: [f64; 3],
    pub(super) constant: f64,
    pub(super) c2: f64,
}

impl RbfModel {
    /// A model from its parts.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when there are no centres or more than [`MAX_CENTERS`],
    /// `weights` and `centers` differ in length, a value is not finite, or `c2 ≤ 0`.
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
        if !(c2.is_finite() && c2 > 0.0) {
            return Err(Error::invalid(format!(
                "the multiquadric c² must be finite and positive, got {c2}"
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
        Ok(RbfModel {
            centers,
            weights,
            linear,
            constant,
            c2,
        })
    }

    /// The field f(p) (see the type's documentation for its accuracy).
    pub fn field(&self, p: [f64; 3]) -> f64 {
        let mut sum =
            self.constant + self.linear[0] * p[0] + self.linear[1] * p[1] + self.linear[2] * p[2];
        for (c, &w) in self.centers.iter().zip(&self.weights) {
            sum += w * multiquadric([p[0] - c[0], p[1] - c[1], p[2] - c[2]], self.c2);
        }
        sum
    }

    /// The field and its exact analytic gradient ∇f(p) = Σ wᵢ (p − cᵢ)/φᵢ + a, with the
    /// same rounding behaviour as [`RbfModel::field`] (the tests check it against central
    /// differences to 10⁻⁶ relative).
    pub fn field_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let mut value =
            self.constant + self.linear[0] * p[0] + self.linear[1] * p[1] + self.linear[2] * p[2];
        let mut gradient = self.linear;
        for (c, &w) in self.centers.iter().zip(&self.weights) {
            let (phi, g) = multiquadric_gradient([p[0] - c[0], p[1] - c[1], p[2] - c[2]], self.c2);
            value += w * phi;
            for k in 0..3 {
                gradient[k] += w * g[k];
            }
        }
        (value, gradient)
    }

    /// The outward unit normal −∇f/|∇f| at `p`, or `None` where the gradient vanishes
    /// (|∇f| < 10⁻³⁰⁰) and no normal is defined.
    pub fn normal(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        let (_, g) = self.field_gradient(p);
        let len = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        (len > 1e-300).then(|| g.map(|v| -v / len))
    }

    /// The centres cᵢ (for a fitted model: the n control points, then the n off-surface
    /// points).
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

    /// The multiquadric c².
    pub fn c2(&self) -> f64 {
        self.c2
    }

    /// Coefficients found by the solve: one weight per centre plus the four of a·x + b
    /// (2n + 4 for n control points). The centres are data, not parameters; a blob stores
    /// 4·centres + 5 `f64` values in all.
    pub fn parameter_count(&self) -> usize {
        self.weights.len() + 4
    }
}

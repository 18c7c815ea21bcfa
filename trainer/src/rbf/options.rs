//! Settings of the RBF fit; defaults are Carcenac's §9 choices plus the off-surface
//! constraint of the reproduction notes.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Most control points [`fit`](super::fit) accepts.
///
/// The system is dense: n points give 2n + 4 unknowns, a (2n)² matrix of `f64` and an
/// O(n³) factorization. At the limit that is 8 004 unknowns, 0.5 GB for the matrix and
/// about a minute of factorization on one core (576 points take ~0.15 s; time grows with the
/// cube of n). Beyond it, use the network (or a fast-multipole RBF, which this is not).
pub const MAX_POINTS: usize = 4_000;

/// Fewest control points [`fit`](super::fit) accepts (the linear polynomial alone has four
/// coefficients).
pub const MIN_POINTS: usize = 4;

/// What shapes a multiquadric RBF fit. All lengths are in the units of the control points
/// (no normalization box: Carcenac fits the RBF in the model's own coordinates).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RbfOptions {
    /// c² of the multiquadric φ(r) = √(r² + c²) (10⁻³, Carcenac §9: smaller values leave
    /// artefacts very close to the control points).
    pub c2: f64,
    /// Offset ε of the off-surface constraint f(xᵢ + ε·nᵢ) = −ε·s (0.01).
    pub epsilon: f64,
    /// Slope s of the field across the surface (5, the implicit network's Table-1 slope, so
    /// both models share scale and sign: f > 0 inside, f < 0 outside, ∇f ≈ −s·n on the
    /// surface).
    pub slope: f64,
}

impl Default for RbfOptions {
    fn default() -> Self {
        RbfOptions {
            c2: 1e-3,
            epsilon: 0.01,
            slope: 5.0,
        }
    }
}

impl RbfOptions {
    /// Checks every setting is finite and positive.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the offending setting.
    pub fn check(&self) -> Result<()> {
        for (name, value) in [
            ("c2", self.c2),
            ("epsilon", self.epsilon),
            ("slope", self.slope),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::invalid(format!(
                    "RBF option {name} must be finite and positive, got {value}"
                )));
            }
        }
        Ok(())
    }
}

//! Settings of the RBF fit. Every length is a fraction of the control points' bounding
//! diagonal D, so the same settings fit the same surface whatever the data's units and
//! position; the defaults are Carcenac's §9 multiquadric, its c² = 10⁻³ carried over from the
//! Table 5 torus, with Hermite-style off-surface points on both sides (Carr et al. 2001).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Most control points [`fit`](super::fit) accepts.
///
/// The system is dense: n points give m = 3n centres and m + 4 unknowns, an m² matrix of
/// `f64` (72·n² bytes) and an m³/3-flop Cholesky factorization (faer, on every thread of the
/// current rayon pool). Measured on this project's 2-core machine while it was shared (about
/// one core's worth): 1 500 points (4 500 centres) take 1–2 s, 0.8–1.4 s of it factoring;
/// at this limit, 15 000 centres, the fit peaks at 1.8 GB and took 30 s (26 s factoring).
/// Time grows with the cube of n, memory with its square. Beyond it, use the network (or a
/// fast-multipole RBF, which this is not).
pub const MAX_POINTS: usize = 5_000;

/// Fewest control points [`fit`](super::fit) accepts (the linear polynomial alone has four
/// coefficients).
pub const MIN_POINTS: usize = 4;

/// The default c/D of the multiquadric: √(10⁻³ / 16.32) = 0.0078278, so that on the Table 5
/// torus (R = 1, r = 0.4, bounding diagonal D = √16.32 ≈ 4.04) c² = 10⁻³, Carcenac's value.
/// Samples of that torus have a slightly shorter diagonal (c² ≈ 0.99·10⁻³ at 48 points).
pub const C_RELATIVE: f64 = 0.007_827_803_638_564_37;

/// The default ε₀/D of the off-surface points: 1 % of the bounding diagonal.
pub const EPSILON_RELATIVE: f64 = 0.01;

/// Most times an off-surface offset is halved (ε₀/2³⁰ ≈ 10⁻¹¹·D at the default ε₀): enough
/// for any two control points farther apart than the duplicate tolerance.
pub const MAX_HALVINGS: u32 = 30;

/// The radial function φ.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RbfKernel {
    /// φ(r) = √(r² + c²), Carcenac §9's multiquadric, with c = [`RbfOptions::c_relative`]·D.
    #[default]
    Multiquadric,
    /// φ(r) = r, the biharmonic spline (Carr et al. 2001's choice; the multiquadric with
    /// c = 0): no shape parameter, smoothest interpolant in the sense of the thin-plate energy.
    Biharmonic,
}

impl RbfKernel {
    /// `multiquadric` or `biharmonic`.
    pub fn name(self) -> &'static str {
        match self {
            RbfKernel::Multiquadric => "multiquadric",
            RbfKernel::Biharmonic => "biharmonic",
        }
    }
}

/// What shapes an RBF fit.
///
/// Each control point xᵢ with unit normal nᵢ gives three constraints: f(xᵢ) = 0,
/// f(xᵢ + εᵢ⁺nᵢ) = −s·εᵢ⁺ outside and f(xᵢ − εᵢ⁻nᵢ) = +s·εᵢ⁻ inside, where each offset starts
/// at ε₀ = [`RbfOptions::epsilon_relative`]·D and is halved until the offset point's nearest
/// control point is xᵢ itself (Carr et al. 2001), so no off-surface point lands near another
/// part of the surface. D is the control points' bounding diagonal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RbfOptions {
    /// The radial function (default: the multiquadric, the paper's).
    pub kernel: RbfKernel,
    /// c/D of the multiquadric φ(r) = √(r² + c²) (default [`C_RELATIVE`]: c² = 10⁻³ on the
    /// Table 5 torus, Carcenac §9: smaller values leave artefacts very close to the control
    /// points). Ignored by the biharmonic kernel.
    pub c_relative: f64,
    /// ε₀/D, the starting offset of the off-surface points (default [`EPSILON_RELATIVE`]).
    pub epsilon_relative: f64,
    /// Slope s of the field across the surface (5, the implicit network's Table-1 slope, so
    /// both models share scale and sign: f > 0 inside, f < 0 outside, ∇f ≈ −s·n on the
    /// surface, in the data's units).
    pub slope: f64,
}

impl Default for RbfOptions {
    fn default() -> Self {
        RbfOptions {
            kernel: RbfKernel::Multiquadric,
            c_relative: C_RELATIVE,
            epsilon_relative: EPSILON_RELATIVE,
            slope: 5.0,
        }
    }
}

impl RbfOptions {
    /// Checks every setting is finite and positive (and ε₀ below D/2, c below D).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the offending setting.
    pub fn check(&self) -> Result<()> {
        for (name, value) in [
            ("c_relative", self.c_relative),
            ("epsilon_relative", self.epsilon_relative),
            ("slope", self.slope),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(Error::invalid(format!(
                    "RBF option {name} must be finite and positive, got {value}"
                )));
            }
        }
        if self.epsilon_relative >= 0.5 {
            return Err(Error::invalid(format!(
                "RBF option epsilon_relative is a fraction of the bounding diagonal and must be \
                 below 0.5, got {}",
                self.epsilon_relative
            )));
        }
        if self.c_relative > 1.0 {
            return Err(Error::invalid(format!(
                "RBF option c_relative is a fraction of the bounding diagonal and must be at \
                 most 1, got {}",
                self.c_relative
            )));
        }
        Ok(())
    }

    /// The multiquadric's c/D, or 0 for the biharmonic kernel.
    pub fn shape(&self) -> f64 {
        match self.kernel {
            RbfKernel::Multiquadric => self.c_relative,
            RbfKernel::Biharmonic => 0.0,
        }
    }
}

//! The blending functions F (paper §4) and the source domains, with their blob codes.

use crate::scalar::Scalar;

/// Largest sharpness q a blob may give a key point, for either blending function.
///
/// In Q16.16 the exponential's argument q·(s − 1) stays within ±2¹² for |s| ≤ 32, and F′ = q·F
/// within the clamp; powers up to 64 take at most 12 multiplications.
pub const MAX_SHARPNESS: f64 = 64.0;

/// How a key point turns the cosine s = x·wᵢ into its activation kᵢ = Fᵢ(s).
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Blending {
    /// F(s) = s^q for s > 0, else 0 (paper eq. 4); q a whole number 0 … 64.
    Power,
    /// F(s) = e^{q(s−1)} (paper eq. 5); q any value in [0, 64].
    Exponential,
    /// F(s) = u³ with u = 1 + q(s − 1) for u > 0, else 0: local support (the paper's §5 open
    /// question). A key point only reaches the cap s > 1 − 1/q around its weight (q ≥ 1/2 for
    /// a cap smaller than the sphere), F is C¹ at the cap's edge, F(1) = 1 like the
    /// exponential, and keys stored in groups (see [`crate::caoen`]) that cannot reach a source
    /// point are skipped whole. q any value in [0, 64]; q = 0 gives F = 1 everywhere. Sums of
    /// caps vary between the keys, so the normalized form (a partition of unity) suits it best;
    /// unnormalized, the surface sags where few caps overlap.
    Compact,
}

impl Blending {
    /// The blob code: 0 power, 1 exponential, 2 compact.
    pub const fn code(self) -> u8 {
        match self {
            Blending::Power => 0,
            Blending::Exponential => 1,
            Blending::Compact => 2,
        }
    }

    /// The blending a blob code names.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Blending::Power),
            1 => Some(Blending::Exponential),
            2 => Some(Blending::Compact),
            _ => None,
        }
    }

    /// The largest valid code.
    pub(crate) const LAST_CODE: u8 = 2;
}

/// What the network maps from, which fixes how tangents (and so normals) are formed.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub enum Domain {
    /// The unit sphere (m = 3) or a hypersphere (m > 3): x with |x| = 1.
    Sphere,
    /// The torus (m = 4): x = (cos θ, sin θ, cos φ, sin φ) (paper eq. 18).
    Torus,
}

impl Domain {
    /// The blob code: 0 sphere, 1 torus.
    pub const fn code(self) -> u8 {
        match self {
            Domain::Sphere => 0,
            Domain::Torus => 1,
        }
    }

    /// The domain a blob code names.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Domain::Sphere),
            1 => Some(Domain::Torus),
            _ => None,
        }
    }

    /// The largest valid code.
    pub(crate) const LAST_CODE: u8 = 1;
}

/// F(s) and, when `DERIVATIVE`, F′(s), both clamped to ±`limit` (see the accuracy notes in
/// [`crate::caoen`]). `power` is q as a whole number (power blending only).
#[inline(always)]
pub(crate) fn blend<S: Scalar, const DERIVATIVE: bool>(
    blending: Blending,
    s: S,
    q: S,
    power: u8,
    limit: S,
) -> (S, S) {
    let (value, slope) = match blending {
        Blending::Power => {
            match s.partial_cmp(&S::ZERO) {
                Some(core::cmp::Ordering::Greater) => {}
                // F(s) = s has a kink at 0, with one-sided slopes 0 and q. Their mean keeps
                // keys of opposite weights exact there (F(s) − F(−s) = s has slope q·1, not
                // 0), so a source point with a zero coordinate keeps a nonzero normal.
                Some(core::cmp::Ordering::Equal) if power == 1 => {
                    let slope = if DERIVATIVE {
                        clamp(q.times_power_of_two(-1), limit)
                    } else {
                        S::ZERO
                    };
                    return (S::ZERO, slope);
                }
                // NaN is not greater than 0 either and gives 0, like any s < 0.
                _ => return (S::ZERO, S::ZERO),
            }
            if power == 0 {
                return (S::ONE, S::ZERO);
            }
            let below = powi(s, u32::from(power) - 1);
            let slope = if DERIVATIVE { q.mul(below) } else { S::ZERO };
            (below.mul(s), slope)
        }
        Blending::Exponential => {
            let value = q.mul(s.sub(S::ONE)).exp();
            let slope = if DERIVATIVE { q.mul(value) } else { S::ZERO };
            (value, slope)
        }
        Blending::Compact => {
            let u = S::ONE.add(q.mul(s.sub(S::ONE)));
            // NaN is not greater than 0 either and gives 0, like any point off the cap.
            if u.partial_cmp(&S::ZERO) != Some(core::cmp::Ordering::Greater) {
                return (S::ZERO, S::ZERO);
            }
            let square = u.mul(u);
            let slope = if DERIVATIVE {
                q.mul(square.add(square).add(square))
            } else {
                S::ZERO
            };
            (square.mul(u), slope)
        }
    };
    (clamp(value, limit), clamp(slope, limit))
}

/// base^exponent by binary powering (at most 2·⌈log₂(exponent + 1)⌉ rounded products).
#[inline(always)]
fn powi<S: Scalar>(base: S, mut exponent: u32) -> S {
    let mut result = S::ONE;
    let mut square = base;
    while exponent > 0 {
        if exponent & 1 == 1 {
            result = result.mul(square);
        }
        exponent >>= 1;
        if exponent > 0 {
            square = square.mul(square);
        }
    }
    result
}

/// x limited to [−limit, limit]; NaN stays NaN.
#[inline(always)]
pub(crate) fn clamp<S: Scalar>(x: S, limit: S) -> S {
    if x > limit {
        limit
    } else if x < limit.neg() {
        limit.neg()
    } else {
        x
    }
}

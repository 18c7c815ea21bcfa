//! Jets: a neuron's value together with its derivatives along `D` input directions, for `L`
//! points at once.
//!
//! This is forward-mode differentiation (Carcenac §4): the tangent of neuron i with respect to
//! input coordinate k is ᵏGᵢ = a′(Hᵢ)·ᵏIᵢ with ᵏIᵢ = Σ w·ᵏG of the previous layer. `D = 0`
//! evaluates values only, `D = 3` values and gradients. `L` lanes hold independent points in
//! structure-of-arrays form, so the inner loops run over contiguous lanes and vectorize.

use crate::scalar::Scalar;

/// One neuron's value and `D` directional derivatives at `L` points.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Jet<S, const L: usize, const D: usize> {
    /// The value at each lane.
    pub value: [S; L],
    /// `tangent[k][l]`: derivative with respect to input direction `k` at lane `l`.
    pub tangent: [[S; L]; D],
}

impl<S: Scalar, const L: usize, const D: usize> Jet<S, L, D> {
    /// All zeros.
    pub const ZERO: Self = Jet {
        value: [S::ZERO; L],
        tangent: [[S::ZERO; L]; D],
    };
}

impl<S: Scalar, const L: usize, const D: usize> Default for Jet<S, L, D> {
    fn default() -> Self {
        Self::ZERO
    }
}

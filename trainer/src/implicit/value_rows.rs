//! Φ alone and its one Jacobian row ∂Φ/∂θ, [`LANES`] points at a time: for the points that
//! constrain only the field's value (off-surface and sign points), which need neither the
//! input tangents nor the three gradient rows of [`super::jacobian::jacobian_lanes`].
//!
//! The backward sweep is plain back-propagation: H̄ = Ō·a′ per layer, ∂Φ/∂w_jc = H̄_j·O_c.

use neurosurf_core::implicit::MAX_WIDTH;
use neurosurf_core::scalar::{ACTIVATION_AMPLITUDE, ACTIVATION_GAIN};

use super::jacobian::TrainedLayout;
use crate::solve::{LANES, Lanes, madd, tanh_lanes};

/// The forward pass of [`LANES`] points: each hidden layer's values and slopes, and Φ.
#[derive(Clone, Debug)]
pub(crate) struct ValueTape {
    a_value: [Lanes; MAX_WIDTH],
    a_slope: [Lanes; MAX_WIDTH],
    b_value: [Lanes; MAX_WIDTH],
    b_slope: [Lanes; MAX_WIDTH],
    out_slope: Lanes,
    /// Φ.
    pub value: Lanes,
}

impl ValueTape {
    pub const ZERO: Self = ValueTape {
        a_value: [[0.0; LANES]; MAX_WIDTH],
        a_slope: [[0.0; LANES]; MAX_WIDTH],
        b_value: [[0.0; LANES]; MAX_WIDTH],
        b_slope: [[0.0; LANES]; MAX_WIDTH],
        out_slope: [0.0; LANES],
        value: [0.0; LANES],
    };
}

/// (a, a′) on every lane.
#[inline(always)]
fn activate<const FMA: bool>(h: Lanes) -> (Lanes, Lanes) {
    let t = tanh_lanes::<FMA>(h.map(|x| ACTIVATION_GAIN * x));
    (
        t.map(|t| ACTIVATION_AMPLITUDE * t),
        t.map(|t| ACTIVATION_AMPLITUDE * ACTIVATION_GAIN * (1.0 - t * t)),
    )
}

/// One dense layer of `n` neurons over `values`, activated.
#[inline(always)]
fn layer<const FMA: bool>(
    n: usize,
    weights: &[f64],
    biases: &[f64],
    values: &[Lanes],
    value: &mut [Lanes; MAX_WIDTH],
    slope: &mut [Lanes; MAX_WIDTH],
) {
    let d = values.len();
    for j in 0..n {
        let row = &weights[j * d..(j + 1) * d];
        let mut h = [biases[j]; LANES];
        for c in 0..d {
            for l in 0..LANES {
                h[l] = madd::<FMA>(row[c], values[c][l], h[l]);
            }
        }
        (value[j], slope[j]) = activate::<FMA>(h);
    }
}

/// Φ of [`LANES`] points (`inputs[c][l]`: input c of point l).
#[inline(always)]
pub(crate) fn forward_value_lanes<const FMA: bool>(
    layout: &TrainedLayout,
    params: &[f64],
    inputs: &[Lanes],
    tape: &mut ValueTape,
) {
    let n = layout.width;
    let d = layout.inputs;
    layer::<FMA>(
        n,
        &params[layout.a_weights..layout.a_biases],
        &params[layout.a_biases..layout.a_biases + n],
        &inputs[..d],
        &mut tape.a_value,
        &mut tape.a_slope,
    );
    let a_value = tape.a_value;
    layer::<FMA>(
        n,
        &params[layout.b_weights..layout.b_biases],
        &params[layout.b_biases..layout.b_biases + n],
        &a_value[..n],
        &mut tape.b_value,
        &mut tape.b_slope,
    );
    let w = &params[layout.out_weights..layout.out_weights + n];
    let mut h = [params[layout.out_bias]; LANES];
    for j in 0..n {
        for l in 0..LANES {
            h[l] = madd::<FMA>(w[j], tape.b_value[j][l], h[l]);
        }
    }
    (tape.value, tape.out_slope) = activate::<FMA>(h);
}

/// ∂Φ/∂θ of the [`LANES`] points of `tape`, lane-minor: `out[θ][l]`.
#[inline(always)]
pub(crate) fn value_row_lanes<const FMA: bool>(
    layout: &TrainedLayout,
    params: &[f64],
    inputs: &[Lanes],
    tape: &ValueTape,
    out: &mut [Lanes],
) {
    let n = layout.width;
    let d = layout.inputs;
    let w_out = &params[layout.out_weights..layout.out_weights + n];
    let w_b = &params[layout.b_weights..layout.b_biases];
    let h = tape.out_slope;
    out[layout.out_bias] = h;
    let mut b_bar = [[0.0; LANES]; MAX_WIDTH];
    for j in 0..n {
        out[layout.out_weights + j] = std::array::from_fn(|l| h[l] * tape.b_value[j][l]);
        b_bar[j] = std::array::from_fn(|l| w_out[j] * h[l] * tape.b_slope[j][l]);
    }
    let mut a_bar = [[0.0; LANES]; MAX_WIDTH];
    for j in 0..n {
        let row = &mut out[layout.b_weights + j * n..layout.b_weights + (j + 1) * n];
        let w_row = &w_b[j * n..(j + 1) * n];
        for c in 0..n {
            row[c] = std::array::from_fn(|l| b_bar[j][l] * tape.a_value[c][l]);
            for l in 0..LANES {
                a_bar[c][l] = madd::<FMA>(w_row[c], b_bar[j][l], a_bar[c][l]);
            }
        }
        out[layout.b_biases + j] = b_bar[j];
    }
    for j in 0..n {
        let h = std::array::from_fn::<f64, LANES, _>(|l| a_bar[j][l] * tape.a_slope[j][l]);
        let row = &mut out[layout.a_weights + j * d..layout.a_weights + (j + 1) * d];
        for c in 0..d {
            row[c] = std::array::from_fn(|l| h[l] * inputs[c][l]);
        }
        out[layout.a_biases + j] = h;
    }
}

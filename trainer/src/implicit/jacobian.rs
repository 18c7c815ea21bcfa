//! One module's forward pass and the analytic Jacobian of [Φ, γ∇Φ] with respect to every
//! trained weight and bias (Carcenac §4–5).
//!
//! The paper derives the Jacobian with forward recurrences (∂Oᵢˡ/∂w, ∂ᵏGᵢˡ/∂w). We compute the
//! same derivatives in reverse mode: one backward sweep per output row (Φ and the three
//! gradient components), through both the values and the forward-mode tangents of the network.
//! For a 3→9→9→1 leaf that is ~2 000 multiply–adds per control point instead of ~50 000.
//!
//! A module maps `d` inputs (a leaf: its 3 normalized coordinates; a node: the 2N last-hidden
//! neurons of its children, then its own 3 normalized coordinates) through hidden layers of
//! width N to one output. Each input comes
//! with its tangents — derivatives with respect to the world coordinates x₀, x₁, x₂ — so the
//! module's output gradient is ∇Φ in world space.
//!
//! Training evaluates [`LANES`] control points at once, one per SIMD lane
//! ([`forward_lanes`], [`jacobian_lanes`]): the same sweeps with a vectorizable tanh, compiled
//! for AVX2 and FMA when the CPU has them (see `problem.rs`).
//!
//! This file is long (about 830 lines) because the one-point sweeps and their four-lane twins
//! must stay line for line the same arithmetic; side by side they can be read against each
//! other.

use neurosurf_core::implicit::MAX_WIDTH;
use neurosurf_core::scalar::{ACTIVATION_AMPLITUDE, ACTIVATION_GAIN};

use super::activation::activation;
use crate::solve::{LANES, Lanes, madd, tanh_lanes};

/// Most inputs a module can have (a node: two children of width [`MAX_WIDTH`] and its 3
/// normalized coordinates).
pub const MAX_INPUTS: usize = 2 * MAX_WIDTH + 3;

/// Offsets of a module's trained parameters, relative to the first trained parameter.
///
/// Same order as the core's [`neurosurf_core::implicit::ModuleLayout`]: hidden a W (N×d) and b
/// (N), hidden b W (N×N) and b (N), output w (N) and b (1).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct TrainedLayout {
    /// Inputs d.
    pub inputs: usize,
    /// Width N.
    pub width: usize,
    /// hidden a weights.
    pub a_weights: usize,
    /// hidden a biases.
    pub a_biases: usize,
    /// hidden b weights.
    pub b_weights: usize,
    /// hidden b biases.
    pub b_biases: usize,
    /// output weights.
    pub out_weights: usize,
    /// output bias.
    pub out_bias: usize,
    /// Number of trained parameters.
    pub len: usize,
}

impl TrainedLayout {
    /// The layout of a module with `inputs` inputs and hidden width `width`.
    pub const fn new(inputs: usize, width: usize) -> Self {
        let a_biases = inputs * width;
        let b_weights = a_biases + width;
        let b_biases = b_weights + width * width;
        let out_weights = b_biases + width;
        let out_bias = out_weights + width;
        TrainedLayout {
            inputs,
            width,
            a_weights: 0,
            a_biases,
            b_weights,
            b_biases,
            out_weights,
            out_bias,
            len: out_bias + 1,
        }
    }

    /// Whether the given parameter index is a bias (initialized to 0, per the paper).
    pub fn is_bias(&self, index: usize) -> bool {
        (self.a_biases..self.b_weights).contains(&index)
            || (self.b_biases..self.out_weights).contains(&index)
            || index == self.out_bias
    }
}

/// A module input at one point: values and tangents along x₀, x₁, x₂.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct InputJet<'a> {
    /// Input values (d).
    pub values: &'a [f64],
    /// Tangents: `tangents[k][c]` = ∂ input c / ∂ xₖ.
    pub tangents: [&'a [f64]; 3],
}

/// One hidden layer's intermediates kept for the backward sweep.
#[derive(Copy, Clone, Debug)]
struct HiddenTape {
    value: [f64; MAX_WIDTH],
    slope: [f64; MAX_WIDTH],
    curvature: [f64; MAX_WIDTH],
    /// ᵏI: net-input tangents.
    net_tangent: [[f64; MAX_WIDTH]; 3],
    /// ᵏG = a′·ᵏI: output tangents.
    tangent: [[f64; MAX_WIDTH]; 3],
}

impl HiddenTape {
    const ZERO: Self = HiddenTape {
        value: [0.0; MAX_WIDTH],
        slope: [0.0; MAX_WIDTH],
        curvature: [0.0; MAX_WIDTH],
        net_tangent: [[0.0; MAX_WIDTH]; 3],
        tangent: [[0.0; MAX_WIDTH]; 3],
    };
}

/// Everything the forward pass of one module at one point produces.
#[derive(Copy, Clone, Debug)]
pub struct Tape {
    a: HiddenTape,
    b: HiddenTape,
    out_slope: f64,
    out_curvature: f64,
    out_net_tangent: [f64; 3],
    /// Φ.
    pub value: f64,
    /// ∇Φ.
    pub gradient: [f64; 3],
}

impl Tape {
    /// The last hidden layer (b): values and tangents along x₀, x₁, x₂ (first N entries used).
    pub fn last_hidden(&self) -> HiddenJet {
        HiddenJet {
            values: self.b.value,
            tangents: self.b.tangent,
        }
    }
}

/// A hidden layer's values and world-space tangents at one point.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct HiddenJet {
    /// Neuron values (first N used).
    pub values: [f64; MAX_WIDTH],
    /// `tangents[k][j]` = ∂ neuron j / ∂ xₖ.
    pub tangents: [[f64; MAX_WIDTH]; 3],
}

/// Runs a module forward at one point.
pub fn forward(layout: &TrainedLayout, params: &[f64], input: &InputJet<'_>) -> Tape {
    let n = layout.width;
    let d = layout.inputs;
    let mut a = HiddenTape::ZERO;
    hidden(
        n,
        &params[layout.a_weights..layout.a_biases],
        &params[layout.a_biases..layout.a_biases + n],
        &input.values[..d],
        [
            &input.tangents[0][..d],
            &input.tangents[1][..d],
            &input.tangents[2][..d],
        ],
        &mut a,
    );
    let mut b = HiddenTape::ZERO;
    hidden(
        n,
        &params[layout.b_weights..layout.b_biases],
        &params[layout.b_biases..layout.b_biases + n],
        &a.value[..n],
        [&a.tangent[0][..n], &a.tangent[1][..n], &a.tangent[2][..n]],
        &mut b,
    );
    let w = &params[layout.out_weights..layout.out_weights + n];
    let mut h = params[layout.out_bias];
    let mut net_tangent = [0.0; 3];
    for j in 0..n {
        h += w[j] * b.value[j];
        for k in 0..3 {
            net_tangent[k] += w[j] * b.tangent[k][j];
        }
    }
    let act = activation(h);
    Tape {
        a,
        b,
        out_slope: act.slope,
        out_curvature: act.curvature,
        out_net_tangent: net_tangent,
        value: act.value,
        gradient: net_tangent.map(|t| act.slope * t),
    }
}

fn hidden(
    n: usize,
    weights: &[f64],
    biases: &[f64],
    values: &[f64],
    tangents: [&[f64]; 3],
    tape: &mut HiddenTape,
) {
    let d = values.len();
    for j in 0..n {
        let row = &weights[j * d..(j + 1) * d];
        let mut h = biases[j];
        let mut t = [0.0; 3];
        for c in 0..d {
            let w = row[c];
            h += w * values[c];
            t[0] += w * tangents[0][c];
            t[1] += w * tangents[1][c];
            t[2] += w * tangents[2][c];
        }
        let act = activation(h);
        tape.value[j] = act.value;
        tape.slope[j] = act.slope;
        tape.curvature[j] = act.curvature;
        for k in 0..3 {
            tape.net_tangent[k][j] = t[k];
            tape.tangent[k][j] = act.slope * t[k];
        }
    }
}

/// Writes the four Jacobian rows of one point into `rows` (4 × `layout.len`, row-major):
/// ∂Φ/∂θ, then γ·∂(∂Φ/∂xₖ)/∂θ for k = 0, 1, 2.
///
/// The four backward sweeps share most of their work. The Φ row starts with no tangent
/// adjoint, and none appears on the way down, so its weight derivatives are plain outer
/// products H̄·Oᵀ. The γ∂Φ/∂xₖ row starts with ᵏĪ = γa′ and no other tangent adjoint, and at
/// every layer that adjoint, ᵏĪ = a′·Σ w·ᵏĪ, does not depend on k: one vector serves all three
/// rows, and only the value adjoints H̄ differ. The arithmetic per entry is that of the
/// general sweep (the terms it skips are exact zeros).
pub fn jacobian_rows(
    layout: &TrainedLayout,
    params: &[f64],
    input: &InputJet<'_>,
    tape: &Tape,
    gamma: f64,
    rows: &mut [f64],
) {
    let n = layout.width;
    let d = layout.inputs;
    let p = layout.len;
    let (a, b) = (&tape.a, &tape.b);
    let w_out = &params[layout.out_weights..layout.out_weights + n];
    let w_b = &params[layout.b_weights..layout.b_biases];
    let mut rows: [&mut [f64]; 4] = {
        let (r0, rest) = rows.split_at_mut(p);
        let (r1, rest) = rest.split_at_mut(p);
        let (r2, r3) = rest.split_at_mut(p);
        [r0, r1, r2, &mut r3[..p]]
    };

    // Seeds at the output neuron: H̄ per row, and the tangent adjoint of the gradient rows.
    let h_seed = [
        tape.out_slope,
        tape.out_curvature * tape.out_net_tangent[0] * gamma,
        tape.out_curvature * tape.out_net_tangent[1] * gamma,
        tape.out_curvature * tape.out_net_tangent[2] * gamma,
    ];
    let i_seed = tape.out_slope * gamma;

    // Output layer; adjoints of hidden b's outputs.
    let mut value_bar = [[0.0; MAX_WIDTH]; 4];
    let mut tangent_bar = [0.0; MAX_WIDTH];
    for (r, row) in rows.iter_mut().enumerate() {
        let h = h_seed[r];
        let out = &mut row[layout.out_weights..layout.out_weights + n];
        if r == 0 {
            for j in 0..n {
                out[j] = h * b.value[j];
            }
        } else {
            let t = &b.tangent[r - 1];
            for j in 0..n {
                out[j] = h * b.value[j] + i_seed * t[j];
            }
        }
        row[layout.out_bias] = h;
        for j in 0..n {
            value_bar[r][j] = w_out[j] * h;
        }
    }
    for j in 0..n {
        tangent_bar[j] = w_out[j] * i_seed;
    }

    // Hidden b; adjoints of hidden a's outputs.
    let (b_h, b_i) = layer_adjoints(n, b, &value_bar, &tangent_bar);
    let a_jet = [
        &a.value[..n],
        &a.tangent[0][..n],
        &a.tangent[1][..n],
        &a.tangent[2][..n],
    ];
    write_layer(
        n,
        n,
        layout.b_weights,
        layout.b_biases,
        &b_h,
        &b_i,
        a_jet,
        &mut rows,
    );
    let mut value_bar = [[0.0; MAX_WIDTH]; 4];
    let mut tangent_bar = [0.0; MAX_WIDTH];
    for j in 0..n {
        let w_row = &w_b[j * n..(j + 1) * n];
        for r in 0..4 {
            let h = b_h[r][j];
            for c in 0..n {
                value_bar[r][c] += w_row[c] * h;
            }
        }
        let t = b_i[j];
        for c in 0..n {
            tangent_bar[c] += w_row[c] * t;
        }
    }

    // Hidden a.
    let (a_h, a_i) = layer_adjoints(n, a, &value_bar, &tangent_bar);
    let x_jet = [
        &input.values[..d],
        &input.tangents[0][..d],
        &input.tangents[1][..d],
        &input.tangents[2][..d],
    ];
    write_layer(
        n,
        d,
        layout.a_weights,
        layout.a_biases,
        &a_h,
        &a_i,
        x_jet,
        &mut rows,
    );
}

/// A hidden layer's net-input adjoints from its output adjoints: H̄ per row (Ō·a′, plus
/// ᵏḠ·a″·ᵏI in the gradient rows) and the shared ᵏĪ = ᵏḠ·a′.
#[inline(always)]
fn layer_adjoints(
    n: usize,
    tape: &HiddenTape,
    value_bar: &[[f64; MAX_WIDTH]; 4],
    tangent_bar: &[f64; MAX_WIDTH],
) -> ([[f64; MAX_WIDTH]; 4], [f64; MAX_WIDTH]) {
    let mut h_bar = [[0.0; MAX_WIDTH]; 4];
    let mut i_bar = [0.0; MAX_WIDTH];
    for j in 0..n {
        h_bar[0][j] = value_bar[0][j] * tape.slope[j];
        for k in 0..3 {
            h_bar[1 + k][j] = value_bar[1 + k][j] * tape.slope[j]
                + tangent_bar[j] * tape.curvature[j] * tape.net_tangent[k][j];
        }
        i_bar[j] = tangent_bar[j] * tape.slope[j];
    }
    (h_bar, i_bar)
}

/// A hidden layer's weight and bias derivatives in all four rows: ∂/∂w_jc = H̄_j·O_c in the Φ
/// row, H̄_j·O_c + Ī_j·ᵏO_c in the gradient row k, where O are the layer's inputs.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn write_layer(
    n: usize,
    d: usize,
    weights: usize,
    biases: usize,
    h_bar: &[[f64; MAX_WIDTH]; 4],
    i_bar: &[f64; MAX_WIDTH],
    inputs: [&[f64]; 4],
    rows: &mut [&mut [f64]; 4],
) {
    for (r, row) in rows.iter_mut().enumerate() {
        let (w_grads, rest) = row[weights..].split_at_mut(n * d);
        let values = &inputs[0][..d];
        for (j, grad_row) in w_grads.chunks_exact_mut(d).enumerate() {
            let h = h_bar[r][j];
            if r == 0 {
                for c in 0..d {
                    grad_row[c] = h * values[c];
                }
            } else {
                let t = &inputs[r][..d];
                let i = i_bar[j];
                for c in 0..d {
                    grad_row[c] = h * values[c] + i * t[c];
                }
            }
        }
        rest[biases - weights - n * d..][..n].copy_from_slice(&h_bar[r][..n]);
    }
}

/// The inputs of [`LANES`] points, lane-minor: `values[c][l]`, `tangents[k][c][l]`.
#[derive(Clone, Debug)]
pub(crate) struct InputLanes {
    pub values: [Lanes; MAX_INPUTS],
    pub tangents: [[Lanes; MAX_INPUTS]; 3],
}

impl InputLanes {
    pub const ZERO: Self = InputLanes {
        values: [[0.0; LANES]; MAX_INPUTS],
        tangents: [[[0.0; LANES]; MAX_INPUTS]; 3],
    };
}

/// [`activation`] on every lane: (a, a′, a″), with [`tanh_lanes`].
#[inline(always)]
fn activation_lanes<const FMA: bool>(h: Lanes) -> [Lanes; 3] {
    let t = tanh_lanes::<FMA>(h.map(|x| ACTIVATION_GAIN * x));
    let mut out = [[0.0; LANES]; 3];
    for l in 0..LANES {
        let slope = ACTIVATION_AMPLITUDE * ACTIVATION_GAIN * (1.0 - t[l] * t[l]);
        out[0][l] = ACTIVATION_AMPLITUDE * t[l];
        out[1][l] = slope;
        out[2][l] = -2.0 * ACTIVATION_GAIN * t[l] * slope;
    }
    out
}

/// One hidden layer on [`LANES`] points.
#[derive(Clone, Debug)]
struct HiddenLanes {
    value: [Lanes; MAX_WIDTH],
    slope: [Lanes; MAX_WIDTH],
    curvature: [Lanes; MAX_WIDTH],
    net_tangent: [[Lanes; MAX_WIDTH]; 3],
    tangent: [[Lanes; MAX_WIDTH]; 3],
}

impl HiddenLanes {
    const ZERO: Self = HiddenLanes {
        value: [[0.0; LANES]; MAX_WIDTH],
        slope: [[0.0; LANES]; MAX_WIDTH],
        curvature: [[0.0; LANES]; MAX_WIDTH],
        net_tangent: [[[0.0; LANES]; MAX_WIDTH]; 3],
        tangent: [[[0.0; LANES]; MAX_WIDTH]; 3],
    };
}

/// [`Tape`] of [`LANES`] points, lane-minor.
#[derive(Clone, Debug)]
pub(crate) struct TapeLanes {
    a: HiddenLanes,
    b: HiddenLanes,
    out_slope: Lanes,
    out_curvature: Lanes,
    out_net_tangent: [Lanes; 3],
    /// Φ.
    pub value: Lanes,
    /// ∇Φ.
    pub gradient: [Lanes; 3],
}

impl TapeLanes {
    pub const ZERO: Self = TapeLanes {
        a: HiddenLanes::ZERO,
        b: HiddenLanes::ZERO,
        out_slope: [0.0; LANES],
        out_curvature: [0.0; LANES],
        out_net_tangent: [[0.0; LANES]; 3],
        value: [0.0; LANES],
        gradient: [[0.0; LANES]; 3],
    };
}

/// [`hidden`] on [`LANES`] points: net inputs first, then the activations (independent
/// chains the CPU overlaps).
#[inline(always)]
fn hidden_lanes<const FMA: bool>(
    n: usize,
    weights: &[f64],
    biases: &[f64],
    values: &[Lanes],
    tangents: [&[Lanes]; 3],
    out: &mut HiddenLanes,
) {
    let d = values.len();
    let mut net = [[0.0; LANES]; MAX_WIDTH];
    for j in 0..n {
        let row = &weights[j * d..(j + 1) * d];
        let mut h = [biases[j]; LANES];
        let mut t = [[0.0; LANES]; 3];
        for c in 0..d {
            let w = row[c];
            for l in 0..LANES {
                h[l] = madd::<FMA>(w, values[c][l], h[l]);
                for k in 0..3 {
                    t[k][l] = madd::<FMA>(w, tangents[k][c][l], t[k][l]);
                }
            }
        }
        net[j] = h;
        for k in 0..3 {
            out.net_tangent[k][j] = t[k];
        }
    }
    for j in 0..n {
        let [value, slope, curvature] = activation_lanes::<FMA>(net[j]);
        out.value[j] = value;
        out.slope[j] = slope;
        out.curvature[j] = curvature;
        for k in 0..3 {
            for l in 0..LANES {
                out.tangent[k][j][l] = slope[l] * out.net_tangent[k][j][l];
            }
        }
    }
}

/// [`forward`] on [`LANES`] points at once (one per lane), with [`tanh_lanes`] and, when
/// `FMA`, fused multiply–adds.
#[inline(always)]
pub(crate) fn forward_lanes<const FMA: bool>(
    layout: &TrainedLayout,
    params: &[f64],
    input: &InputLanes,
    tape: &mut TapeLanes,
) {
    let n = layout.width;
    let d = layout.inputs;
    hidden_lanes::<FMA>(
        n,
        &params[layout.a_weights..layout.a_biases],
        &params[layout.a_biases..layout.a_biases + n],
        &input.values[..d],
        [
            &input.tangents[0][..d],
            &input.tangents[1][..d],
            &input.tangents[2][..d],
        ],
        &mut tape.a,
    );
    let a = &tape.a;
    hidden_lanes::<FMA>(
        n,
        &params[layout.b_weights..layout.b_biases],
        &params[layout.b_biases..layout.b_biases + n],
        &a.value[..n],
        [&a.tangent[0][..n], &a.tangent[1][..n], &a.tangent[2][..n]],
        &mut tape.b,
    );
    let b = &tape.b;
    let w = &params[layout.out_weights..layout.out_weights + n];
    let mut h = [params[layout.out_bias]; LANES];
    let mut net_tangent = [[0.0; LANES]; 3];
    for j in 0..n {
        for l in 0..LANES {
            h[l] = madd::<FMA>(w[j], b.value[j][l], h[l]);
            for k in 0..3 {
                net_tangent[k][l] = madd::<FMA>(w[j], b.tangent[k][j][l], net_tangent[k][l]);
            }
        }
    }
    let [value, slope, curvature] = activation_lanes::<FMA>(h);
    for k in 0..3 {
        for l in 0..LANES {
            tape.gradient[k][l] = slope[l] * net_tangent[k][l];
        }
    }
    tape.out_slope = slope;
    tape.out_curvature = curvature;
    tape.out_net_tangent = net_tangent;
    tape.value = value;
}

/// x·y per lane.
#[inline(always)]
fn mul(x: Lanes, y: Lanes) -> Lanes {
    std::array::from_fn(|l| x[l] * y[l])
}

/// x·y + z·w per lane (fused once when `FMA`).
#[inline(always)]
fn mul_add2<const FMA: bool>(x: Lanes, y: Lanes, z: Lanes, w: Lanes) -> Lanes {
    std::array::from_fn(|l| madd::<FMA>(x[l], y[l], z[l] * w[l]))
}

/// [`jacobian_rows`] of [`LANES`] points at once: `out[r · stride + θ][l]` = row r of point l.
///
/// The same sweeps and the same arithmetic as [`jacobian_rows`], one point per lane (with
/// fused multiply–adds when `FMA`).
#[inline(always)]
pub(crate) fn jacobian_lanes<const FMA: bool>(
    layout: &TrainedLayout,
    params: &[f64],
    input: &InputLanes,
    tape: &TapeLanes,
    gamma: f64,
    out: &mut [Lanes],
    stride: usize,
) {
    let n = layout.width;
    let d = layout.inputs;
    let p = layout.len;
    let (a, b) = (&tape.a, &tape.b);
    let w_out = &params[layout.out_weights..layout.out_weights + n];
    let w_b = &params[layout.b_weights..layout.b_biases];
    let mut rows: [&mut [Lanes]; 4] = {
        let (r0, rest) = out.split_at_mut(stride);
        let (r1, rest) = rest.split_at_mut(stride);
        let (r2, r3) = rest.split_at_mut(stride);
        [&mut r0[..p], &mut r1[..p], &mut r2[..p], &mut r3[..p]]
    };

    let mut h_seed = [tape.out_slope; 4];
    for m in 0..3 {
        h_seed[1 + m] =
            std::array::from_fn(|l| tape.out_curvature[l] * tape.out_net_tangent[m][l] * gamma);
    }
    let i_seed: Lanes = tape.out_slope.map(|s| s * gamma);

    let mut value_bar = [[[0.0; LANES]; MAX_WIDTH]; 4];
    let mut tangent_bar = [[0.0; LANES]; MAX_WIDTH];
    for (r, row) in rows.iter_mut().enumerate() {
        let h = h_seed[r];
        let o = &mut row[layout.out_weights..layout.out_weights + n];
        if r == 0 {
            for j in 0..n {
                o[j] = mul(h, b.value[j]);
            }
        } else {
            for j in 0..n {
                o[j] = mul_add2::<FMA>(h, b.value[j], i_seed, b.tangent[r - 1][j]);
            }
        }
        row[layout.out_bias] = h;
        for j in 0..n {
            value_bar[r][j] = h.map(|x| w_out[j] * x);
        }
    }
    for j in 0..n {
        tangent_bar[j] = i_seed.map(|x| w_out[j] * x);
    }

    let (b_h, b_i) = layer_adjoints_lanes::<FMA>(n, b, &value_bar, &tangent_bar);
    write_layer_lanes::<FMA>(
        n,
        n,
        layout.b_weights,
        layout.b_biases,
        &b_h,
        &b_i,
        [&a.value, &a.tangent[0], &a.tangent[1], &a.tangent[2]],
        &mut rows,
    );
    let mut value_bar = [[[0.0; LANES]; MAX_WIDTH]; 4];
    let mut tangent_bar = [[0.0; LANES]; MAX_WIDTH];
    for j in 0..n {
        let w_row = &w_b[j * n..(j + 1) * n];
        for c in 0..n {
            let w = w_row[c];
            for r in 0..4 {
                for l in 0..LANES {
                    value_bar[r][c][l] = madd::<FMA>(w, b_h[r][j][l], value_bar[r][c][l]);
                }
            }
            for l in 0..LANES {
                tangent_bar[c][l] = madd::<FMA>(w, b_i[j][l], tangent_bar[c][l]);
            }
        }
    }

    let (a_h, a_i) = layer_adjoints_lanes::<FMA>(n, a, &value_bar, &tangent_bar);
    write_layer_lanes::<FMA>(
        n,
        d,
        layout.a_weights,
        layout.a_biases,
        &a_h,
        &a_i,
        [
            &input.values[..d],
            &input.tangents[0][..d],
            &input.tangents[1][..d],
            &input.tangents[2][..d],
        ],
        &mut rows,
    );
}

/// [`layer_adjoints`] per lane.
#[inline(always)]
fn layer_adjoints_lanes<const FMA: bool>(
    n: usize,
    tape: &HiddenLanes,
    value_bar: &[[Lanes; MAX_WIDTH]; 4],
    tangent_bar: &[Lanes; MAX_WIDTH],
) -> ([[Lanes; MAX_WIDTH]; 4], [Lanes; MAX_WIDTH]) {
    let mut h_bar = [[[0.0; LANES]; MAX_WIDTH]; 4];
    let mut i_bar = [[0.0; LANES]; MAX_WIDTH];
    for j in 0..n {
        h_bar[0][j] = mul(value_bar[0][j], tape.slope[j]);
        for k in 0..3 {
            h_bar[1 + k][j] = std::array::from_fn(|l| {
                madd::<FMA>(
                    value_bar[1 + k][j][l],
                    tape.slope[j][l],
                    tangent_bar[j][l] * tape.curvature[j][l] * tape.net_tangent[k][j][l],
                )
            });
        }
        i_bar[j] = mul(tangent_bar[j], tape.slope[j]);
    }
    (h_bar, i_bar)
}

/// [`write_layer`] per lane.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn write_layer_lanes<const FMA: bool>(
    n: usize,
    d: usize,
    weights: usize,
    biases: usize,
    h_bar: &[[Lanes; MAX_WIDTH]; 4],
    i_bar: &[Lanes; MAX_WIDTH],
    inputs: [&[Lanes]; 4],
    rows: &mut [&mut [Lanes]; 4],
) {
    for (r, row) in rows.iter_mut().enumerate() {
        let (w_grads, rest) = row[weights..].split_at_mut(n * d);
        let values = &inputs[0][..d];
        for (j, grad_row) in w_grads.chunks_exact_mut(d).enumerate() {
            let h = h_bar[r][j];
            if r == 0 {
                for c in 0..d {
                    grad_row[c] = mul(h, values[c]);
                }
            } else {
                let t = &inputs[r][..d];
                let i = i_bar[j];
                for c in 0..d {
                    grad_row[c] = mul_add2::<FMA>(h, values[c], i, t[c]);
                }
            }
        }
        rest[biases - weights - n * d..][..n].copy_from_slice(&h_bar[r][..n]);
    }
}

/// Copies lane-minor rows (`lanes[r · stride + θ][l]`, from [`jacobian_lanes`]) of the first
/// `count` points to row-major rows `rows[(4l + r) · stride + θ]`, for θ < `stride` (a multiple
/// of 4), by 4 × 4 transposes (AVX shuffles when `AVX`).
#[inline(always)]
pub(crate) fn transpose_lanes<const AVX: bool>(
    lanes: &[Lanes],
    stride: usize,
    count: usize,
    rows: &mut [f64],
) {
    assert!(stride.is_multiple_of(4));
    assert!(lanes.len() >= 4 * stride && rows.len() >= 4 * count * stride);
    #[cfg(target_arch = "x86_64")]
    if AVX && count == LANES {
        // SAFETY: `AVX` builds run only on CPUs with AVX2; the sizes are checked above.
        unsafe { transpose_avx(lanes, stride, rows) };
        return;
    }
    for r in 0..4 {
        let src = lanes[r * stride..(r + 1) * stride].as_chunks::<4>().0;
        for (c0, tile) in src.iter().enumerate() {
            for l in 0..count {
                let dst = &mut rows[(4 * l + r) * stride + 4 * c0..][..4];
                for t in 0..4 {
                    dst[t] = tile[t][l];
                }
            }
        }
    }
}

/// [`transpose_lanes`] of [`LANES`] points with AVX shuffles.
///
/// # Safety
/// The CPU has AVX2; `lanes` holds 4 · `stride` entries, `rows` 16 · `stride`, and `stride`
/// is a multiple of 4.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn transpose_avx(lanes: &[Lanes], stride: usize, rows: &mut [f64]) {
    use std::arch::x86_64::{
        _mm256_loadu_pd, _mm256_permute2f128_pd, _mm256_storeu_pd, _mm256_unpackhi_pd,
        _mm256_unpacklo_pd,
    };
    let src = lanes.as_ptr().cast::<f64>();
    let dst = rows.as_mut_ptr();
    for r in 0..4 {
        for c in (0..stride).step_by(4) {
            // SAFETY: in bounds by the caller's contract.
            unsafe {
                let tile = src.add((r * stride + c) * LANES);
                let t0 = _mm256_loadu_pd(tile);
                let t1 = _mm256_loadu_pd(tile.add(4));
                let t2 = _mm256_loadu_pd(tile.add(8));
                let t3 = _mm256_loadu_pd(tile.add(12));
                let lo01 = _mm256_unpacklo_pd(t0, t1);
                let hi01 = _mm256_unpackhi_pd(t0, t1);
                let lo23 = _mm256_unpacklo_pd(t2, t3);
                let hi23 = _mm256_unpackhi_pd(t2, t3);
                let row = |l: usize| dst.add((4 * l + r) * stride + c);
                _mm256_storeu_pd(row(0), _mm256_permute2f128_pd::<0x20>(lo01, lo23));
                _mm256_storeu_pd(row(1), _mm256_permute2f128_pd::<0x20>(hi01, hi23));
                _mm256_storeu_pd(row(2), _mm256_permute2f128_pd::<0x31>(lo01, lo23));
                _mm256_storeu_pd(row(3), _mm256_permute2f128_pd::<0x31>(hi01, hi23));
            }
        }
    }
}

#[cfg(test)]
mod lane_tests {
    use super::*;

    #[test]
    fn lane_activation_matches_the_scalar_one() {
        for i in -200..=200 {
            let h = f64::from(i) * 0.05;
            let [v, s, c] = activation_lanes::<false>([h; LANES]);
            let a = activation(h);
            assert!((v[0] - a.value).abs() <= 1e-15);
            assert!((s[0] - a.slope).abs() <= 1e-15);
            assert!((c[0] - a.curvature).abs() <= 1e-15);
        }
    }
}

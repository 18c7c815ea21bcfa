//! Shared helpers of the core's integration tests: `f64` vector helpers, a seeded PRNG, random models on the Q16.16
//! grid, blob framing, and an independent `f64` reference evaluator written from the documented
//! parameter layout (`core/src/implicit/layout.rs`).
#![allow(dead_code)]

use neurosurf_core::blob::{self, ModelKind};
use neurosurf_core::implicit::{ImplicitPayload, ModuleKind, ModuleLayout, NORMALIZATION_LEN};
use neurosurf_core::scalar::{
    ACTIVATION_AMPLITUDE, ACTIVATION_GAIN, Q16, Q16_ACTIVATION_MAX_ERROR, ScalarKind,
};

/// Largest absolute error of the Q16.16 a′ (`activation_slope` of the Q16.16 activation of a
/// Q16.16 input) against the exact a′ at that input. Measured exhaustively in `activation.rs`:
/// 4.61·10⁻⁵ = 3.02 LSB (at H = −2.14667: the activation error times |∂a′/∂a| ≤ 1.34 plus the two
/// roundings of the slope); bound 2⁻¹⁴.
pub const Q16_SLOPE_MAX_ERROR: f64 = 1.0 / 16384.0;
/// Largest absolute error of the Q16.16 a″ against the exact a″. Measured exhaustively:
/// 5.97·10⁻⁵ = 3.91 LSB (at H = −4.02939); bound 1.25·2⁻¹⁴.
pub const Q16_CURVATURE_MAX_ERROR: f64 = 1.25 / 16384.0;
/// Largest absolute error of the `f32` a′ over H ∈ [−50, 50] (measured 3.5·10⁻⁷).
pub const F32_SLOPE_MAX_ERROR: f64 = 5.0e-7;
/// Largest absolute error of the `f32` a″ over H ∈ [−50, 50] (measured 4.5·10⁻⁷).
pub const F32_CURVATURE_MAX_ERROR: f64 = 5.0e-7;

/// `a − b`.
pub fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `Σ aᵢ·bᵢ`, summed in order.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `a × b`.
pub fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `|v|`.
pub fn norm(v: [f64; 3]) -> f64 {
    dot(&v, &v).sqrt()
}

/// One Q16.16 unit in the last place.
pub const LSB: f64 = 1.0 / 65536.0;

/// SplitMix64: small, seeded, good enough for test data.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, n) (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }

    pub fn byte(&mut self) -> u8 {
        self.next_u64() as u8
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1_u64 << 53) as f64
    }

    /// Uniform in [lo, hi), rounded to the Q16.16 grid (so exact in f32, Q16.16 and f64).
    pub fn grid(&mut self, lo: f64, hi: f64) -> f64 {
        to_grid(lo + (hi - lo) * self.unit())
    }

    /// A point of the test box [−1, 1]³ on the Q16.16 grid.
    pub fn point(&mut self) -> [f64; 3] {
        [(); 3].map(|()| self.grid(-1.0, 1.0))
    }
}

/// Rounds to the nearest multiple of 2⁻¹⁶.
pub fn to_grid(x: f64) -> f64 {
    (x * 65536.0).round() / 65536.0
}

/// The tree shapes the tests use, as post-order module kind codes.
pub const SINGLE_LEAF: &[u8] = &[0];
/// (0, 1): two leaves and their node.
pub const PAIR: &[u8] = &[0, 0, 1];
/// ((0, 1), 2).
pub const LEFT_COMB: &[u8] = &[0, 0, 1, 0, 1];
/// ((0, 1), (2, 3)).
pub const BALANCED_4: &[u8] = &[0, 0, 1, 0, 0, 1, 1];
pub const TREES: [&[u8]; 4] = [SINGLE_LEAF, PAIR, LEFT_COMB, BALANCED_4];

pub fn kind(code: u8) -> ModuleKind {
    ModuleKind::from_code(code).expect("valid module code")
}

/// Module offsets into the parameter array.
pub fn offsets(tree: &[u8], width: usize) -> Vec<usize> {
    let mut offset = 0;
    tree.iter()
        .map(|&c| {
            let here = offset;
            offset += ModuleLayout::new(kind(c), width).len;
            here
        })
        .collect()
}

pub fn parameter_count(tree: &[u8], width: usize) -> usize {
    tree.iter()
        .map(|&c| ModuleLayout::new(kind(c), width).len)
        .sum()
}

/// 3×3 rotation from a (normalized) random quaternion.
fn rotation(rng: &mut Rng) -> [[f64; 3]; 3] {
    let q = [(); 4].map(|()| rng.unit() * 2.0 - 1.0);
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-9);
    let [w, x, y, z] = q.map(|v| v / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Random parameters for `tree` at `width`, all on the Q16.16 grid: weights and biases in
/// [−`weight`, `weight`] (a node's position columns included); every module's (leaf's and
/// node's) center in [−0.25, 0.25]³ and axes A = S·R (a rotation R into the module's box, then
/// per-axis scales S in [0.5, 2]).
pub fn random_parameters(rng: &mut Rng, tree: &[u8], width: usize, weight: f64) -> Vec<f64> {
    let mut params = Vec::with_capacity(parameter_count(tree, width));
    for &code in tree {
        let layout = ModuleLayout::new(kind(code), width);
        assert_eq!(layout.trainable_start, NORMALIZATION_LEN);
        for _ in 0..3 {
            params.push(rng.grid(-0.25, 0.25));
        }
        let r = rotation(rng);
        for row in r {
            let scale = 0.5 + 1.5 * rng.unit();
            for v in row {
                params.push(to_grid(scale * v));
            }
        }
        for _ in 0..layout.trainable_len() {
            params.push(rng.grid(-weight, weight));
        }
    }
    assert_eq!(params.len(), parameter_count(tree, width));
    params
}

/// The stored words of `params` in `kind`.
pub fn encode_parameters(params: &[f64], kind: ScalarKind) -> Vec<u8> {
    params
        .iter()
        .flat_map(|&p| kind.encode(p).expect("encodable parameter"))
        .collect()
}

/// Writes an implicit-model blob with `blob::write`.
pub fn implicit_blob(
    kind: ScalarKind,
    width: u8,
    tree: &[u8],
    parameters: &[u8],
    metadata: &[u8],
) -> Vec<u8> {
    let payload = ImplicitPayload {
        width,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        tree,
        parameters,
        metadata,
    };
    let mut out = vec![0_u8; 64 + tree.len() + parameters.len() + metadata.len()];
    let len = blob::write(ModelKind::Implicit, kind, &payload, &mut out).expect("blob fits");
    out.truncate(len);
    out
}

/// An implicit blob of `params` (f64 values) stored as `kind`.
pub fn model_blob(kind: ScalarKind, width: usize, tree: &[u8], params: &[f64]) -> Vec<u8> {
    implicit_blob(
        kind,
        u8::try_from(width).expect("width"),
        tree,
        &encode_parameters(params, kind),
        b"test",
    )
}

/// Frames arbitrary payload bytes by hand (header, payload, CRC) with arbitrary kind codes.
pub fn frame(version: u16, model: u8, scalar: u8, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(payload.len() + 16);
    out.extend_from_slice(&blob::MAGIC);
    out.extend_from_slice(&version.to_le_bytes());
    out.push(model);
    out.push(scalar);
    out.extend_from_slice(&u32::try_from(payload.len()).expect("len").to_le_bytes());
    out.extend_from_slice(payload);
    let crc = blob::crc32(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Recomputes the CRC of a blob whose framing is otherwise intact (any length ≥ 4).
pub fn fix_crc(bytes: &mut [u8]) {
    if let Some(body_len) = bytes.len().checked_sub(4) {
        let crc = blob::crc32(&bytes[..body_len]);
        bytes[body_len..].copy_from_slice(&crc.to_le_bytes());
    }
}

pub fn q16_point(p: [f64; 3]) -> [Q16; 3] {
    p.map(Q16::from_num)
}

pub fn f32_point(p: [f64; 3]) -> [f32; 3] {
    p.map(|v| v as f32)
}

// ---------------------------------------------------------------------------------------------
// The f64 reference.

/// Exact a(H), a′(H), a″(H).
pub fn activation(h: f64) -> (f64, f64, f64) {
    let t = (ACTIVATION_GAIN * h).tanh();
    let value = ACTIVATION_AMPLITUDE * t;
    let slope = ACTIVATION_AMPLITUDE * ACTIVATION_GAIN * (1.0 - t * t);
    let curvature = -2.0 * ACTIVATION_GAIN * t * slope;
    (value, slope, curvature)
}

/// max |a″| = 1.7159·(2/3)²·max|2t(1 − t²)| = 1.7159·(4/9)·(4/(3√3)).
pub fn max_curvature() -> f64 {
    ACTIVATION_AMPLITUDE * ACTIVATION_GAIN * ACTIVATION_GAIN * 4.0 / (3.0 * 3.0_f64.sqrt())
}

/// Half a Q16.16 LSB: the error of one rounding of a Q32.32 accumulator or product.
const HALF_LSB: f64 = 1.0 / 131_072.0;

/// A layer's neurons at one point: values, gradients with respect to the world point, and a
/// rigorous bound on how far a Q16.16 evaluation can be from them (running error analysis).
#[derive(Clone, Debug, Default)]
pub struct Neurons {
    pub value: Vec<f64>,
    pub gradient: Vec<[f64; 3]>,
    /// Bound on |Q16 value − value|.
    pub value_error: Vec<f64>,
    /// Bound on |Q16 gradient − gradient|, per direction.
    pub gradient_error: Vec<[f64; 3]>,
}

impl Neurons {
    fn concat(mut self, other: Neurons) -> Neurons {
        self.value.extend(other.value);
        self.gradient.extend(other.gradient);
        self.value_error.extend(other.value_error);
        self.gradient_error.extend(other.gradient_error);
        self
    }
}

/// One dense layer with the activation on every neuron: Hⱼ = bⱼ + Σᵢ Wⱼᵢ·xᵢ, Oⱼ = a(Hⱼ),
/// ∇Oⱼ = a′(Hⱼ)·Σᵢ Wⱼᵢ·∇xᵢ (row-major W, then biases).
///
/// Error bound for Q16.16 (the core computes each H and each net tangent T = Σ W·∇x exactly in
/// Q32.32 and rounds once, ±2⁻¹⁷; the activation comes from a table, ±ε_a; the slope from the
/// rounded activation, ±ε_s at the rounded H; the tangent is slope·T rounded, ±2⁻¹⁷):
/// - |H̃ − H| ≤ e = Σ|W|·δx + 2⁻¹⁷,
/// - |Õ − O| ≤ ε_a + max_{|u−H|≤e} a′(u)·e (mean value theorem; a′ peaks at 0),
/// - |s̃ − a′(H)| ≤ σ = ε_s + max|a″|·e,
/// - |T̃ − T| ≤ t = Σ|W|·δ∇x + 2⁻¹⁷,
/// - |G̃ − a′(H)·T| ≤ (a′(H) + σ)·t + |T|·σ + 2⁻¹⁷.
fn dense(params: &[f64], weights: usize, inputs: usize, outputs: usize, x: &Neurons) -> Neurons {
    let biases = weights + inputs * outputs;
    let mut out = Neurons::default();
    for j in 0..outputs {
        let row = &params[weights + j * inputs..weights + (j + 1) * inputs];
        let mut h = params[biases + j];
        let mut t = [0.0; 3];
        let mut e = HALF_LSB;
        let mut te = [HALF_LSB; 3];
        for i in 0..inputs {
            h += row[i] * x.value[i];
            e += row[i].abs() * x.value_error[i];
            for k in 0..3 {
                t[k] += row[i] * x.gradient[i][k];
                te[k] += row[i].abs() * x.gradient_error[i][k];
            }
        }
        let (a, slope, _) = activation(h);
        let (_, slope_max, _) = activation((h.abs() - e).max(0.0));
        let sigma = Q16_SLOPE_MAX_ERROR + max_curvature() * e;
        out.value.push(a);
        out.gradient.push(t.map(|tk| slope * tk));
        out.value_error
            .push(Q16_ACTIVATION_MAX_ERROR + slope_max * e);
        out.gradient_error.push(std::array::from_fn(|k| {
            (slope + sigma) * te[k] + t[k].abs() * sigma + HALF_LSB
        }));
    }
    out
}

/// The f64 reference model: the documented layout evaluated directly.
#[derive(Clone, Debug)]
pub struct Reference {
    pub width: usize,
    pub tree: Vec<u8>,
    pub params: Vec<f64>,
    offsets: Vec<usize>,
    /// Left child of each node (the right child is `index − 1`).
    lefts: Vec<usize>,
}

impl Reference {
    pub fn new(width: usize, tree: &[u8], params: &[f64]) -> Self {
        assert_eq!(params.len(), parameter_count(tree, width));
        let mut lefts = vec![usize::MAX; tree.len()];
        let mut pending = Vec::new();
        for (i, &c) in tree.iter().enumerate() {
            if kind(c) == ModuleKind::Node {
                let _right = pending.pop().expect("right child");
                lefts[i] = pending.pop().expect("left child");
            }
            pending.push(i);
        }
        assert_eq!(pending.len(), 1);
        Reference {
            width,
            tree: tree.to_vec(),
            params: params.to_vec(),
            offsets: offsets(tree, width),
            lefts,
        }
    }

    pub fn root(&self) -> usize {
        self.tree.len() - 1
    }

    /// First module of the subtree rooted at `i`.
    pub fn subtree_start(&self, i: usize) -> usize {
        match kind(self.tree[i]) {
            ModuleKind::Leaf => i,
            ModuleKind::Node => self.subtree_start(self.lefts[i]),
        }
    }

    /// Last hidden layer (b) of module `i`.
    fn hidden_b(&self, i: usize, x: [f64; 3]) -> Neurons {
        let n = self.width;
        let p = &self.params[self.offsets[i]..];
        let layout = ModuleLayout::new(kind(self.tree[i]), n);
        // Every module's normalized position x′ = A·(x − c): exact inputs on the grid, one
        // rounding in Q16.16, exact tangents (the rows of A).
        let (c, a) = (&p[0..3], &p[3..12]);
        let mut position = Neurons::default();
        for r in 0..3 {
            let row = &a[3 * r..3 * r + 3];
            position
                .value
                .push((0..3).map(|k| row[k] * (x[k] - c[k])).sum());
            position.gradient.push([row[0], row[1], row[2]]);
            position.value_error.push(HALF_LSB);
            position.gradient_error.push([0.0; 3]);
        }
        let input = match layout.kind {
            // A leaf reads x′ alone.
            ModuleKind::Leaf => position,
            // A node reads [b of the left child, b of the right child, x′].
            ModuleKind::Node => self
                .hidden_b(self.lefts[i], x)
                .concat(self.hidden_b(i - 1, x))
                .concat(position),
        };
        let a = dense(
            p,
            layout.hidden_a.weights,
            layout.hidden_a.inputs,
            n,
            &input,
        );
        dense(p, layout.hidden_b.weights, n, n, &a)
    }

    /// Φ and ∇Φ of module `i`'s subtree through its own output neuron (which, like every
    /// neuron, applies the activation), with the Q16.16 error bounds of both.
    pub fn eval_module_bounded(&self, i: usize, x: [f64; 3]) -> (f64, [f64; 3], f64, [f64; 3]) {
        let layout = ModuleLayout::new(kind(self.tree[i]), self.width);
        let b = self.hidden_b(i, x);
        let out = dense(
            &self.params[self.offsets[i]..],
            layout.output.weights,
            self.width,
            1,
            &b,
        );
        (
            out.value[0],
            out.gradient[0],
            out.value_error[0],
            out.gradient_error[0],
        )
    }

    pub fn eval_module(&self, i: usize, x: [f64; 3]) -> (f64, [f64; 3]) {
        let (v, g, _, _) = self.eval_module_bounded(i, x);
        (v, g)
    }

    pub fn eval(&self, x: [f64; 3]) -> (f64, [f64; 3]) {
        self.eval_module(self.root(), x)
    }

    /// The parameters of the subtree rooted at `i`, with its tree (a stand-alone model).
    pub fn subtree(&self, i: usize) -> Reference {
        let start = self.subtree_start(i);
        let from = self.offsets[start];
        let to = self.offsets[i] + ModuleLayout::new(kind(self.tree[i]), self.width).len;
        Reference::new(self.width, &self.tree[start..=i], &self.params[from..to])
    }
}

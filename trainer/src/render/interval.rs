//! Interval arithmetic through the module tree: bounds of Φ (and of its derivative along a
//! ray) over a ray segment or an axis-aligned box. Every module's inputs are bounded: a leaf's
//! normalized position x′ = A·(x − c), and a node's children's last hidden layers followed by
//! its own x′ (blob format 2).
//!
//! Every layer is affine followed by the activation a(H) = 1.7159·tanh(2H/3), which is
//! monotone, so an interval \[H\] maps to [a(H.lo), a(H.hi)]; affine maps are bounded in
//! center–radius form (center W·m + b, radius |W|·r), which is exact for one layer. The
//! derivative along the ray is carried as a second interval (forward mode: O′ = a′(H)·H′, with
//! a′ even and decreasing in |H|). Over a segment the mean-value form
//! Φ(t_m) + [Φ′]·(\[t\] − t_m) is intersected with the direct bound: it shrinks quadratically
//! with the segment, where the direct bound suffers from the wrapping effect the paper
//! complains about (§6).
//!
//! Accuracy: computed in `f64` without directed rounding; every final bound is widened by
//! [`ROUNDING_MARGIN`], far above the accumulated rounding (≈ 10⁻¹⁴ for Carcenac-sized
//! modules) and far below the field's resolution near the surface.

use neurosurf_core::implicit::MAX_WIDTH;
use neurosurf_core::scalar::{ACTIVATION_AMPLITUDE as AMPLITUDE, ACTIVATION_GAIN as GAIN};

use crate::implicit::{ImplicitNetwork, MAX_INPUTS, Normalization};

/// Absolute widening of every final bound, covering floating-point rounding.
pub const ROUNDING_MARGIN: f64 = 1e-9;

/// A closed interval `[lo, hi]`.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
pub struct Interval {
    /// Lower bound.
    pub lo: f64,
    /// Upper bound.
    pub hi: f64,
}

impl Interval {
    /// `[v, v]`.
    pub const fn point(v: f64) -> Self {
        Interval { lo: v, hi: v }
    }

    /// `[lo, hi]` (the caller keeps lo ≤ hi).
    pub const fn new(lo: f64, hi: f64) -> Self {
        Interval { lo, hi }
    }

    /// Whether 0 ∈ [lo, hi] (NaN bounds count as containing it).
    pub fn contains_zero(&self) -> bool {
        !(self.lo > 0.0 || self.hi < 0.0)
    }

    /// The product of two intervals.
    pub fn times(self, other: Interval) -> Interval {
        let p = [
            self.lo * other.lo,
            self.lo * other.hi,
            self.hi * other.lo,
            self.hi * other.hi,
        ];
        Interval {
            lo: p.iter().copied().fold(f64::INFINITY, f64::min),
            hi: p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    /// `[lo − m, hi + m]`.
    pub fn widen(self, m: f64) -> Interval {
        Interval {
            lo: self.lo - m,
            hi: self.hi + m,
        }
    }

    /// The intersection (the first interval if they are disjoint, which exact arithmetic
    /// rules out).
    pub fn intersect(self, other: Interval) -> Interval {
        let lo = self.lo.max(other.lo);
        let hi = self.hi.min(other.hi);
        if lo <= hi { Interval { lo, hi } } else { self }
    }
}

/// Values and derivatives along the ray of one layer's neurons, as intervals.
#[derive(Copy, Clone, Debug)]
struct Layer {
    value: [Interval; MAX_INPUTS],
    slope: [Interval; MAX_INPUTS],
}

impl Layer {
    const ZERO: Layer = Layer {
        value: [Interval::point(0.0); MAX_INPUTS],
        slope: [Interval::point(0.0); MAX_INPUTS],
    };
}

/// Where the network is bounded: a ray segment `origin + t·direction`, t ∈ \[t\], or a box.
#[derive(Copy, Clone, Debug)]
pub enum Domain {
    /// A segment of a ray.
    Segment {
        /// Ray origin.
        origin: [f64; 3],
        /// Ray direction.
        direction: [f64; 3],
        /// Parameter range.
        t: Interval,
    },
    /// An axis-aligned box (center and half sides); derivatives are not tracked.
    Box {
        /// Center.
        center: [f64; 3],
        /// Half sides.
        half: [f64; 3],
    },
}

/// Bounds of Φ and of dΦ/dt (zero for a box) over `domain`, by direct propagation through
/// every module (no mean-value form, no margin): see [`segment_bounds`] and [`box_bounds`].
fn propagate(network: &ImplicitNetwork, domain: &Domain) -> (Interval, Interval) {
    let root = module(network, network.root(), domain, true);
    (root.value[0], root.slope[0])
}

/// Bounds of Φ and dΦ/dt over a ray segment (mean-value form intersected with the direct
/// bound, widened by [`ROUNDING_MARGIN`]). `direction` need not be unit; t ∈ \[t\].
pub fn segment_bounds(
    network: &ImplicitNetwork,
    origin: [f64; 3],
    direction: [f64; 3],
    t: Interval,
) -> (Interval, Interval) {
    let (direct, slope) = propagate(
        network,
        &Domain::Segment {
            origin,
            direction,
            t,
        },
    );
    let mid = 0.5 * (t.lo + t.hi);
    let (at_mid, _) = propagate(
        network,
        &Domain::Segment {
            origin,
            direction,
            t: Interval::point(mid),
        },
    );
    let offset = Interval::new(t.lo - mid, t.hi - mid);
    let mean_value = slope.times(offset);
    let mean_value = Interval::new(at_mid.lo + mean_value.lo, at_mid.hi + mean_value.hi);
    (
        direct.intersect(mean_value).widen(ROUNDING_MARGIN),
        slope.widen(ROUNDING_MARGIN),
    )
}

/// Bounds of Φ over the axis-aligned box `center ± half`, widened by [`ROUNDING_MARGIN`].
pub fn box_bounds(network: &ImplicitNetwork, center: [f64; 3], half: [f64; 3]) -> Interval {
    propagate(network, &Domain::Box { center, half })
        .0
        .widen(ROUNDING_MARGIN)
}

/// Module `i`: its last hidden layer (`output = false`) or its output neuron in entry 0.
fn module(network: &ImplicitNetwork, i: usize, domain: &Domain, output: bool) -> Layer {
    let n = network.width();
    let mut input = Layer::ZERO;
    // Every module reads its normalized position x′ = A·(x − c): a leaf as its whole input, a
    // node after its children's last hidden layers ([b_left, b_right, x′]).
    let (position, d) = match network.children(i) {
        Some((l, r)) => {
            for (half, child) in [l, r].into_iter().enumerate() {
                let b = module(network, child, domain, false);
                input.value[half * n..(half + 1) * n].copy_from_slice(&b.value[..n]);
                input.slope[half * n..(half + 1) * n].copy_from_slice(&b.slope[..n]);
            }
            (2 * n, 2 * n + 3)
        }
        None => (0, 3),
    };
    let Some(norm) = network.normalization(i) else {
        return Layer::ZERO;
    };
    for (k, (value, slope)) in normalized_position(&norm, domain).into_iter().enumerate() {
        input.value[position + k] = value;
        input.slope[position + k] = slope;
    }
    let layout = network.trained_layout(i);
    debug_assert_eq!(layout.inputs, d);
    let params = network.trained_params(i);
    let a = dense(
        &params[layout.a_weights..layout.a_biases],
        &params[layout.a_biases..layout.a_biases + n],
        &input,
        d,
        n,
    );
    let b = dense(
        &params[layout.b_weights..layout.b_biases],
        &params[layout.b_biases..layout.b_biases + n],
        &a,
        n,
        n,
    );
    if !output {
        return b;
    }
    dense(
        &params[layout.out_weights..layout.out_weights + n],
        &params[layout.out_bias..layout.out_bias + 1],
        &b,
        n,
        1,
    )
}

/// Bounds of the normalized position x′ = A·(x − c) and of its derivative along the ray over
/// `domain`, coordinate by coordinate: each x′ₖ is affine in the point, so over a segment its
/// range is exact (the ends) and its slope the constant rowₖ·d, and over a box it is the
/// center's value ± Σ|Aₖⱼ|·halfⱼ. (Independent bounds per coordinate: conservative where the
/// next layer mixes them, as every input interval is.)
fn normalized_position(norm: &Normalization, domain: &Domain) -> [(Interval, Interval); 3] {
    norm.matrix.map(|row| match domain {
        Domain::Segment {
            origin,
            direction,
            t,
        } => {
            // u(t) = row·(o − c) + t·row·d: affine in t, so exact.
            let base: f64 = (0..3).map(|j| row[j] * (origin[j] - norm.center[j])).sum();
            let rate: f64 = (0..3).map(|j| row[j] * direction[j]).sum();
            let (a, b) = (base + rate * t.lo, base + rate * t.hi);
            (Interval::new(a.min(b), a.max(b)), Interval::point(rate))
        }
        Domain::Box { center, half } => {
            let mid: f64 = (0..3).map(|j| row[j] * (center[j] - norm.center[j])).sum();
            let radius: f64 = (0..3).map(|j| row[j].abs() * half[j]).sum();
            (
                Interval::new(mid - radius, mid + radius),
                Interval::point(0.0),
            )
        }
    })
}

/// One dense layer and its activation, in center–radius form.
fn dense(weights: &[f64], biases: &[f64], input: &Layer, d: usize, n: usize) -> Layer {
    let mut out = Layer::ZERO;
    for j in 0..n.min(MAX_WIDTH) {
        let row = &weights[j * d..(j + 1) * d];
        let (mut mid, mut radius) = (biases[j], 0.0);
        let (mut slope_mid, mut slope_radius) = (0.0, 0.0);
        for (w, (v, s)) in row.iter().zip(input.value.iter().zip(&input.slope)) {
            mid += w * 0.5 * (v.lo + v.hi);
            radius += w.abs() * 0.5 * (v.hi - v.lo);
            slope_mid += w * 0.5 * (s.lo + s.hi);
            slope_radius += w.abs() * 0.5 * (s.hi - s.lo);
        }
        let h = Interval::new(mid - radius, mid + radius);
        let h_slope = Interval::new(slope_mid - slope_radius, slope_mid + slope_radius);
        out.value[j] = Interval::new(activation(h.lo), activation(h.hi));
        out.slope[j] = activation_slope(h).times(h_slope);
    }
    out
}

fn activation(h: f64) -> f64 {
    AMPLITUDE * (GAIN * h).tanh()
}

/// The range of a′ over [h]: a′ is even and decreasing in |h|.
fn activation_slope(h: Interval) -> Interval {
    let slope = |x: f64| {
        let t = (GAIN * x).tanh();
        AMPLITUDE * GAIN * (1.0 - t * t)
    };
    let far = h.lo.abs().max(h.hi.abs());
    let near = if h.contains_zero() {
        0.0
    } else {
        h.lo.abs().min(h.hi.abs())
    };
    Interval::new(slope(far), slope(near))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::{ImplicitNetwork, Normalization, TreeSpec};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random 3-leaf network (tree ((0,1),2), width 5), leaves normalized around the origin.
    pub(crate) fn random_network(seed: u64) -> ImplicitNetwork {
        let tree: TreeSpec = "((0,1),2)".parse().unwrap();
        let mut net = ImplicitNetwork::new(5, &tree).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for i in 0..net.module_count() {
            for p in net.trained_params_mut(i) {
                *p = rng.random_range(-1.5..1.5);
            }
            let normalization = Normalization {
                center: [0.1 * i as f64, 0.0, -0.1],
                matrix: [[1.0, 0.2, 0.0], [0.0, 0.9, 0.1], [0.3, 0.0, 1.1]],
            };
            net.set_normalization(i, &normalization);
        }
        net
    }

    #[test]
    fn bounds_enclose_samples() {
        let net = random_network(3);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        for _ in 0..40 {
            let origin: [f64; 3] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
            let direction: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let t0 = rng.random_range(0.0..2.0);
            let t = Interval::new(t0, t0 + rng.random_range(0.0..0.5));
            let (value, slope) = segment_bounds(&net, origin, direction, t);
            for s in 0..=20 {
                let tt = t.lo + (t.hi - t.lo) * f64::from(s) / 20.0;
                let p = [0, 1, 2].map(|k| origin[k] + tt * direction[k]);
                let (phi, g) = net.eval(p);
                let dphi: f64 = (0..3).map(|k| g[k] * direction[k]).sum();
                assert!(value.lo <= phi && phi <= value.hi, "{phi} ∉ {value:?}");
                assert!(slope.lo <= dphi && dphi <= slope.hi, "{dphi} ∉ {slope:?}");
            }
            let center = origin;
            let half = [0.1, 0.2, 0.05];
            let bound = box_bounds(&net, center, half);
            for s in 0..27 {
                let p: [f64; 3] = std::array::from_fn(|k| {
                    center[k] + half[k] * f64::from((s / 3_i32.pow(k as u32)) % 3 - 1)
                });
                let phi = net.eval(p).0;
                assert!(bound.lo <= phi && phi <= bound.hi, "{phi} ∉ {bound:?}");
            }
        }
    }

    /// Nodes whose position inputs dominate (their a′ weights on x′ ten times the others):
    /// the bounds must still hold, along segments and over boxes — they would not if the
    /// nodes' x′ were left out of the propagation.
    #[test]
    fn bounds_enclose_samples_when_node_positions_dominate() {
        let mut net = random_network(7);
        let n = net.width();
        for i in 0..net.module_count() {
            if net.children(i).is_none() {
                continue;
            }
            let layout = net.trained_layout(i);
            assert_eq!(layout.inputs, 2 * n + 3);
            let params = net.trained_params_mut(i);
            for j in 0..n {
                for k in 0..3 {
                    params[layout.a_weights + j * layout.inputs + 2 * n + k] *= 10.0;
                }
            }
        }
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        for _ in 0..60 {
            let origin: [f64; 3] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
            let direction: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
            let t0 = rng.random_range(0.0..2.0);
            let t = Interval::new(t0, t0 + rng.random_range(0.0..0.3));
            let (value, slope) = segment_bounds(&net, origin, direction, t);
            for s in 0..=30 {
                let tt = t.lo + (t.hi - t.lo) * f64::from(s) / 30.0;
                let p = [0, 1, 2].map(|k| origin[k] + tt * direction[k]);
                let (phi, g) = net.eval(p);
                let dphi: f64 = (0..3).map(|k| g[k] * direction[k]).sum();
                assert!(value.lo <= phi && phi <= value.hi, "{phi} ∉ {value:?}");
                assert!(slope.lo <= dphi && dphi <= slope.hi, "{dphi} ∉ {slope:?}");
            }
            let half = [0.15, 0.05, 0.1];
            let bound = box_bounds(&net, origin, half);
            for s in 0..125 {
                let p: [f64; 3] = std::array::from_fn(|k| {
                    let step = (s / 5_i32.pow(k as u32)) % 5 - 2;
                    origin[k] + half[k] * f64::from(step) / 2.0
                });
                let phi = net.eval(p).0;
                assert!(bound.lo <= phi && phi <= bound.hi, "{phi} ∉ {bound:?}");
            }
        }
    }

    #[test]
    fn mean_value_form_tightens_short_segments() {
        let net = random_network(5);
        let (wide, _) = segment_bounds(
            &net,
            [0.2, -0.1, 0.0],
            [1.0, 0.0, 0.0],
            Interval::new(0.0, 1e-3),
        );
        // Φ varies by at most |Φ′|·10⁻³ over the segment: the bound must be that tight.
        assert!(wide.hi - wide.lo < 0.05, "{wide:?}");
    }
}

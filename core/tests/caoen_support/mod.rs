//! Shared helpers of the Cao En tests: blob builders and an independent `f64` reference
//! written from the contract in `core/src/caoen/mod.rs` — plain sums, `powi`/`exp` from std,
//! and normals from an explicit tangent frame (not the core's cofactor form).
#![allow(dead_code)]

use neurosurf_core::caoen::CaoEnPayload;
use neurosurf_core::scalar::{Q16, ScalarKind};

#[allow(unused_imports)]
pub use common::{LSB, Rng, fix_crc, frame, to_grid};

/// The PRNG, test constants and framing shared with the other core tests.
#[path = "../common/mod.rs"]
mod common;
pub use common::{cross, dot, norm, sub};

/// A Cao En network in f64, as the trainer would hold it.
#[derive(Clone, Debug, PartialEq)]
pub struct RefNet {
    /// 0 sphere, 1 torus.
    pub domain: u8,
    /// 0 power, 1 exponential.
    pub blending: u8,
    pub normalized: bool,
    pub weights: Vec<Vec<f64>>,
    pub targets: Vec<Vec<f64>>,
    pub sharpness: Vec<f64>,
}

impl RefNet {
    pub fn m(&self) -> usize {
        self.weights[0].len()
    }

    pub fn p(&self) -> usize {
        self.targets[0].len()
    }

    /// F and F′ of key i at s.
    pub fn blend(&self, i: usize, s: f64) -> (f64, f64) {
        let q = self.sharpness[i];
        if self.blending == 0 {
            if s == 0.0 && q == 1.0 {
                // The kink of F(s) = s: the mean of the one-sided slopes 0 and 1.
                (0.0, 0.5)
            } else if s <= 0.0 {
                (0.0, 0.0)
            } else if q == 0.0 {
                (1.0, 0.0)
            } else {
                (s.powi(q as i32), q * s.powi(q as i32 - 1))
            }
        } else if self.blending == 1 {
            let f = (q * (s - 1.0)).exp();
            (f, q * f)
        } else {
            let u = 1.0 + q * (s - 1.0);
            if u > 0.0 {
                (u.powi(3), 3.0 * q * u * u)
            } else {
                (0.0, 0.0)
            }
        }
    }

    /// Σᵢ Fᵢ(x·wᵢ), the normalizing sum.
    pub fn blend_sum(&self, x: &[f64]) -> f64 {
        (0..self.weights.len())
            .map(|i| self.blend(i, dot(&self.weights[i], x)).0)
            .sum()
    }

    /// y and ∂y/∂x (p × m) at x (any point of ℝᵐ).
    pub fn eval(&self, x: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
        let (m, p) = (self.m(), self.p());
        let mut a = vec![0.0; p];
        let mut da = vec![vec![0.0; m]; p];
        let mut b = 0.0;
        let mut db = vec![0.0; m];
        for i in 0..self.weights.len() {
            let s: f64 = (0..m).map(|h| x[h] * self.weights[i][h]).sum();
            let (f, df) = self.blend(i, s);
            b += f;
            for h in 0..m {
                db[h] += df * self.weights[i][h];
            }
            for g in 0..p {
                a[g] += f * self.targets[i][g];
                for h in 0..m {
                    da[g][h] += df * self.weights[i][h] * self.targets[i][g];
                }
            }
        }
        if !self.normalized {
            return (a, da);
        }
        if b == 0.0 {
            return (vec![0.0; p], vec![vec![0.0; m]; p]);
        }
        let y: Vec<f64> = a.iter().map(|v| v / b).collect();
        let j = (0..p)
            .map(|g| (0..m).map(|h| (da[g][h] - y[g] * db[h]) / b).collect())
            .collect();
        (y, j)
    }

    pub fn position(&self, x: &[f64]) -> Vec<f64> {
        self.eval(x).0
    }

    /// Two tangent vectors of the domain at x: a right-handed orthonormal frame (e₁, e₂, x) on
    /// the sphere, ∂x/∂θ and ∂x/∂φ on the torus.
    pub fn tangents(&self, x: &[f64]) -> ([f64; 4], [f64; 4]) {
        if self.domain == 1 {
            return ([-x[1], x[0], 0.0, 0.0], [0.0, 0.0, -x[3], x[2]]);
        }
        let n = [x[0], x[1], x[2]];
        let helper = if n[0].abs() < 0.6 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let e1 = normalize(cross(helper, n));
        let e2 = cross(n, e1);
        ([e1[0], e1[1], e1[2], 0.0], [e2[0], e2[1], e2[2], 0.0])
    }

    /// The exact unit normal (J·e₁) × (J·e₂), `None` where it degenerates.
    pub fn normal(&self, x: &[f64]) -> Option<[f64; 3]> {
        let (n, _) = self.raw_normal(x);
        (norm(n) > 1e-12).then(|| normalize(n))
    }

    /// How well defined the normal is: |(J·e₁) × (J·e₂)| / max|Jᵍʰ|² (0 for a degenerate
    /// Jacobian, ~1 for a conformal one).
    pub fn normal_strength(&self, x: &[f64]) -> f64 {
        let (n, largest) = self.raw_normal(x);
        if largest == 0.0 {
            0.0
        } else {
            norm(n) / (largest * largest)
        }
    }

    /// max|Jᵍʰ|.
    pub fn jacobian_size(&self, x: &[f64]) -> f64 {
        self.raw_normal(x).1
    }

    /// (J·e₁) × (J·e₂) and max|Jᵍʰ|.
    fn raw_normal(&self, x: &[f64]) -> ([f64; 3], f64) {
        let (_, j) = self.eval(x);
        let (e1, e2) = self.tangents(x);
        let image = |e: [f64; 4]| -> [f64; 3] {
            std::array::from_fn(|g| (0..self.m()).map(|h| j[g][h] * e[h]).sum())
        };
        let largest = j.iter().flatten().map(|v| v.abs()).fold(0.0, f64::max);
        (cross(image(e1), image(e2)), largest)
    }

    /// The normal from central finite differences of positions along the tangents (step
    /// `step`, staying on the sphere/torus by renormalizing), for checking the exact one.
    pub fn normal_by_differences(&self, x: &[f64], step: f64) -> Option<[f64; 3]> {
        let (e1, e2) = self.tangents(x);
        let along = |e: [f64; 4], t: f64| -> [f64; 3] {
            let moved: Vec<f64> = (0..self.m()).map(|h| x[h] + t * e[h]).collect();
            let moved = self.project_to_domain(&moved);
            let y = self.position(&moved);
            [y[0], y[1], y[2]]
        };
        let d1 = sub(along(e1, step), along(e1, -step));
        let d2 = sub(along(e2, step), along(e2, -step));
        let n = cross(d1, d2);
        (norm(n) > 1e-18).then(|| normalize(n))
    }

    /// Back onto the unit sphere, or onto the torus (each circle normalized).
    pub fn project_to_domain(&self, x: &[f64]) -> Vec<f64> {
        if self.domain == 1 {
            let a = x[0].hypot(x[1]);
            let b = x[2].hypot(x[3]);
            vec![x[0] / a, x[1] / a, x[2] / b, x[3] / b]
        } else {
            let r = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            x.iter().map(|v| v / r).collect()
        }
    }

    /// The payload words in `kind`.
    pub fn words(&self, kind: ScalarKind) -> [Vec<u8>; 3] {
        let encode = |rows: &[Vec<f64>]| -> Vec<u8> {
            rows.iter()
                .flatten()
                .flat_map(|&v| kind.encode(v).expect("encodable"))
                .collect()
        };
        [
            encode(&self.weights),
            encode(&self.targets),
            encode(std::slice::from_ref(&self.sharpness)),
        ]
    }

    pub fn blob(&self, kind: ScalarKind) -> Vec<u8> {
        let [w, t, q] = self.words(kind);
        raw_blob(
            kind,
            [
                self.domain,
                self.blending,
                u8::from(self.normalized),
                self.m() as u8,
                self.p() as u8,
            ],
            [&w, &t, &q],
        )
    }
}

/// A Cao En blob from raw fields: [domain, blending, normalized, m, p] and [W, V, q] bytes.
pub fn raw_blob(kind: ScalarKind, fields: [u8; 5], words: [&[u8]; 3]) -> Vec<u8> {
    let [domain, blending, normalized, m, p] = fields;
    let payload = CaoEnPayload {
        domain,
        blending,
        normalized: normalized != 0,
        source_dimension: m,
        target_dimension: p,
        weights: words[0],
        targets: words[1],
        sharpness: words[2],
        metadata: b"test cao en",
    };
    let mut out = vec![0_u8; 64 + words.iter().map(|w| w.len()).sum::<usize>()];
    let len = payload.write(kind, &mut out).unwrap();
    out.truncate(len);
    out
}

/// The six axis points ±eₖ.
pub fn axis_points() -> Vec<Vec<f64>> {
    let mut points = Vec::new();
    for k in 0..3 {
        for sign in [1.0, -1.0] {
            let mut p = vec![0.0; 3];
            p[k] = sign;
            points.push(p);
        }
    }
    points
}

/// The paper's Fig. 2/3 network: W = V = the six axis points, one q for all.
pub fn axis_network(blending: u8, normalized: bool, q: f64) -> RefNet {
    RefNet {
        domain: 0,
        blending,
        normalized,
        weights: axis_points(),
        targets: axis_points(),
        sharpness: vec![q; 6],
    }
}

/// A uniformly random unit vector of ℝᵐ on the Q16.16 grid (renormalized in f64 after
/// rounding, so it is a unit vector in f64 to 1e-16 but not exactly on the grid).
pub fn unit_vector(rng: &mut Rng, m: usize) -> Vec<f64> {
    loop {
        let v: Vec<f64> = (0..m).map(|_| rng.unit() * 2.0 - 1.0).collect();
        let r = v.iter().map(|c| c * c).sum::<f64>().sqrt();
        if (0.2..=1.0).contains(&r) {
            return v.iter().map(|c| to_grid(c / r)).collect();
        }
    }
}

/// A random network: unit weights, targets in [−scale, scale]ᵖ, q per blending (power 1 … 8,
/// exponential 0.5 … 16, compact 0.5 … 16/3).
pub fn random_network(
    rng: &mut Rng,
    n: usize,
    dims: (usize, usize),
    blending: u8,
    normalized: bool,
    scale: f64,
) -> RefNet {
    let (m, p) = dims;
    RefNet {
        domain: 0,
        blending,
        normalized,
        weights: (0..n).map(|_| unit_vector(rng, m)).collect(),
        targets: (0..n)
            .map(|_| (0..p).map(|_| rng.grid(-scale, scale)).collect())
            .collect(),
        sharpness: (0..n)
            .map(|_| {
                match blending {
                    0 => (1 + rng.below(8)) as f64,
                    // F′(1) = 3q for compact blending (q for exponential): the same steepness
                    // at the key, where the input's rounding matters most.
                    2 => rng.grid(0.5, 16.0 / 3.0),
                    _ => rng.grid(0.5, 16.0),
                }
            })
            .collect(),
    }
}

pub fn normalize(v: [f64; 3]) -> [f64; 3] {
    let r = norm(v);
    v.map(|c| c / r)
}

/// Angle between two vectors, radians.
pub fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(cross(a, b)).atan2(dot(&a, &b))
}

pub fn q16s<const N: usize>(x: &[f64]) -> [Q16; N] {
    std::array::from_fn(|h| Q16::from_num(x.get(h).copied().unwrap_or(0.0)))
}

pub fn f32s<const N: usize>(x: &[f64]) -> [f32; N] {
    std::array::from_fn(|h| x.get(h).copied().unwrap_or(0.0) as f32)
}

//! The f64 Cao En network: the trainer's model and the reference the core is compared with.

use crate::geometry::vector::{cross, inner};
use neurosurf_core::caoen::{Blending, Domain, MAX_KEY_POINTS, MAX_SHARPNESS};
use neurosurf_core::caoen::{MAX_SOURCE_DIMENSION, MAX_TARGET_DIMENSION};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// y = Σᵢ kᵢ·tᵢ with kᵢ = Fᵢ(x·wᵢ) (or Fᵢ/Σ F when `normalized`): the contract of
/// `neurosurf_core::caoen`, evaluated in f64.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaoEnNetwork {
    /// 0 sphere / hypersphere, 1 torus ([`Domain::code`]).
    pub domain: u8,
    /// 0 power, 1 exponential, 2 compact ([`Blending::code`]).
    pub blending: u8,
    /// Whether k is normalized by Σ F (the rational form).
    pub normalized: bool,
    /// wᵢ, m coordinates each.
    pub weights: Vec<Vec<f64>>,
    /// tᵢ, p coordinates each (the columns of V).
    pub targets: Vec<Vec<f64>>,
    /// qᵢ.
    pub sharpness: Vec<f64>,
}

/// Position and Jacobian ∂y/∂x (p rows of m) at one source point.
#[derive(Clone, Debug, PartialEq)]
pub struct Evaluation {
    /// y.
    pub position: Vec<f64>,
    /// ∂y/∂x.
    pub jacobian: Vec<Vec<f64>>,
}

impl CaoEnNetwork {
    /// Number of key points n.
    pub fn key_count(&self) -> usize {
        self.weights.len()
    }

    /// m (0 without keys).
    pub fn source_dimension(&self) -> usize {
        self.weights.first().map_or(0, Vec::len)
    }

    /// p (0 without keys).
    pub fn target_dimension(&self) -> usize {
        self.targets.first().map_or(0, Vec::len)
    }

    /// Checks what the core's loader checks (shapes, caps, finiteness, q range).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the problem.
    pub fn validate(&self) -> Result<()> {
        let (n, m, p) = (
            self.key_count(),
            self.source_dimension(),
            self.target_dimension(),
        );
        let domain = Domain::from_code(self.domain)
            .ok_or_else(|| Error::invalid(format!("unknown domain code {}", self.domain)))?;
        Blending::from_code(self.blending)
            .ok_or_else(|| Error::invalid(format!("unknown blending code {}", self.blending)))?;
        if n == 0 || n > MAX_KEY_POINTS {
            return Err(Error::invalid(format!(
                "a Cao En network needs 1 to {MAX_KEY_POINTS} key points, got {n}"
            )));
        }
        let m_ok = match domain {
            Domain::Torus => m == 4,
            _ => (3..=MAX_SOURCE_DIMENSION).contains(&m),
        };
        if !m_ok || !(1..=MAX_TARGET_DIMENSION).contains(&p) {
            return Err(Error::invalid(format!(
                "source dimension {m} / target dimension {p} not supported for {domain:?}"
            )));
        }
        if self.targets.len() != n || self.sharpness.len() != n {
            return Err(Error::invalid(
                "weights, targets and sharpness differ in count",
            ));
        }
        for (i, (w, t)) in self.weights.iter().zip(&self.targets).enumerate() {
            if w.len() != m || t.len() != p {
                return Err(Error::invalid(format!(
                    "key point {i} has the wrong dimension"
                )));
            }
            if w.iter().chain(t).any(|v| !v.is_finite()) {
                return Err(Error::invalid(format!("key point {i} is not finite")));
            }
        }
        for (i, &q) in self.sharpness.iter().enumerate() {
            let whole = self.blending != 0 || q.fract() == 0.0;
            if !(0.0..=MAX_SHARPNESS).contains(&q) || !whole {
                return Err(Error::invalid(format!(
                    "sharpness q{i} = {q} is outside [0, {MAX_SHARPNESS}] or not whole for power \
                     blending"
                )));
            }
        }
        Ok(())
    }

    /// F and F′ of key `i` at s.
    pub fn blend(&self, i: usize, s: f64) -> (f64, f64) {
        let q = self.sharpness[i];
        match self.blending {
            0 => {
                if s == 0.0 && q == 1.0 {
                    // The kink of F(s) = s: the mean of the one-sided slopes, as the core
                    // takes it (`neurosurf_core::caoen`), so a zero coordinate keeps a normal.
                    (0.0, 0.5)
                } else if s <= 0.0 {
                    (0.0, 0.0)
                } else if q == 0.0 {
                    (1.0, 0.0)
                } else {
                    let below = s.powi(q as i32 - 1);
                    (below * s, q * below)
                }
            }
            1 => {
                let f = (q * (s - 1.0)).exp();
                (f, q * f)
            }
            _ => {
                let u = 1.0 + q * (s - 1.0);
                if u > 0.0 {
                    (u * u * u, 3.0 * q * u * u)
                } else {
                    (0.0, 0.0)
                }
            }
        }
    }

    /// The activations kᵢ at x (normalized when the network is).
    pub fn activations(&self, x: &[f64]) -> Vec<f64> {
        let k: Vec<f64> = self
            .weights
            .iter()
            .enumerate()
            .map(|(i, w)| self.blend(i, inner(w, x)).0)
            .collect();
        if !self.normalized {
            return k;
        }
        let sum: f64 = k.iter().sum();
        if sum == 0.0 {
            vec![0.0; k.len()]
        } else {
            k.iter().map(|v| v / sum).collect()
        }
    }

    /// y and ∂y/∂x at x (any point of ℝᵐ).
    pub fn evaluate(&self, x: &[f64]) -> Evaluation {
        let (m, p) = (self.source_dimension(), self.target_dimension());
        let mut a = vec![0.0; p];
        let mut da = vec![vec![0.0; m]; p];
        let (mut b, mut db) = (0.0, vec![0.0; m]);
        for (i, (w, t)) in self.weights.iter().zip(&self.targets).enumerate() {
            let (f, df) = self.blend(i, inner(w, x));
            b += f;
            for (h, &wh) in w.iter().enumerate() {
                db[h] += df * wh;
                for (g, &tg) in t.iter().enumerate() {
                    da[g][h] += df * wh * tg;
                }
            }
            for (g, &tg) in t.iter().enumerate() {
                a[g] += f * tg;
            }
        }
        if !self.normalized {
            return Evaluation {
                position: a,
                jacobian: da,
            };
        }
        if b == 0.0 {
            return Evaluation {
                position: vec![0.0; p],
                jacobian: vec![vec![0.0; m]; p],
            };
        }
        let position: Vec<f64> = a.iter().map(|v| v / b).collect();
        let jacobian = (0..p)
            .map(|g| {
                (0..m)
                    .map(|h| (da[g][h] - position[g] * db[h]) / b)
                    .collect()
            })
            .collect();
        Evaluation { position, jacobian }
    }

    /// y at x.
    ///
    /// The same sums in the same order as [`CaoEnNetwork::evaluate`] (so the same bits),
    /// without the Jacobian.
    pub fn position(&self, x: &[f64]) -> Vec<f64> {
        let mut a = vec![0.0; self.target_dimension()];
        let mut b = 0.0;
        for (i, (w, t)) in self.weights.iter().zip(&self.targets).enumerate() {
            let f = self.blend(i, inner(w, x)).0;
            b += f;
            for (g, &tg) in t.iter().enumerate() {
                a[g] += f * tg;
            }
        }
        if !self.normalized {
            return a;
        }
        if b == 0.0 {
            return vec![0.0; a.len()];
        }
        a.iter().map(|v| v / b).collect()
    }

    /// The exact unit normal at a sphere (m = 3) or torus point for p = 3, with the core's
    /// formulas (cofactor of J applied to x; tangent images on the torus); `None` elsewhere or
    /// where it degenerates.
    pub fn normal(&self, x: &[f64]) -> Option<[f64; 3]> {
        if self.target_dimension() != 3 {
            return None;
        }
        let j = self.evaluate(x).jacobian;
        let column = |h: usize| [j[0][h], j[1][h], j[2][h]];
        let n = match (self.domain, self.source_dimension()) {
            (0, 3) => {
                let cof = [
                    cross(column(1), column(2)),
                    cross(column(2), column(0)),
                    cross(column(0), column(1)),
                ];
                [0, 1, 2].map(|k| (0..3).map(|h| x[h] * cof[h][k]).sum())
            }
            (1, 4) => {
                let tangent = |c: usize, s: usize| {
                    let (a, b) = (column(c), column(s));
                    [0, 1, 2].map(|k| -x[s] * a[k] + x[c] * b[k])
                };
                cross(tangent(0, 1), tangent(2, 3))
            }
            _ => return None,
        };
        let length = inner(&n, &n).sqrt();
        (length > 1e-300).then(|| n.map(|c| c / length))
    }

    /// Where the blending is flat at a key point (power blending maps the key's whole
    /// neighbourhood to first order onto its target, so ∂y/∂x vanishes there), the normal as
    /// the mean of the normals a step of [`LIMIT_STEP`] away, in every diagonal direction
    /// (each source coordinate moved, with every combination of signs, by different amounts:
    /// a coordinate left at 0 can keep the Jacobian singular), back on the domain.
    fn limit_normal(&self, x: &[f64]) -> Option<[f64; 3]> {
        let mut sum = [0.0; 3];
        for signs in 0..1_u32 << x.len() {
            let near: Vec<f64> = x
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    let sign = if signs >> k & 1 == 1 { -1.0 } else { 1.0 };
                    c + sign * LIMIT_STEP * (1.0 + 0.37 * k as f64)
                })
                .collect();
            if let Some(n) = self.normal(&on_domain(self.domain, &near)) {
                sum = [0, 1, 2].map(|c| sum[c] + n[c]);
            }
        }
        let length = inner(&sum, &sum).sqrt();
        (length > 1e-12).then(|| sum.map(|c| c / length))
    }

    /// The paper's approximate-normal network (§7): the same key points and blending, with
    /// each target replaced by the exact unit normal at its key point (x = wᵢ normalized).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the network has no normals or one vanishes at a key point.
    pub fn normal_network(&self) -> Result<CaoEnNetwork> {
        let targets = self
            .weights
            .iter()
            .enumerate()
            .map(|(i, w)| {
                let x = on_domain(self.domain, w);
                self.normal(&x)
                    .or_else(|| self.limit_normal(&x))
                    .map(|n| n.to_vec())
                    .ok_or_else(|| {
                        Error::invalid(format!(
                            "the surface has no normal at key point {i} nor around it: the \
                             network maps the neighbourhood of the key to one point; refit it \
                             (more keys, or another --blending or --power) before deriving \
                             the normal network"
                        ))
                    })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(CaoEnNetwork {
            targets,
            ..self.clone()
        })
    }
}

/// How far from a key point [`CaoEnNetwork::normal_network`] looks for the normal where the
/// blending is flat at the key.
pub const LIMIT_STEP: f64 = 1e-4;

/// A point brought back onto the unit sphere, or onto the torus (each circle normalized).
pub fn on_domain(domain: u8, x: &[f64]) -> Vec<f64> {
    let unit = |v: &[f64]| {
        let r = inner(v, v).sqrt();
        v.iter().map(|c| c / r).collect::<Vec<_>>()
    };
    if domain == 1 && x.len() == 4 {
        let mut out = unit(&x[..2]);
        out.extend(unit(&x[2..]));
        out
    } else {
        unit(x)
    }
}

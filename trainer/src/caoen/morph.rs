//! Metamorphosis between two Cao En models (paper §12.1): both are maps from the same
//! sphere, so they are already in correspondence; the in-between network moves each key
//! point's weight, target and sharpness from one model to the other.
//!
//! Key points are paired greedily, nearest weights first (for power blending only keys of
//! the same whole q pair). A paired key interpolates its target and q linearly and its
//! weight along the great circle (direction interpolated and renormalized, length
//! interpolated). A key without a partner is *empty* at the end where it does not exist:
//!
//! - unnormalized form: its target scales to zero (the paper's empty key point: Vᵢ = 0
//!   contributes nothing);
//! - normalized form with power blending: its weight scales to zero (sᵢ = 0 gives F = 0, so
//!   the key drops out of Σ F as well);
//! - normalized form with compact blending: the same, for keys with q ≥ 1 (s = 0 is then off
//!   the key's cap);
//! - normalized form with exponential blending (or a compact key with q < 1): no key is ever
//!   empty (F > 0 at s = 0), so models with different key counts are refused.
//!
//! At t = 0 and t = 1 the network equals the two models up to rounding (the test asserts
//! surfaces within 10⁻⁹).

use neurosurf_core::caoen::{Blending, Domain};

use super::mesh::{CaoEnMesh, map_mesh};
use super::network::CaoEnNetwork;
use super::{icosphere, torus_grid};
use crate::error::{Error, Result};
use crate::geometry::vector::inner;

/// The most frames [`morph_meshes`] makes.
pub const MAX_FRAMES: usize = 10_000;

/// A metamorphosis from one network to another.
#[derive(Clone, Debug, PartialEq)]
pub struct Morph {
    from: CaoEnNetwork,
    to: CaoEnNetwork,
    /// Key i of the in-between network: a key of `from`, of `to`, or both.
    pairs: Vec<(Option<usize>, Option<usize>)>,
}

impl Morph {
    /// Pairs the key points of `from` and `to`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for invalid networks, networks that differ in domain,
    /// blending, form or dimensions, normalized exponential networks whose keys cannot all
    /// be paired, or more keys than a network may have.
    pub fn new(from: &CaoEnNetwork, to: &CaoEnNetwork) -> Result<Morph> {
        from.validate()?;
        to.validate()?;
        let differences: Vec<&str> = [
            (from.domain != to.domain, "domain"),
            (from.blending != to.blending, "blending"),
            (from.normalized != to.normalized, "form"),
            (
                from.source_dimension() != to.source_dimension()
                    || from.target_dimension() != to.target_dimension(),
                "dimensions",
            ),
        ]
        .into_iter()
        .filter_map(|(differs, what)| differs.then_some(what))
        .collect();
        if !differences.is_empty() {
            return Err(Error::invalid(format!(
                "these networks differ in {}: the first is {}, the second {}. A morph needs \
                 the same domain, blending, form and dimensions (fit both with the same \
                 --domain, --blending and --normalized)",
                differences.join(" and "),
                describe(from),
                describe(to)
            )));
        }
        let power = from.blending == Blending::Power.code();
        let mut candidates: Vec<(f64, usize, usize)> = Vec::new();
        for (i, a) in from.weights.iter().enumerate() {
            for (j, b) in to.weights.iter().enumerate() {
                if !power || from.sharpness[i] == to.sharpness[j] {
                    let cos = inner(a, b) / (inner(a, a) * inner(b, b)).sqrt().max(1e-300);
                    candidates.push((cos, i, j));
                }
            }
        }
        candidates.sort_by(|a, b| b.0.total_cmp(&a.0).then((a.1, a.2).cmp(&(b.1, b.2))));
        let (mut used_from, mut used_to) =
            (vec![false; from.key_count()], vec![false; to.key_count()]);
        let mut pairs = Vec::new();
        for (_, i, j) in candidates {
            if !used_from[i] && !used_to[j] {
                used_from[i] = true;
                used_to[j] = true;
                pairs.push((Some(i), Some(j)));
            }
        }
        pairs.extend(
            (0..from.key_count())
                .filter(|&i| !used_from[i])
                .map(|i| (Some(i), None)),
        );
        pairs.extend(
            (0..to.key_count())
                .filter(|&j| !used_to[j])
                .map(|j| (None, Some(j))),
        );
        pairs.sort();
        // In the normalized form a key is emptied by scaling its weight to zero: s = 0 must
        // give F = 0, as power blending does and compact blending does for q ≥ 1.
        let emptiable =
            |network: &CaoEnNetwork, i: usize| match Blending::from_code(network.blending) {
                Some(Blending::Power) => true,
                Some(Blending::Compact) => network.sharpness[i] >= 1.0,
                _ => false,
            };
        let stuck = pairs.iter().any(|pair| match *pair {
            (Some(i), None) => !emptiable(from, i),
            (None, Some(j)) => !emptiable(to, j),
            _ => false,
        });
        if from.normalized && stuck {
            return Err(Error::invalid(
                "no key point is ever empty in the normalized form with exponential blending \
                 (nor with compact blending and q < 1), so these networks with different key \
                 counts cannot morph (use power blending, compact blending with q ≥ 1, or the \
                 unnormalized form)",
            ));
        }
        let morph = Morph {
            from: from.clone(),
            to: to.clone(),
            pairs,
        };
        morph.at(0.5)?;
        Ok(morph)
    }

    /// Key points of every in-between network.
    pub fn key_count(&self) -> usize {
        self.pairs.len()
    }

    /// The in-between network at `t` (0: `from`, 1: `to`, up to rounding).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for t outside [0, 1].
    pub fn at(&self, t: f64) -> Result<CaoEnNetwork> {
        if !(0.0..=1.0).contains(&t) {
            return Err(Error::invalid(format!("morph time {t} is outside [0, 1]")));
        }
        let lerp = |a: &[f64], b: &[f64]| -> Vec<f64> {
            a.iter()
                .zip(b)
                .map(|(x, y)| (1.0 - t) * x + t * y)
                .collect()
        };
        let scale = |a: &[f64], s: f64| -> Vec<f64> { a.iter().map(|x| s * x).collect() };
        let empty_by_weight = self.from.normalized;
        let mut network = CaoEnNetwork {
            weights: Vec::with_capacity(self.pairs.len()),
            targets: Vec::with_capacity(self.pairs.len()),
            sharpness: Vec::with_capacity(self.pairs.len()),
            ..self.from.clone()
        };
        for &pair in &self.pairs {
            let (w, target, q) = match pair {
                (Some(i), Some(j)) => {
                    let (a, b) = (&self.from.weights[i], &self.to.weights[j]);
                    let direction = lerp(a, b);
                    let norm = inner(&direction, &direction).sqrt();
                    let length = (1.0 - t) * inner(a, a).sqrt() + t * inner(b, b).sqrt();
                    let w = if t == 0.0 {
                        a.clone()
                    } else if t == 1.0 || norm == 0.0 {
                        b.clone()
                    } else {
                        scale(&direction, length / norm)
                    };
                    let q = (1.0 - t) * self.from.sharpness[i] + t * self.to.sharpness[j];
                    (w, lerp(&self.from.targets[i], &self.to.targets[j]), q)
                }
                (Some(i), None) => self.fading(&self.from, i, 1.0 - t, empty_by_weight),
                (None, Some(j)) => self.fading(&self.to, j, t, empty_by_weight),
                (None, None) => continue,
            };
            network.weights.push(w);
            network.targets.push(target);
            network.sharpness.push(q);
        }
        network.validate()?;
        Ok(network)
    }

    /// Key `i` of `network` at strength `s` ∈ [0, 1] (0: empty).
    fn fading(
        &self,
        network: &CaoEnNetwork,
        i: usize,
        s: f64,
        by_weight: bool,
    ) -> (Vec<f64>, Vec<f64>, f64) {
        let (w, target) = (&network.weights[i], &network.targets[i]);
        let scaled = |v: &[f64]| v.iter().map(|x| s * x).collect::<Vec<f64>>();
        if by_weight {
            (scaled(w), target.clone(), network.sharpness[i])
        } else {
            (w.clone(), scaled(target), network.sharpness[i])
        }
    }
}

/// A network's kind in words: "a sphere network with power blending, unnormalized, 3 → 3
/// coordinates".
fn describe(network: &CaoEnNetwork) -> String {
    let domain = match Domain::from_code(network.domain) {
        Some(Domain::Torus) => "torus",
        _ if network.source_dimension() > 3 => "hypersphere",
        _ => "sphere",
    };
    let blending = match Blending::from_code(network.blending) {
        Some(Blending::Power) => "power",
        Some(Blending::Compact) => "compact",
        _ => "exponential",
    };
    format!(
        "a {domain} network with {blending} blending, {}, {} → {} coordinates",
        if network.normalized {
            "normalized"
        } else {
            "unnormalized"
        },
        network.source_dimension(),
        network.target_dimension()
    )
}

/// `frames` meshes from `from` to `to` (t = k/(frames − 1)), each the source grid of
/// `subdivisions` (an icosphere, or a torus grid of 10·2ˢ × 5·2ˢ) mapped through the
/// in-between network.
///
/// # Errors
/// As [`Morph::new`] and [`map_mesh`]; [`Error::InvalidInput`] for fewer than 2 or more
/// than [`MAX_FRAMES`] frames.
pub fn morph_meshes(
    from: &CaoEnNetwork,
    to: &CaoEnNetwork,
    frames: usize,
    subdivisions: usize,
) -> Result<Vec<CaoEnMesh>> {
    if !(2..=MAX_FRAMES).contains(&frames) {
        return Err(Error::invalid(format!(
            "a morph needs 2 to {MAX_FRAMES} frames, got {frames}"
        )));
    }
    let morph = Morph::new(from, to)?;
    let (sources, triangles): (Vec<Vec<f64>>, Vec<[u32; 3]>) = if from.domain == 1 {
        let grid = torus_grid(10 << subdivisions.min(8), 5 << subdivisions.min(8))?;
        (grid.sources, grid.triangles)
    } else if from.source_dimension() == 3 {
        let sphere = icosphere(subdivisions)?;
        (
            sphere.positions.iter().map(|p| p.to_vec()).collect(),
            sphere.triangles,
        )
    } else {
        return Err(Error::invalid(
            "morph meshes need a sphere (m = 3) or torus network",
        ));
    };
    (0..frames)
        .map(|k| {
            let t = k as f64 / (frames - 1) as f64;
            map_mesh(&morph.at(t)?, sources.clone(), triangles.clone())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::sphere_mesh;
    use crate::caoen::support::{fibonacci, fitted};

    /// A fitted network through `radii`-scaled key points.
    fn shape(n: usize, radii: [f64; 3], blending: Blending, normalized: bool) -> CaoEnNetwork {
        let keys = fibonacci(n);
        let targets: Vec<Vec<f64>> = keys
            .iter()
            .map(|k| (0..3).map(|j| radii[j] * k[j]).collect())
            .collect();
        fitted(&keys, &targets, blending, normalized, 4.0)
    }

    /// Ends reproduce the two surfaces within 1e-9 for the forms that have empty keys; the
    /// middle is a different surface between them; the normalized exponential form with
    /// different counts is refused.
    #[test]
    fn ends_reproduce_both_models() {
        for (blending, normalized) in [
            (Blending::Exponential, false),
            (Blending::Power, false),
            (Blending::Power, true),
            (Blending::Compact, false),
            (Blending::Compact, true),
        ] {
            let a = shape(26, [1.0, 1.0, 1.0], blending, normalized);
            let b = shape(40, [2.0, 0.6, 1.0], blending, normalized);
            let frames = morph_meshes(&a, &b, 5, 3).unwrap();
            assert_eq!(frames.len(), 5);
            for (frame, model) in [(&frames[0], &a), (&frames[4], &b)] {
                let direct = sphere_mesh(model, 3).unwrap();
                let worst = frame
                    .mesh
                    .positions
                    .iter()
                    .zip(&direct.mesh.positions)
                    .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
                    .fold(0.0, f64::max);
                assert!(worst < 1e-9, "{blending:?} {normalized}: {worst:e}");
            }
            let morph = Morph::new(&a, &b).unwrap();
            assert_eq!(morph.key_count(), 40, "{blending:?} {normalized}");
            // Halfway, the x extent lies between the two models' (1 and 2).
            let x = frames[2]
                .mesh
                .positions
                .iter()
                .map(|p| p[0])
                .fold(0.0, f64::max);
            assert!(x > 1.1 && x < 1.9, "{x}");
        }
        let a = shape(26, [1.0; 3], Blending::Exponential, true);
        let b = shape(40, [1.0; 3], Blending::Exponential, true);
        let e = Morph::new(&a, &b).unwrap_err().to_string();
        assert!(e.contains("ever empty"), "{e}");
        assert!(Morph::new(&a, &a).is_ok());
        let c = shape(26, [1.0; 3], Blending::Power, false);
        let e = Morph::new(&a, &c).unwrap_err().to_string();
        assert!(
            e.contains(
                "differ in blending and form: the first is a sphere network with \
                        exponential blending, normalized, 3 → 3 coordinates, the second a \
                        sphere network with power blending, unnormalized"
            ) && !e.contains("(0,"),
            "{e}"
        );
        assert!(Morph::new(&a, &a).unwrap().at(1.5).is_err());
        assert!(morph_meshes(&a, &a, 1, 2).is_err());
    }
}

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
//! - normalized form with compact blending and q < 1: the same, its q rising to 1 as the
//!   weight shrinks (u = 1 − q ≤ 0 at s = 0, so F = 0);
//! - normalized form with exponential blending: its weight scales to zero while its q rises
//!   to [`MAX_SHARPNESS`], so it ends at F = e⁻⁶⁴ ≈ 1.6·10⁻²⁸. That is empty up to 10⁻¹⁴
//!   wherever the strongest other key blends to e⁻³² or more, which is checked over the
//!   domain; networks whose keys leave a region that weak are refused.
//!
//! At t = 0 and t = 1 the network equals the two models up to rounding (the test asserts
//! surfaces within 10⁻⁹).

use neurosurf_core::caoen::{Blending, Domain, MAX_SHARPNESS};

use super::mesh::{CaoEnMesh, map_mesh};
use super::network::{CaoEnNetwork, on_domain};
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
        // In the normalized form an exponential key empties only to e⁻⁶⁴, which must stay
        // negligible beside the others (see the module documentation).
        let unpaired = pairs
            .iter()
            .any(|pair| pair.0.is_none() || pair.1.is_none());
        if from.normalized && unpaired && from.blending == Blending::Exponential.code() {
            for (which, network) in [("first", from), ("second", to)] {
                let weakest = weakest_cover(network);
                if weakest < COVER_FLOOR {
                    return Err(Error::invalid(format!(
                        "these normalized exponential networks have different key counts, and \
                         a key without a partner fades only to e^-64: somewhere on the domain \
                         the {which} network's strongest key blends to {weakest:.1e}, below \
                         e^-32, so the faded key would not be negligible there (fit both with \
                         the same key count, or with more keys or a lower sharpness)"
                    )));
                }
            }
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
        let (w, target, q) = (
            &network.weights[i],
            &network.targets[i],
            network.sharpness[i],
        );
        let scaled = |v: &[f64]| v.iter().map(|x| s * x).collect::<Vec<f64>>();
        if !by_weight {
            return (w.clone(), scaled(target), q);
        }
        // The sharpness at which a key of zero weight gives F(0) = 0 (power, compact) or
        // e⁻⁶⁴ (exponential); power keeps its whole q.
        let empty = match Blending::from_code(network.blending) {
            Some(Blending::Power) => q,
            Some(Blending::Compact) => q.max(1.0),
            _ => MAX_SHARPNESS,
        };
        (scaled(w), target.clone(), empty + s * (q - empty))
    }
}

/// How weak the strongest key of a normalized exponential network may be anywhere on its
/// domain for a morph that empties keys: where some key blends to at least e⁻³², an emptied
/// key's e⁻⁶⁴ is 10⁻¹⁴ of it.
const COVER_FLOOR: f64 = 1.266_416_554_909_417e-14;

/// Source points (m coordinates each) and the triangles between them.
type SourceMesh = (Vec<Vec<f64>>, Vec<[u32; 3]>);

/// The source grid `network` is meshed on: an icosphere of `subdivisions`, or a torus grid of
/// 10·2ˢ × 5·2ˢ; `None` for a hypersphere.
fn domain_grid(network: &CaoEnNetwork, subdivisions: usize) -> Result<Option<SourceMesh>> {
    Ok(if network.domain == Domain::Torus.code() {
        let grid = torus_grid(10 << subdivisions.min(8), 5 << subdivisions.min(8))?;
        Some((grid.sources, grid.triangles))
    } else if network.source_dimension() == 3 {
        let sphere = icosphere(subdivisions)?;
        Some((
            sphere.positions.iter().map(|p| p.to_vec()).collect(),
            sphere.triangles,
        ))
    } else {
        None
    })
}

/// Points spread over `network`'s source domain: the vertices of [`domain_grid`] at
/// `subdivisions`, or 4 096 quasi-random points of a hypersphere.
pub(super) fn domain_samples(network: &CaoEnNetwork, subdivisions: usize) -> Vec<Vec<f64>> {
    if let Ok(Some((sources, _))) = domain_grid(network, subdivisions) {
        return sources;
    }
    // Additive recurrences with the square roots of the first primes, put on the
    // hypersphere: spread over it, the same on every run.
    const ROOTS: [f64; 8] = [1.414, 1.732, 2.236, 2.646, 3.317, 3.606, 4.123, 4.359];
    let m = network.source_dimension();
    (1..=4096)
        .map(|i| {
            let v: Vec<f64> = (0..m)
                .map(|h| (f64::from(i) * ROOTS[h % ROOTS.len()]).fract() * 2.0 - 1.0)
                .collect();
            on_domain(network.domain, &v)
        })
        .collect()
}

/// The smallest, over points of the domain ([`domain_samples`] at 3 subdivisions), of the
/// largest F of `network`'s keys.
fn weakest_cover(network: &CaoEnNetwork) -> f64 {
    domain_samples(network, 3)
        .iter()
        .map(|x| {
            (0..network.key_count())
                .map(|i| network.blend(i, inner(x, &network.weights[i])).0)
                .fold(0.0, f64::max)
        })
        .fold(f64::INFINITY, f64::min)
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
    let Some((sources, triangles)) = domain_grid(from, subdivisions)? else {
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

    /// Ends reproduce the two surfaces within 1e-9 in every blending and form, with different
    /// key counts; the middle is a different surface between them. Normalized exponential
    /// networks with keys too sharp to empty are refused, by a sentence.
    #[test]
    fn ends_reproduce_both_models() {
        for (blending, normalized) in [
            (Blending::Exponential, false),
            (Blending::Exponential, true),
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
        assert!(Morph::new(&a, &b).is_ok());
        // Keys of q = 64 and length 0.5 blend to at most e^-32 anywhere: refused.
        let mut weak = b.clone();
        weak.sharpness = vec![64.0; weak.key_count()];
        for w in &mut weak.weights {
            w.iter_mut().for_each(|c| *c *= 0.5);
        }
        let e = Morph::new(&a, &weak).unwrap_err().to_string();
        assert!(e.contains("the second network's strongest key"), "{e}");
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

//! Analytic shapes: sphere, ellipsoid, torus and the three-feature head.
//!
//! About 610 lines, 280 of them tests of each shape's sampling and exact distances.

use std::f64::consts::TAU;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};
use crate::points::PointSet;

use super::check_count;
use crate::geometry::vector::norm;

/// A built-in closed surface to sample control points from.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Sphere of the given radius centred at the origin.
    Sphere {
        /// Radius, > 0.
        radius: f64,
    },
    /// Axis-aligned ellipsoid `(x/a)² + (y/b)² + (z/c)² = 1` centred at the origin.
    Ellipsoid {
        /// Semi-axes `[a, b, c]` along x, y, z, each > 0.
        axes: [f64; 3],
    },
    /// Ring torus around the z axis, centred at the origin:
    /// `(√(x² + y²) − major)² + z² = minor²`.
    Torus {
        /// Distance from the axis to the centre of the tube, > `minor`.
        major: f64,
        /// Radius of the tube, > 0.
        minor: f64,
    },
    /// A cartoon head in the spirit of Carcenac (2004): the boundary of the union of three
    /// overlapping ellipsoids, labelled with three features (see [`HEAD_FEATURES`]):
    /// 0 = the bare head, 1 = the nose, 2 = the mouth.
    ///
    /// Frame: z points up, the face looks toward +y, x runs from ear to ear.
    ///
    /// | feature | ellipsoid centre | semi-axes (x, y, z) | share of the area |
    /// |---|---|---|---|
    /// | 0 head | (0, 0, 0) | (0.75, 0.85, 1) | ≈ 0.666 |
    /// | 1 nose | (0, 1, 0.22) | (0.39, 0.7, 0.4) | ≈ 0.167 |
    /// | 2 mouth | (0, 0.88, −0.6) | (0.62, 0.44, 0.32) | ≈ 0.167 |
    ///
    /// The nose, elongated along +y, sticks out of the face at mid height; the mouth, a wide
    /// flat ellipsoid (lips), sits below it. Nose and mouth each overlap the head and not each
    /// other, so the union is one closed genus-0 surface. The sizes make the exposed areas
    /// ≈ 4 : 1 : 1 (measured by Monte Carlo, 400 000 points). Sampling is stratified by
    /// feature: each feature gets its area share of the points exactly (99 points: 66 head,
    /// 17 nose, 16 mouth), area-uniform within it — like the paper's hand-placed head, every
    /// feature is always well covered.
    Head,
}

/// Names of the [`Shape::Head`] features, indexed by feature label.
pub const HEAD_FEATURES: [&str; 3] = ["head", "nose", "mouth"];

/// An axis-aligned ellipsoid, a building block of [`Shape::Head`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Ellipsoid {
    pub(super) center: [f64; 3],
    pub(super) axes: [f64; 3],
}

/// The head, nose and mouth of [`Shape::Head`], in feature order.
pub(super) const HEAD_PARTS: [Ellipsoid; 3] = [
    Ellipsoid {
        center: [0.0, 0.0, 0.0],
        axes: [0.75, 0.85, 1.0],
    },
    Ellipsoid {
        center: [0.0, 1.0, 0.22],
        axes: [0.39, 0.7, 0.4],
    },
    Ellipsoid {
        center: [0.0, 0.88, -0.6],
        axes: [0.62, 0.44, 0.32],
    },
];

impl Ellipsoid {
    /// `|q / axes| − 1` with `q = p − center`: negative inside, zero on the surface.
    pub(super) fn level(&self, p: [f64; 3]) -> f64 {
        let q = [0, 1, 2].map(|k| (p[k] - self.center[k]) / self.axes[k]);
        norm(q) - 1.0
    }

    /// First-order distance estimate `f / |∇f|` of `f = |q / axes| − 1`: exact on the
    /// surface, at the centre and for spheres; the sign is always right.
    pub(super) fn distance(&self, p: [f64; 3]) -> f64 {
        let q = [0, 1, 2].map(|k| p[k] - self.center[k]);
        let k0 = norm([0, 1, 2].map(|k| q[k] / self.axes[k]));
        let k1 = norm([0, 1, 2].map(|k| q[k] / (self.axes[k] * self.axes[k])));
        if k1 == 0.0 {
            return -self.axes.iter().copied().fold(f64::INFINITY, f64::min);
        }
        k0 * (k0 - 1.0) / k1
    }

    /// Weights of the area element of the map `u ↦ center + axes ∘ u` from the unit sphere:
    /// `dA = |(bc·u_x, ac·u_y, ab·u_z)| dΩ`.
    fn area_weights(&self) -> [f64; 3] {
        let [a, b, c] = self.axes;
        [b * c, a * c, a * b]
    }

    /// The largest area element, the envelope of the rejection sampler.
    fn max_area_weight(&self) -> f64 {
        self.area_weights().into_iter().fold(0.0, f64::max)
    }

    /// One proposal of the area-uniform sampler: a point on the unit sphere accepted with
    /// probability `dA / (max dA)`. Returns the surface point and its outward unit normal.
    pub(super) fn propose(&self, rng: &mut ChaCha8Rng) -> Option<([f64; 3], [f64; 3])> {
        let u = unit_sphere(rng);
        let w = self.area_weights();
        let element = norm([w[0] * u[0], w[1] * u[1], w[2] * u[2]]);
        if rng.random::<f64>() * self.max_area_weight() >= element {
            return None;
        }
        let p = [0, 1, 2].map(|k| self.center[k] + self.axes[k] * u[k]);
        let g = [0, 1, 2].map(|k| u[k] / self.axes[k]);
        let len = norm(g);
        Some((p, g.map(|x| x / len)))
    }
}

/// A uniformly distributed point on the unit sphere (Archimedes: z uniform in [−1, 1]).
pub(super) fn unit_sphere(rng: &mut ChaCha8Rng) -> [f64; 3] {
    let z = 2.0 * rng.random::<f64>() - 1.0;
    let phi = TAU * rng.random::<f64>();
    let r = (1.0 - z * z).max(0.0).sqrt();
    [r * phi.cos(), r * phi.sin(), z]
}

/// Checks `value` is a finite positive number, naming `what` otherwise.
fn positive(value: f64, what: &str) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "{what} must be a finite positive number, got {value}"
        )))
    }
}

impl Shape {
    /// Checks the dimensions.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the parameter: non-positive or non-finite radius, axis,
    /// major or minor radius, `minor >= major`, or axes so extreme that the area element
    /// overflows.
    pub fn check(&self) -> Result<()> {
        match self {
            Shape::Sphere { radius } => positive(*radius, "sphere radius"),
            Shape::Ellipsoid { axes } => {
                for (k, name) in ["a (x)", "b (y)", "c (z)"].iter().enumerate() {
                    positive(axes[k], &format!("ellipsoid semi-axis {name}"))?;
                }
                let e = Ellipsoid {
                    center: [0.0; 3],
                    axes: *axes,
                };
                let w = e.area_weights();
                if w.iter().any(|x| !x.is_finite() || *x < f64::MIN_POSITIVE) {
                    return Err(Error::invalid(format!(
                        "ellipsoid semi-axes {axes:?} are out of range"
                    )));
                }
                Ok(())
            }
            Shape::Torus { major, minor } => {
                positive(*major, "torus major radius")?;
                positive(*minor, "torus minor radius")?;
                if minor >= major {
                    return Err(Error::invalid(format!(
                        "torus minor radius ({minor}) must be smaller than the major radius ({major})"
                    )));
                }
                Ok(())
            }
            Shape::Head => Ok(()),
        }
    }

    /// Number of feature labels the samples carry: 3 for [`Shape::Head`], otherwise 1
    /// (and no labels are stored).
    pub fn feature_count(&self) -> usize {
        match self {
            Shape::Head => HEAD_PARTS.len(),
            _ => 1,
        }
    }

    /// Signed distance from `p` to the surface, negative inside.
    ///
    /// Exact for [`Shape::Sphere`] and [`Shape::Torus`]. For [`Shape::Ellipsoid`] it is the
    /// first-order estimate `f / |∇f|` with `f = |p / axes| − 1` (exact on the surface and
    /// at the centre, correct sign everywhere, off by a factor between `min(axes)/max(axes)`
    /// and `max(axes)/min(axes)` far away). For [`Shape::Head`] it is the minimum of those
    /// estimates over the three ellipsoids: zero exactly on the surface, correct sign, an
    /// approximation elsewhere (the minimum is not the true distance inside the union).
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        match self {
            Shape::Sphere { radius } => norm(p) - radius,
            Shape::Ellipsoid { axes } => Ellipsoid {
                center: [0.0; 3],
                axes: *axes,
            }
            .distance(p),
            Shape::Torus { major, minor } => (p[0].hypot(p[1]) - major).hypot(p[2]) - minor,
            Shape::Head => HEAD_PARTS
                .iter()
                .map(|e| e.distance(p))
                .fold(f64::INFINITY, f64::min),
        }
    }
}

/// Draws `count` points area-uniformly on `shape` with exact outward unit normals,
/// deterministically for a given `seed` (`ChaCha8Rng::seed_from_u64`).
///
/// * Sphere: uniform directions.
/// * Ellipsoid: uniform directions `u` mapped to `axes ∘ u`, accepted with probability
///   proportional to the area element, so the density is uniform in area.
/// * Torus: the ring angle is uniform, the tube angle `v` is accepted with probability
///   `(R + r cos v) / (R + r)`, the area element's dependence on `v`.
/// * Head: a primitive is chosen with probability proportional to its envelope area, a
///   point is drawn on it as for the ellipsoid, and rejected if it lies strictly inside
///   another primitive; the accepted points are area-uniform on the boundary of the union.
///   Only this shape sets [`PointSet::features`] (see [`HEAD_FEATURES`]).
///
/// # Errors
/// [`Error::InvalidInput`] when `count` is 0 or above [`MAX_SAMPLES`](super::MAX_SAMPLES), or
/// the dimensions are invalid (see [`Shape::check`]).
pub fn sample_shape(shape: &Shape, count: usize, seed: u64) -> Result<PointSet> {
    check_count(count)?;
    shape.check()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut positions = Vec::with_capacity(count);
    let mut normals = Vec::with_capacity(count);
    let mut features = matches!(shape, Shape::Head).then(|| Vec::with_capacity(count));
    while positions.len() < count {
        let sample = match shape {
            Shape::Sphere { radius } => {
                let u = unit_sphere(&mut rng);
                Some((u.map(|c| radius * c), u, 0))
            }
            Shape::Ellipsoid { axes } => Ellipsoid {
                center: [0.0; 3],
                axes: *axes,
            }
            .propose(&mut rng)
            .map(|(p, n)| (p, n, 0)),
            Shape::Torus { major, minor } => torus_proposal(*major, *minor, &mut rng),
            Shape::Head => {
                let part = head_part_for(positions.len(), count);
                head_proposal(&HEAD_PARTS, part, &mut rng)
            }
        };
        if let Some((p, n, feature)) = sample {
            positions.push(p);
            normals.push(n);
            if let Some(f) = features.as_mut() {
                f.push(feature);
            }
        }
    }
    Ok(PointSet {
        positions,
        normals,
        features,
    })
}

/// One proposal of the torus sampler.
fn torus_proposal(
    major: f64,
    minor: f64,
    rng: &mut ChaCha8Rng,
) -> Option<([f64; 3], [f64; 3], u32)> {
    let u = TAU * rng.random::<f64>();
    let v = TAU * rng.random::<f64>();
    let ring = major + minor * v.cos();
    if rng.random::<f64>() * (major + minor) >= ring {
        return None;
    }
    let (su, cu) = u.sin_cos();
    let (sv, cv) = v.sin_cos();
    Some((
        [ring * cu, ring * su, minor * sv],
        [cv * cu, cv * su, sv],
        0,
    ))
}

/// One proposal of the head sampler.
/// Exposed-area shares of the head's features (see [`Shape::Head`]).
const HEAD_SHARES: [f64; 3] = [4.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0];

/// The feature the `index`-th of `count` head samples belongs to: the first
/// round(count·share₀) points are on the head, the next round(count·(share₀+share₁)) − … on the
/// nose, the rest on the mouth.
fn head_part_for(index: usize, count: usize) -> usize {
    let mut cumulative = 0.0;
    for (part, share) in HEAD_SHARES.iter().enumerate() {
        cumulative += share;
        if (index as f64) < (count as f64 * cumulative).round() {
            return part;
        }
    }
    HEAD_SHARES.len() - 1
}

/// An area-uniform point of `parts[part]` that no other part covers, or `None` (rejected).
fn head_proposal(
    parts: &[Ellipsoid; 3],
    part: usize,
    rng: &mut ChaCha8Rng,
) -> Option<([f64; 3], [f64; 3], u32)> {
    let (p, n) = parts[part].propose(rng)?;
    let covered = parts
        .iter()
        .enumerate()
        .any(|(j, e)| j != part && e.level(p) < 0.0);
    (!covered).then_some((p, n, part as u32))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SHAPES: [Shape; 4] = [
        Shape::Sphere { radius: 1.7 },
        Shape::Ellipsoid {
            axes: [1.0, 0.7, 0.5],
        },
        Shape::Torus {
            major: 1.0,
            minor: 0.4,
        },
        Shape::Head,
    ];

    use crate::geometry::vector::dot;

    #[test]
    fn points_lie_on_the_surface() {
        for shape in &SHAPES {
            let points = sample_shape(shape, 2000, 7).unwrap();
            assert_eq!(points.len(), 2000);
            for p in &points.positions {
                let d = shape.signed_distance(*p);
                assert!(d.abs() < 1e-9, "{shape:?} {p:?} {d}");
            }
        }
        let axes = [1.0, 0.7, 0.5];
        let points = sample_shape(&Shape::Ellipsoid { axes }, 2000, 8).unwrap();
        for p in &points.positions {
            let f: f64 = (0..3).map(|k| (p[k] / axes[k]).powi(2)).sum();
            assert!((f - 1.0).abs() < 1e-12, "{p:?}");
        }
    }

    #[test]
    fn normals_are_unit_outward_and_exact() {
        for shape in &SHAPES {
            let points = sample_shape(shape, 1000, 3).unwrap();
            for (p, n) in points.positions.iter().zip(&points.normals) {
                assert!((norm(*n) - 1.0).abs() < 1e-12, "{shape:?}");
                let h = 1e-4;
                let outside = [0, 1, 2].map(|k| p[k] + h * n[k]);
                let inside = [0, 1, 2].map(|k| p[k] - h * n[k]);
                assert!(shape.signed_distance(outside) > 0.0, "{shape:?} {p:?}");
                assert!(shape.signed_distance(inside) < 0.0, "{shape:?} {p:?}");
                // The gradient of the distance is the normal (exact SDFs; on the surface the
                // ellipsoid estimate has the right gradient too).
                let e = 1e-6;
                let grad = [0, 1, 2].map(|k| {
                    let mut a = *p;
                    let mut b = *p;
                    a[k] += e;
                    b[k] -= e;
                    (shape.signed_distance(a) - shape.signed_distance(b)) / (2.0 * e)
                });
                if !matches!(shape, Shape::Head) {
                    assert!(dot(grad, *n) > 1.0 - 1e-6, "{shape:?} {p:?} {grad:?} {n:?}");
                } else {
                    let g = grad.map(|x| x / norm(grad));
                    assert!(dot(g, *n) > 1.0 - 1e-6, "{p:?} {g:?} {n:?}");
                }
            }
        }
    }

    #[test]
    fn deterministic_for_a_seed() {
        for shape in &SHAPES {
            let a = sample_shape(shape, 500, 42).unwrap();
            assert_eq!(a, sample_shape(shape, 500, 42).unwrap(), "{shape:?}");
            assert_ne!(a, sample_shape(shape, 500, 43).unwrap(), "{shape:?}");
            assert_eq!(a.features.is_some(), matches!(shape, Shape::Head));
        }
    }

    #[test]
    fn torus_is_area_uniform() {
        let (major, minor) = (1.0, 0.4);
        let n = 20_000;
        let points = sample_shape(&Shape::Torus { major, minor }, n, 1).unwrap();
        // Outer half (cos v > 0, i.e. x² + y² > R²): ∫(R + r cos v) over |v| < π/2 divided by
        // the integral over the full circle = (πR + 2r) / (2πR).
        let pi = std::f64::consts::PI;
        let expected = (pi * major + 2.0 * minor) / (2.0 * pi * major);
        let outer = points
            .positions
            .iter()
            .filter(|p| p[0] * p[0] + p[1] * p[1] > major * major)
            .count() as f64
            / n as f64;
        let sigma = (expected * (1.0 - expected) / n as f64).sqrt();
        assert!(
            (outer - expected).abs() < 4.0 * sigma,
            "{outer} vs {expected}"
        );
        // Upper half (z > 0) holds exactly half the area.
        let upper = points.positions.iter().filter(|p| p[2] > 0.0).count() as f64 / n as f64;
        assert!(
            (upper - 0.5).abs() < 4.0 * (0.25 / n as f64).sqrt(),
            "{upper}"
        );
    }

    #[test]
    fn ellipsoid_is_area_uniform() {
        // A prolate spheroid (a = b = 1, c = 2): the fraction of points in the band |z| < 1
        // must match the band's share of the area, integrated numerically as the surface of
        // revolution of x(z) = √(1 − z²/4): dA = 2π·x·√(1 + x'²) dz.
        let axes = [1.0, 1.0, 2.0];
        let band = |lo: f64, hi: f64| {
            let steps = 20_000;
            let h = (hi - lo) / steps as f64;
            (0..steps)
                .map(|i| {
                    let z = lo + (i as f64 + 0.5) * h;
                    let s = 1.0 - (z / 2.0).powi(2);
                    let x = s.sqrt();
                    let dx = -z / (4.0 * x);
                    TAU * x * (1.0 + dx * dx).sqrt() * h
                })
                .sum::<f64>()
        };
        let expected = band(0.0, 1.0) / band(0.0, 2.0);
        let n = 20_000;
        let points = sample_shape(&Shape::Ellipsoid { axes }, n, 9).unwrap();
        let middle = points.positions.iter().filter(|p| p[2].abs() < 1.0).count() as f64 / n as f64;
        let sigma = (expected * (1.0 - expected) / n as f64).sqrt();
        assert!(
            (middle - expected).abs() < 4.0 * sigma,
            "{middle} vs {expected}"
        );
    }

    #[test]
    fn head_has_three_features_and_no_buried_points() {
        let points = sample_shape(&Shape::Head, 99, 1).unwrap();
        let features = points.features.as_ref().unwrap();
        let counts = [0, 1, 2].map(|f| features.iter().filter(|&&x| x == f).count());
        assert!(counts.iter().all(|&c| c > 0), "{counts:?}");
        assert_eq!(counts.iter().sum::<usize>(), 99);

        let n = 30_000;
        let points = sample_shape(&Shape::Head, n, 2).unwrap();
        let features = points.features.as_ref().unwrap();
        let fractions =
            [0, 1, 2].map(|f| features.iter().filter(|&&x| x == f).count() as f64 / n as f64);
        for (fraction, expected) in fractions.iter().zip([4.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0]) {
            assert!((fraction - expected).abs() < 0.03, "{fractions:?}");
        }
        for (p, &f) in points.positions.iter().zip(features) {
            let own = HEAD_PARTS[f as usize].level(*p);
            assert!(own.abs() < 1e-12, "{p:?}");
            for (j, part) in HEAD_PARTS.iter().enumerate() {
                if j != f as usize {
                    assert!(
                        part.level(*p) >= 0.0,
                        "feature {f} point {p:?} inside part {j}"
                    );
                }
            }
        }
    }

    #[test]
    fn head_parts_overlap_into_one_surface() {
        // The back ends of nose and mouth lie inside the head, their front ends outside, and
        // nose and mouth are disjoint (separated in z).
        let [head, nose, mouth] = HEAD_PARTS;
        for part in [nose, mouth] {
            let back = [
                part.center[0],
                part.center[1] - part.axes[1],
                part.center[2],
            ];
            let front = [
                part.center[0],
                part.center[1] + part.axes[1],
                part.center[2],
            ];
            assert!(head.level(back) < 0.0 && head.level(front) > 0.0);
        }
        assert!(nose.center[2] - nose.axes[2] > mouth.center[2] + mouth.axes[2]);
        // Nose in front (+y), mouth below it.
        assert!(nose.center[1] + nose.axes[1] > head.axes[1] + 0.3);
        assert!(mouth.center[2] < nose.center[2]);
        assert_eq!(Shape::Head.feature_count(), HEAD_FEATURES.len());
    }

    #[test]
    fn rejects_bad_parameters() {
        let cases: [(Shape, &str); 9] = [
            (Shape::Sphere { radius: 0.0 }, "sphere radius"),
            (Shape::Sphere { radius: f64::NAN }, "sphere radius"),
            (
                Shape::Ellipsoid {
                    axes: [1.0, -1.0, 1.0],
                },
                "semi-axis b",
            ),
            (
                Shape::Ellipsoid {
                    axes: [1.0, 1.0, f64::INFINITY],
                },
                "semi-axis c",
            ),
            (
                Shape::Ellipsoid {
                    axes: [1e200, 1e200, 1.0],
                },
                "out of range",
            ),
            (
                Shape::Torus {
                    major: 1.0,
                    minor: 1.0,
                },
                "smaller than the major",
            ),
            (
                Shape::Torus {
                    major: 1.0,
                    minor: 0.0,
                },
                "minor radius",
            ),
            (
                Shape::Torus {
                    major: f64::NAN,
                    minor: 0.5,
                },
                "major radius",
            ),
            (
                Shape::Torus {
                    major: 0.5,
                    minor: 1.0,
                },
                "smaller than the major",
            ),
        ];
        for (shape, needle) in cases {
            let e = sample_shape(&shape, 10, 1).unwrap_err();
            assert!(matches!(e, Error::InvalidInput(_)), "{e}");
            assert!(e.to_string().contains(needle), "{shape:?}: {e}");
        }
        for count in [0, 50_000_001] {
            let e = sample_shape(&Shape::Head, count, 1).unwrap_err();
            assert!(matches!(e, Error::InvalidInput(_)), "{e}");
        }
        assert_eq!(sample_shape(&SHAPES[0], 1, 1).unwrap().len(), 1);
    }

    #[test]
    fn signed_distances_are_exact_where_promised() {
        let sphere = Shape::Sphere { radius: 2.0 };
        assert_eq!(sphere.signed_distance([0.0, 3.0, 4.0]), 3.0);
        assert_eq!(sphere.signed_distance([0.0; 3]), -2.0);
        let torus = Shape::Torus {
            major: 2.0,
            minor: 0.5,
        };
        assert_eq!(torus.signed_distance([0.0; 3]), 1.5);
        assert_eq!(torus.signed_distance([2.0, 0.0, 0.0]), -0.5);
        assert_eq!(torus.signed_distance([0.0, 5.0, 4.0]), 4.5);
        let ellipsoid = Shape::Ellipsoid {
            axes: [3.0, 2.0, 1.0],
        };
        assert_eq!(ellipsoid.signed_distance([0.0; 3]), -1.0);
        assert!((ellipsoid.signed_distance([4.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
        assert!((ellipsoid.signed_distance([0.0, 0.0, 1.5]) - 0.5).abs() < 1e-12);
        assert!(Shape::Head.signed_distance([0.0; 3]) < 0.0);
        assert!(Shape::Head.signed_distance([0.0, 0.0, 3.0]) > 0.0);
    }
}

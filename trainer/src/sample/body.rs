//! Carcenac §7's human body: 17 features (the three of [`Shape::Head`](super::Shape::Head),
//! neck, torso, upper arms, forearms, hands, thighs, shins, feet), 316 control points with
//! exact normals, in any [`Pose`] of the animation (both arms raised and flexed, the right leg
//! raised and flexed).
//!
//! Every feature is one analytic primitive — the head's three ellipsoids, capsules for the
//! neck and limbs, ellipsoids for the torso, hands and feet — moved by a rigid motion about
//! its joints. A feature's candidate points are area-uniform on its primitive where no other
//! primitive covers it, so they lie exactly on the boundary of the union and carry its outward
//! normal; its control points are an evenly spread subset of 8× as many candidates (greedy
//! farthest-point selection). Purely random control points leave holes that the network fills
//! with bulges (measured: RMS distance to the true body 1.3 % of its diameter against 0.15 %).
//!
//! The animation keeps the points' identity: a feature's candidates are drawn in its rest
//! frame from a random stream of its own and then moved with it. Between two frames a point
//! moves only as its limb moves (a few change where a joint hides or exposes candidates), which
//! is what makes a warm start from the previous frame cheap.
//!
//! Frame: z up (the body is ≈ 14 units tall, the head 2, as in [`Shape::Head`]), the face
//! looks toward +y, the body's right side is +x.

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use super::shape::{Ellipsoid, HEAD_PARTS, unit_sphere};
use crate::error::{Error, Result};
use crate::geometry::vector::norm;
use crate::points::PointSet;

/// Names of the body's features, indexed by feature label.
pub const BODY_FEATURES: [&str; 17] = [
    "head",
    "nose",
    "mouth",
    "neck",
    "torso",
    "right upper arm",
    "right forearm",
    "right hand",
    "left upper arm",
    "left forearm",
    "left hand",
    "right thigh",
    "right shin",
    "right foot",
    "left thigh",
    "left shin",
    "left foot",
];

/// Control points per feature: the head's 99 as in the head demo (66, 17, 16), the other 217
/// roughly by size; 316 in all, as in the paper.
pub const BODY_POINTS: [usize; 17] = [
    66, 17, 16, 10, 37, 14, 14, 12, 14, 14, 12, 16, 15, 14, 16, 15, 14,
];

/// The blending tree (our reading of the paper's Fig. 8, which the text describes as "most
/// intuitive" and "approximately balanced"): the head (head + nose, + mouth, + neck) with
/// the torso, the two arms (upper arm + forearm, + hand) together, both blended at the
/// shoulders; the two legs (thigh + shin, + foot) together; the root blends them at the hips.
/// 17 leaves, 16 nodes, 7 modules tall.
pub const BODY_TREE: &str =
    "((((((0,1),2),3),4),(((5,6),7),((8,9),10))),(((11,12),13),((14,15),16)))";

/// The joint angles of a frame, in degrees.
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct Pose {
    /// Both arms raised sideways at the shoulders (0: hanging).
    pub shoulders: f64,
    /// Both forearms flexed upward at the elbows, in the plane of the raise.
    pub elbows: f64,
    /// The right thigh raised forward at the hip.
    pub hip: f64,
    /// The right shin flexed backward at the knee.
    pub knee: f64,
}

impl Pose {
    /// Standing, arms hanging.
    pub const REST: Pose = Pose {
        shoulders: 0.0,
        elbows: 0.0,
        hip: 0.0,
        knee: 0.0,
    };

    /// The last frame of the animation.
    pub const RAISED: Pose = Pose {
        shoulders: 95.0,
        elbows: 70.0,
        hip: 70.0,
        knee: 80.0,
    };

    /// Frame `frame` of an animation of `frames` frames from [`Pose::REST`] (frame 0) to
    /// [`Pose::RAISED`] (the last frame), eased in and out (smoothstep), so that consecutive
    /// frames differ by at most ≈ 1.5 % of the motion (50 frames).
    pub fn animation(frame: usize, frames: usize) -> Pose {
        let t = if frames > 1 {
            (frame.min(frames - 1) as f64) / ((frames - 1) as f64)
        } else {
            1.0
        };
        let s = t * t * (3.0 - 2.0 * t);
        let mix = |a: f64, b: f64| a + s * (b - a);
        Pose {
            shoulders: mix(Pose::REST.shoulders, Pose::RAISED.shoulders),
            elbows: mix(Pose::REST.elbows, Pose::RAISED.elbows),
            hip: mix(Pose::REST.hip, Pose::RAISED.hip),
            knee: mix(Pose::REST.knee, Pose::RAISED.knee),
        }
    }
}

/// A rigid motion p ↦ R·p + t.
#[derive(Copy, Clone, Debug, PartialEq)]
struct Rigid {
    rotation: Matrix3<f64>,
    shift: Vector3<f64>,
}

impl Rigid {
    const IDENTITY: Rigid = Rigid {
        rotation: Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
        shift: Vector3::new(0.0, 0.0, 0.0),
    };

    /// A rotation by `degrees` about the line through `pivot` along `axis`.
    fn about(pivot: [f64; 3], axis: Vector3<f64>, degrees: f64) -> Rigid {
        let rotation =
            *Rotation3::from_axis_angle(&Unit::new_normalize(axis), degrees.to_radians()).matrix();
        let c = Vector3::from(pivot);
        Rigid {
            rotation,
            shift: c - rotation * c,
        }
    }

    /// `self` after `inner`.
    fn after(&self, inner: &Rigid) -> Rigid {
        Rigid {
            rotation: self.rotation * inner.rotation,
            shift: self.rotation * inner.shift + self.shift,
        }
    }

    fn point(&self, p: [f64; 3]) -> [f64; 3] {
        (self.rotation * Vector3::from(p) + self.shift).into()
    }

    fn vector(&self, v: [f64; 3]) -> [f64; 3] {
        (self.rotation * Vector3::from(v)).into()
    }

    fn inverse_point(&self, p: [f64; 3]) -> [f64; 3] {
        (self.rotation.transpose() * (Vector3::from(p) - self.shift)).into()
    }
}

/// A feature's shape in its rest pose.
#[derive(Copy, Clone, Debug, PartialEq)]
enum Primitive {
    Ellipsoid(Ellipsoid),
    /// The points within `radius` of the segment `a`–`b`.
    Capsule {
        a: [f64; 3],
        b: [f64; 3],
        radius: f64,
    },
}

/// How far up the head's ellipsoids are moved to sit on the body.
const HEAD_HEIGHT: f64 = 12.9;

const fn raised(e: Ellipsoid) -> Ellipsoid {
    Ellipsoid {
        center: [e.center[0], e.center[1], e.center[2] + HEAD_HEIGHT],
        axes: e.axes,
    }
}

const fn capsule(a: [f64; 3], b: [f64; 3], radius: f64) -> Primitive {
    Primitive::Capsule { a, b, radius }
}

const fn ellipsoid(center: [f64; 3], axes: [f64; 3]) -> Primitive {
    Primitive::Ellipsoid(Ellipsoid { center, axes })
}

/// The right shoulder, elbow, hip and knee (the left ones mirror x).
const SHOULDER: [f64; 3] = [1.45, 0.0, 10.4];
const ELBOW: [f64; 3] = [1.75, 0.0, 8.0];
const HIP: [f64; 3] = [0.65, 0.0, 6.6];
const KNEE: [f64; 3] = [0.75, 0.0, 3.7];

const fn mirror(p: [f64; 3]) -> [f64; 3] {
    [-p[0], p[1], p[2]]
}

/// The rest-pose primitives, in feature order.
const PARTS: [Primitive; 17] = [
    Primitive::Ellipsoid(raised(HEAD_PARTS[0])),
    Primitive::Ellipsoid(raised(HEAD_PARTS[1])),
    Primitive::Ellipsoid(raised(HEAD_PARTS[2])),
    capsule([0.0, -0.15, 10.9], [0.0, -0.15, 12.2], 0.42),
    ellipsoid([0.0, 0.0, 8.7], [1.45, 0.8, 2.6]),
    capsule(SHOULDER, ELBOW, 0.36),
    capsule(ELBOW, [1.95, 0.1, 5.7], 0.3),
    ellipsoid([1.98, 0.1, 5.0], [0.24, 0.4, 0.55]),
    capsule(mirror(SHOULDER), mirror(ELBOW), 0.36),
    capsule(mirror(ELBOW), [-1.95, 0.1, 5.7], 0.3),
    ellipsoid([-1.98, 0.1, 5.0], [0.24, 0.4, 0.55]),
    capsule(HIP, KNEE, 0.55),
    capsule(KNEE, [0.8, 0.0, 0.85], 0.42),
    ellipsoid([0.82, 0.4, 0.3], [0.38, 0.8, 0.3]),
    capsule(mirror(HIP), mirror(KNEE), 0.55),
    capsule(mirror(KNEE), [-0.8, 0.0, 0.85], 0.42),
    ellipsoid([-0.82, 0.4, 0.3], [0.38, 0.8, 0.3]),
];

impl Primitive {
    /// Negative inside, zero on the surface.
    fn level(&self, p: [f64; 3]) -> f64 {
        match self {
            Primitive::Ellipsoid(e) => e.level(p),
            Primitive::Capsule { a, b, radius } => segment_distance(p, *a, *b) / radius - 1.0,
        }
    }

    /// Signed distance (exact for capsules, the first-order estimate for ellipsoids).
    fn distance(&self, p: [f64; 3]) -> f64 {
        match self {
            Primitive::Ellipsoid(e) => e.distance(p),
            Primitive::Capsule { a, b, radius } => segment_distance(p, *a, *b) - radius,
        }
    }

    /// An area-uniform surface point and its outward normal, or `None` (rejected proposal).
    fn propose(&self, rng: &mut ChaCha8Rng) -> Option<([f64; 3], [f64; 3])> {
        match self {
            Primitive::Ellipsoid(e) => e.propose(rng),
            Primitive::Capsule { a, b, radius } => {
                let axis = [0, 1, 2].map(|k| b[k] - a[k]);
                let length = norm(axis);
                let side = std::f64::consts::TAU * radius * length;
                let caps = 2.0 * std::f64::consts::TAU * radius * radius;
                if rng.random::<f64>() * (side + caps) < side {
                    let t = rng.random::<f64>();
                    let phi = std::f64::consts::TAU * rng.random::<f64>();
                    let w = Vector3::from(axis) / length;
                    let u = w
                        .cross(&Vector3::x())
                        .try_normalize(1e-9)
                        .unwrap_or_else(|| w.cross(&Vector3::y()).normalize());
                    let v = w.cross(&u);
                    let n = u * phi.cos() + v * phi.sin();
                    let p = Vector3::from(*a) + w * (t * length) + n * *radius;
                    Some((p.into(), n.into()))
                } else {
                    let d = unit_sphere(rng);
                    let along = d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2];
                    let end = if along > 0.0 { b } else { a };
                    Some(([0, 1, 2].map(|k| end[k] + radius * d[k]), d))
                }
            }
        }
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = Vector3::from(b) - Vector3::from(a);
    let ap = Vector3::from(p) - Vector3::from(a);
    let t = (ap.dot(&ab) / ab.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    (ap - ab * t).norm()
}

/// Every feature's rigid motion in `pose`.
fn motions(pose: &Pose) -> [Rigid; 17] {
    let mut out = [Rigid::IDENTITY; 17];
    for (side, first) in [(1.0, 5), (-1.0, 8)] {
        let at = |p: [f64; 3]| [side * p[0], p[1], p[2]];
        // Raising an arm sideways turns its downward direction toward ±x: about y by ∓angle.
        let upper = Rigid::about(at(SHOULDER), Vector3::y(), -side * pose.shoulders);
        let lower = upper.after(&Rigid::about(at(ELBOW), Vector3::y(), -side * pose.elbows));
        out[first] = upper;
        out[first + 1] = lower;
        out[first + 2] = lower;
    }
    // The right thigh turns forward (toward +y) about x; the shin back.
    let thigh = Rigid::about(HIP, Vector3::x(), pose.hip);
    let shin = thigh.after(&Rigid::about(KNEE, Vector3::x(), -pose.knee));
    out[11] = thigh;
    out[12] = shin;
    out[13] = shin;
    out
}

/// The body in a pose: each feature's rest primitive and its motion.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    motions: [Rigid; 17],
}

/// Proposals a feature may draw before its control points are declared impossible.
const MAX_PROPOSALS: usize = 1_000_000;
/// Candidates drawn per control point; the control points are an evenly spread subset.
const POOL: usize = 8;

impl Body {
    /// The body in `pose`.
    pub fn new(pose: &Pose) -> Body {
        Body {
            motions: motions(pose),
        }
    }

    /// Level of feature `f`'s posed primitive at `p`: negative inside.
    fn level(&self, f: usize, p: [f64; 3]) -> f64 {
        PARTS[f].level(self.motions[f].inverse_point(p))
    }

    /// Signed distance to the body's surface (the union of its parts), negative inside: exact
    /// near capsules, first order near ellipsoids, zero exactly on the surface.
    pub fn signed_distance(&self, p: [f64; 3]) -> f64 {
        (0..PARTS.len())
            .map(|f| PARTS[f].distance(self.motions[f].inverse_point(p)))
            .fold(f64::INFINITY, f64::min)
    }

    /// `counts[f]` control points on every feature `f`, labelled with their feature,
    /// deterministic for a seed (feature `f` draws from stream `f` of
    /// `ChaCha8Rng::seed_from_u64(seed)`).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when a count is 0, or a feature is so covered by the others
    /// that its points cannot be found.
    pub fn sample(&self, counts: &[usize; 17], seed: u64) -> Result<PointSet> {
        let total = counts.iter().sum();
        let mut points = PointSet {
            positions: Vec::with_capacity(total),
            normals: Vec::with_capacity(total),
            features: Some(Vec::with_capacity(total)),
        };
        for (f, &count) in counts.iter().enumerate() {
            if count == 0 {
                return Err(Error::invalid(format!(
                    "the body's {} needs at least one control point",
                    BODY_FEATURES[f]
                )));
            }
            let pool = self.exposed(f, count * POOL, seed);
            if pool.len() < count {
                return Err(Error::invalid(format!(
                    "the body's {} is too covered by the other parts for {count} control points",
                    BODY_FEATURES[f]
                )));
            }
            for i in farthest_points(&pool, count) {
                let (p, n) = pool[i];
                points.positions.push(p);
                points.normals.push(n);
                if let Some(labels) = points.features.as_mut() {
                    labels.push(f as u32);
                }
            }
        }
        Ok(points)
    }

    /// Up to `wanted` posed candidates of feature `f` that no other part covers, in the order
    /// they were drawn.
    fn exposed(&self, f: usize, wanted: usize, seed: u64) -> Vec<([f64; 3], [f64; 3])> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(f as u64);
        let mut out = Vec::with_capacity(wanted);
        for _ in 0..MAX_PROPOSALS {
            if out.len() == wanted {
                break;
            }
            let Some((p, n)) = PARTS[f].propose(&mut rng) else {
                continue;
            };
            let (p, n) = (self.motions[f].point(p), self.motions[f].vector(n));
            if (0..PARTS.len()).any(|g| g != f && self.level(g, p) < 0.0) {
                continue;
            }
            out.push((p, n));
        }
        out
    }
}

/// `count` indices into `pool` spread evenly: greedy farthest-point selection from the first
/// candidate (each next point is the candidate farthest from those already chosen).
fn farthest_points(pool: &[([f64; 3], [f64; 3])], count: usize) -> Vec<usize> {
    let mut chosen = Vec::with_capacity(count);
    let mut nearest = vec![f64::INFINITY; pool.len()];
    let mut next = 0;
    while chosen.len() < count.min(pool.len()) {
        chosen.push(next);
        let c = pool[next].0;
        for (d, (p, _)) in nearest.iter_mut().zip(pool) {
            *d = d.min(norm([0, 1, 2].map(|k| p[k] - c[k])));
        }
        next = (0..pool.len())
            .max_by(|&a, &b| nearest[a].total_cmp(&nearest[b]).then(b.cmp(&a)))
            .unwrap_or(0);
    }
    chosen
}

/// [`BODY_POINTS`] scaled so they sum to about `total` (each feature at least 4): dense
/// held-out samples with the same proportions.
pub fn scaled_counts(total: usize) -> [usize; 17] {
    let sum: usize = BODY_POINTS.iter().sum();
    BODY_POINTS.map(|c| ((c * total) as f64 / sum as f64).round().max(4.0) as usize)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::TreeSpec;

    fn frames() -> Vec<Pose> {
        vec![Pose::REST, Pose::animation(20, 50), Pose::RAISED]
    }

    #[test]
    fn the_paper_counts_and_tree() {
        assert_eq!(BODY_POINTS.iter().sum::<usize>(), 316);
        assert_eq!(&BODY_POINTS[..3], &[66, 17, 16]);
        let tree: TreeSpec = BODY_TREE.parse().unwrap();
        tree.check_features(17).unwrap();
        assert_eq!(tree.post_order().len(), 33);
        assert_eq!(tree.height(), 7);
    }

    #[test]
    fn points_lie_on_the_posed_surface_with_outward_normals() {
        for pose in frames() {
            let body = Body::new(&pose);
            let points = body.sample(&BODY_POINTS, 3).unwrap();
            assert_eq!(points.len(), 316);
            let labels = points.features.as_ref().unwrap();
            for f in 0..17 {
                let n = labels.iter().filter(|&&l| l as usize == f).count();
                assert_eq!(n, BODY_POINTS[f], "{pose:?} feature {f}");
            }
            for ((p, n), &f) in points.positions.iter().zip(&points.normals).zip(labels) {
                assert!(body.signed_distance(*p).abs() < 1e-9, "{pose:?} {f} {p:?}");
                assert!((norm(*n) - 1.0).abs() < 1e-12);
                let out = [0, 1, 2].map(|k| p[k] + 1e-4 * n[k]);
                let inside = [0, 1, 2].map(|k| p[k] - 1e-4 * n[k]);
                assert!(body.signed_distance(out) > 0.0, "{pose:?} {f} {p:?}");
                assert!(body.signed_distance(inside) < 0.0, "{pose:?} {f} {p:?}");
            }
        }
    }

    #[test]
    fn the_rest_body_stands_and_the_raised_one_moves_only_its_limbs() {
        let rest = Body::new(&Pose::REST).sample(&BODY_POINTS, 1).unwrap();
        let top = rest.positions.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
        let bottom = rest.positions.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
        assert!(
            (13.5..14.0).contains(&top) && (-1e-9..0.1).contains(&bottom),
            "{bottom}..{top}"
        );
        let raised = Body::new(&Pose::RAISED).sample(&BODY_POINTS, 1).unwrap();
        let labels = rest.features.as_ref().unwrap();
        // The hands end up above the shoulders, the right foot in front; the left leg and
        // the head do not move.
        for ((a, b), &f) in rest.positions.iter().zip(&raised.positions).zip(labels) {
            match f {
                7 | 10 => assert!(b[2] > SHOULDER[2], "hand at {b:?}"),
                13 => assert!(b[1] > 1.5 && b[2] > 1.0, "right foot at {b:?}"),
                0..=2 | 14..=16 => assert_eq!(a, b),
                _ => {}
            }
        }
    }

    #[test]
    fn consecutive_frames_keep_most_points() {
        let a = Body::new(&Pose::animation(24, 50))
            .sample(&BODY_POINTS, 1)
            .unwrap();
        let b = Body::new(&Pose::animation(25, 50))
            .sample(&BODY_POINTS, 1)
            .unwrap();
        let moved = a
            .positions
            .iter()
            .zip(&b.positions)
            .filter(|(p, q)| norm([0, 1, 2].map(|k| p[k] - q[k])) > 0.5)
            .count();
        assert!(
            moved <= 316 / 10,
            "{moved} points jumped between frames 24 and 25"
        );
    }

    #[test]
    fn deterministic_for_a_seed() {
        let body = Body::new(&Pose::animation(10, 50));
        let a = body.sample(&BODY_POINTS, 5).unwrap();
        assert_eq!(a, body.sample(&BODY_POINTS, 5).unwrap());
        assert_ne!(a, body.sample(&BODY_POINTS, 6).unwrap());
        let mut counts = BODY_POINTS;
        counts[3] = 0;
        let err = body.sample(&counts, 5).unwrap_err().to_string();
        assert!(err.contains("neck"), "{err}");
        assert_eq!(scaled_counts(316), BODY_POINTS);
        assert!(scaled_counts(2000).iter().sum::<usize>().abs_diff(2000) < 17);
    }
}

//! Evaluation points drawn from a model itself, for comparisons without a point file: random
//! points in the leaves' normalization boxes, pushed onto the surface Φ = 0 by Newton steps.

use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::implicit::ImplicitNetwork;

/// Points drawn in the boxes by default.
pub const SURFACE_SAMPLES: usize = 1000;
/// Newton steps at most per point.
pub const NEWTON_STEPS: usize = 8;
/// A projected point is kept when |Φ| is below this (in `f64`).
pub const SURFACE_TOLERANCE: f64 = 1e-6;
/// Fewer surviving points than this and the unprojected box samples are used instead.
pub const MIN_SURFACE_POINTS: usize = 50;
/// The fixed seed of the box samples: the same model always gives the same points.
pub const SURFACE_SEED: u64 = 0x5EED_5AFE;
/// A projected point must stay inside some leaf's box grown by this factor (Newton steps from
/// the far field can land on a stray zero set the model never learned).
const BOX_MARGIN: f64 = 1.5;

/// Where evaluation points came from.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PointSource {
    /// A file the user gave.
    File,
    /// Box samples projected onto the model's surface.
    Surface,
    /// Box samples, unprojected (too few projections converged).
    Boxes,
}

/// Evaluation points and how they were made.
#[derive(Clone, Debug, PartialEq)]
pub struct EvaluationPoints {
    /// The points, each coordinate rounded to `f32` (what the core receives).
    pub points: Vec<[f64; 3]>,
    /// Their origin.
    pub source: PointSource,
    /// Box samples drawn (0 for [`PointSource::File`]).
    pub sampled: usize,
    /// Box samples that reached the surface (0 for [`PointSource::File`]).
    pub projected: usize,
}

impl EvaluationPoints {
    /// Points given by the user, rounded to `f32`.
    pub fn from_file(points: &[[f64; 3]]) -> Self {
        EvaluationPoints {
            points: round_to_f32(points),
            source: PointSource::File,
            sampled: 0,
            projected: 0,
        }
    }

    /// `samples` points uniform in the leaves' normalization boxes (the cube
    /// [−`box_size`/2, `box_size`/2]³ of each leaf's normalized space, mapped back to the world;
    /// leaves take turns), from the fixed [`SURFACE_SEED`]. Each is then moved onto the surface
    /// by up to [`NEWTON_STEPS`] Newton steps x ← x − Φ∇Φ/|∇Φ|² in `f64`, and kept when
    /// |Φ| < [`SURFACE_TOLERANCE`] and it is still within a leaf box grown by half. If fewer
    /// than [`MIN_SURFACE_POINTS`] survive, the box samples are returned unprojected
    /// ([`PointSource::Boxes`]). Coordinates are rounded to `f32` at the end.
    pub fn on_surface(network: &ImplicitNetwork, box_size: f64, samples: usize) -> Self {
        let boxes: Vec<LeafBox> = network
            .subtree_leaves(network.root())
            .into_iter()
            .filter_map(|leaf| LeafBox::new(network, leaf, box_size))
            .collect();
        if boxes.is_empty() {
            return EvaluationPoints {
                points: Vec::new(),
                source: PointSource::Boxes,
                sampled: 0,
                projected: 0,
            };
        }
        let mut rng = ChaCha8Rng::seed_from_u64(SURFACE_SEED);
        let half = 0.5 * box_size;
        let drawn: Vec<[f64; 3]> = (0..samples)
            .map(|i| {
                let local = [(); 3].map(|()| rng.random_range(-half..=half));
                boxes[i % boxes.len()].to_world(local)
            })
            .collect();
        let projected: Vec<[f64; 3]> = drawn
            .iter()
            .filter_map(|&x| project(network, x))
            .filter(|&x| boxes.iter().any(|b| b.contains(x, BOX_MARGIN * half)))
            .collect();
        let survivors = projected.len();
        let (points, source) = if survivors >= MIN_SURFACE_POINTS {
            (projected, PointSource::Surface)
        } else {
            (drawn, PointSource::Boxes)
        };
        EvaluationPoints {
            points: round_to_f32(&points),
            source,
            sampled: samples,
            projected: survivors,
        }
    }
}

/// Rounds every coordinate to the nearest `f32` (exactly what the core does on input), so a
/// reference evaluated at these points sees the same inputs as the core.
pub fn round_to_f32(points: &[[f64; 3]]) -> Vec<[f64; 3]> {
    points
        .iter()
        .map(|p| p.map(|c| f64::from(c as f32)))
        .collect()
}

/// Newton's method on Φ along ∇Φ from `x`; the point if it reached the surface.
fn project(network: &ImplicitNetwork, mut x: [f64; 3]) -> Option<[f64; 3]> {
    let (mut phi, mut gradient) = network.eval(x);
    for _ in 0..NEWTON_STEPS {
        if phi.abs() < SURFACE_TOLERANCE * 1e-6 {
            break;
        }
        let squared: f64 = gradient.iter().map(|g| g * g).sum();
        if !(squared > 0.0 && squared.is_finite()) {
            return None;
        }
        for k in 0..3 {
            x[k] -= phi * gradient[k] / squared;
        }
        (phi, gradient) = network.eval(x);
    }
    (phi.abs() < SURFACE_TOLERANCE && x.iter().all(|c| c.is_finite())).then_some(x)
}

/// One leaf's normalization x′ = A·(x − c) and its inverse.
struct LeafBox {
    center: Vector3<f64>,
    matrix: Matrix3<f64>,
    inverse: Matrix3<f64>,
}

impl LeafBox {
    fn new(network: &ImplicitNetwork, leaf: usize, box_size: f64) -> Option<Self> {
        let n = network.normalization(leaf)?;
        let matrix = Matrix3::from_fn(|i, j| n.matrix[i][j]);
        let inverse = matrix.try_inverse()?;
        (box_size > 0.0 && inverse.iter().all(|v| v.is_finite())).then_some(LeafBox {
            center: Vector3::from(n.center),
            matrix,
            inverse,
        })
    }

    fn to_world(&self, local: [f64; 3]) -> [f64; 3] {
        (self.inverse * Vector3::from(local) + self.center).into()
    }

    fn contains(&self, x: [f64; 3], half: f64) -> bool {
        let local = self.matrix * (Vector3::from(x) - self.center);
        local.iter().all(|c| c.abs() <= half)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::{self, FitRequest, ImplicitOptions};
    use crate::sample::{Shape, sample_shape};

    fn sphere() -> ImplicitNetwork {
        let points = sample_shape(&Shape::Sphere { radius: 1.0 }, 60, 3).unwrap();
        let options = ImplicitOptions {
            width: 5,
            ..ImplicitOptions::default()
        };
        implicit::fit(points, &FitRequest::default(), &options, &|_| {})
            .unwrap()
            .network
    }

    #[test]
    fn points_land_on_the_surface_deterministically() {
        let network = sphere();
        let a = EvaluationPoints::on_surface(&network, 2.0, 300);
        assert_eq!(a.source, PointSource::Surface);
        assert_eq!(a.sampled, 300);
        assert_eq!(a.projected, a.points.len());
        assert!(a.points.len() >= MIN_SURFACE_POINTS, "{}", a.points.len());
        for p in &a.points {
            // On the learned sphere (the model approximates radius 1), rounded to f32.
            let r = p.iter().map(|c| c * c).sum::<f64>().sqrt();
            assert!((r - 1.0).abs() < 0.05, "{p:?} at radius {r}");
            assert!(p.iter().all(|&c| f64::from(c as f32) == c));
            assert!(network.eval(*p).0.abs() < 1e-5);
        }
        assert_eq!(a, EvaluationPoints::on_surface(&network, 2.0, 300));
    }

    #[test]
    fn too_few_survivors_fall_back_to_the_box_samples() {
        let network = sphere();
        let few = EvaluationPoints::on_surface(&network, 2.0, MIN_SURFACE_POINTS - 1);
        assert_eq!(few.source, PointSource::Boxes);
        assert_eq!(few.points.len(), MIN_SURFACE_POINTS - 1);
        assert!(few.projected < MIN_SURFACE_POINTS);
    }

    #[test]
    fn file_points_are_rounded_to_f32() {
        let p = EvaluationPoints::from_file(&[[0.1, 1.0 / 3.0, 2.0]]);
        assert_eq!(p.source, PointSource::File);
        assert_eq!(
            p.points,
            vec![[f64::from(0.1_f32), f64::from(1.0_f32 / 3.0), 2.0]]
        );
    }
}

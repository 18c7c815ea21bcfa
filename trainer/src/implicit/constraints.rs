//! What holds a field in place away from its control points. Carcenac constrains Φ and ∇Φ
//! only at the control points, and between and beyond them the field is free to cross zero:
//! stray sheets and blobs. Two kinds of extra points pin it down:
//!
//! - **off-surface points** xᵢ ± ε·nᵢ with Φ = ∓s·ε, as Turk & O'Brien's and Carr et al.'s
//!   RBFs use (ε shrinks where another control point is nearer than xᵢ, so thin parts keep
//!   their sign);
//! - **sign points** drawn in a module's region away from every control point, inside or
//!   outside by the winding number of the control points ([`Oracle`]); each penalizes Φ only
//!   while it is on the wrong side of ±margin.

use nalgebra::Matrix3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::normalize::Normalization;
use super::oracle::Oracle;

/// Halvings of ε at most before an off-surface point is dropped.
const OFFSET_HALVINGS: usize = 4;

/// An off-surface point and the value Φ should take there.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct OffSurface {
    /// The point.
    pub position: [f64; 3],
    /// Φ there: ∓s·ε.
    pub value: f64,
}

/// The two off-surface points of control point `i` at ±`epsilon` along its normal, ε halved
/// until `i` is the nearest control point to each; fewer where that never happens.
pub fn off_surface(
    oracle: &Oracle,
    i: usize,
    normal: [f64; 3],
    epsilon: f64,
    slope: f64,
) -> Vec<OffSurface> {
    let p = oracle.positions()[i];
    let mut out = Vec::with_capacity(2);
    for side in [1.0, -1.0] {
        let mut e = epsilon;
        for _ in 0..=OFFSET_HALVINGS {
            let q = [0, 1, 2].map(|k| p[k] + side * e * normal[k]);
            if oracle.nearest(q).0 == i {
                out.push(OffSurface {
                    position: q,
                    value: -side * slope * e,
                });
                break;
            }
            e *= 0.5;
        }
    }
    out
}

/// A parallelepiped {x : |A·(x − c)|∞ ≤ h} to draw points in.
#[derive(Copy, Clone, Debug)]
pub struct SampleBox {
    center: [f64; 3],
    inverse: Matrix3<f64>,
    half: f64,
    volume: f64,
}

impl SampleBox {
    /// The box of a normalization with half side `half`; `None` when A is singular.
    pub fn new(normalization: &Normalization, half: f64) -> Option<SampleBox> {
        let a = Matrix3::from_fn(|i, j| normalization.matrix[i][j]);
        let inverse = a.try_inverse()?;
        let volume = (2.0 * half).powi(3) * inverse.determinant().abs();
        (volume > 0.0 && volume.is_finite()).then_some(SampleBox {
            center: normalization.center,
            inverse,
            half,
            volume,
        })
    }

    /// An axis-aligned box.
    pub fn aligned(lo: [f64; 3], hi: [f64; 3]) -> Option<SampleBox> {
        let half = [0, 1, 2].map(|k| 0.5 * (hi[k] - lo[k]));
        let normalization = Normalization {
            center: [0, 1, 2].map(|k| 0.5 * (lo[k] + hi[k])),
            matrix: [0, 1, 2].map(|r| [0, 1, 2].map(|c| if r == c { 1.0 / half[r] } else { 0.0 })),
        };
        Self::new(&normalization, 1.0)
    }

    fn draw(&self, rng: &mut ChaCha8Rng) -> [f64; 3] {
        let u = nalgebra::Vector3::from_fn(|_, _| rng.random_range(-self.half..=self.half));
        let x = self.inverse * u;
        [0, 1, 2].map(|k| self.center[k] + x[k])
    }
}

/// A sign point: where, and whether Φ must be positive (inside) there.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct SignPoint {
    /// The point.
    pub position: [f64; 3],
    /// Inside the surface (Φ > 0) or outside (Φ < 0).
    pub inside: bool,
    /// A lower bound of its distance to the surface ([`Oracle::surface_distance`]).
    pub distance: f64,
}

/// Up to `count` sign points drawn uniformly in the union of `boxes` (by volume), each at
/// least `clearance` from the sampled surface (by [`Oracle::surface_distance`]) and owned by the module: `owned(j)` says whether
/// the nearest control point j belongs to it. Gives up after 20·`count` draws.
pub fn sign_points(
    oracle: &Oracle,
    boxes: &[SampleBox],
    count: usize,
    clearance: f64,
    owned: &dyn Fn(usize) -> bool,
    rng: &mut ChaCha8Rng,
) -> Vec<SignPoint> {
    let total: f64 = boxes.iter().map(|b| b.volume).sum();
    let mut out = Vec::with_capacity(count);
    if boxes.is_empty() || total.is_nan() || total <= 0.0 {
        return out;
    }
    for _ in 0..20 * count {
        if out.len() == count {
            break;
        }
        let mut pick = rng.random_range(0.0..total);
        let chosen = boxes
            .iter()
            .find(|b| {
                pick -= b.volume;
                pick < 0.0
            })
            .unwrap_or(&boxes[boxes.len() - 1]);
        let q = chosen.draw(rng);
        let (nearest, distance) = oracle.surface_distance(q);
        if distance < clearance || !owned(nearest) {
            continue;
        }
        out.push(SignPoint {
            position: q,
            inside: oracle.inside(q),
            distance,
        });
    }
    out
}

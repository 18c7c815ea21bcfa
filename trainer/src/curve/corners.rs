//! Corners of ordered points, kept exactly by a uniform cubic B-spline.
//!
//! A uniform cubic B-spline whose control points P_i = P_{i+1} = P_{i+2} = P coincide passes
//! through P at the knot t_i, and its segments on either side are straight lines into P:
//! a sharp corner with the knots left uniform (the only knots the core evaluates). The fit
//! therefore moves the data's parameters so that each corner falls on a knot, and ties the
//! three control points there into one unknown.
//!
//! A corner is a point where the ordered points turn by [`CORNER_ANGLE`] to
//! [`MAX_CORNER_ANGLE`] between two
//! straight arms: lines fitted to the points before and after it, each explaining its points
//! to within [`ARM_STRAIGHTNESS`] of its length with the points advancing along it in order,
//! and at a local maximum of that turn; arms half as long must see about the same turn. A bend turns gradually, so its arms are not
//! straight at the scale where its turn is large, and shorter arms see less of it.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// The least turn, in radians, between the arms of a corner (40°).
pub const CORNER_ANGLE: f64 = 40.0 * std::f64::consts::PI / 180.0;
/// The largest (160°): beyond it the points double back, which is an order that reverses
/// rather than a corner.
pub const MAX_CORNER_ANGLE: f64 = 160.0 * std::f64::consts::PI / 180.0;
/// An arm is straight when its points lie within this fraction of its length of its line
/// (root mean square).
pub const ARM_STRAIGHTNESS: f64 = 0.025;
/// Arms of half the length see this share of a corner's turn …
const CONCENTRATION: f64 = 1.0;
/// … within this margin (a bend shows about a half, noise that passes for a turn more or
/// less than all of it).
const CONCENTRATION_MARGIN: f64 = 0.15;
/// Fewest points on each arm.
const MIN_ARM: usize = 4;
/// Most points on each arm.
const MAX_ARM: usize = 30;
/// Arms span about this fraction of the points.
const ARM_SHARE: usize = 40;

/// A line fitted to points: its unit direction (oriented from the first point to the last),
/// a point on it (the points' mean), its length and the root-mean-square distance of the
/// points from it.
struct Arm {
    direction: Vector3<f64>,
    centre: Vector3<f64>,
    length: f64,
    residual: f64,
    /// Whether the points advance along the line in order, to within twice the residual (a
    /// zig-zagging order is noise).
    advancing: bool,
}

fn arm(points: &[[f64; 3]]) -> Option<Arm> {
    let count = points.len() as f64;
    let mean = points
        .iter()
        .fold(Vector3::zeros(), |s, p| s + Vector3::from(*p))
        / count;
    let mut scatter = Matrix3::zeros();
    for p in points {
        let d = Vector3::from(*p) - mean;
        scatter += d * d.transpose();
    }
    let eigen = SymmetricEigen::new(scatter);
    let (largest, _) = eigen
        .eigenvalues
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))?;
    let mut direction: Vector3<f64> = eigen.eigenvectors.column(largest).into();
    let chord = Vector3::from(points[points.len() - 1]) - Vector3::from(points[0]);
    if direction.dot(&chord) < 0.0 {
        direction = -direction;
    }
    let along = eigen.eigenvalues[largest].max(0.0);
    let across = (eigen.eigenvalues.sum() - along).max(0.0);
    // Points spread evenly along a segment of length L have variance L²/12.
    let length = (12.0 * along / count).sqrt();
    let along_line: Vec<f64> = points
        .iter()
        .map(|p| (Vector3::from(*p) - mean).dot(&direction))
        .collect();
    let residual = (across / count).sqrt();
    // Noise as wide as the scatter across the line may swap close neighbours along it.
    let advancing = along_line.windows(2).all(|w| w[1] - w[0] > -2.0 * residual);
    (length > 0.0 && direction.iter().all(|c| c.is_finite())).then_some(Arm {
        direction,
        centre: mean,
        length,
        residual,
        advancing,
    })
}

/// The turn at `i` between arms of `w` points before and after it, and whether both arms are
/// straight; `None` where an arm is missing (an open curve's ends).
fn turn(ordered: &[[f64; 3]], closed: bool, i: usize, w: usize) -> Option<(f64, bool)> {
    let n = ordered.len();
    let pick = |offset: isize| -> Option<[f64; 3]> {
        let j = i as isize + offset;
        if closed {
            Some(ordered[j.rem_euclid(n as isize) as usize])
        } else {
            (0..n as isize).contains(&j).then(|| ordered[j as usize])
        }
    };
    // The point at `i` belongs to neither arm: where the corner falls between two samples,
    // the nearer one lies on one arm and up to a spacing off the other's line.
    let w = w as isize;
    let before: Option<Vec<[f64; 3]>> = (-w..0).map(pick).collect();
    let after: Option<Vec<[f64; 3]>> = (1..=w).map(pick).collect();
    let (a, b) = (arm(&before?)?, arm(&after?)?);
    let straight = |arm: &Arm| arm.advancing && arm.residual <= ARM_STRAIGHTNESS * arm.length;
    Some((
        a.direction.dot(&b.direction).clamp(-1.0, 1.0).acos(),
        straight(&a) && straight(&b),
    ))
}

/// Points on each arm of a corner among `n` points.
fn arm_points(n: usize) -> usize {
    (n / ARM_SHARE).clamp(MIN_ARM, MAX_ARM)
}

/// A corner of ordered points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Corner {
    /// The ordered point where the turn peaks.
    pub index: usize,
    /// The turn between the arms, in radians.
    pub turn: f64,
    /// Where the arms' lines meet: the corner itself, which no point need sample (the point
    /// at [`Self::index`] is the nearest sample, up to a spacing away along an arm). `None`
    /// where they do not meet near that point.
    pub tip: Option<[f64; 3]>,
}

/// The points of `ordered` where it turns by a corner, in order. Needs at least 17 points
/// (four arms' worth); fewer give none.
pub fn find_corners(ordered: &[[f64; 3]], closed: bool) -> Vec<Corner> {
    let n = ordered.len();
    if n < 4 * MIN_ARM + 1 {
        return Vec::new();
    }
    let w = arm_points(n);
    let turns: Vec<f64> = (0..n)
        .map(|i| match turn(ordered, closed, i, w) {
            Some((angle, true)) => angle,
            _ => 0.0,
        })
        .collect();
    // A corner turns within its tip: arms half as long see the same turn, where a bend
    // spreads it along its length and they see about half.
    let concentrated = |i: usize| {
        turn(ordered, closed, i, w / 2).is_some_and(|(angle, _)| {
            (angle / turns[i] - CONCENTRATION).abs() <= CONCENTRATION_MARGIN
        })
    };
    let neighbour = |i: usize, d: usize, ahead: bool| -> Option<usize> {
        if closed {
            Some(if ahead {
                (i + d) % n
            } else {
                (i + n - d % n) % n
            })
        } else if ahead {
            (i + d < n).then_some(i + d)
        } else {
            i.checked_sub(d)
        }
    };
    (0..n)
        .filter(|&i| {
            (CORNER_ANGLE..=MAX_CORNER_ANGLE).contains(&turns[i])
                && concentrated(i)
                && (1..=w).all(|d| {
                    // A strict maximum ahead and at least as large as behind: one point per
                    // corner, also where neighbours tie.
                    neighbour(i, d, true).is_none_or(|j| turns[j] < turns[i])
                        && neighbour(i, d, false).is_none_or(|j| turns[j] <= turns[i])
                })
        })
        .map(|i| Corner {
            index: i,
            turn: turns[i],
            tip: tip(ordered, closed, i, w),
        })
        .collect()
}

/// Where the lines of the `w` points before `i` and the `w` after it meet (the midpoint of
/// their common perpendicular in 3-D), the point `i` itself left out: it may lie on either
/// arm. `None` where an arm is missing or the arms are nearly parallel, where the lines do
/// not meet ahead of the arm before and behind the arm after (each arm's middle), or farther
/// from point `i` than the longer arm's length and the longer step from `i` to a neighbour.
fn tip(ordered: &[[f64; 3]], closed: bool, i: usize, w: usize) -> Option<[f64; 3]> {
    let n = ordered.len() as isize;
    let pick = |offset: isize| -> Option<[f64; 3]> {
        let j = i as isize + offset;
        if closed {
            Some(ordered[j.rem_euclid(n) as usize])
        } else {
            (0..n).contains(&j).then(|| ordered[j as usize])
        }
    };
    let w = w as isize;
    let before: Option<Vec<[f64; 3]>> = (-w..0).map(pick).collect();
    let after: Option<Vec<[f64; 3]>> = (1..=w).map(pick).collect();
    let (a, b) = (arm(&before?)?, arm(&after?)?);
    let cos = a.direction.dot(&b.direction);
    let sin2 = 1.0 - cos * cos;
    if sin2 < 1e-6 {
        return None;
    }
    // The nearest points a.centre + s·a.direction and b.centre + t·b.direction.
    let gap = a.centre - b.centre;
    let (d, e) = (a.direction.dot(&gap), b.direction.dot(&gap));
    let s = (cos * e - d) / sin2;
    let t = (e - cos * d) / sin2;
    let meet = (a.centre + s * a.direction + b.centre + t * b.direction) / 2.0;
    let sample = Vector3::from(ordered[i]);
    // Ahead of the arm before, behind the arm after, and near the sampled turn.
    let between =
        (meet - a.centre).dot(&a.direction) >= 0.0 && (meet - b.centre).dot(&b.direction) <= 0.0;
    let step = |offset: isize| pick(offset).map_or(0.0, |p| (Vector3::from(p) - sample).norm());
    let reach = a.length.max(b.length) + step(-1).max(step(1));
    (between && (meet - sample).norm() <= reach).then(|| meet.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertex `k` of a regular polygon with `sides` sides, radius 1.
    fn vertex(sides: usize, k: usize) -> [f64; 3] {
        let a = std::f64::consts::TAU * k as f64 / sides as f64;
        [a.cos(), a.sin(), 0.0]
    }

    #[test]
    fn a_polygon_has_a_corner_at_each_vertex() {
        for (sides, per_side) in [(4, 50), (3, 30), (6, 12), (5, 200)] {
            for offset in [0.0, 0.3, 0.7] {
                let points = polygon(sides, per_side, offset);
                let corners = find_corners(&points, true);
                assert_eq!(corners.len(), sides, "{sides} sides");
                let turn = std::f64::consts::TAU / sides as f64;
                let n = sides * per_side;
                let mut found: Vec<usize> = Vec::new();
                for c in &corners {
                    // The turn peaks at a sample next to a vertex.
                    let k = (c.index + per_side / 2) / per_side % sides;
                    let apart = c.index.abs_diff(k * per_side);
                    assert!(apart.min(n - apart) <= 2, "{c:?}");
                    assert!((c.turn - turn).abs() < 1e-6, "{c:?}");
                    // The tip is the vertex itself, sampled or not.
                    let (tip, v) = (c.tip.expect("the arms meet"), vertex(sides, k));
                    assert!((0..3).all(|a| (tip[a] - v[a]).abs() < 1e-9), "{c:?} {v:?}");
                    found.push(k);
                }
                found.sort_unstable();
                found.dedup();
                assert_eq!(found.len(), sides, "{sides} sides, offset {offset}");
            }
        }
    }

    /// `per_side` points along each side of a regular polygon with `sides` sides, radius 1,
    /// starting `offset` of a spacing after each vertex (0: the vertices are samples).
    fn polygon(sides: usize, per_side: usize, offset: f64) -> Vec<[f64; 3]> {
        (0..sides)
            .flat_map(|k| {
                let (a, b) = (vertex(sides, k), vertex(sides, k + 1));
                (0..per_side).map(move |j| {
                    let u = (j as f64 + offset) / per_side as f64;
                    [0, 1, 2].map(|c| a[c] + u * (b[c] - a[c]))
                })
            })
            .collect()
    }

    #[test]
    fn smooth_curves_have_none() {
        // A circle, an ellipse of axis ratio 4 and a tight spiral, densely and sparsely.
        for n in [24, 100, 1000] {
            let circle: Vec<[f64; 3]> = (0..n)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / n as f64;
                    [a.cos(), 0.25 * a.sin(), 0.0]
                })
                .collect();
            assert!(find_corners(&circle, true).is_empty(), "{n}");
            let spiral: Vec<[f64; 3]> = (0..n)
                .map(|i| {
                    let a = 4.0 * std::f64::consts::TAU * i as f64 / n as f64;
                    let r = 0.2 + a;
                    [r * a.cos(), r * a.sin(), 0.0]
                })
                .collect();
            assert!(find_corners(&spiral, false).is_empty(), "{n}");
        }
    }
}

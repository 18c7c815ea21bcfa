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
/// its length and the root-mean-square distance of the points from it.
struct Arm {
    direction: Vector3<f64>,
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
    let w = w as isize;
    let before: Option<Vec<[f64; 3]>> = (-w..=0).map(pick).collect();
    let after: Option<Vec<[f64; 3]>> = (0..=w).map(pick).collect();
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

/// The points of `ordered` where it turns by a corner, in order, each with its turn in
/// radians. Needs at least 17 points (four arms' worth); fewer give none.
pub fn find_corners(ordered: &[[f64; 3]], closed: bool) -> Vec<(usize, f64)> {
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
        .map(|i| (i, turns[i]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `per_side` points along each side of a regular polygon with `sides` sides, radius 1.
    fn polygon(sides: usize, per_side: usize) -> Vec<[f64; 3]> {
        let vertex = |k: usize| {
            let a = std::f64::consts::TAU * k as f64 / sides as f64;
            [a.cos(), a.sin(), 0.0]
        };
        (0..sides)
            .flat_map(|k| {
                let (a, b) = (vertex(k), vertex(k + 1));
                (0..per_side).map(move |j| {
                    let u = j as f64 / per_side as f64;
                    [0, 1, 2].map(|c| a[c] + u * (b[c] - a[c]))
                })
            })
            .collect()
    }

    #[test]
    fn a_polygon_has_a_corner_at_each_vertex() {
        for (sides, per_side) in [(4, 50), (3, 30), (6, 12), (5, 200)] {
            let points = polygon(sides, per_side);
            let corners = find_corners(&points, true);
            let at: Vec<usize> = corners.iter().map(|c| c.0).collect();
            let expected: Vec<usize> = (0..sides).map(|k| k * per_side).collect();
            assert_eq!(at, expected, "{sides} sides");
            let turn = std::f64::consts::TAU / sides as f64;
            assert!(corners.iter().all(|c| (c.1 - turn).abs() < 1e-6));
        }
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

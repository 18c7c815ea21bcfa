//! Tubes: points with two separate edges, like an open cylinder, a pipe or a vase without a
//! bottom. One open patch would be slit along the tube and overlap or gap at the slit; a
//! surface closed around the tube has neither.
//!
//! Two edges alone do not make a tube: two sides of a patch whose boundary breaks at its
//! corners look like two edges too, and an S-shaped side even surrounds its centre. So
//! `curve surface` fits points with two edges both ways and keeps the tube unless one patch
//! fits far better (`TubeMode::Auto` in `surface.rs`); `--tube` and `--patch` decide instead.
//!
//! A tube is recognized by its boundaries ([`boundaries`]), which come in pieces where the
//! edge points leave gaps. The largest piece starts the first edge and takes in every piece
//! within two [`TUBE_GAP`]s of it, round after round, so that the pieces of one edge chain
//! around it (and a patch's sides chain at its corners into one edge); the largest piece
//! left starts the second edge the same way. The edges must lie farther apart than
//! [`TUBE_GAP`] point spacings. Smaller pieces within an eighth of that distance from an edge
//! join it; one of [`CLOSED_BELOW`]·√n points or more farther in is a third edge, and the
//! points are no tube. Each edge then needs at least that many points. Each point then gets coordinates:
//! - along the tube, v = d₀/(d₀ + d₁), d₀ and d₁ its path lengths through neighbours to each
//!   edge (0 on the first edge, 1 on the second);
//! - around it, u ∈ [0, 1): the angle about the tube's axis, the centroids of
//!   [`TUBE_SLICES`] slices of equal v, from one reference direction made square to the
//!   axis at each slice.
//!
//! Long tubes have few edge points for their √n, in pieces: cylinders of radius 1 and height
//! 6–15 are tubes on 9 of 9 point sets (500–8 000 points; 6 of 9 when each edge's largest
//! piece alone had to have √n/2 points), their areas within 0.97–1.00 of the true ones. A
//! band much wider than it is tall (radius 1.5, height 0.8) has its edges found on some
//! point sets only, and then fits poorly.
//!
//! The angle needs an axis that each slice surrounds and that never turns square to the
//! reference direction: a pipe bent through less than a quarter turn works; a tube folded
//! back on itself does not.

use super::path_graph::{neighbour_graph, shortest_paths};
use super::surface_boundary::{CLOSED_BELOW, boundaries};
use crate::geometry::vector::{cross, dot, norm, sub};

/// Nearest points joined in the path graph.
pub const TUBE_NEIGHBOURS: usize = 8;
/// Slices along the tube whose centroids make its axis.
pub const TUBE_SLICES: usize = 24;
/// Slices on either side of a slice whose centroids give the axis direction there.
const TANGENT_REACH: usize = 3;
/// Least distance between a tube's two edges, in median point spacings.
pub const TUBE_GAP: f64 = 4.0;
/// Gaps across which pieces of one edge chain, in [`TUBE_GAP`]s.
const CHAIN: f64 = 2.0;

/// Each point's (u, v) on the tube: u ∈ [0, 1) around it, v ∈ [0, 1] along it; `None` when the
/// points have no two separate edges, or a third (see the module's documentation). A patch
/// whose boundary breaks at its corners into two long sides passes too.
pub fn tube_parameters(points: &[[f64; 3]]) -> Option<Vec<[f64; 2]>> {
    let n = points.len();
    let mut pieces = boundaries(points);
    let least = CLOSED_BELOW * (n as f64).sqrt();
    if (pieces.first()?.len() as f64) < least {
        return None;
    }
    let graph = neighbour_graph(points, TUBE_NEIGHBOURS)?;
    // The nearest other point comes second in each list (the point itself first).
    let mut spacing: Vec<f64> = graph
        .iter()
        .filter_map(|list| list.get(1))
        .map(|f| f.1)
        .collect();
    spacing.sort_by(f64::total_cmp);
    let reach = TUBE_GAP * *spacing.get(spacing.len() / 2)?;
    // An edge whose boundary points leave gaps comes in pieces. The largest piece starts the
    // first edge, which takes every piece within `chain` of it, round after round, so that
    // the pieces of a wide edge chain around it (and a patch's sides chain at its corners
    // into one edge); the largest piece left starts the second edge the same way.
    // Gaps are bridged up to an eighth of the farthest point's distance from the largest
    // piece, too: where points are few, `CHAIN · reach` reaches far into a tube.
    let largest = pieces.remove(0);
    let across = shortest_paths(&graph, &largest)
        .into_iter()
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max);
    let chain = (CHAIN * reach).min(across / 8.0);
    let first_edge = Edge::grow(largest, &mut pieces, &graph, chain);
    if pieces.is_empty() {
        return None;
    }
    let second_edge = Edge::grow(pieces.remove(0), &mut pieces, &graph, chain);
    let apart = second_edge
        .points
        .iter()
        .map(|&i| first_edge.distance[i])
        .fold(f64::INFINITY, f64::min);
    if apart.is_nan() || apart <= reach || first_edge.distance.iter().any(|d| !d.is_finite()) {
        return None;
    }
    // Then pieces within an eighth of the edges' distance join the nearer edge (in one pass:
    // joined round after round, pieces of noise inside would creep towards the middle). A
    // large piece left farther in is a third edge, and the points are no tube.
    let (mut first, mut second) = (first_edge.points.clone(), second_edge.points.clone());
    let join = apart / 8.0;
    for piece in &pieces {
        let (a, b) = (first_edge.gap(piece), second_edge.gap(piece));
        if a <= join && a <= b {
            first.extend(piece);
        } else if b <= join {
            second.extend(piece);
        } else if piece.len() as f64 >= least {
            return None;
        }
    }
    if (first.len().min(second.len()) as f64) < least {
        return None;
    }
    let to_first = shortest_paths(&graph, &first);
    let to_second = shortest_paths(&graph, &second);
    let along: Vec<f64> = to_first
        .iter()
        .zip(&to_second)
        .map(|(&a, &b)| if a + b > 0.0 { a / (a + b) } else { 0.5 })
        .collect();
    let axis = Axis::new(points, &along)?;
    Some(
        points
            .iter()
            .zip(&along)
            .map(|(&p, &v)| [axis.around(p, v), v])
            .collect(),
    )
}

/// One edge of a tube: its boundary points and every point's path length to them.
struct Edge {
    points: Vec<usize>,
    distance: Vec<f64>,
}

impl Edge {
    /// The edge of `start` and the `pieces` that chain to it, each within `reach` of the
    /// edge grown so far (taken out of `pieces`).
    fn grow(
        start: Vec<usize>,
        pieces: &mut Vec<Vec<usize>>,
        graph: &[Vec<(usize, f64)>],
        reach: f64,
    ) -> Self {
        let mut edge = Edge {
            distance: shortest_paths(graph, &start),
            points: start,
        };
        loop {
            let before = edge.points.len();
            pieces.retain(|piece| {
                if edge.gap(piece) <= reach {
                    edge.points.extend(piece.iter());
                    false
                } else {
                    true
                }
            });
            if edge.points.len() == before {
                return edge;
            }
            edge.distance = shortest_paths(graph, &edge.points);
        }
    }

    /// The shortest path length from the edge to any point of `piece`.
    fn gap(&self, piece: &[usize]) -> f64 {
        piece
            .iter()
            .map(|&i| self.distance.get(i).copied().unwrap_or(f64::INFINITY))
            .fold(f64::INFINITY, f64::min)
    }
}

/// The tube's axis: slice centroids and an untwisted frame at each.
struct Axis {
    centres: Vec<[f64; 3]>,
    /// Per slice: the axis direction, a reference direction across it, and their cross
    /// product.
    frames: Vec<[[f64; 3]; 3]>,
}

impl Axis {
    fn new(points: &[[f64; 3]], along: &[f64]) -> Option<Self> {
        let slices = TUBE_SLICES;
        let mut sums = vec![([0.0; 3], 0usize); slices];
        for (p, &v) in points.iter().zip(along) {
            let (sum, count) = &mut sums[slice(v, slices)];
            for k in 0..3 {
                sum[k] += p[k];
            }
            *count += 1;
        }
        if sums.iter().any(|&(_, count)| count == 0) {
            return None;
        }
        let centres: Vec<[f64; 3]> = sums
            .iter()
            .map(|&(sum, count)| sum.map(|c| c / count as f64))
            .collect();
        let unit = |d: [f64; 3]| {
            let length = norm(d);
            (length > 0.0).then(|| d.map(|c| c / length))
        };
        // Tangents over ±`TANGENT_REACH` slices: a slice's centroid moves by the noise of
        // its few points, which neighbouring slices alone would turn into a wobbling axis.
        let tangents: Vec<[f64; 3]> = (0..slices)
            .map(|k| {
                let (a, b) = (
                    k.saturating_sub(TANGENT_REACH),
                    (k + TANGENT_REACH).min(slices - 1),
                );
                unit(sub(centres[b], centres[a]))
            })
            .collect::<Option<_>>()?;
        // One reference direction for all slices, made square to each tangent: carried from
        // slice to slice instead, the noise of each tangent would add up to a twist.
        let i = along.iter().position(|&v| slice(v, slices) == 0)?;
        let start = sub(points[i], centres[0]);
        let frames = tangents
            .iter()
            .map(|&tangent| {
                let across = unit(sub(start, tangent.map(|c| c * dot(start, tangent))))?;
                Some([tangent, across, cross(tangent, across)])
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Axis { centres, frames })
    }

    /// The angle of `p` about the axis at `v`, as a share of a turn in [0, 1).
    fn around(&self, p: [f64; 3], v: f64) -> f64 {
        let k = slice(v, self.centres.len());
        let d = sub(p, self.centres[k]);
        let [_, across, side] = self.frames[k];
        let turn = dot(d, side).atan2(dot(d, across)) / std::f64::consts::TAU;
        turn.rem_euclid(1.0).min(1.0 - f64::EPSILON)
    }
}

/// The slice of v ∈ [0, 1] among `slices` equal ones.
fn slice(v: f64, slices: usize) -> usize {
    ((v * slices as f64) as usize).min(slices - 1)
}

#[cfg(test)]
mod tests {
    use super::super::surface_boundary::tests::random;
    use super::*;

    /// u against the true angle (a share of a turn, either way round, up to an offset) and
    /// v against the true height: the 95th percentiles of the errors.
    fn errors(points: &[[f64; 3]], parameters: &[[f64; 2]], height: f64) -> (f64, f64) {
        let wrap = |x: f64| (x + 0.5).rem_euclid(1.0) - 0.5;
        let turn = |p: &[f64; 3]| p[1].atan2(p[0]) / std::f64::consts::TAU;
        let percentile = |mut errors: Vec<f64>| {
            errors.sort_by(f64::total_cmp);
            errors[errors.len() * 95 / 100]
        };
        let mut best_u = f64::INFINITY;
        for sign in [1.0, -1.0] {
            // The offset: the median of the differences.
            let mut differences: Vec<f64> = points
                .iter()
                .zip(parameters)
                .map(|(p, q)| {
                    wrap(q[0] - sign * turn(p) - wrap(parameters[0][0] - sign * turn(&points[0])))
                })
                .collect();
            differences.sort_by(f64::total_cmp);
            let offset = wrap(parameters[0][0] - sign * turn(&points[0]))
                + differences[differences.len() / 2];
            let errors = points
                .iter()
                .zip(parameters)
                .map(|(p, q)| wrap(q[0] - sign * turn(p) - offset).abs())
                .collect();
            best_u = best_u.min(percentile(errors));
        }
        let flipped = parameters[0][1] > 0.5 && points[0][2] < 0.5 * height
            || parameters[0][1] < 0.5 && points[0][2] > 0.5 * height;
        let errors_v = points
            .iter()
            .zip(parameters)
            .map(|(p, q)| {
                let v = if flipped { 1.0 - q[1] } else { q[1] };
                (v - p[2] / height).abs()
            })
            .collect();
        (best_u, percentile(errors_v))
    }

    #[test]
    fn a_cylinder_is_a_tube_with_its_angle_and_height() {
        let tau = std::f64::consts::TAU;
        for (n, seed) in [(500, 1), (2_000, 2), (8_000, 3)] {
            let cylinder = random(n, seed, |u, v| [(tau * u).cos(), (tau * u).sin(), 3.0 * v]);
            let parameters = tube_parameters(&cylinder).expect("a tube");
            let (u, v) = errors(&cylinder, &parameters, 3.0);
            // 95 % of the points (measured): u within 0.03–0.07 of a turn, v within
            // 0.06–0.09. The fit's projection corrects them further.
            assert!(u < 0.1 && v < 0.12, "{n}: u {u}, v {v}");
        }
    }

    #[test]
    fn discs_and_closed_surfaces_are_not_tubes() {
        let tau = std::f64::consts::TAU;
        for (n, seed) in [(500, 4), (4_000, 5)] {
            let disc = random(n, seed, |u, v| {
                let r = u.sqrt();
                [r * (tau * v).cos(), r * (tau * v).sin(), 0.2 * r * r]
            });
            assert!(tube_parameters(&disc).is_none());
            let sphere = random(n, seed, |u, v| {
                let z = 2.0 * u - 1.0;
                let r = (1.0 - z * z).sqrt();
                [r * (tau * v).cos(), r * (tau * v).sin(), z]
            });
            assert!(tube_parameters(&sphere).is_none());
        }
    }
}

//! Distance between two triangle meshes: exact point-to-triangle distances through a bounding
//! volume hierarchy, sampled at the vertices of each mesh, in both directions.
//!
//! This is how a fitted Cao En surface is scored against the mesh it approximates: the
//! surface is sampled densely (an icosphere mapped through the network), every surface sample
//! is measured to the nearest point of the mesh's triangles and every mesh vertex to the
//! nearest point of the sampled surface's triangles. Distances are exact to rounding for the
//! triangles given; the surface's own error between its samples (chordal error) is part of
//! the measured distance, below 10⁻³ of the diagonal at the densities used in the tests.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::{OuterSurface, bounding_diagonal};

use super::topology::cap_holes;
use crate::geometry::vector::{dot, sub};
use crate::io::Mesh;

/// Triangles per leaf of the hierarchy.
const LEAF_SIZE: usize = 4;

/// A bounding volume hierarchy over a mesh's triangles for nearest-point queries.
#[derive(Clone, Debug)]
pub struct TriangleTree {
    /// Each triangle with its index in the mesh.
    triangles: Vec<([[f64; 3]; 3], u32)>,
    nodes: Vec<Node>,
}

#[derive(Clone, Debug)]
struct Node {
    low: [f64; 3],
    high: [f64; 3],
    /// Leaf: `triangles[start..start + count]`; inner node: children `start`, `start + 1`.
    start: usize,
    count: usize,
}

impl TriangleTree {
    /// Builds the hierarchy (median splits on the longest axis of the centroids' box).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an invalid mesh (see [`Mesh::validated`]).
    pub fn new(mesh: &Mesh) -> Result<Self> {
        let mesh = mesh.clone().validated()?;
        let mut triangles: Vec<([[f64; 3]; 3], u32)> = mesh
            .triangles
            .iter()
            .zip(0..)
            .map(|(t, index)| (t.map(|v| mesh.positions[v as usize]), index))
            .collect();
        let mut nodes = vec![bounds(&triangles, 0, triangles.len())];
        let mut pending = vec![0];
        while let Some(index) = pending.pop() {
            let (start, count) = (nodes[index].start, nodes[index].count);
            if count <= LEAF_SIZE {
                continue;
            }
            let slice = &mut triangles[start..start + count];
            let centre = |(t, _): &([[f64; 3]; 3], u32), k: usize| t[0][k] + t[1][k] + t[2][k];
            let (mut low, mut high) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for t in slice.iter() {
                for k in 0..3 {
                    low[k] = low[k].min(centre(t, k));
                    high[k] = high[k].max(centre(t, k));
                }
            }
            let axis = (0..3)
                .max_by(|&a, &b| (high[a] - low[a]).total_cmp(&(high[b] - low[b])))
                .unwrap_or(0);
            let half = count / 2;
            slice.select_nth_unstable_by(half, |a, b| centre(a, axis).total_cmp(&centre(b, axis)));
            let first = nodes.len();
            nodes.push(bounds(&triangles, start, half));
            nodes.push(bounds(&triangles, start + half, count - half));
            nodes[index].start = first;
            nodes[index].count = 0;
            pending.extend([first, first + 1]);
        }
        Ok(TriangleTree { triangles, nodes })
    }

    /// The distance from `p` to the nearest point of any triangle.
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        self.nearest(p).1
    }

    /// The index (in the mesh) of the triangle nearest to `p`, and the distance to it.
    pub fn nearest(&self, p: [f64; 3]) -> (usize, f64) {
        let mut best = f64::INFINITY;
        let mut nearest = 0;
        let mut stack = vec![0_usize];
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index];
            if box_distance_squared(node, p) >= best {
                continue;
            }
            if node.count > 0 {
                for (t, index) in &self.triangles[node.start..node.start + node.count] {
                    let d = triangle_distance_squared(p, t);
                    if d < best {
                        (best, nearest) = (d, *index as usize);
                    }
                }
            } else {
                let (a, b) = (node.start, node.start + 1);
                let (da, db) = (
                    box_distance_squared(&self.nodes[a], p),
                    box_distance_squared(&self.nodes[b], p),
                );
                // Visit the nearer child first (pushed last).
                if da < db {
                    stack.extend([b, a]);
                } else {
                    stack.extend([a, b]);
                }
            }
        }
        (nearest, best.sqrt())
    }
}

/// The box of `count` triangles from `start` as a leaf node.
fn bounds(triangles: &[([[f64; 3]; 3], u32)], start: usize, count: usize) -> Node {
    let (mut low, mut high) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for (t, _) in &triangles[start..start + count] {
        for v in t {
            for k in 0..3 {
                low[k] = low[k].min(v[k]);
                high[k] = high[k].max(v[k]);
            }
        }
    }
    Node {
        low,
        high,
        start,
        count,
    }
}

fn box_distance_squared(node: &Node, p: [f64; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let d = (node.low[k] - p[k]).max(p[k] - node.high[k]).max(0.0);
            d * d
        })
        .sum()
}

/// Squared distance from `p` to triangle `t` (Ericson, Real-Time Collision Detection §5.1.5:
/// the Voronoi region of the nearest feature; degenerate triangles fall to an edge or vertex).
fn triangle_distance_squared(p: [f64; 3], t: &[[f64; 3]; 3]) -> f64 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let at = |q: [f64; 3]| {
        let d = sub(p, q);
        dot(d, d)
    };
    let along =
        |o: [f64; 3], e: [f64; 3], s: f64| [o[0] + s * e[0], o[1] + s * e[1], o[2] + s * e[2]];
    if d1 <= 0.0 && d2 <= 0.0 {
        return at(a);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return at(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return at(along(a, ab, d1 / (d1 - d3)));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return at(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return at(along(a, ac, d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return at(along(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denominator = va + vb + vc;
    if denominator.abs().partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        // Degenerate (zero-area) triangle: the nearest of its edges.
        return [(a, b), (b, c), (c, a)]
            .iter()
            .map(|&(u, v)| {
                let e = sub(v, u);
                let s = (dot(sub(p, u), e) / dot(e, e).max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
                at(along(u, e, s))
            })
            .fold(f64::INFINITY, f64::min);
    }
    let (v, w) = (vb / denominator, vc / denominator);
    at([0, 1, 2].map(|k| a[k] + ab[k] * v + ac[k] * w))
}

/// Two-sided distance between a surface and a reference mesh, relative to the reference's
/// bounding-box diagonal.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceDistance {
    /// RMS distance from the surface's vertices to the reference's triangles.
    pub rms_to_reference: f64,
    /// RMS distance from the reference's vertices to the surface's triangles.
    pub rms_to_surface: f64,
    /// RMS over both directions' samples together.
    pub rms: f64,
    /// Largest distance from a surface vertex to the reference.
    pub max_to_reference: f64,
    /// Largest distance from a reference vertex to the surface.
    pub max_to_surface: f64,
    /// The (vertex-sampled) Hausdorff distance: the larger of the two maxima.
    pub hausdorff: f64,
    /// The reference's bounding-box diagonal, the unit of every other field.
    pub diagonal: f64,
}

/// Measures `surface` against `reference` (see the module documentation).
///
/// # Errors
/// [`Error::InvalidInput`] for an invalid mesh or a reference with a zero diagonal.
pub fn surface_distance(surface: &Mesh, reference: &Mesh) -> Result<SurfaceDistance> {
    let to_reference = TriangleTree::new(reference)?;
    let to_surface = TriangleTree::new(surface)?;
    let diagonal = bounding_diagonal(reference);
    if !(diagonal > 0.0 && diagonal.is_finite()) {
        return Err(Error::invalid(
            "the reference mesh has a zero or non-finite bounding box",
        ));
    }
    let measure = |points: &[[f64; 3]], tree: &TriangleTree| -> Vec<f64> {
        points
            .par_iter()
            .map(|&p| tree.distance(p) / diagonal)
            .collect()
    };
    let forward = measure(&surface.positions, &to_reference);
    let backward = measure(&reference.positions, &to_surface);
    Ok(SurfaceDistance::of_samples(&forward, &backward, diagonal))
}

/// [`SurfaceDistance`] between the outer surfaces of a surface and a reference made of
/// overlapping parts (see [`outer_surface_distance`]).
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize)]
pub struct OuterDistance {
    /// The distance over what each outer surface shows.
    pub distance: SurfaceDistance,
    /// The share of the surface's vertices hidden inside it (not measured).
    pub hidden_surface: f64,
    /// The share of the reference's vertices hidden inside it (not measured).
    pub hidden_reference: f64,
    /// The voxel cell that decides what is hidden, relative to the diagonal: gaps narrower
    /// than it count as closed, points up to about 1.5 cells under the outer surface as on it.
    pub cell: f64,
}

/// Measures the outer surface of `surface` against the outer surface of `reference`: the
/// surface's vertices an observer outside can reach ([`OuterSurface`], cells of `cell` times
/// the reference's diagonal) to the reference's triangles whose corners are all reachable,
/// and the reference's reachable vertices to the surface's reachable triangles. Each is
/// taken apart from the other; the reference's holes are capped ([`cap_holes`], where their
/// outlines are simple loops) so that a part open where another covers it still encloses its
/// inside.
///
/// For shapes made of overlapping closed parts (the teapot's four surfaces), where the
/// surface inside the whole (a spout's root within the body, caps pressed on each other) is
/// no part of the shape.
///
/// # Errors
/// [`Error::InvalidInput`] for an invalid mesh, a reference with a zero diagonal, a `cell`
/// that makes the grid too fine, or a side with nothing outer to measure.
pub fn outer_surface_distance(
    surface: &Mesh,
    reference: &Mesh,
    cell: f64,
) -> Result<OuterDistance> {
    let diagonal = bounding_diagonal(reference);
    if !(diagonal > 0.0 && diagonal.is_finite()) {
        return Err(Error::invalid(
            "the reference mesh has a zero or non-finite bounding box",
        ));
    }
    // Where a hole's outline is not a simple loop, the reference stays open there: the
    // outside then reaches in, and more of the reference is measured, not less.
    let closed = cap_holes(reference).unwrap_or_else(|_| reference.clone());
    let outer = |mesh: &Mesh, walls: &Mesh| -> Result<(Vec<bool>, Mesh)> {
        let grid = OuterSurface::new(&[walls], cell * diagonal)?;
        let shown: Vec<bool> = mesh
            .positions
            .par_iter()
            .map(|&p| grid.is_outer(p))
            .collect();
        let triangles: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .filter(|t| t.iter().all(|&v| shown[v as usize]))
            .copied()
            .collect();
        if triangles.is_empty() {
            return Err(Error::invalid(
                "no triangle of the mesh is on its outer surface",
            ));
        }
        let outer_mesh = Mesh {
            positions: mesh.positions.clone(),
            triangles,
        };
        Ok((shown, outer_mesh))
    };
    let (surface_shown, surface_outer) = outer(surface, surface)?;
    let (reference_shown, reference_outer) = outer(reference, &closed)?;
    let to_reference = TriangleTree::new(&reference_outer)?;
    let to_surface = TriangleTree::new(&surface_outer)?;
    let measure = |points: &[[f64; 3]], shown: &[bool], tree: &TriangleTree| -> Vec<f64> {
        points
            .par_iter()
            .zip(shown)
            .filter(|(_, s)| **s)
            .map(|(&p, _)| tree.distance(p) / diagonal)
            .collect()
    };
    let forward = measure(&surface.positions, &surface_shown, &to_reference);
    let backward = measure(&reference.positions, &reference_shown, &to_surface);
    let hidden =
        |shown: &[bool]| shown.iter().filter(|s| !**s).count() as f64 / shown.len().max(1) as f64;
    Ok(OuterDistance {
        distance: SurfaceDistance::of_samples(&forward, &backward, diagonal),
        hidden_surface: hidden(&surface_shown),
        hidden_reference: hidden(&reference_shown),
        cell,
    })
}

impl SurfaceDistance {
    /// The summary of sampled distances, already divided by `diagonal`: `forward` from the
    /// surface to the reference, `backward` from the reference to the surface.
    pub fn of_samples(forward: &[f64], backward: &[f64], diagonal: f64) -> SurfaceDistance {
        let squares = |d: &[f64]| d.iter().map(|x| x * x).sum::<f64>();
        let rms = |d: &[f64]| (squares(d) / d.len().max(1) as f64).sqrt();
        let max = |d: &[f64]| d.iter().copied().fold(0.0, f64::max);
        SurfaceDistance {
            rms_to_reference: rms(forward),
            rms_to_surface: rms(backward),
            rms: ((squares(forward) + squares(backward))
                / (forward.len() + backward.len()).max(1) as f64)
                .sqrt(),
            max_to_reference: max(forward),
            max_to_surface: max(backward),
            hausdorff: max(forward).max(max(backward)),
            diagonal,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::icosphere;

    fn ball(r: f64, c: [f64; 3]) -> Mesh {
        let mut m = icosphere(4).unwrap();
        for p in &mut m.positions {
            *p = [0, 1, 2].map(|k| c[k] + r * p[k]);
        }
        m
    }

    fn join(a: &Mesh, b: &Mesh) -> Mesh {
        let mut m = a.clone();
        let offset = m.positions.len() as u32;
        m.positions.extend(&b.positions);
        m.triangles
            .extend(b.triangles.iter().map(|t| t.map(|v| v + offset)));
        m
    }

    /// Two overlapping balls against the same union made finer: what shows matches closely
    /// (the chordal error), while every surface together reaches into the other ball's inside
    /// only through the hidden parts, which the outer measure leaves out.
    #[test]
    fn the_outer_measure_leaves_out_what_the_union_hides() {
        let (a, b) = (ball(1.0, [0.0; 3]), ball(0.8, [1.2, 0.0, 0.0]));
        let surface = join(&a, &b);
        // The reference: the same balls, without the part of each inside the other.
        let outside = |m: &Mesh, c: [f64; 3], r: f64| Mesh {
            positions: m.positions.clone(),
            triangles: m
                .triangles
                .iter()
                .filter(|t| {
                    t.iter().any(|&v| {
                        let p = m.positions[v as usize];
                        (0..3).map(|k| (p[k] - c[k]).powi(2)).sum::<f64>().sqrt() > r
                    })
                })
                .copied()
                .collect(),
        };
        let reference = join(
            &outside(&a, [1.2, 0.0, 0.0], 0.8),
            &outside(&b, [0.0; 3], 1.0),
        );
        let outer = outer_surface_distance(&surface, &reference, 0.005).unwrap();
        assert!(outer.distance.hausdorff < 0.01, "{outer:?}");
        assert!(
            outer.hidden_surface > 0.05 && outer.hidden_surface < 0.3,
            "{outer:?}"
        );
        let all = surface_distance(&surface, &reference).unwrap();
        assert!(all.hausdorff > 0.1, "{all:?}");
    }
}

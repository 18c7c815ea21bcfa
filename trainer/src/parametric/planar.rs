//! Planar triangulations in the parameter domain, through `spade` (Delaunay and constrained
//! Delaunay triangulations with exact predicates). Used for the boundary of a parameter point
//! set, the Delaunay tessellation of §5.3, hole filling (§7.3) and direct triangulation (§7.1).

use spade::handles::FixedVertexHandle;
use spade::{ConstrainedDelaunayTriangulation, DelaunayTriangulation, Point2, Triangulation};

use crate::error::{Error, Result};

/// A triangulated region of the parameter plane; triangles are counter-clockwise.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct PlanarMesh {
    /// (u, v) of every vertex.
    pub vertices: Vec<[f64; 2]>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

fn point(p: [f64; 2]) -> Point2<f64> {
    Point2::new(p[0], p[1])
}

fn insertion_error(e: spade::InsertionError) -> Error {
    Error::invalid(format!(
        "the triangulation rejected a parameter point: {e:?}"
    ))
}

/// The Delaunay triangulation of `points` (the convex hull filled), counter-clockwise.
/// Coincident points keep the first index.
///
/// # Errors
/// [`Error::InvalidInput`] for non-finite or out-of-range coordinates, or fewer than three
/// non-collinear points.
pub fn delaunay(points: &[[f64; 2]]) -> Result<Vec<[u32; 3]>> {
    let mut dt = DelaunayTriangulation::<Point2<f64>>::new();
    let mut map: Vec<u32> = Vec::new();
    for (i, &p) in points.iter().enumerate() {
        let handle = dt.insert(point(p)).map_err(insertion_error)?;
        if handle.index() == map.len() {
            map.push(i as u32);
        }
    }
    let triangles: Vec<[u32; 3]> = dt
        .inner_faces()
        .map(|f| f.vertices().map(|v| map[v.fix().index()]))
        .collect();
    if triangles.is_empty() {
        return Err(Error::invalid(
            "the parameter points are collinear: no triangle can be formed",
        ));
    }
    Ok(triangles)
}

/// The constrained Delaunay triangulation of the closed polygon `boundary` (in order, either
/// orientation) and `interior` points inside it, keeping only triangles inside the polygon.
/// The result's vertices are `boundary` followed by `interior`, and every boundary edge is an
/// edge of the result.
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than 3 boundary points, non-finite coordinates, a
/// self-intersecting boundary, coincident points, or a boundary edge that did not survive
/// (an interior point on it).
pub fn triangulate_polygon(boundary: &[[f64; 2]], interior: &[[f64; 2]]) -> Result<PlanarMesh> {
    if boundary.len() < 3 {
        return Err(Error::invalid("a polygon needs at least 3 vertices"));
    }
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let all: Vec<[f64; 2]> = boundary.iter().chain(interior).copied().collect();
    let mut handles: Vec<FixedVertexHandle> = Vec::with_capacity(all.len());
    let mut map: Vec<u32> = Vec::new();
    for (i, &p) in all.iter().enumerate() {
        let handle = cdt.insert(point(p)).map_err(insertion_error)?;
        if handle.index() != map.len() {
            return Err(Error::invalid(format!(
                "parameter point {i} coincides with an earlier one"
            )));
        }
        map.push(i as u32);
        handles.push(handle);
    }
    let m = boundary.len();
    for i in 0..m {
        let (a, b) = (handles[i], handles[(i + 1) % m]);
        if !cdt.can_add_constraint(a, b) || cdt.try_add_constraint(a, b).is_empty() {
            return Err(Error::invalid(format!(
                "boundary edge {i} crosses another: the boundary loop intersects itself"
            )));
        }
    }
    let all_triangles: Vec<[u32; 3]> = cdt
        .inner_faces()
        .map(|f| f.vertices().map(|v| map[v.fix().index()]))
        .collect();
    let triangles = inside_by_parity(&all_triangles, m as u32);
    let uses = crate::geometry::mesh_graph::edge_uses(&triangles);
    for i in 0..m {
        let (a, b) = (i as u32, ((i + 1) % m) as u32);
        if uses.get(&(a.min(b), a.max(b))) != Some(&1) {
            return Err(Error::invalid(format!(
                "boundary edge {i} was split or lost: keep interior points off the boundary"
            )));
        }
    }
    Ok(PlanarMesh {
        vertices: all,
        triangles,
    })
}

/// The triangles inside the polygon whose vertices are 0 … m−1 in order: a flood fill from
/// the convex hull that flips sides whenever it crosses a polygon edge.
fn inside_by_parity(triangles: &[[u32; 3]], m: u32) -> Vec<[u32; 3]> {
    use std::collections::VecDeque;
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let is_constraint = |a: u32, b: u32| a < m && b < m && ((a + 1) % m == b || (b + 1) % m == a);
    let by_edge = crate::geometry::mesh_graph::edge_faces(triangles);
    let mut side: Vec<Option<bool>> = vec![None; triangles.len()];
    let mut queue = VecDeque::new();
    for (&(a, b), list) in &by_edge {
        if list.len() == 1 && side[list[0]].is_none() {
            let t = list[0];
            side[t] = Some(is_constraint(a, b));
            queue.push_back(t);
        }
    }
    while let Some(t) = queue.pop_front() {
        let inside = side[t].unwrap_or(false);
        let tri = triangles[t];
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            for &u in by_edge.get(&key(a, b)).map(Vec::as_slice).unwrap_or(&[]) {
                if u != t && side[u].is_none() {
                    side[u] = Some(inside != is_constraint(a, b));
                    queue.push_back(u);
                }
            }
        }
    }
    triangles
        .iter()
        .zip(&side)
        .filter(|(_, s)| **s == Some(true))
        .map(|(t, _)| *t)
        .collect()
}

/// Even–odd point-in-polygon test.
pub fn inside_polygon(p: [f64; 2], polygon: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = polygon.len();
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Distance from `p` to the closed polygon's edges.
pub fn distance_to_polygon(p: [f64; 2], polygon: &[[f64; 2]]) -> f64 {
    let n = polygon.len();
    (0..n)
        .map(|i| segment_distance(p, polygon[i], polygon[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    ((p[0] - a[0] - t * d[0]).powi(2) + (p[1] - a[1] - t * d[1]).powi(2)).sqrt()
}

/// Signed area of a closed polygon (positive when counter-clockwise).
pub fn signed_area(polygon: &[[f64; 2]]) -> f64 {
    let n = polygon.len();
    0.5 * (0..n)
        .map(|i| {
            let (a, b) = (polygon[i], polygon[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum::<f64>()
}

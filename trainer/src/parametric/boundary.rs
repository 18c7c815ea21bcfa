//! The outer boundary loop of a 2-D point set: the Delaunay triangulation carved from the
//! convex hull inwards (a χ-shape, Duckham et al. 2008), the "closed polyline that encloses
//! all of the points but with the smallest area" of §5.3 made concrete.
//!
//! Boundary edges longer than [`BoundaryOptions::carve_factor`] times the median Delaunay edge
//! are removed longest first, together with their triangle, as long as the triangle's third
//! vertex is not already on the boundary (so the region stays a topological disk and every
//! point stays inside or on it).

use std::collections::{BinaryHeap, HashMap};

use super::planar::{delaunay, signed_area};
use crate::error::{Error, Result};
use crate::geometry::mesh_graph::boundary_loops;

/// Boundary settings.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoundaryOptions {
    /// Carve boundary edges longer than this many median edge lengths (3).
    pub carve_factor: f64,
}

impl Default for BoundaryOptions {
    fn default() -> Self {
        BoundaryOptions { carve_factor: 3.0 }
    }
}

/// The boundary loop of `points` as indices, counter-clockwise.
///
/// # Errors
/// [`Error::InvalidInput`] when the points are collinear or coincide, or the carved region is
/// not a single disk.
pub fn boundary_loop(points: &[[f64; 2]], options: &BoundaryOptions) -> Result<Vec<u32>> {
    let triangles = delaunay(points)?;
    let len = |a: u32, b: u32| {
        let (p, q) = (points[a as usize], points[b as usize]);
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
    };
    let mut faces: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    let mut lengths = Vec::new();
    for (t, tri) in triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            let list = faces.entry((a.min(b), a.max(b))).or_default();
            if list.is_empty() {
                lengths.push(len(a, b));
            }
            list.push(t);
        }
    }
    lengths.sort_by(f64::total_cmp);
    let limit = options.carve_factor * lengths[lengths.len() / 2];
    let mut alive = vec![true; triangles.len()];
    let mut on_boundary = vec![false; points.len()];
    struct Edge(f64, u32, u32);
    impl PartialEq for Edge {
        fn eq(&self, other: &Self) -> bool {
            self.cmp(other) == std::cmp::Ordering::Equal
        }
    }
    impl Eq for Edge {}
    impl PartialOrd for Edge {
        fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(other))
        }
    }
    impl Ord for Edge {
        fn cmp(&self, other: &Self) -> std::cmp::Ordering {
            self.0
                .total_cmp(&other.0)
                .then((self.1, self.2).cmp(&(other.1, other.2)))
        }
    }
    let mut heap = BinaryHeap::new();
    for (&(a, b), list) in &faces {
        if list.len() == 1 {
            on_boundary[a as usize] = true;
            on_boundary[b as usize] = true;
            heap.push(Edge(len(a, b), a, b));
        }
    }
    while let Some(Edge(length, a, b)) = heap.pop() {
        if length <= limit {
            break;
        }
        let Some(list) = faces.get(&(a, b)) else {
            continue;
        };
        let live: Vec<usize> = list.iter().copied().filter(|&t| alive[t]).collect();
        if live.len() != 1 {
            continue;
        }
        let t = live[0];
        let Some(&c) = triangles[t].iter().find(|&&v| v != a && v != b) else {
            continue;
        };
        if on_boundary[c as usize] {
            continue;
        }
        alive[t] = false;
        on_boundary[c as usize] = true;
        for (p, q) in [(a, c), (b, c)] {
            heap.push(Edge(len(p, q), p.min(q), p.max(q)));
        }
    }
    let kept: Vec<[u32; 3]> = triangles
        .iter()
        .zip(&alive)
        .filter(|(_, a)| **a)
        .map(|(t, _)| *t)
        .collect();
    let mut loops = boundary_loops(&kept)?;
    if loops.len() != 1 {
        return Err(Error::invalid(format!(
            "the parameter points have {} boundary loops, not one",
            loops.len()
        )));
    }
    let mut cycle = loops.remove(0);
    let polygon: Vec<[f64; 2]> = cycle.iter().map(|&i| points[i as usize]).collect();
    if signed_area(&polygon) < 0.0 {
        cycle.reverse();
    }
    Ok(cycle)
}

/// `count` points at equal arc-length steps along the closed polygon, starting at its first
/// vertex.
pub fn resample_closed(polygon: &[[f64; 2]], count: usize) -> Vec<[f64; 2]> {
    let n = polygon.len();
    if n == 0 || count == 0 {
        return Vec::new();
    }
    let mut cumulative = vec![0.0];
    for i in 0..n {
        let (a, b) = (polygon[i], polygon[(i + 1) % n]);
        let l = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
        cumulative.push(cumulative[i] + l);
    }
    let total = cumulative[n];
    let mut out = Vec::with_capacity(count);
    let mut seg = 0;
    for k in 0..count {
        let s = total * k as f64 / count as f64;
        while seg + 1 < n && cumulative[seg + 1] <= s {
            seg += 1;
        }
        let l = cumulative[seg + 1] - cumulative[seg];
        let t = if l > 0.0 {
            (s - cumulative[seg]) / l
        } else {
            0.0
        };
        let (a, b) = (polygon[seg], polygon[(seg + 1) % n]);
        out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
    }
    out
}

//! Connectivity of triangle meshes: one-rings (the mesh variant of LLE, §4.2), edge use
//! counts, boundary loops, unused vertices and the watertightness test every stitched or
//! filled mesh must pass.

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::io::Mesh;

/// The one-ring neighbours of every vertex (vertices sharing an edge), sorted.
pub fn one_rings(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<Vec<usize>> {
    let mut rings = vec![Vec::new(); vertex_count];
    for t in triangles {
        for e in 0..3 {
            let (a, b) = (t[e] as usize, t[(e + 1) % 3] as usize);
            if a < vertex_count && b < vertex_count {
                rings[a].push(b);
                rings[b].push(a);
            }
        }
    }
    for r in rings.iter_mut() {
        r.sort_unstable();
        r.dedup();
    }
    rings
}

/// The triangles (indices) on each undirected edge (keys with the smaller index first).
pub fn edge_faces(triangles: &[[u32; 3]]) -> HashMap<(u32, u32), Vec<usize>> {
    let mut faces: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (t, triangle) in triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (triangle[e], triangle[(e + 1) % 3]);
            faces.entry((a.min(b), a.max(b))).or_default().push(t);
        }
    }
    faces
}

/// How many triangles use each undirected edge (keys with the smaller index first).
pub fn edge_uses(triangles: &[[u32; 3]]) -> HashMap<(u32, u32), usize> {
    let mut uses = HashMap::new();
    for t in triangles {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    uses
}

/// Edge statistics of a mesh: the watertightness test.
#[derive(Copy, Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct EdgeReport {
    /// Undirected edges.
    pub edges: usize,
    /// Edges used by exactly one triangle (holes, open boundaries).
    pub boundary: usize,
    /// Edges used by three or more triangles.
    pub non_manifold: usize,
    /// Directed edges used twice in the same direction (inconsistent orientation).
    pub misoriented: usize,
}

impl EdgeReport {
    /// Every edge shared by exactly two triangles, consistently oriented.
    pub fn is_watertight(&self) -> bool {
        self.boundary == 0 && self.non_manifold == 0 && self.misoriented == 0 && self.edges > 0
    }
}

/// Counts boundary, non-manifold and misoriented edges of `mesh`.
pub fn edge_report(mesh: &Mesh) -> EdgeReport {
    let uses = edge_uses(&mesh.triangles);
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &mesh.triangles {
        for e in 0..3 {
            *directed.entry((t[e], t[(e + 1) % 3])).or_insert(0) += 1;
        }
    }
    EdgeReport {
        edges: uses.len(),
        boundary: uses.values().filter(|&&u| u == 1).count(),
        non_manifold: uses.values().filter(|&&u| u > 2).count(),
        misoriented: directed.values().filter(|&&u| u > 1).count(),
    }
}

/// The boundary loops of a mesh: closed vertex cycles along edges used by one triangle, each
/// in the direction the triangles traverse them (so the mesh lies to the left).
///
/// # Errors
/// [`Error::InvalidInput`] when a boundary vertex has more than one outgoing boundary edge
/// (the boundary is not a set of simple loops).
pub fn boundary_loops(triangles: &[[u32; 3]]) -> Result<Vec<Vec<u32>>> {
    let uses = edge_uses(triangles);
    let mut next: HashMap<u32, u32> = HashMap::new();
    for t in triangles {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            if uses.get(&(a.min(b), a.max(b))) == Some(&1) && next.insert(a, b).is_some() {
                return Err(Error::invalid(format!(
                    "vertex {a} has two outgoing boundary edges: the boundary is not simple"
                )));
            }
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut loops = Vec::new();
    for s in starts {
        if seen.contains(&s) {
            continue;
        }
        let mut cycle = vec![s];
        seen.insert(s);
        let mut v = s;
        loop {
            let Some(&w) = next.get(&v) else {
                return Err(Error::invalid(format!(
                    "the boundary through vertex {v} is open"
                )));
            };
            if w == s {
                break;
            }
            if !seen.insert(w) {
                return Err(Error::invalid(format!(
                    "the boundary revisits vertex {w}: not a simple loop"
                )));
            }
            cycle.push(w);
            v = w;
        }
        loops.push(cycle);
    }
    Ok(loops)
}

/// Removes the vertices no triangle uses (scans often keep them), renumbering the rest in
/// order. Returns the mesh and how many were removed.
pub fn drop_unused_vertices(mesh: &Mesh) -> (Mesh, usize) {
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            if let Some(u) = used.get_mut(v as usize) {
                *u = true;
            }
        }
    }
    let mut index = vec![u32::MAX; mesh.positions.len()];
    let mut positions = Vec::with_capacity(mesh.positions.len());
    for (v, &p) in mesh.positions.iter().enumerate() {
        if used[v] {
            index[v] = positions.len() as u32;
            positions.push(p);
        }
    }
    let removed = mesh.positions.len() - positions.len();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| index.get(v as usize).copied().unwrap_or(u32::MAX)))
        .collect();
    (
        Mesh {
            positions,
            triangles,
        },
        removed,
    )
}

/// The angle between the normals of the two triangles on each edge two triangles share
/// (radians, 0 where the surface is flat across the edge, π where it folds back).
pub fn dihedral_angles(mesh: &Mesh) -> Vec<f64> {
    use crate::geometry::vector::{cross, dot, norm, sub};
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        let length = norm(n);
        if length > 0.0 {
            n.map(|x| x / length)
        } else {
            [0.0; 3]
        }
    };
    edge_faces(&mesh.triangles)
        .values()
        .filter(|f| f.len() == 2)
        .map(|f| {
            let (n, m) = (normal(&mesh.triangles[f[0]]), normal(&mesh.triangles[f[1]]));
            dot(n, m).clamp(-1.0, 1.0).acos()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles on the edge (1, 0, 0)–(0, 1, 0), the second with its free corner at `d`.
    fn hinge(d: [f64; 3]) -> Vec<f64> {
        dihedral_angles(&Mesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], d],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        })
    }

    #[test]
    fn dihedral_angles_are_zero_across_a_flat_edge_and_a_right_angle_across_an_upright_one() {
        let flat = hinge([1.0, 1.0, 0.0]);
        assert!(flat.len() == 1 && flat[0].abs() < 1e-12, "{flat:?}");
        // Upright on the edge: its normal is (1, 1, 0)/√2, square to the first's (0, 0, 1).
        let upright = hinge([0.5, 0.5, 1.0]);
        assert!(
            upright.len() == 1 && (upright[0] - std::f64::consts::FRAC_PI_2).abs() < 1e-12,
            "{upright:?}"
        );
    }
}

//! Mesh topology for parameterizing meshes onto the sphere or the torus: welding coincident
//! vertices, splitting into edge-connected parts, boundary loops, capping holes, and the check
//! that a mesh is a closed oriented surface of genus 0.

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::io::Mesh;

/// Merges vertices whose coordinates round to the same multiple of `tolerance` (exact
/// duplicates always merge; near duplicates straddling a rounding boundary may not), drops
/// triangles that collapse, and keeps the first position of every merged group. Returns the
/// welded mesh and, for every old vertex, its new index.
///
/// # Errors
/// [`Error::InvalidInput`] for a non-positive or non-finite tolerance or an invalid mesh.
pub fn weld(mesh: &Mesh, tolerance: f64) -> Result<(Mesh, Vec<u32>)> {
    if !(tolerance > 0.0 && tolerance.is_finite()) {
        return Err(Error::invalid(format!(
            "the weld tolerance must be positive, got {tolerance}"
        )));
    }
    let mesh = mesh.clone().validated()?;
    let mut cells: HashMap<[i64; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let remap: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = p.map(|c| (c / tolerance).round() as i64);
            *cells.entry(key).or_insert_with(|| {
                positions.push(*p);
                (positions.len() - 1) as u32
            })
        })
        .collect();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| remap[v as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    Ok((
        Mesh {
            positions,
            triangles,
        },
        remap,
    ))
}

/// The parts of `mesh` whose triangles connect through shared edges (a single shared vertex
/// does not join two parts), each with its own vertex numbering, largest part first.
pub fn edge_components(mesh: &Mesh) -> Vec<Mesh> {
    let mut parent: Vec<usize> = (0..mesh.triangles.len()).collect();
    fn root(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    let mut first_on_edge: HashMap<(u32, u32), usize> = HashMap::new();
    for (i, t) in mesh.triangles.iter().enumerate() {
        for (a, b) in edges(t) {
            let j = *first_on_edge.entry((a.min(b), a.max(b))).or_insert(i);
            let (ra, rb) = (root(&mut parent, i), root(&mut parent, j));
            parent[ra] = rb;
        }
    }
    let mut groups: HashMap<usize, Vec<usize>> = HashMap::new();
    for i in 0..mesh.triangles.len() {
        groups.entry(root(&mut parent, i)).or_default().push(i);
    }
    let mut parts: Vec<Mesh> = groups
        .into_values()
        .map(|triangles| {
            let mut index: HashMap<u32, u32> = HashMap::new();
            let mut positions = Vec::new();
            let triangles = triangles
                .iter()
                .map(|&i| {
                    mesh.triangles[i].map(|v| {
                        *index.entry(v).or_insert_with(|| {
                            positions.push(mesh.positions[v as usize]);
                            (positions.len() - 1) as u32
                        })
                    })
                })
                .collect();
            Mesh {
                positions,
                triangles,
            }
        })
        .collect();
    parts.sort_by_key(|p| std::cmp::Reverse(p.triangles.len()));
    parts
}

/// The three directed edges of a triangle.
pub(crate) fn edges(t: &[u32; 3]) -> [(u32, u32); 3] {
    [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
}

/// Every directed edge once and its triangle, checking the mesh is an oriented 2-manifold
/// with boundary: no directed edge twice (a non-manifold edge or inconsistent winding).
fn directed_edges(mesh: &Mesh) -> Result<HashMap<(u32, u32), usize>> {
    let mut directed = HashMap::with_capacity(3 * mesh.triangles.len());
    for (i, t) in mesh.triangles.iter().enumerate() {
        for edge in edges(t) {
            if directed.insert(edge, i).is_some() {
                return Err(Error::invalid(format!(
                    "edge {edge:?} is used twice in the same direction (triangle {i}): the mesh \
                     is not an oriented manifold"
                )));
            }
        }
    }
    Ok(directed)
}

/// The boundary loops of an oriented manifold mesh, each as vertices in the order of its
/// triangles' edges (so the loop runs counter-clockwise around the surface it bounds): the
/// shared [`crate::geometry::boundary_loops`], after checking the mesh is an oriented manifold.
///
/// # Errors
/// [`Error::InvalidInput`] for a non-manifold or inconsistently wound mesh, or a boundary
/// vertex where two loops touch.
pub fn oriented_boundary_loops(mesh: &Mesh) -> Result<Vec<Vec<u32>>> {
    directed_edges(mesh)?;
    crate::geometry::boundary_loops(&mesh.triangles)
}

/// Closes every boundary loop with a fan around a new vertex at the loop's centroid (wound to
/// match the surface). The original vertices keep their indices; the caps' vertices follow.
///
/// # Errors
/// As [`oriented_boundary_loops`].
pub fn cap_holes(mesh: &Mesh) -> Result<Mesh> {
    let loops = oriented_boundary_loops(mesh)?;
    let mut capped = mesh.clone();
    for chain in loops {
        let mut centre = [0.0; 3];
        for &v in &chain {
            for k in 0..3 {
                centre[k] += mesh.positions[v as usize][k] / chain.len() as f64;
            }
        }
        capped.positions.push(centre);
        let c = (capped.positions.len() - 1) as u32;
        for (i, &a) in chain.iter().enumerate() {
            let b = chain[(i + 1) % chain.len()];
            // The surface has a → b, so the cap has b → a.
            capped.triangles.push([b, a, c]);
        }
    }
    Ok(capped)
}

/// Checks that `mesh` is a closed, connected, consistently wound surface of genus 0
/// (every edge shared by exactly two triangles in opposite directions, V − E + F = 2).
///
/// # Errors
/// [`Error::InvalidInput`] naming what fails: an invalid mesh, a boundary edge, a
/// non-manifold or inconsistently wound edge, several parts, or the genus.
pub fn check_sphere_topology(mesh: &Mesh) -> Result<()> {
    let mesh = mesh.clone().validated()?;
    let directed = directed_edges(&mesh)?;
    if let Some(&(a, b)) = directed
        .keys()
        .find(|&&(a, b)| !directed.contains_key(&(b, a)))
    {
        return Err(Error::invalid(format!(
            "edge ({a}, {b}) (vertex numbers from 0) is on a boundary: the mesh is not \
             closed; a Cao En fit needs a closed surface without holes"
        )));
    }
    let parts = edge_components(&mesh).len();
    if parts != 1 {
        return Err(Error::invalid(format!(
            "the mesh has {parts} parts, expected one"
        )));
    }
    let used = {
        let mut used = vec![false; mesh.positions.len()];
        for t in &mesh.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        used.iter().filter(|&&u| u).count()
    };
    let euler = used as i64 - (directed.len() / 2) as i64 + mesh.triangles.len() as i64;
    if euler != 2 || used != mesh.positions.len() {
        return Err(Error::invalid(format!(
            "the mesh has Euler characteristic {euler} and {} unused vertices: not a sphere \
             (genus {})",
            mesh.positions.len() - used,
            (2 - euler) / 2
        )));
    }
    Ok(())
}

/// The vertices adjacent to each vertex (each once).
pub(crate) fn neighbours(mesh: &Mesh) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); mesh.positions.len()];
    for t in &mesh.triangles {
        for (a, b) in edges(t) {
            for (x, y) in [(a, b), (b, a)] {
                let list: &mut Vec<u32> = &mut out[x as usize];
                if !list.contains(&y) {
                    list.push(y);
                }
            }
        }
    }
    out
}

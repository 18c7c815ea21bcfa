//! Mesh topology for parameterizing meshes onto the sphere or the torus: welding coincident
//! vertices, splitting into edge-connected parts, boundary loops, capping holes, and the check
//! that a mesh is a closed oriented surface of genus 0.

use std::collections::HashMap;

use crate::error::{Error, Result};
use crate::geometry::mesh_graph::drop_unused_vertices;
use crate::io::Mesh;
use crate::parametric::{
    PlanarMesh, SymmetricMatrix, distance_to_polygon, inside_polygon, triangulate_polygon,
};

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
/// match the surface). The original vertices keep their indices; the caps' vertices follow,
/// one per loop.
///
/// # Errors
/// As [`oriented_boundary_loops`].
pub fn cap_holes(mesh: &Mesh) -> Result<Mesh> {
    let loops = oriented_boundary_loops(mesh)?;
    let mut capped = mesh.clone();
    for chain in loops {
        fan_cap(&mut capped, &chain);
    }
    Ok(capped)
}

/// Closes every boundary loop, wound to match the surface, with caps as fine as the scan.
/// The original vertices keep their indices; the caps' vertices follow.
///
/// A loop whose projection onto its best-fitting plane is a simple polygon gets a planar cap:
/// a constrained Delaunay triangulation of the polygon with interior points on a grid of the
/// loop's mean edge length, lifted as a membrane (each interior vertex at the mean of its
/// neighbours, the loop fixed), so the cap follows the rim without the slivers and the long
/// spokes of a fan. Any other loop (its projection crosses itself, or the cap would join two
/// rim vertices the surface already joins) gets the fan of [`cap_holes`].
///
/// # Errors
/// As [`oriented_boundary_loops`], and a failed membrane solve.
pub fn cap_holes_planar(mesh: &Mesh) -> Result<Mesh> {
    let loops = oriented_boundary_loops(mesh)?;
    let mut capped = mesh.clone();
    let existing: std::collections::HashSet<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(edges)
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    for chain in loops {
        if !planar_cap(&mut capped, &chain, &existing)? {
            fan_cap(&mut capped, &chain);
        }
    }
    Ok(capped)
}

/// A fan around a new vertex at the loop's centroid.
fn fan_cap(capped: &mut Mesh, chain: &[u32]) {
    let mut centre = [0.0; 3];
    for &v in chain {
        for k in 0..3 {
            centre[k] += capped.positions[v as usize][k] / chain.len() as f64;
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

/// The planar cap of [`cap_holes`]; `false` (nothing added) when the loop's projection is not
/// a simple polygon, or when the cap would join two rim vertices the surface already joins
/// (an edge of four triangles).
fn planar_cap(
    capped: &mut Mesh,
    chain: &[u32],
    existing: &std::collections::HashSet<(u32, u32)>,
) -> Result<bool> {
    let rim: Vec<[f64; 3]> = chain
        .iter()
        .map(|&v| capped.positions[v as usize])
        .collect();
    let Some((origin, axes)) = best_plane(&rim) else {
        return Ok(false);
    };
    let project = |p: [f64; 3]| {
        let d = [0, 1, 2].map(|k| p[k] - origin[k]);
        axes.map(|a| a[0] * d[0] + a[1] * d[1] + a[2] * d[2])
    };
    let polygon: Vec<[f64; 2]> = rim.iter().map(|&p| project(p)).collect();
    let m = polygon.len();
    let spacing = (0..m)
        .map(|i| planar_distance(polygon[i], polygon[(i + 1) % m]))
        .sum::<f64>()
        / m as f64;
    if !(spacing > 0.0 && spacing.is_finite()) {
        return Ok(false);
    }
    let interior = grid_inside(&polygon, spacing);
    let Ok(planar) = triangulate_polygon(&polygon, &interior) else {
        return Ok(false);
    };
    // Vertex i < m is chain[i]; the rest are new.
    let first = capped.positions.len() as u32;
    let index = |i: u32| {
        if (i as usize) < m {
            chain[i as usize]
        } else {
            first + i - m as u32
        }
    };
    let joins_existing = planar.triangles.iter().flat_map(edges).any(|(a, b)| {
        let (a, b) = (index(a), index(b));
        existing.contains(&(a.min(b), a.max(b)))
            && !(0..m).any(|i| {
                let (p, q) = (chain[i], chain[(i + 1) % m]);
                (p, q) == (a, b) || (q, p) == (a, b)
            })
    });
    if joins_existing {
        return Ok(false);
    }
    // The surface has chain[0] → chain[1]; the cap must have it the other way.
    let forward = planar
        .triangles
        .iter()
        .any(|t| (0..3).any(|e| t[e] == 0 && t[(e + 1) % 3] == 1));
    let membrane = membrane(&planar, &rim)?;
    capped.positions.extend_from_slice(&membrane[m..]);
    for t in &planar.triangles {
        let t = t.map(index);
        capped
            .triangles
            .push(if forward { [t[0], t[2], t[1]] } else { t });
    }
    Ok(true)
}

/// The centroid and two orthonormal axes of the plane that best fits `points` (the two
/// largest principal directions), or `None` for fewer than 3 points or a degenerate spread.
fn best_plane(points: &[[f64; 3]]) -> Option<([f64; 3], [[f64; 3]; 2])> {
    if points.len() < 3 {
        return None;
    }
    let count = points.len() as f64;
    let centre = points
        .iter()
        .fold([0.0; 3], |c, p| [0, 1, 2].map(|k| c[k] + p[k] / count));
    let mut covariance = nalgebra::Matrix3::<f64>::zeros();
    for p in points {
        let d = nalgebra::Vector3::from([0, 1, 2].map(|k| p[k] - centre[k]));
        covariance += d * d.transpose();
    }
    let eigen = covariance.symmetric_eigen();
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| eigen.eigenvalues[b].total_cmp(&eigen.eigenvalues[a]));
    if eigen.eigenvalues[order[1]].partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let axis = |i: usize| {
        let c = eigen.eigenvectors.column(order[i]);
        [c[0], c[1], c[2]]
    };
    Some((centre, [axis(0), axis(1)]))
}

/// Points of a square grid of `spacing` inside `polygon`, at least half a spacing from its
/// edges.
fn grid_inside(polygon: &[[f64; 2]], spacing: f64) -> Vec<[f64; 2]> {
    let (mut low, mut high) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in polygon {
        for k in 0..2 {
            low[k] = low[k].min(p[k]);
            high[k] = high[k].max(p[k]);
        }
    }
    let steps = [0, 1].map(|k| ((high[k] - low[k]) / spacing).floor() as usize);
    let mut points = Vec::new();
    for i in 1..steps[0].max(1) {
        for j in 1..steps[1].max(1) {
            let p = [low[0] + i as f64 * spacing, low[1] + j as f64 * spacing];
            if inside_polygon(p, polygon) && distance_to_polygon(p, polygon) > 0.5 * spacing {
                points.push(p);
            }
        }
    }
    points
}

fn planar_distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// 3-D positions for a planar cap: the rim fixed, every interior vertex at the mean of its
/// neighbours (a uniform-weight membrane spanning the rim).
fn membrane(planar: &PlanarMesh, rim: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
    let m = rim.len();
    let n = planar.vertices.len();
    let mut positions: Vec<[f64; 3]> = rim.to_vec();
    positions.resize(n, [0.0; 3]);
    if n == m {
        return Ok(positions);
    }
    let mut matrix = SymmetricMatrix::new(n - m);
    let mut rhs = vec![vec![0.0; n - m]; 3];
    let mut seen = std::collections::HashSet::new();
    for t in &planar.triangles {
        for (a, b) in edges(t) {
            if !seen.insert((a.min(b), a.max(b))) {
                continue;
            }
            for (i, j) in [(a as usize, b as usize), (b as usize, a as usize)] {
                if i < m {
                    continue;
                }
                matrix.add(i - m, i - m, 1.0);
                if j < m {
                    for k in 0..3 {
                        rhs[k][i - m] += rim[j][k];
                    }
                } else {
                    matrix.add(i - m, j - m, -1.0);
                }
            }
        }
    }
    matrix.compress()?.cholesky()?.solve(&mut rhs);
    for (i, p) in positions.iter_mut().enumerate().skip(m) {
        *p = [rhs[0][i - m], rhs[1][i - m], rhs[2][i - m]];
    }
    Ok(positions)
}

/// What [`close_for_sphere`] changed.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Closing {
    /// Vertices no triangle used, removed.
    pub unused_vertices: usize,
    /// The boundary edges of every hole capped, largest first.
    pub holes: Vec<usize>,
}

/// Prepares a scan for a sphere map: removes unused vertices and caps every hole
/// ([`cap_holes_planar`]), then checks what is left is a closed genus-0 surface.
///
/// # Errors
/// As [`check_sphere_topology`] after the repair: a non-manifold or inconsistently wound
/// mesh, several parts, or another genus (named).
pub fn close_for_sphere(mesh: &Mesh) -> Result<(Mesh, Closing)> {
    let mesh = mesh.clone().validated()?;
    let (mesh, unused_vertices) = drop_unused_vertices(&mesh);
    let mut holes: Vec<usize> = oriented_boundary_loops(&mesh)?
        .iter()
        .map(Vec::len)
        .collect();
    holes.sort_unstable_by(|a, b| b.cmp(a));
    let closed = if holes.is_empty() {
        mesh
    } else {
        cap_holes_planar(&mesh)?
    };
    check_sphere_topology(&closed)?;
    Ok((
        closed,
        Closing {
            unused_vertices,
            holes,
        },
    ))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::icosphere;

    /// The unit icosphere with every triangle whose centroid lies within `angle` of one of
    /// `directions` removed.
    fn punched(directions: &[[f64; 3]], angle: f64) -> Mesh {
        let mut mesh = icosphere(4).unwrap();
        mesh.triangles.retain(|t| {
            let c = [0, 1, 2].map(|k| {
                t.iter()
                    .map(|&v| mesh.positions[v as usize][k])
                    .sum::<f64>()
            });
            let r = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            directions
                .iter()
                .all(|d| (c[0] * d[0] + c[1] * d[1] + c[2] * d[2]) / r < angle.cos())
        });
        mesh
    }

    /// Two round holes get fine planar caps (not fans): the closed mesh is a sphere again, its
    /// cap vertices lie on the holes' flat disks, and no cap edge is longer than twice the
    /// longest edge of the scan (a fan's spokes would be six times as long).
    #[test]
    fn planar_caps_close_holes_with_triangles_like_the_scan() {
        let mesh = punched(&[[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]], 0.5);
        let longest = mesh
            .triangles
            .iter()
            .flat_map(edges)
            .map(|(a, b)| {
                let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
            })
            .fold(0.0, f64::max);
        let (closed, closing) = close_for_sphere(&mesh).unwrap();
        assert_eq!(closing.holes.len(), 2);
        // The vertices inside the punched disks are no longer used.
        let (kept, unused) = drop_unused_vertices(&mesh);
        assert!(unused > 0);
        assert_eq!(closing.unused_vertices, unused);
        let added = closed.positions.len() - kept.positions.len();
        assert!(
            added > 20,
            "{added} cap vertices: expected fine caps, not fans"
        );
        for p in &closed.positions[kept.positions.len()..] {
            let height = p[2].max(p[0]);
            assert!(
                (height - 0.5f64.cos()).abs() < 0.03,
                "{p:?} is off the hole's disk"
            );
        }
        for t in &closed.triangles[kept.triangles.len()..] {
            for (a, b) in edges(t) {
                let (p, q) = (closed.positions[a as usize], closed.positions[b as usize]);
                let length = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
                assert!(length <= 2.0 * longest, "cap edge {length} > 2 × {longest}");
            }
        }
        // A one-triangle hole is closed by that triangle; the fan keeps one vertex per hole.
        let mut one = icosphere(2).unwrap();
        one.triangles.pop();
        let (closed, _) = close_for_sphere(&one).unwrap();
        assert_eq!(closed.positions.len(), one.positions.len());
        assert_eq!(
            cap_holes(&kept).unwrap().positions.len(),
            kept.positions.len() + 2
        );
    }

    /// Unused vertices are dropped and counted; another genus is refused by name.
    #[test]
    fn closing_drops_unused_vertices_and_refuses_other_genera() {
        let mut mesh = icosphere(1).unwrap();
        mesh.positions.insert(0, [5.0, 5.0, 5.0]);
        for t in &mut mesh.triangles {
            *t = t.map(|v| v + 1);
        }
        let (closed, closing) = close_for_sphere(&mesh).unwrap();
        assert_eq!(closing.unused_vertices, 1);
        assert_eq!(closed.positions.len(), mesh.positions.len() - 1);
        let grid = crate::caoen::torus_grid(12, 6).unwrap();
        let torus = Mesh {
            positions: grid
                .sources
                .iter()
                .map(|s| {
                    let r = 1.0 + 0.3 * s[2];
                    [r * s[0], r * s[1], 0.3 * s[3]]
                })
                .collect(),
            triangles: grid.triangles.clone(),
        };
        let error = close_for_sphere(&torus).unwrap_err().to_string();
        assert!(error.contains("genus 1"), "{error}");
    }
}

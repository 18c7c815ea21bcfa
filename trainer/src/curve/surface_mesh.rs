//! Triangle meshes of B-spline surfaces.

use crate::error::{Error, Result};
use crate::io::Mesh;

use super::spline::BSplineSurface;
use crate::geometry::vector::{add, cross, norm, sub};

/// Most vertices of a surface mesh.
pub const MAX_MESH_VERTICES: usize = 16_000_000;

/// A tessellated surface: the mesh (write it with [`crate::io::write_mesh`]) and one unit
/// normal per vertex.
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceMesh {
    /// Vertices S(i/resolution_u, j/resolution_v) and two triangles per parameter cell,
    /// wound so that (b − a) × (c − a) points along ∂S/∂u × ∂S/∂v.
    pub mesh: Mesh,
    /// The surface normal at every vertex; where ∂S/∂u × ∂S/∂v vanishes, the normalized sum
    /// of the adjacent triangles' normals (or +z if that vanishes too).
    pub normals: Vec<[f64; 3]>,
}

/// Tessellates `surface` on a `resolution_u × resolution_v` grid of parameter cells. Closed
/// directions share their seam vertices. Cost: one evaluation per vertex.
///
/// # Errors
/// [`Error::InvalidInput`] for an invalid surface ([`BSplineSurface::validate`]), a zero
/// resolution (fewer than 3 cells along a closed direction), or more than
/// [`MAX_MESH_VERTICES`] vertices.
pub fn surface_mesh(
    surface: &BSplineSurface,
    resolution_u: usize,
    resolution_v: usize,
) -> Result<SurfaceMesh> {
    surface.validate()?;
    if resolution_u == 0 || resolution_v == 0 {
        return Err(Error::invalid(format!(
            "a surface mesh needs at least one cell per direction, got {resolution_u} × \
             {resolution_v}"
        )));
    }
    if (surface.closed_u && resolution_u < 3) || (surface.closed_v && resolution_v < 3) {
        return Err(Error::invalid(format!(
            "a closed surface direction needs at least 3 mesh cells, got {resolution_u} × \
             {resolution_v}"
        )));
    }
    let columns = if surface.closed_u {
        resolution_u
    } else {
        resolution_u + 1
    };
    let rows = if surface.closed_v {
        resolution_v
    } else {
        resolution_v + 1
    };
    if columns.saturating_mul(rows) > MAX_MESH_VERTICES {
        return Err(Error::invalid(format!(
            "a {resolution_u} × {resolution_v} surface mesh exceeds {MAX_MESH_VERTICES} vertices"
        )));
    }
    let mut positions = Vec::with_capacity(columns * rows);
    let mut normals = Vec::with_capacity(columns * rows);
    for j in 0..rows {
        let v = j as f64 / resolution_v as f64;
        for i in 0..columns {
            let u = i as f64 / resolution_u as f64;
            positions.push(surface.point(u, v));
            normals.push(surface.normal(u, v));
        }
    }
    let index = |i: usize, j: usize| ((j % rows) * columns + (i % columns)) as u32;
    let mut triangles = Vec::with_capacity(2 * resolution_u * resolution_v);
    for j in 0..resolution_v {
        for i in 0..resolution_u {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    // Fallback normals from the triangles around degenerate vertices.
    let mut summed = vec![[0.0; 3]; positions.len()];
    if normals.iter().any(Option::is_none) {
        for t in &triangles {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let face = cross(sub(b, a), sub(c, a));
            for &v in t {
                summed[v as usize] = add(summed[v as usize], face);
            }
        }
    }
    let normals = normals
        .into_iter()
        .zip(&summed)
        .map(|(n, &s)| {
            n.unwrap_or_else(|| {
                let length = norm(s);
                if length > 0.0 && length.is_finite() {
                    s.map(|c| c / length)
                } else {
                    [0.0, 0.0, 1.0]
                }
            })
        })
        .collect();
    Ok(SurfaceMesh {
        mesh: Mesh {
            positions,
            triangles,
        },
        normals,
    })
}

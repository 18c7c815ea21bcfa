//! Polygon meshes of Cao En surfaces (paper §10.2): a subdivided sphere (icosphere) or a torus
//! grid of source points, each mapped through the network.

use std::collections::HashMap;

use super::network::CaoEnNetwork;
use crate::error::{Error, Result};
use crate::geometry::vector::{cross, inner, sub};
use crate::io::Mesh;

/// Most subdivisions of the icosahedron (level 8: 655 362 vertices).
pub const MAX_SUBDIVISIONS: usize = 8;

/// A mapped mesh: the surface mesh, the source point of every vertex (for texture
/// coordinates or re-evaluation), and the exact normal of every vertex where defined.
#[derive(Clone, Debug, PartialEq)]
pub struct CaoEnMesh {
    /// Vertices y(x), triangles wound as on the source (outward for a sphere).
    pub mesh: Mesh,
    /// The source point of each vertex.
    pub sources: Vec<Vec<f64>>,
    /// The unit normal per vertex (the mesh's own area-weighted normal where the network's
    /// vanishes).
    pub normals: Vec<[f64; 3]>,
}

/// Source points and the triangles between them, before mapping.
#[derive(Clone, Debug, PartialEq)]
pub struct SourceGrid {
    /// The source points (m coordinates each).
    pub sources: Vec<Vec<f64>>,
    /// Triangles as indices into `sources`.
    pub triangles: Vec<[u32; 3]>,
}

/// The unit icosphere: the icosahedron with each triangle split into four `subdivisions`
/// times, midpoints pushed onto the sphere (10·4ˢ + 2 vertices, outward winding).
///
/// # Errors
/// [`Error::InvalidInput`] beyond [`MAX_SUBDIVISIONS`].
pub fn icosphere(subdivisions: usize) -> Result<Mesh> {
    if subdivisions > MAX_SUBDIVISIONS {
        return Err(Error::invalid(format!(
            "at most {MAX_SUBDIVISIONS} subdivisions, got {subdivisions}"
        )));
    }
    let t = (1.0 + 5.0_f64.sqrt()) / 2.0;
    let raw = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ];
    let mut positions: Vec<[f64; 3]> = raw.iter().map(|&p| unit(p)).collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<[f64; 3]>| -> u32 {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (p, q) = (positions[a as usize], positions[b as usize]);
                positions.push(unit([0, 1, 2].map(|k| p[k] + q[k])));
                (positions.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    Ok(Mesh {
        positions,
        triangles,
    })
}

/// A `around × across` grid on the torus: source points (cos θ, sin θ, cos φ, sin φ), two
/// triangles per cell, wound so that ∂θ × ∂φ is their normal (outward for the standard torus).
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than 3 cells in a direction.
pub fn torus_grid(around: usize, across: usize) -> Result<SourceGrid> {
    if around < 3 || across < 3 || around.saturating_mul(across) > 1 << 22 {
        return Err(Error::invalid(format!(
            "a torus grid needs 3 to 4 Mi cells per direction product, got {around} × {across}"
        )));
    }
    let mut sources = Vec::with_capacity(around * across);
    for i in 0..around {
        for j in 0..across {
            let theta = std::f64::consts::TAU * i as f64 / around as f64;
            let phi = std::f64::consts::TAU * j as f64 / across as f64;
            sources.push(vec![theta.cos(), theta.sin(), phi.cos(), phi.sin()]);
        }
    }
    let index = |i: usize, j: usize| ((i % around) * across + j % across) as u32;
    let mut triangles = Vec::with_capacity(2 * around * across);
    for i in 0..around {
        for j in 0..across {
            let (a, b, c, d) = (
                index(i, j),
                index(i + 1, j),
                index(i + 1, j + 1),
                index(i, j + 1),
            );
            triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    Ok(SourceGrid { sources, triangles })
}

/// Maps source points and triangles through `network` (p ≥ 3: the first three outputs).
///
/// # Errors
/// [`Error::InvalidInput`] for an invalid network, p < 3, or source points of the wrong
/// dimension.
pub fn map_mesh(
    network: &CaoEnNetwork,
    sources: Vec<Vec<f64>>,
    triangles: Vec<[u32; 3]>,
) -> Result<CaoEnMesh> {
    network.validate()?;
    let m = network.source_dimension();
    if network.target_dimension() < 3 || sources.iter().any(|x| x.len() != m) {
        return Err(Error::invalid(format!(
            "a mesh needs a network with p ≥ 3 and source points of dimension {m}"
        )));
    }
    let positions: Vec<[f64; 3]> = sources
        .iter()
        .map(|x| {
            let y = network.position(x);
            [y[0], y[1], y[2]]
        })
        .collect();
    let mut fallback = vec![[0.0; 3]; positions.len()];
    for t in &triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let n = cross(sub(b, a), sub(c, a));
        for &v in t {
            for k in 0..3 {
                fallback[v as usize][k] += n[k];
            }
        }
    }
    // A shape with extra outputs (shading) has the normal of its first three.
    let shape = super::texture::position_part(network);
    let normals = sources
        .iter()
        .zip(fallback)
        .map(|(x, f)| shape.normal(x).unwrap_or_else(|| unit_or_z(f)))
        .collect();
    Ok(CaoEnMesh {
        mesh: Mesh {
            positions,
            triangles,
        },
        sources,
        normals,
    })
}

/// The icosphere of `subdivisions` mapped through a sphere network (m = 3).
///
/// # Errors
/// As [`icosphere`] and [`map_mesh`].
pub fn sphere_mesh(network: &CaoEnNetwork, subdivisions: usize) -> Result<CaoEnMesh> {
    let sphere = icosphere(subdivisions)?;
    let sources = sphere.positions.iter().map(|p| p.to_vec()).collect();
    map_mesh(network, sources, sphere.triangles)
}

/// The torus grid mapped through a torus network (m = 4).
///
/// # Errors
/// As [`torus_grid`] and [`map_mesh`].
pub fn torus_mesh(network: &CaoEnNetwork, around: usize, across: usize) -> Result<CaoEnMesh> {
    let grid = torus_grid(around, across)?;
    map_mesh(network, grid.sources, grid.triangles)
}

fn unit(p: [f64; 3]) -> [f64; 3] {
    let r = inner(&p, &p).sqrt();
    p.map(|c| c / r)
}

fn unit_or_z(p: [f64; 3]) -> [f64; 3] {
    if inner(&p, &p) > 0.0 {
        unit(p)
    } else {
        [0.0, 0.0, 1.0]
    }
}

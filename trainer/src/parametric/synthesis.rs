//! Surface synthesis (§5.4): the tessellation's vertices through the network; the mesh keeps
//! the tessellation's topology, and the network's analytic normals come along.

use super::network::SurfaceNetwork;
use super::planar::PlanarMesh;
use crate::io::Mesh;

/// A synthesized surface.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthesizedSurface {
    /// The 3-D mesh (triangles as in the tessellation).
    pub mesh: Mesh,
    /// Unit normals ∂p/∂u × ∂p/∂v, one per vertex (oriented like the tessellation's
    /// counter-clockwise triangles).
    pub normals: Vec<[f64; 3]>,
}

/// Maps every tessellation vertex through `network`.
pub fn synthesize(network: &SurfaceNetwork, tessellation: &PlanarMesh) -> SynthesizedSurface {
    let mut positions = Vec::with_capacity(tessellation.vertices.len());
    let mut normals = Vec::with_capacity(tessellation.vertices.len());
    for &[u, v] in &tessellation.vertices {
        let point = network.evaluate(u, v);
        positions.push(point.position);
        normals.push(point.normal());
    }
    SynthesizedSurface {
        mesh: Mesh {
            positions,
            triangles: tessellation.triangles.clone(),
        },
        normals,
    }
}

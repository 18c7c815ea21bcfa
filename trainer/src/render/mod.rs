//! Seeing implicit models (Carcenac §6–7): ray casting to PNG and mesh extraction.
//!
//! - [`Field`]: what is rendered — the core in `f32` ([`CoreField`]: what a microcontroller
//!   computes, and the fastest on the host), the `f64` network with interval bounds
//!   ([`NetworkField`]), the RBF baseline in `f64` ([`RbfField`]), or an analytic sphere
//!   ([`SphereField`]);
//! - [`Region`]: the leaf modules' inflated normalization boxes, where the surface is assumed
//!   to lie (§6, Fig. 5);
//! - [`Camera`] and [`View`]: a pinhole camera and an orbit around the scene;
//! - [`Octree`]: voxels meeting the boxes (the paper's) or whose interval bound of Φ contains 0
//!   (guaranteed);
//! - [`punctual`]: the paper's Newton search in each voxel's bounding sphere;
//!   [`guaranteed`]: interval bounds of Φ and Φ′ along the ray ([`interval`]) that never miss a
//!   sign change;
//! - [`render`]: anti-aliased, Lambert/Phong-shaded, tiles in parallel; [`compare_methods`]:
//!   missed pixels and times of both searches against dense sampling;
//! - [`extract_mesh`]: marching tetrahedra restricted to the boxes, watertight, normals from
//!   ∇Φ.

mod camera;
mod compare;
mod field;
pub mod guaranteed;
pub mod interval;
mod mesh;
mod octree;
pub mod punctual;
mod raycast;
mod region;
mod shade;

pub use camera::{Camera, MAX_SIDE, View};
pub use compare::{MAX_DENSE_SAMPLES, MethodComparison, compare_methods, dense_hit};
pub use field::{
    CoreField, DEFAULT_BOX_SIZE, DEFAULT_INFLATE, DEFAULT_RBF_INFLATE, Field, NetworkField,
    Q16Field, RbfField, SphereField,
};
pub use interval::Interval;
pub use mesh::{BLOCK, ExtractedMesh, MAX_RESOLUTION, MeshGrid, MeshStats, extract_mesh};
pub use octree::{MAX_DEPTH, Octree, PROBE_GRID, PROBE_REACH};
pub use raycast::{
    EDGE_COSINE, EDGE_DEPTH, MAX_SAMPLES, Method, RenderOptions, RenderStats, Rendered, TILE,
    Tracer, hit_map, render, write_png,
};
pub use region::{Aabb, Region, bounds_of, ray_spans};
pub use shade::{Shading, to_srgb8};

#[cfg(test)]
mod tests;

//! Geometry every family shares: small vector helpers on `[f64; 3]`, mesh bounds and the
//! connectivity of triangle meshes (one-rings, edge uses, boundary loops, unused vertices, the
//! watertightness test).

pub mod bounds;
pub mod mesh_graph;
pub mod outer_surface;
pub mod vector;

pub use bounds::{bounding_diagonal, point_bounds};
pub use mesh_graph::{
    EdgeReport, boundary_loops, drop_unused_vertices, edge_report, edge_uses, one_rings,
};
pub use outer_surface::OuterSurface;

//! Cao En surfaces (Wyvill, Cao & Trotman 1992) on the host, in f64: the network and its
//! reference evaluation (`network`), construction from key/target points and least-squares
//! fitting of V and of q per key point (`fit`), blob conversion (`blob`, keys ordered for
//! the core's group skipping under compact blending by `groups`), and polygon meshes
//! from an icosphere or a torus grid (`mesh`). Fitting to a genus-0 mesh:
//! `topology` (welding, parts, capping holes), `spherical` (a planar Tutte embedding lifted
//! to the sphere, balanced by stretch reweighting), `mesh_fit` (keys, least squares against every vertex, the error
//! table), `distance` (two-sided surface-to-mesh distance). Pictures: `render` (depth buffer
//! through the projection network) and `raymarch` (the convex implicit form in the core).
//! Applications: `morph` (metamorphosis with empty key points), `distort` (S³ → ℝ³),
//! `teapot` (four sphere surfaces, measured by what shows), `image` (compression on S⁴), `texture`
//! (texture coordinates from the source sphere, the cosine law folded into extra outputs). The core evaluates what this writes
//! (`neurosurf_core::caoen`).
//!
//! ```
//! use neurosurf_trainer::caoen::{fit_shape, from_key_points, sphere_mesh, to_blob};
//! use neurosurf_core::caoen::{Blending, Domain};
//! use neurosurf_core::scalar::ScalarKind;
//! // Six key points on the axes, an elongated target for each: a rounded spindle.
//! let keys: Vec<Vec<f64>> = (0..6).map(|i| {
//!     let mut k = vec![0.0; 3];
//!     k[i / 2] = if i % 2 == 0 { 1.0 } else { -1.0 };
//!     k
//! }).collect();
//! let targets: Vec<Vec<f64>> = keys.iter().map(|k| vec![k[0], k[1], 2.0 * k[2]]).collect();
//! let built = from_key_points(Domain::Sphere, Blending::Exponential, false, &keys, &targets, 4.0)?;
//! let fitted = fit_shape(&built, &keys, &targets)?; // now y(wᵢ) = tᵢ exactly
//! let y = fitted.position(&keys[4]);
//! assert!((y[2] - 2.0).abs() < 1e-9);
//! let mesh = sphere_mesh(&fitted, 2)?;
//! assert_eq!(mesh.mesh.vertex_count(), 162);
//! let blob = to_blob(&fitted, ScalarKind::Q16_16, b"spindle")?;
//! assert!(neurosurf_core::caoen::CaoEnModel::<f32>::from_blob(&blob).is_ok());
//! # Ok::<(), neurosurf_trainer::Error>(())
//! ```

mod blob;
mod capacity;
mod distance;
mod distort;
mod fit;
mod groups;
pub mod image;
mod mesh;
mod mesh_fit;
mod morph;
mod network;
mod normals;
mod perspective;
mod raymarch;
mod render;
mod spherical;
mod teapot;
mod texture;
mod topology;

pub use crate::geometry::bounding_diagonal;
pub use crate::geometry::mesh_graph::drop_unused_vertices;
pub use blob::{DecodedCaoEn, from_blob, to_blob};
pub use capacity::check_key_count;
pub use distance::{
    OuterDistance, SurfaceDistance, TriangleTree, outer_surface_distance, surface_distance,
};
pub use distort::Distortion;
pub use fit::{
    AUTO_SHARPNESS, AUTO_SPACING, BetweenKeys, between_keys, cube_directions, fit_auto, fit_shape,
    fit_sharpness, from_key_points, leave_one_out, rms_error,
};
pub use groups::order_for_groups;
pub use image::{
    CompressedImage, ImageCodec, ImageOptions, MAX_ITERATIONS, MAX_PIXELS, compress_image,
    edge_test_image, least_bytes, psnr, smooth_test_image, thumbnail,
};
pub use mesh::{
    CaoEnMesh, MAX_SUBDIVISIONS, SourceGrid, icosphere, map_mesh, sphere_mesh, torus_grid,
    torus_mesh,
};
pub use mesh_fit::{
    FitRow, KeyPlacement, MeshFit, MeshFitOptions, farthest_points, fit_error_table,
    fit_parameterized, sixfold_points,
};
pub use morph::{MAX_FRAMES, Morph, morph_meshes};
pub use network::{CaoEnNetwork, Evaluation, on_domain};
pub use normals::{NormalFit, approximate_normals};
pub use perspective::{PerspectiveCamera, PerspectiveFit, perspective_network};
pub use raymarch::{
    ConvexSolid, Csg, convex_implicit, framing as ray_march_framing, ray_marched_image,
};
pub use render::{MAX_SAMPLE_GAP, Rendering, View, depth_buffer_image};
pub use spherical::{SphericalMap, flipped_triangles, spherical_parameterization};
pub use teapot::{TEAPOT_CELL, TEAPOT_KEYS, Teapot, TeapotLayout, TeapotPart, fit_teapot};
pub use texture::{
    LIGHTING_CHECK_SUBDIVISIONS, LightingFit, cosine_law, fold_lighting, mesh_texture,
    position_part, texture_coordinates,
};
pub use topology::{
    Closing, cap_holes, cap_holes_planar, check_sphere_topology, close_for_sphere, edge_components,
    oriented_boundary_loops, weld,
};

#[cfg(test)]
mod support;
#[cfg(test)]
mod tests;

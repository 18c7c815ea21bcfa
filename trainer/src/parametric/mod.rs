//! Parametric surfaces from unstructured points (Yumer & Kara 2012): a locally linear
//! embedding flattens the points to (u, v), a small multilayer network learns (u, v) → (x, y,
//! z), and a grid in the parameter plane pushed through the network is the surface.
//!
//! The pipeline, one file per step:
//!
//! 1. **Embedding** (§4, `embedding`): k nearest neighbours from a `kiddo` k-d tree
//!    (`neighbors`, which also rejects duplicate and collinear input), reconstruction weights
//!    with a regularized local Gram matrix (`weights`), the sparse M = (I − W)ᵀ(I − W) and its
//!    2nd and 3rd smallest eigenvectors by shift-and-invert subspace iteration on a `faer`
//!    sparse Cholesky (`eigen`, `sparse`); [`embed_mesh`] uses mesh one-rings instead (§4.2).
//!    `folds` rejects embeddings that fold or collapse; `quality` scores one against a known
//!    parameterization. A patch whose sampling density changes is unrolled instead
//!    (`unrolling`: Isomap smoothed by the LLE matrix), since LLE squeezes its sparse part.
//! 2. **Regression** (§5.1–5.2): [`SurfaceNetwork`] (`network`: the exact forward formula, the
//!    `f64` reference with ∂p/∂u, ∂p/∂v and the normal) with the four activations
//!    (`activation`); the stratified 85/10/5 split (`split`); Levenberg–Marquardt with early
//!    stopping (`train`); the topology search (`topology`); [`fit_network`] (`fit`) ties them.
//! 3. **Tessellation** (§5.3): the boundary loop of the parameter points (`boundary`, a carved
//!    Delaunay triangulation), the Coons quad grid between four stretches of it (`coons`) or the
//!    resampled loop filled with grid points and triangulated by constrained Delaunay (`grid`,
//!    `planar` on `spade`). **Synthesis** (§5.4, `synthesis`): the grid through the network.
//!    [`reconstruct`] (`pipeline`) runs 1–3.
//!
//! 4. **Blobs** (`blob`): [`network_to_blob`] / [`network_from_blob`] — the network as the
//!    core's `parametric::SurfaceNetworkModel` evaluates it, in `f32` or Q16.16, on the host
//!    and on the microcontroller.
//! 5. **Several patches** (§6): [`find_seams`] (`seams`) finds where patch boundaries meet,
//!    along whole loops or stretches of them, and [`stitch`] (`stitch`) welds them by a
//!    cotangent-Laplacian least squares; `hole` fills holes. [`reconstruct_closed`]
//!    (`closed`) cuts a closed mesh into disc patches, fits each and stitches them watertight.
//!
//! `samples` makes test surfaces with known parameters.
//!
//! Crates: `kiddo` (k-d tree, k-NN), `faer` (sparse Cholesky with AMD ordering; no dense n × n
//! matrix is ever formed), `spade` (Delaunay and constrained Delaunay with exact predicates).
//!
//! ```
//! use neurosurf_trainer::parametric::{
//!     ReconstructOptions, SampleSurface, reconstruct, sample_surface,
//! };
//! let sample = sample_surface(SampleSurface::Wavy, 400, 0.0, 3)?;
//! let result = reconstruct(&sample.points, &ReconstructOptions::default())?;
//! assert_eq!(result.surface.mesh.vertex_count(), 30 * 30);
//! assert!(result.fit.relative_rms_error < 0.02);
//! # Ok::<(), neurosurf_trainer::Error>(())
//! ```

mod activation;
mod bench;
mod blob;
mod boundary;
mod capacity;
mod closed;
mod cloud_mesh;
mod compare;
mod coons;
mod crease_fill;
mod eigen;
mod embedding;
mod fairing;
mod fit;
mod fit_outliers;
mod folds;
mod grid;
mod growth;
mod hole;
mod laplacian;
mod neighbors;
mod network;
mod normal;
mod outliers;
mod packed;
mod patch_compare;
mod picture;
mod pipeline;
mod planar;
mod quality;
mod robust;
mod samples;
mod seams;
mod sparse;
mod split;
mod stitch;
mod synthesis;
mod thin_plate;
mod topology;
mod train;
mod tutte;
mod unrolling;
mod weights;

pub use crate::geometry::mesh_graph::{
    EdgeReport, boundary_loops, edge_report, edge_uses, one_rings,
};
pub use activation::Activation;
pub use bench::{
    BACK_SEED, BENCHMARK_SIZES, BenchmarkRow, PATCH_VERTICES, back_patch_points, benchmark,
};
pub use blob::{
    DecodedNetwork, MAX_REGION_VERTICES, NetworkSummary, network_from_blob, network_to_blob,
    parameter_region,
};
pub use boundary::{BoundaryOptions, boundary_loop, resample_closed};
pub use capacity::{check_capacity, largest_parameter_count};
pub use closed::{
    ClosedOptions, ClosedPatch, ClosedReconstruction, FIT_SAMPLES, MAX_NORMAL_CONE, MAX_PATCHES,
    NORMAL_PENALTY, NORMAL_SHARE, SeamCurve, reconstruct_closed,
};
pub use cloud_mesh::{
    CloudMesh, DEBRIS_SHARE, DISTANCE_NEIGHBORS, FAR_REACH, FLAT_NOISE, FLAT_SPREAD,
    MAX_CLOUD_RESOLUTION, MAX_NEIGHBORS, NOISE_BANDWIDTH, NORMAL_NEIGHBORS, WINDING_POINTS,
    mesh_closed_cloud, reconstruct_closed_points,
};
pub use compare::{ComparisonRow, compare_methods, dihedral_variance};
pub use coons::{
    CoonsBoundary, SIDE_SMOOTHING_ROUNDS, UNTANGLE_ROUNDS, WINSLOW_MIN_ROUNDS, coons_boundary,
    coons_boundary_of_polygon, coons_grid, folded_triangles, polyline_point,
};
pub use eigen::{Eigenpairs, MAX_EIGEN_ITERATIONS, smallest_nonconstant};
pub use embedding::{
    Embedding, LleOptions, OTHER_NEIGHBORS, Parameterization, embed_mesh, embed_points,
    embed_with_neighbors,
};
pub use fairing::{FAIRING_ROUNDS, fair_new_vertices};
pub use fit::{MIN_FIT_POINTS, SurfaceFit, fit_network};
pub use folds::{
    COLLAPSE_RATIO, FoldReport, MAX_COLLAPSE_FRACTION, MAX_FLIP_FRACTION, check_flat, fold_report,
};
pub use grid::{delaunay_grid, fill_polygon, grid_inside};
pub use hole::{
    FillDeviation, HoleFill, HoleOptions, fill_deviation, fill_hole, point_triangle_distance,
    punch_hole,
};
pub use laplacian::cotangent_laplacian;
pub use neighbors::{DUPLICATE_TOLERANCE, LINE_TOLERANCE, check_points, nearest_neighbors};
pub use network::{Layer, SurfaceNetwork, SurfacePoint, unit_cross};
pub use outliers::{OutlierOptions, Outliers, PLANES_ASKED, find_outliers};
pub use packed::{LaneRecord, PackedNetwork};
pub use patch_compare::{PatchCompareOptions, PatchComparison, PatchMethodRow, compare_patch};
pub use picture::wireframe;
pub use pipeline::{ReconstructOptions, Reconstruction, Tessellation, reconstruct};
pub use planar::{
    PlanarMesh, delaunay, distance_to_polygon, inside_polygon, signed_area, triangulate_polygon,
};
pub use quality::{align_affine, distance_correlation, neighborhood_preservation, pearson};
pub use robust::{RobustFit, fit_robustly};
pub use samples::{SampleSurface, SurfaceSample, sample_surface};
pub use seams::{MAX_SEAM_GAP, PARALLEL, SNAP, WHOLE_LOOP_SHARE, boundary_seam, find_seams};
pub use sparse::{Cholesky, CompressedMatrix, SymmetricMatrix};
pub use split::{Split, stratified_split};
pub use stitch::{
    ANCHOR_WEIGHT, CONSTRAINT_WEIGHT, Seam, Stitched, face_outward, orient_consistently,
    signed_volume, stitch,
};
pub use synthesis::{SynthesizedSurface, synthesize};
pub use topology::{Candidate, TopologyOptions, TopologySearch};
pub use train::{Samples, TrainReport, TrainSettings, mean_square, randomize, train};
pub use tutte::tutte_disk;
pub(crate) use tutte::weighted_means;
pub use unrolling::{
    SMOOTHING_ANCHOR, UNEVEN_AREA_SHARE, UNROLL_LANDMARKS, local_spacing, sparse_area_share,
    unrolled_parameters,
};
pub use weights::{embedding_matrix, reconstruction_weights};

#[cfg(test)]
mod test_meshes;
#[cfg(test)]
mod tests;

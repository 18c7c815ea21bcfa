//! Free-form curves through scattered points (Hoffmann & Várady): a Kohonen chain orders the
//! points, then standard B-spline approximation and interpolation apply.
//!
//! The pipeline, one file per step:
//!
//! 1. [`CurvePoints`] (`points`): validated 2-D or 3-D scattered points.
//! 2. [`train_chain`] (`kohonen`): a 1-D Kohonen chain of m = 4n neurons, open or a ring,
//!    with the paper's two convergence tests ([`Convergence`], `convergence`).
//! 3. [`order_points`] (`ordering`): each point to its winner neuron, sorted along the chain;
//!    then, an addition to the paper, [`refine_order`] (`refine`, `tour`) repairs the few
//!    arm-to-arm jumps a chain can keep on a spiral by 2-opt and stretch insertion.
//! 4. [`approximate`] / [`interpolate`] (`fit`): uniform cubic [`BSplineCurve`]s (`spline`,
//!    the representation the core evaluates) through the ordered points.
//! 5. [`fit_surface`] (`surface`): the paper's planned extension — a 2-D Kohonen map over
//!    3-D points parametrizes them for a [`BSplineSurface`], meshed by [`surface_mesh`].
//!
//! [`reconstruct_curve`] (`pipeline`) runs steps 1–4; [`sample_curve`] makes scored test data,
//! [`adjacency_fraction`] and [`hausdorff_distance`] score a result, `plot` draws it as SVG or PNG,
//! and [`benchmark`] times the pipeline.
//!
//! ```
//! use neurosurf_trainer::curve::{
//!     CurveOptions, SampleCurve, SampleOptions, adjacency_fraction, reconstruct_curve,
//!     sample_curve,
//! };
//! let options = SampleOptions { count: 40, ..SampleOptions::default() };
//! let sample = sample_curve(SampleCurve::Ellipse, &options)?;
//! let points = sample.curve_points()?;
//! let topology = SampleCurve::Ellipse.topology();
//! let result = reconstruct_curve(&points, &CurveOptions::new(topology, 7))?;
//! let adjacency = adjacency_fraction(&result.ordering.order, &sample.parameters, true)?;
//! assert!(adjacency >= 0.95);
//! # Ok::<(), neurosurf_trainer::Error>(())
//! ```

mod basis;
mod bench;
mod blob;
mod bridge;
mod convergence;
mod corners;
mod dxf;
mod export;
mod fit;
mod grid;
mod grid_map;
mod groups;
mod iges;
mod kohonen;
mod least_squares;
mod metrics;
mod noise;
mod ordering;
mod path_graph;
mod pipeline;
mod plot;
mod points;
mod principal;
mod refine;
mod samples;
mod schedule;
mod skeleton;
mod som;
mod spline;
mod surface;
mod surface_boundary;
mod surface_extent;
mod surface_fit;
mod surface_interpolate;
mod surface_mesh;
mod surface_stray;
mod surface_tube;
mod tour;
mod tridiagonal;

pub use basis::{cubic_basis, cubic_basis_derivative, locate};
pub use bench::{BENCHMARK_SIZES, BenchmarkRow, benchmark};
pub use blob::{
    DecodedCurve, DecodedSurface, FitSummary, curve_from_blob, curve_to_blob, surface_from_blob,
    surface_to_blob,
};
pub use convergence::Convergence;
pub use corners::{ARM_STRAIGHTNESS, CORNER_ANGLE, MAX_CORNER_ANGLE, find_corners};
pub use dxf::curves_dxf;
pub use export::{
    CurveExport, DEGREE, SurfaceExport, bezier_segments, clamped, curve_svg, export_curve,
    export_surface,
};
pub use fit::{
    Approximation, ApproximationOptions, DENSITY_WINDOW, Ends, approximate, check_curve_capacity,
    chord_length_parameters, control_range, default_control_points, density_parameters,
    interpolate, interpolation_parameter,
};
pub use grid_map::{KohonenMap, KohonenMapOptions, MapReport, train_map, train_map_from};
pub use groups::{GROUP_NEIGHBOURS, GROUP_REACH, point_groups};
pub use iges::iges;
pub use kohonen::{
    KohonenChain, KohonenOptions, MAX_NEURONS, Topology, TrainingReport, train_chain,
};
pub use metrics::{
    adjacency_fraction, directed_distance, distance_to_polyline, hausdorff_distance,
};
pub use noise::BandReport;
pub use ordering::{LongSteps, Ordering, order_points};
pub(crate) use path_graph::list_both_ways;
pub use pipeline::{CurveOptions, CurveReconstruction, reconstruct_curve};
pub use plot::{PlotLayers, PlotOptions, Projection, plot_scene, render_svg, write_plot};
pub use points::{CurvePoints, DUPLICATE_TOLERANCE, MAX_POINTS, MIN_POINTS};
pub use refine::{RefineOptions, RefineReport, refine_order};
pub use samples::{CurveSample, SampleCurve, SampleOptions, TRUTH_VERTICES, sample_curve};
pub use spline::{BSplineCurve, BSplineSurface, MIN_CONTROL_POINTS, check_degree};
pub use surface::{
    INTERPOLATION_SWING, InterpolationReport, SETTLING_RADIUS, SETTLING_RATE, SurfaceFit,
    SurfaceOptions, TUBE_AROUND, TUBE_MIDDLE, TUBE_PREFERENCE, TUBE_SETTLING, TUBE_STRAY,
    TubeCheck, TubeMode, control_grid_surface, fit_surface, fit_unrolled_surface, map_parameters,
    shaped_grid,
};
pub use surface_boundary::{
    BOUNDARY_GAP, BOUNDARY_NEIGHBOURS, CLOSED_BELOW, boundaries, largest_boundary,
};
pub(crate) use surface_extent::unroll_graph;
pub use surface_extent::{
    EXTENT_LANDMARKS, EXTENT_NEIGHBOURS, EXTENT_SAMPLE, Unrolled, patch_aspect, unroll,
};
pub use surface_fit::{
    MAX_SURFACE_CONTROL_POINTS, fit_surface_of_degree, fit_surface_to_parameters,
};
pub use surface_interpolate::{
    CONTROL_PER_POINT, INTERPOLATION_ROUNDS, INTERPOLATION_TOLERANCE, SWING_CELLS,
    SurfaceInterpolation, interpolate_surface, interpolation_grid, swing,
};
pub use surface_mesh::{MAX_MESH_VERTICES, SurfaceMesh, surface_mesh};
pub use surface_stray::{SPACING_RANK, STRAY_SAMPLES, stray_distance};
pub use surface_tube::{TUBE_GAP, TUBE_NEIGHBOURS, TUBE_SLICES, tube_parameters};

#[cfg(test)]
mod tests;

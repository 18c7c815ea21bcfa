//! The comparison of §7.1 on any patch, with no known surface: the network against thin-plate
//! RBF fits and direct Delaunay triangulation, all in the same LLE parameter plane.
//!
//! A seeded fraction of the points is held out; every method is fitted on the rest. Each is
//! then measured both ways:
//! - **held-out → mesh**: the distance of each held-out point to the method's mesh (how well
//!   the surface passes through data it did not see, and covers it: a held-out point beyond
//!   the tessellated region counts its distance to the region's border);
//! - **mesh → reference**: the distance of the mesh's vertices and triangle centroids to the
//!   reference: a truth mesh when one is given. Otherwise the data's local planes: from a
//!   sample, the nearest input point's plane (fitted to its [`PLANE_NEIGHBORS`] nearest), plus
//!   how far the sample lies beyond that point's neighbourhood along the plane. Point spacing
//!   does not count, and flaps and overshoots away from the data do.
//!
//! plus the variance of the dihedral angles (radians², lower is smoother) and the time.
//! Distances are fractions of the points' bounding-box diagonal.
//!
//! The methods:
//! - `network`: the §5.2 topology search, tessellated as a Coons grid of the parameter region;
//! - `rbf-low`: a g × g grid of thin-plate centres over the parameter box, least squares, x, y
//!   and z each a spline of (u, v), on the network's Coons grid;
//! - `rbf-high`: one centre per point (interpolating), or past a cap an interpolated even
//!   subsample, on the same grid;
//! - `delaunay`: the Delaunay triangulation of the training points' parameters.

use std::time::Instant;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rand::SeedableRng;
use rand::seq::SliceRandom;

use super::boundary::BoundaryOptions;
use super::compare::dihedral_variance;
use super::coons::{coons_boundary, coons_grid};
use super::embedding::{LleOptions, embed_points};
use super::fit::fit_network;
use super::neighbors::nearest_neighbors;
use super::outliers::Plane;
use super::planar::{PlanarMesh, delaunay};
use super::synthesis::synthesize;
use super::thin_plate::{Centers, ThinPlate};
use super::topology::TopologyOptions;
use crate::caoen::TriangleTree;
use crate::error::{Error, Result};
use crate::geometry::vector::{bounds, distance, dot, sub};
use crate::io::Mesh;

/// Settings of [`compare_patch`].
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize)]
pub struct PatchCompareOptions {
    /// Fraction of the points held out of every fit (0.1; more than 0, at most 0.5).
    pub held_out: f64,
    /// Seed of the held-out choice (and of the network, through `topology`).
    pub seed: u64,
    /// Embedding of the training points.
    pub embedding: LleOptions,
    /// The network's topology search.
    pub topology: TopologyOptions,
    /// Boundary of the parameter points.
    pub boundary: BoundaryOptions,
    /// Coons grid vertices per side (30).
    pub resolution: usize,
    /// `rbf-low` centres per side (5: the paper's few centres).
    pub rbf_grid: usize,
    /// Most `rbf-high` centres (1 500): a dense solve grows with their cube.
    pub rbf_max_centers: usize,
}

impl Default for PatchCompareOptions {
    fn default() -> Self {
        PatchCompareOptions {
            held_out: 0.1,
            seed: 1,
            embedding: LleOptions {
                more_neighbors: true,
                ..LleOptions::default()
            },
            topology: TopologyOptions::default(),
            boundary: BoundaryOptions::default(),
            resolution: 30,
            rbf_grid: 5,
            rbf_max_centers: 1_500,
        }
    }
}

/// One method, measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PatchMethodRow {
    /// `network`, `rbf-low`, `rbf-high` or `delaunay`.
    pub method: &'static str,
    /// Its size: hidden layers, centres or triangles.
    pub size: String,
    /// RMS distance of the held-out points to the mesh (fraction of the diagonal).
    pub held_out_rms: f64,
    /// Largest such distance.
    pub held_out_max: f64,
    /// RMS distance of the mesh's vertices and centroids to the reference.
    pub mesh_rms: f64,
    /// Largest such distance.
    pub mesh_max: f64,
    /// Variance of the dihedral angles (radians²).
    pub dihedral_variance: f64,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Wall time of the fit and its mesh (s; the shared embedding not included).
    pub seconds: f64,
}

/// What [`compare_patch`] measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PatchComparison {
    /// Points given.
    pub points: usize,
    /// Points every method was fitted to.
    pub training: usize,
    /// Points held out.
    pub held_out: usize,
    /// Bounding-box diagonal of the points (distances are fractions of it).
    pub diagonal: f64,
    /// Neighbours per point k of the shared embedding.
    pub neighbors: usize,
    /// Wall time of the shared embedding and boundary (s).
    pub embedding_seconds: f64,
    /// `truth mesh` or `local planes of the input points`: what mesh → reference distances
    /// are measured to.
    pub reference: &'static str,
    /// One row per method.
    pub rows: Vec<PatchMethodRow>,
}

/// Runs the four methods on `points` (an open patch) and measures them; with `truth`, the
/// mesh → reference distances go to that mesh.
///
/// # Errors
/// [`Error::InvalidInput`] for a held-out fraction outside (0, 0.5], a resolution below 2, an
/// `rbf_grid` below 2, too few points, an invalid truth mesh, and every error of the
/// embedding, the fit and the tessellation.
pub fn compare_patch(
    points: &[[f64; 3]],
    truth: Option<&Mesh>,
    options: &PatchCompareOptions,
) -> Result<PatchComparison> {
    check_options(options)?;
    let (training, held_out) = split_points(points, options.held_out, options.seed)?;
    let (lo, hi) = bounds(points);
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    if diagonal.is_nan() || diagonal <= 0.0 {
        return Err(Error::invalid(
            "the points have no extent: they are all the same point",
        ));
    }
    let reference = Reference::new(points, truth, diagonal)?;

    let start = Instant::now();
    let embedding = embed_points(&training, &options.embedding)?;
    let parameters = &embedding.parameters;
    let grid = coons_grid(
        &coons_boundary(parameters, &options.boundary)?,
        options.resolution,
        options.resolution,
    )?;
    let embedding_seconds = start.elapsed().as_secs_f64();

    let measure = |method, size: String, mesh: &Mesh, seconds| -> Result<PatchMethodRow> {
        let tree = TriangleTree::new(mesh)?;
        let held: Vec<f64> = held_out.iter().map(|&p| tree.distance(p)).collect();
        let samples = mesh_samples(mesh);
        let back: Vec<f64> = samples.iter().map(|&p| reference.distance(p)).collect();
        let (held_out_rms, held_out_max) = rms_max(&held, diagonal);
        let (mesh_rms, mesh_max) = rms_max(&back, diagonal);
        Ok(PatchMethodRow {
            method,
            size,
            held_out_rms,
            held_out_max,
            mesh_rms,
            mesh_max,
            dihedral_variance: dihedral_variance(mesh),
            vertices: mesh.positions.len(),
            seconds,
        })
    };
    let mut rows = Vec::new();

    let start = Instant::now();
    let topology = TopologyOptions {
        seed: options.seed,
        ..options.topology
    };
    let fit = fit_network(&training, parameters, &topology)?;
    let surface = synthesize(&fit.network, &grid);
    let hidden = fit.network.hidden_sizes();
    rows.push(measure(
        "network",
        format!("hidden {hidden:?}"),
        &surface.mesh,
        start.elapsed().as_secs_f64(),
    )?);

    for (method, centers) in [
        ("rbf-low", Centers::Grid(options.rbf_grid)),
        ("rbf-high", Centers::Points(options.rbf_max_centers)),
    ] {
        let start = Instant::now();
        let spline = ThinPlate::<3>::fit(parameters, &training, centers)?;
        let mesh = grid_through(&grid, |uv| spline.value(uv));
        let size = format!("{} centres", spline.center_count());
        rows.push(measure(method, size, &mesh, start.elapsed().as_secs_f64())?);
    }

    let start = Instant::now();
    let mesh = Mesh {
        positions: training.clone(),
        triangles: delaunay(parameters)?,
    };
    let size = format!("{} triangles", mesh.triangles.len());
    rows.push(measure(
        "delaunay",
        size,
        &mesh,
        start.elapsed().as_secs_f64(),
    )?);

    Ok(PatchComparison {
        points: points.len(),
        training: training.len(),
        held_out: held_out.len(),
        diagonal,
        neighbors: embedding.neighbors,
        embedding_seconds,
        reference: reference.name(),
        rows,
    })
}

fn check_options(options: &PatchCompareOptions) -> Result<()> {
    if options.held_out.is_nan() || options.held_out <= 0.0 || options.held_out > 0.5 {
        return Err(Error::invalid(format!(
            "the held-out fraction {} (--held-out) is outside (0, 0.5]: give e.g. 0.1 (one point in ten)",
            options.held_out
        )));
    }
    // (value, smallest, largest, what it is, a value to give)
    let counts = [
        (
            options.resolution,
            2,
            1_000,
            "vertices per side (--resolution)",
            30,
        ),
        (
            options.rbf_grid,
            2,
            40,
            "RBF centres per side (--rbf-grid)",
            5,
        ),
        (
            options.rbf_max_centers,
            3,
            4_000,
            "RBF centres (--rbf-centers; a dense solve)",
            1_500,
        ),
    ];
    for (value, lo, hi, what, example) in counts {
        if !(lo..=hi).contains(&value) {
            return Err(Error::invalid(format!(
                "{value} {what} is outside {lo}–{hi}: give e.g. {example}"
            )));
        }
    }
    Ok(())
}

/// The points fitted and the points held out.
type TrainingAndHeldOut = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// A seeded `fraction` of the points held out.
fn split_points(points: &[[f64; 3]], fraction: f64, seed: u64) -> Result<TrainingAndHeldOut> {
    let held = ((points.len() as f64 * fraction).round() as usize).max(1);
    if points.len() < held + 20 {
        return Err(Error::invalid(format!(
            "{} points are too few to hold {held} out and fit the rest: give at least {}",
            points.len(),
            held + 20
        )));
    }
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.shuffle(&mut rand_chacha::ChaCha8Rng::seed_from_u64(seed));
    let (out, kept) = order.split_at(held);
    let mut kept = kept.to_vec();
    // The training points keep the input order, so the embedding does not depend on the seed
    // beyond which points are missing.
    kept.sort_unstable();
    Ok((
        kept.iter().map(|&i| points[i]).collect(),
        out.iter().map(|&i| points[i]).collect(),
    ))
}

/// The planar mesh with each vertex mapped through `map`.
fn grid_through(grid: &PlanarMesh, map: impl Fn([f64; 2]) -> [f64; 3]) -> Mesh {
    Mesh {
        positions: grid.vertices.iter().map(|&uv| map(uv)).collect(),
        triangles: grid.triangles.clone(),
    }
}

/// The vertices and triangle centroids of `mesh`.
fn mesh_samples(mesh: &Mesh) -> Vec<[f64; 3]> {
    let mut samples = mesh.positions.clone();
    samples.extend(mesh.triangles.iter().map(|t| {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0)
    }));
    samples
}

/// RMS and largest of `distances`, divided by `diagonal`.
fn rms_max(distances: &[f64], diagonal: f64) -> (f64, f64) {
    let n = distances.len().max(1) as f64;
    let rms = (distances.iter().map(|d| d * d).sum::<f64>() / n).sqrt();
    let max = distances.iter().fold(0.0_f64, |m, &d| m.max(d));
    (rms / diagonal, max / diagonal)
}

/// Neighbours of the local planes that stand for the data when no truth mesh is given.
pub const PLANE_NEIGHBORS: usize = 10;

/// What mesh → reference distances are measured to.
enum Reference {
    Mesh(TriangleTree),
    Planes {
        tree: ImmutableKdTree<f64, 3>,
        points: Vec<[f64; 3]>,
        /// Unit normal of each point's local plane.
        normals: Vec<[f64; 3]>,
        /// Distance to its farthest plane neighbour.
        reach: Vec<f64>,
    },
}

impl Reference {
    fn new(points: &[[f64; 3]], truth: Option<&Mesh>, diagonal: f64) -> Result<Self> {
        Ok(match truth {
            Some(mesh) => Reference::Mesh(TriangleTree::new(&mesh.clone().validated()?)?),
            None => {
                let tree = ImmutableKdTree::new_from_slice(points)
                    .map_err(|e| Error::invalid(format!("the points cannot be indexed: {e}")))?;
                let neighbors = nearest_neighbors(points, PLANE_NEIGHBORS, diagonal)?;
                let (normals, reach) = points
                    .iter()
                    .zip(&neighbors)
                    .map(|(p, list)| {
                        let mut near: Vec<[f64; 3]> = list.iter().map(|&j| points[j]).collect();
                        let reach = near.iter().fold(0.0_f64, |m, &q| m.max(distance(*p, q)));
                        near.push(*p);
                        (Plane::fit(&near).normal, reach)
                    })
                    .unzip();
                Reference::Planes {
                    tree,
                    points: points.to_vec(),
                    normals,
                    reach,
                }
            }
        })
    }

    fn distance(&self, p: [f64; 3]) -> f64 {
        match self {
            Reference::Mesh(tree) => tree.distance(p),
            Reference::Planes {
                tree,
                points,
                normals,
                reach,
            } => {
                let i = tree
                    .query(&p)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute()
                    .item as usize;
                let d = sub(p, points[i]);
                let across = dot(d, normals[i]);
                let along = (dot(d, d) - across * across).max(0.0).sqrt();
                across.hypot((along - reach[i]).max(0.0))
            }
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Reference::Mesh(_) => "truth mesh",
            Reference::Planes { .. } => "local planes of the input points",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parametric::{SampleSurface, sample_surface};

    fn row<'a>(c: &'a PatchComparison, method: &str) -> &'a PatchMethodRow {
        c.rows.iter().find(|r| r.method == method).unwrap()
    }

    #[test]
    fn the_data_planes_measure_across_and_beyond_the_points() {
        let points: Vec<[f64; 3]> = (0..400)
            .map(|k| [(k % 20) as f64 * 0.1, (k / 20) as f64 * 0.1, 0.0])
            .collect();
        let reference = Reference::new(&points, None, 2.7).unwrap();
        // On the data, between points: 0 (spacing does not count).
        assert!(reference.distance([0.95, 0.95, 0.0]) < 1e-12);
        // Across the plane: the height.
        assert!((reference.distance([0.95, 0.95, 0.3]) - 0.3).abs() < 1e-9);
        // Along the plane, 2 beyond the last point: all but the neighbourhood's reach.
        let far = reference.distance([3.9, 1.0, 0.0]);
        assert!(far > 1.7 && far < 2.0, "{far}");
    }

    #[test]
    fn a_c_shaped_patch_shows_delaunay_chords_and_a_close_network() {
        let sample = sample_surface(SampleSurface::OpenCylinder, 1_200, 0.0, 4).unwrap();
        let c = compare_patch(&sample.points, None, &PatchCompareOptions::default()).unwrap();
        assert_eq!((c.points, c.held_out, c.training), (1_200, 120, 1_080));
        let methods: Vec<&str> = c.rows.iter().map(|r| r.method).collect();
        assert_eq!(methods, ["network", "rbf-low", "rbf-high", "delaunay"]);
        let (network, delaunay) = (row(&c, "network"), row(&c, "delaunay"));
        // Both ways: the network is close to the held-out points and adds no surface away
        // from the data; Delaunay passes through the points but bridges the C's opening.
        assert!(network.held_out_rms < 0.01, "{network:?}");
        assert!(
            network.mesh_rms < 0.005 && network.mesh_max < 0.02,
            "{network:?}"
        );
        assert!(delaunay.mesh_max > 0.05, "{delaunay:?}");
        assert!(network.dihedral_variance < delaunay.dihedral_variance);
        // The interpolating RBF uses every training point as a centre.
        assert_eq!(row(&c, "rbf-high").size, "1080 centres");
    }

    #[test]
    fn a_truth_mesh_is_the_reference_when_given() {
        let sample = sample_surface(SampleSurface::Plane, 300, 0.0, 2).unwrap();
        let truth = Mesh {
            positions: vec![
                [-3.0, -3.0, -0.95],
                [3.0, -3.0, -0.35],
                [3.0, 3.0, 0.85],
                [-3.0, 3.0, 0.25],
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let c = compare_patch(
            &sample.points,
            Some(&truth),
            &PatchCompareOptions::default(),
        )
        .unwrap();
        assert_eq!(c.reference, "truth mesh");
        for r in &c.rows {
            // Every method reproduces a plane; the network to its training accuracy.
            assert!(r.mesh_max < 2e-3, "{r:?}");
            // Held-out points beyond the tessellated region count their distance to its
            // border: a plane's held-out distances are all coverage.
            assert!(r.held_out_rms < 0.015, "{r:?}");
        }
    }

    #[test]
    fn absurd_settings_are_refused_by_name() {
        let sample = sample_surface(SampleSurface::Wavy, 200, 0.0, 1).unwrap();
        let defaults = PatchCompareOptions::default();
        for (options, named) in [
            (
                PatchCompareOptions {
                    held_out: 0.0,
                    ..defaults
                },
                "held-out",
            ),
            (
                PatchCompareOptions {
                    held_out: f64::NAN,
                    ..defaults
                },
                "held-out",
            ),
            (
                PatchCompareOptions {
                    resolution: 1,
                    ..defaults
                },
                "--resolution",
            ),
            (
                PatchCompareOptions {
                    rbf_grid: 100,
                    ..defaults
                },
                "--rbf-grid",
            ),
            (
                PatchCompareOptions {
                    rbf_max_centers: 0,
                    ..defaults
                },
                "--rbf-centers",
            ),
        ] {
            let e = compare_patch(&sample.points, None, &options)
                .unwrap_err()
                .to_string();
            assert!(e.contains(named), "{e}");
        }
        let e = compare_patch(&sample.points[..21], None, &defaults)
            .unwrap_err()
            .to_string();
        assert!(e.contains("too few"), "{e}");
    }
}

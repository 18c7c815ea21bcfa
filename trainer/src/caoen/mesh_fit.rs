//! Fitting a Cao En surface to a closed genus-0 mesh (issue 4): parameterize the mesh on the
//! sphere ([`spherical_parameterization`]), choose n key points by farthest-point sampling,
//! give each a sharpness from its spacing, and fit V by least squares over the whole surface
//! (every vertex and every triangle's centroid, weighted by area, with a weak ridge toward
//! the key vertices' positions); then measure the surface against the mesh.
//!
//! Key points are vertices of the mesh; their weights are the vertices' sphere points.
//! [`KeyPlacement::Surface`] samples them farthest-first on the mesh (Euclidean distance in
//! space), so key density follows the mesh's area even where the parameterization shrinks a
//! protrusion; [`KeyPlacement::Sphere`] samples on the sphere instead. The sharpness of key i
//! makes its blending fall to `overlap` at its nearest neighbouring key (angle dᵢ):
//! qᵢ = ln(1/overlap)/(1 − cos dᵢ) for exponential blending (qᵢ = (1 − overlap^⅓)/(1 − cos dᵢ)
//! for compact blending, whose cap then reaches about 1.7 times as far as the neighbour at the
//! default overlap 0.3), clamped to [0.5, 64] (the core's
//! limit, which also bounds how finely the sphere can be resolved: 64 reaches `overlap` = e⁻¹
//! at 10°).
//!
//! Accuracy (spot, 2930 vertices, the default options; distances as fractions of the
//! bounding diagonal, surface sampled at 10 242 points; the test prints this table and asserts
//! that every column falls with n, RMS < 0.005 and Hausdorff < 0.04 at n = 400):
//!
//! | n | RMS at the vertices | two-sided RMS | Hausdorff |
//! |---|---|---|---|
//! | 50 | 0.0246 | 0.0121 | 0.0461 |
//! | 100 | 0.0188 | 0.0102 | 0.0454 |
//! | 200 | 0.0131 | 0.0060 | 0.0328 |
//! | 400 | 0.0079 | 0.0039 | 0.0256 |
//!
//! The least-squares solve accumulates the normal equations on all threads and factors them
//! once (Cholesky); the ridge keeps them positive definite.
//! Fitting q per key ([`super::fit_sharpness`]) is possible but costs one solve per trial.

use neurosurf_core::caoen::{Blending, Domain, MAX_SHARPNESS};

use super::distance::{SurfaceDistance, surface_distance};
use super::mesh::sphere_mesh;
use super::network::CaoEnNetwork;
use super::spherical::spherical_parameterization;
use crate::error::{Error, Result};
use crate::io::Mesh;
use rayon::prelude::*;

/// Where farthest-point sampling picks the key points.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum KeyPlacement {
    /// Farthest-first on the mesh in space (key density follows surface area).
    Surface,
    /// Farthest-first on the parameterization (uniform on the sphere).
    Sphere,
    /// The paper's teapot layout (Fig. 7): a key at each pole of the sphere's x axis and
    /// rings of six keys around it, evenly spaced in latitude, every other ring turned by 30°
    /// ([`sixfold_points`]). Sixfold symmetric when the parameterization's x axis is the
    /// shape's axis (as for the teapot's body and lid).
    Sixfold,
}

/// How [`fit_parameterized`] builds its network.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct MeshFitOptions {
    /// The blending function (exponential takes any q, so spacing sets it exactly).
    pub blending: Blending,
    /// Whether k is normalized (the rational form: y stays a convex combination).
    pub normalized: bool,
    /// Where the keys go.
    pub placement: KeyPlacement,
    /// The blending value at a key's nearest neighbour, in (0, 1).
    pub overlap: f64,
    /// Icosphere subdivisions of the surface samples the distance is measured on.
    pub sample_subdivisions: usize,
}

impl Default for MeshFitOptions {
    fn default() -> Self {
        MeshFitOptions {
            blending: Blending::Exponential,
            normalized: true,
            placement: KeyPlacement::Surface,
            overlap: 0.3,
            sample_subdivisions: 5,
        }
    }
}

/// A fitted network and how well it matches the mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshFit {
    /// The network (sphere domain, m = p = 3).
    pub network: CaoEnNetwork,
    /// The mesh vertex behind each key point.
    pub key_vertices: Vec<usize>,
    /// RMS of |y(xⱼ) − pⱼ| over the mesh vertices, relative to the bounding diagonal.
    pub vertex_rms: f64,
    /// Surface-to-mesh distance (both directions).
    pub distance: SurfaceDistance,
}

/// One row of [`fit_error_table`].
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize)]
pub struct FitRow {
    /// n.
    pub key_points: usize,
    /// RMS of |y(xⱼ) − pⱼ| at the mesh vertices (relative to the diagonal).
    pub vertex_rms: f64,
    /// Surface-to-mesh distance.
    pub distance: SurfaceDistance,
}

/// The points of the sphere (unit vectors) nearest the paper's sixfold teapot layout: the two
/// poles of the x axis and ⌊(`n` − 2)/6⌋ rings of six evenly spaced in latitude, every other
/// ring turned by 30°, so 6·rings + 2 ≤ `n` keys (at least 8). Returns their indices.
///
/// # Errors
/// [`Error::InvalidInput`] when `n` is below 8, or the rings need more distinct points than
/// there are.
pub fn sixfold_points(points: &[[f64; 3]], n: usize) -> Result<Vec<usize>> {
    if n < 8 {
        return Err(Error::invalid(format!(
            "the sixfold layout takes at least 8 keys (two poles and a ring of six), got {n}"
        )));
    }
    let rings = (n - 2) / 6;
    let mut ideal = vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]];
    for j in 0..rings {
        let a = std::f64::consts::PI * (j + 1) as f64 / (rings + 1) as f64;
        for k in 0..6 {
            let phi = std::f64::consts::TAU * (k as f64 + 0.5 * (j % 2) as f64) / 6.0;
            ideal.push([a.cos(), a.sin() * phi.cos(), a.sin() * phi.sin()]);
        }
    }
    let mut chosen: Vec<usize> = Vec::with_capacity(ideal.len());
    for target in &ideal {
        let nearest = (0..points.len())
            .filter(|i| !chosen.contains(i))
            .min_by(|&a, &b| {
                let d = |p: &[f64; 3]| (0..3).map(|k| (p[k] - target[k]).powi(2)).sum::<f64>();
                d(&points[a]).total_cmp(&d(&points[b]))
            })
            .ok_or_else(|| {
                Error::invalid(format!(
                    "the sixfold layout needs {} distinct points, there are {}",
                    ideal.len(),
                    points.len()
                ))
            })?;
        chosen.push(nearest);
    }
    Ok(chosen)
}

/// `n` indices of `points`, farthest-first: the first is the point farthest from the mean,
/// each next one the farthest from those chosen (so every prefix is itself a good spread).
///
/// # Errors
/// [`Error::InvalidInput`] when `n` is 0 or more than the points.
pub fn farthest_points(points: &[[f64; 3]], n: usize) -> Result<Vec<usize>> {
    if n == 0 || n > points.len() {
        return Err(Error::invalid(format!(
            "cannot choose {n} key points among {} vertices",
            points.len()
        )));
    }
    let count = points.len() as f64;
    let mean = points
        .iter()
        .fold([0.0; 3], |c, p| [0, 1, 2].map(|k| c[k] + p[k] / count));
    let squared = |a: [f64; 3], b: [f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>();
    let farthest = |d: &[f64]| {
        (0..d.len())
            .max_by(|&a, &b| d[a].total_cmp(&d[b]).then(b.cmp(&a)))
            .unwrap_or(0)
    };
    let mut nearest: Vec<f64> = points.iter().map(|&p| squared(p, mean)).collect();
    let mut chosen = Vec::with_capacity(n);
    for _ in 0..n {
        let next = farthest(&nearest);
        chosen.push(next);
        for (d, &p) in nearest.iter_mut().zip(points) {
            *d = d.min(squared(p, points[next]));
        }
    }
    Ok(chosen)
}

/// Sharpness per key from the angle to its nearest other key (see the module documentation).
fn spacing_sharpness(keys: &[[f64; 3]], blending: Blending, overlap: f64) -> Vec<f64> {
    keys.iter()
        .enumerate()
        .map(|(i, a)| {
            let cos = keys
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
                .fold(-1.0_f64, f64::max)
                .min(1.0 - 1e-12);
            let q = match blending {
                Blending::Power => (overlap.ln() / cos.max(1e-3).ln()).round(),
                // (1 + q(cos − 1))³ = overlap.
                Blending::Compact => (1.0 - overlap.cbrt()) / (1.0 - cos),
                _ => -overlap.ln() / (1.0 - cos),
            };
            q.clamp(
                if blending == Blending::Power {
                    1.0
                } else {
                    0.5
                },
                MAX_SHARPNESS,
            )
        })
        .collect()
}

/// Fits an n-key network to `mesh` given its sphere points (one unit vector per vertex, e.g.
/// from [`spherical_parameterization`]).
///
/// # Errors
/// [`Error::InvalidInput`] for an invalid mesh, a point count other than the vertex count,
/// n outside 1 … vertices (and the core's key limit), `overlap` outside (0, 1), or a failed
/// solve.
pub fn fit_parameterized(
    mesh: &Mesh,
    sphere: &[[f64; 3]],
    n: usize,
    options: &MeshFitOptions,
) -> Result<MeshFit> {
    let mesh = mesh.clone().validated()?;
    if sphere.len() != mesh.positions.len() {
        return Err(Error::invalid(format!(
            "{} sphere points for {} vertices",
            sphere.len(),
            mesh.positions.len()
        )));
    }
    if !(options.overlap > 0.0 && options.overlap < 1.0) {
        return Err(Error::invalid(format!(
            "the key overlap must be in (0, 1), got {}",
            options.overlap
        )));
    }
    let key_vertices = match options.placement {
        KeyPlacement::Surface => farthest_points(&mesh.positions, n)?,
        KeyPlacement::Sphere => farthest_points(sphere, n)?,
        KeyPlacement::Sixfold => sixfold_points(sphere, n)?,
    };
    let keys: Vec<[f64; 3]> = key_vertices.iter().map(|&v| sphere[v]).collect();
    let network = CaoEnNetwork {
        domain: Domain::Sphere.code(),
        blending: options.blending.code(),
        normalized: options.normalized,
        weights: keys.iter().map(|k| k.to_vec()).collect(),
        targets: key_vertices
            .iter()
            .map(|&v| mesh.positions[v].to_vec())
            .collect(),
        sharpness: spacing_sharpness(&keys, options.blending, options.overlap),
    };
    network.validate()?;
    let points: Vec<Vec<f64>> = sphere.iter().map(|x| x.to_vec()).collect();
    let values: Vec<Vec<f64>> = mesh.positions.iter().map(|p| p.to_vec()).collect();
    let network = fit_over_area(&network, &mesh, sphere)?;
    let surface = sphere_mesh(&network, options.sample_subdivisions)?;
    let distance = surface_distance(&surface.mesh, &mesh)?;
    let vertex_rms = super::fit::rms_error(&network, &points, &values) / distance.diagonal;
    Ok(MeshFit {
        network,
        key_vertices,
        vertex_rms,
        distance,
    })
}

/// Relative weight of the ridge that keeps V near the key vertices' positions, against the
/// mean diagonal of the normal equations.
const RIDGE: f64 = 1e-4;

/// V by least squares over the surface, not only at its vertices: every vertex with a third
/// of its triangles' area, every triangle's centroid (on the sphere, the normalized mean of
/// its corners) with its area, plus a ridge RIDGE · ‖Vᵢ − tᵢ‖² toward the key vertices'
/// positions. Without the centroids and the ridge, a coarse or capped mesh leaves parts of
/// the sphere without a row, and V can swing far there while matching every vertex.
fn fit_over_area(network: &CaoEnNetwork, mesh: &Mesh, sphere: &[[f64; 3]]) -> Result<CaoEnNetwork> {
    let n = network.key_count();
    let mut rows: Vec<([f64; 3], [f64; 3], f64)> =
        Vec::with_capacity(mesh.positions.len() + mesh.triangles.len());
    let mut vertex_weight = vec![0.0; mesh.positions.len()];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        let area = 0.5 * norm(cross(sub(b, a), sub(c, a)));
        for &v in t {
            vertex_weight[v as usize] += area / 6.0;
        }
        let centre = [0, 1, 2].map(|k| (a[k] + b[k] + c[k]) / 3.0);
        let on_sphere = super::spherical::normalize_or_pole(
            [0, 1, 2].map(|k| t.iter().map(|&v| sphere[v as usize][k]).sum::<f64>()),
        );
        rows.push((on_sphere, centre, area / 2.0));
    }
    for ((x, p), w) in sphere.iter().zip(&mesh.positions).zip(&vertex_weight) {
        rows.push((*x, *p, *w));
    }
    // Normal equations AᵀWA V = AᵀW P, accumulated on all threads.
    let (gram, right) = rows
        .par_chunks(1024)
        .map(|chunk| {
            let mut gram = nalgebra::DMatrix::<f64>::zeros(n, n);
            let mut right = nalgebra::DMatrix::<f64>::zeros(n, 3);
            for (x, p, w) in chunk {
                let a = nalgebra::DVector::from_vec(network.activations(x));
                gram.ger(*w, &a, &a, 1.0);
                for k in 0..3 {
                    right.column_mut(k).axpy(w * p[k], &a, 1.0);
                }
            }
            (gram, right)
        })
        .reduce(
            || {
                (
                    nalgebra::DMatrix::zeros(n, n),
                    nalgebra::DMatrix::zeros(n, 3),
                )
            },
            |a, b| (a.0 + b.0, a.1 + b.1),
        );
    let ridge = RIDGE * gram.trace() / n.max(1) as f64;
    let mut gram = gram;
    let mut right = right;
    for i in 0..n {
        gram[(i, i)] += ridge;
        for k in 0..3 {
            right[(i, k)] += ridge * network.targets[i][k];
        }
    }
    let v = gram
        .cholesky()
        .ok_or_else(|| Error::invalid("the least-squares system for V is not positive definite"))?
        .solve(&right);
    let mut fitted = network.clone();
    fitted.targets = (0..n)
        .map(|i| (0..3).map(|k| v[(i, k)]).collect())
        .collect();
    fitted.validate()?;
    Ok(fitted)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Parameterizes `mesh` once and fits it with each key count in `counts`: the fit error as a
/// function of n.
///
/// # Errors
/// As [`spherical_parameterization`] and [`fit_parameterized`].
pub fn fit_error_table(
    mesh: &Mesh,
    counts: &[usize],
    options: &MeshFitOptions,
) -> Result<Vec<FitRow>> {
    let map = spherical_parameterization(mesh)?;
    counts
        .iter()
        .map(|&n| {
            let fit = fit_parameterized(mesh, &map.points, n, options)?;
            Ok(FitRow {
                key_points: n,
                vertex_rms: fit.vertex_rms,
                distance: fit.distance,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::{cap_holes, icosphere};
    use crate::io::{data_file, read_mesh};

    /// On a dense sphere the sixfold layout has its two poles on the x axis and every key a
    /// partner 60° round that axis; too few keys are refused by name.
    #[test]
    fn sixfold_points_ring_the_x_axis() {
        let dense: Vec<[f64; 3]> = crate::caoen::support::fibonacci(20_000)
            .iter()
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        let keys = sixfold_points(&dense, 40).unwrap();
        assert_eq!(keys.len(), 38);
        assert!(dense[keys[0]][0] > 0.999 && dense[keys[1]][0] < -0.999);
        let (c, s) = (
            std::f64::consts::FRAC_PI_3.cos(),
            std::f64::consts::FRAC_PI_3.sin(),
        );
        for &k in &keys {
            let w = dense[k];
            let turned = [w[0], c * w[1] - s * w[2], s * w[1] + c * w[2]];
            let nearest = keys
                .iter()
                .map(|&v| {
                    (0..3)
                        .map(|i| (dense[v][i] - turned[i]).powi(2))
                        .sum::<f64>()
                        .sqrt()
                })
                .fold(f64::INFINITY, f64::min);
            assert!(nearest < 0.04, "{w:?}: nearest turned partner {nearest}");
        }
        let e = sixfold_points(&dense, 7).unwrap_err().to_string();
        assert!(e.contains("at least 8"), "{e}");
    }

    /// Spot: the error falls with every doubling of n and is below the stated bounds at 400.
    #[test]
    fn spot_error_falls_with_key_count() {
        let mesh = read_mesh(&data_file("spot.obj").unwrap()).unwrap();
        let rows =
            fit_error_table(&mesh, &[50, 100, 200, 400], &MeshFitOptions::default()).unwrap();
        println!("n     vertex rms   rms      max→mesh  max→surface  Hausdorff (of the diagonal)");
        for r in &rows {
            let d = r.distance;
            println!(
                "{:<5} {:.4}      {:.4}   {:.4}    {:.4}       {:.4}",
                r.key_points,
                r.vertex_rms,
                d.rms,
                d.max_to_reference,
                d.max_to_surface,
                d.hausdorff
            );
        }
        for pair in rows.windows(2) {
            assert!(pair[1].distance.rms < pair[0].distance.rms, "{pair:?}");
            assert!(pair[1].vertex_rms < pair[0].vertex_rms, "{pair:?}");
        }
        let last = rows[3].distance;
        assert!(last.rms < 0.005 && last.hausdorff < 0.04, "{last:?}");
    }

    /// What cannot be parameterized or fitted is named.
    #[test]
    fn bad_meshes_and_counts_are_errors() {
        let sphere = icosphere(1).unwrap();
        let mut open = sphere.clone();
        open.triangles.pop();
        let e = spherical_parameterization(&open).unwrap_err().to_string();
        assert!(e.contains("boundary"), "{e}");
        assert!(spherical_parameterization(&crate::io::Mesh::default()).is_err());
        // Capping the hole gives a sphere again.
        let capped = cap_holes(&open).unwrap();
        assert_eq!(capped.vertex_count(), sphere.vertex_count() + 1);
        let map = spherical_parameterization(&capped).unwrap();
        assert!(map.smallest_area_ratio > 0.0);
        let points = &spherical_parameterization(&sphere).unwrap().points;
        let options = MeshFitOptions::default();
        assert!(fit_parameterized(&sphere, points, 0, &options).is_err());
        assert!(fit_parameterized(&sphere, points, 43, &options).is_err());
        assert!(fit_parameterized(&sphere, &points[1..], 10, &options).is_err());
        let bad = MeshFitOptions {
            overlap: 1.0,
            ..options
        };
        assert!(fit_parameterized(&sphere, points, 10, &bad).is_err());
        let mut nan = sphere.clone();
        nan.positions[0][0] = f64::NAN;
        assert!(fit_parameterized(&nan, points, 10, &options).is_err());
    }
}

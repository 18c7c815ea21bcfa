//! Two-sided accuracy of a field against a known surface: from the true surface to the
//! model's zero set, from the model's zero set (a mesh of it as `neurosurf mesh` makes it) back
//! to the true surface, the normals, the mesh's pieces, and stray surface.

use rayon::prelude::*;
use serde::Serialize;

use super::stray::{FAR_FRACTION, STRAY_GROWTH, StrayReport, grown_bounds, stray_surface};
use super::truth::Truth;
use crate::caoen::TriangleTree;
use crate::error::Result;
use crate::geometry::vector::{dot, norm, scale, sub};
use crate::io::Mesh;
use crate::render::{Field, Region, extract_mesh};

/// Newton steps at most when pushing a point onto Φ = 0.
const NEWTON_STEPS: usize = 12;
/// A point is on the zero set when |Φ|/|∇Φ| is below this fraction of the diagonal.
const ON_SURFACE: f64 = 1e-7;

/// Distances as percentages of the reference's bounding diagonal.
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct Distances {
    /// Points measured.
    pub count: usize,
    /// Median, % of the diagonal.
    pub median_percent: f64,
    /// Root mean square, % of the diagonal.
    pub rms_percent: f64,
    /// 90th percentile, % of the diagonal.
    pub p90_percent: f64,
    /// Largest, % of the diagonal.
    pub max_percent: f64,
}

impl Distances {
    fn of(mut d: Vec<f64>, diagonal: f64) -> Distances {
        let count = d.len();
        if count == 0 {
            return Distances {
                count,
                median_percent: f64::NAN,
                rms_percent: f64::NAN,
                p90_percent: f64::NAN,
                max_percent: f64::NAN,
            };
        }
        d.sort_by(f64::total_cmp);
        let percent = 100.0 / diagonal;
        let at = |q: f64| d[((count - 1) as f64 * q).round() as usize] * percent;
        Distances {
            count,
            median_percent: at(0.5),
            rms_percent: (d.iter().map(|x| x * x).sum::<f64>() / count as f64).sqrt() * percent,
            p90_percent: at(0.9),
            max_percent: d[count - 1] * percent,
        }
    }
}

/// The model's zero set as a mesh over the reference's grown bounding box.
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct MeshCheck {
    /// Grid cells along the longest side of the grown bounding box.
    pub resolution: usize,
    /// Vertices of the mesh.
    pub vertices: usize,
    /// Connected pieces of the mesh (triangles sharing a vertex).
    pub components: usize,
    /// Vertices farther than [`FAR_FRACTION`] of the diagonal from the true surface, % of all.
    pub far_vertices_percent: f64,
}

/// Everything [`two_sided`] measures.
#[derive(Copy, Clone, Debug, PartialEq, Serialize)]
pub struct TwoSided {
    /// The reference's bounding diagonal, the unit of every percentage.
    pub diagonal: f64,
    /// Whether the reference is a mesh (exact distances) or only points.
    pub exact_reference: bool,
    /// From the true surface's samples to the model's zero set.
    pub truth_to_model: Distances,
    /// From the model's mesh (vertices pushed onto Φ = 0) to the true surface.
    pub model_to_truth: Distances,
    /// Median angle between the model's normal −∇Φ/|∇Φ| (at the nearest zero) and the true
    /// normal, degrees.
    pub normal_median_degrees: f64,
    /// The mesh of the model's zero set.
    pub mesh: MeshCheck,
    /// Sign changes of Φ away from the surface.
    pub stray: StrayReport,
}

impl std::fmt::Display for TwoSided {
    /// One line: both median distances (% of the diagonal), the median normal error, the
    /// stray sign changes and the mesh's pieces.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "truth → model {:.3} %, model → truth {:.3} % of the diagonal, normals {:.2}°, \
             {} stray sign change{}, {} mesh piece{}",
            self.truth_to_model.median_percent,
            self.model_to_truth.median_percent,
            self.normal_median_degrees,
            self.stray.sign_changes,
            if self.stray.sign_changes == 1 {
                ""
            } else {
                "s"
            },
            self.mesh.components,
            if self.mesh.components == 1 { "" } else { "s" },
        )
    }
}

/// A field restricted to one axis-aligned box (the mesher searches only there).
struct Within<'a, F: ?Sized> {
    field: &'a F,
    regions: Vec<Region>,
}

impl<F: Field + ?Sized> Field for Within<'_, F> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.field.value(p)
    }
    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.field.value_gradient(p)
    }
    fn regions(&self) -> &[Region] {
        &self.regions
    }
    fn values(&self, points: &[[f64; 3]], out: &mut [f64]) {
        self.field.values(points, out);
    }
    fn value_gradients(&self, points: &[[f64; 3]], out: &mut [(f64, [f64; 3])]) {
        self.field.value_gradients(points, out);
    }
}

/// Cells along the longest side of the model's mesh in the two-sided measure (the resolution
/// `neurosurf mesh` uses for the issue-style checks).
pub const MEASURE_RESOLUTION: usize = 96;

/// Measures `field` against `truth` both ways (see the module documentation); the model is
/// meshed as `neurosurf mesh` meshes it, with `resolution` cells along the longest side of
/// the field's own regions (the reference's bounding box grown by [`STRAY_GROWTH`] per side
/// for a field without regions), and the stray-surface grid has `stray_resolution` points
/// per axis.
///
/// # Errors
/// [`crate::Error::InvalidInput`] for a resolution the mesher refuses.
pub fn two_sided<F: Field + ?Sized>(
    field: &F,
    truth: &Truth,
    resolution: usize,
    stray_resolution: usize,
) -> Result<TwoSided> {
    let diagonal = truth.diagonal();
    let stray = stray_surface(truth, stray_resolution, &|p, out| field.values(p, out));

    // What `neurosurf mesh` searches (a network's inflated leaf boxes and, with several
    // leaves, their common bounding box), on the same grid; the grown bounding box for a field
    // without regions. Stray surface elsewhere is what the stray-surface grid counts.
    let regions = if field.regions().is_empty() {
        Region::of_box(&grown_bounds(truth, STRAY_GROWTH))
            .into_iter()
            .collect()
    } else {
        field.regions().to_vec()
    };
    let within = Within { field, regions };
    let extracted = extract_mesh(&within, resolution, &|_, _| {})?;
    let mut mesh = extracted.mesh;
    let components = components(&mesh);

    // Model → truth: every mesh vertex, pushed onto the zero set first.
    let projected = project(field, &mesh.positions, diagonal);
    for (p, q) in mesh.positions.iter_mut().zip(&projected) {
        if let Some((q, _)) = q
            && norm(sub(*q, *p)) < extracted.stats.cell_size
        {
            *p = *q;
        }
    }
    let far = FAR_FRACTION * diagonal;
    let model_to_truth: Vec<f64> = mesh
        .positions
        .par_iter()
        .map(|&p| truth.distance(p))
        .collect();
    let far_vertices = model_to_truth.iter().filter(|&&d| d > far).count();

    // Truth → model: Newton from each sample; the mesh where Newton does not settle nearby.
    let tree = (!mesh.triangles.is_empty())
        .then(|| TriangleTree::new(&mesh).ok())
        .flatten();
    let landed = project(field, truth.positions(), diagonal);
    let (truth_to_model, angles): (Vec<f64>, Vec<f64>) = truth
        .positions()
        .par_iter()
        .zip(truth.normals())
        .zip(&landed)
        .map(|((&p, &n), landing)| {
            let by_mesh = tree.as_ref().map_or(f64::INFINITY, |t| t.distance(p));
            let (distance, gradient) = match landing {
                Some((q, g)) if norm(sub(*q, p)) <= by_mesh + extracted.stats.cell_size => {
                    (norm(sub(*q, p)), *g)
                }
                _ => (by_mesh, field.value_gradient(p).1),
            };
            let len = norm(gradient);
            let angle = if len > 0.0 && len.is_finite() {
                (-dot(gradient, n) / len)
                    .clamp(-1.0, 1.0)
                    .acos()
                    .to_degrees()
            } else {
                180.0
            };
            (distance, angle)
        })
        .unzip();
    let mut angles = angles;
    angles.sort_by(f64::total_cmp);
    let normal_median_degrees = angles[angles.len() / 2];

    Ok(TwoSided {
        diagonal,
        exact_reference: truth.is_exact(),
        truth_to_model: Distances::of(truth_to_model, diagonal),
        model_to_truth: Distances::of(model_to_truth, diagonal),
        normal_median_degrees,
        mesh: MeshCheck {
            resolution,
            vertices: mesh.positions.len(),
            components,
            far_vertices_percent: 100.0 * far_vertices as f64 / mesh.positions.len().max(1) as f64,
        },
        stray,
    })
}

/// Newton steps x ← x − Φ∇Φ/|∇Φ|² from each point, all points at once; the zero reached and
/// its gradient, or `None` where the steps do not settle.
fn project<F: Field + ?Sized>(
    field: &F,
    points: &[[f64; 3]],
    diagonal: f64,
) -> Vec<Option<([f64; 3], [f64; 3])>> {
    let mut current = points.to_vec();
    let mut result = vec![None; points.len()];
    let mut active: Vec<usize> = (0..points.len()).collect();
    let mut samples = Vec::new();
    for _ in 0..NEWTON_STEPS {
        if active.is_empty() {
            break;
        }
        let at: Vec<[f64; 3]> = active.iter().map(|&i| current[i]).collect();
        samples.resize(at.len(), (0.0, [0.0; 3]));
        at.par_chunks(256)
            .zip(samples.par_chunks_mut(256))
            .for_each(|(p, out)| field.value_gradients(p, out));
        let mut still = Vec::new();
        for (&i, &(phi, g)) in active.iter().zip(&samples) {
            let g2 = dot(g, g);
            if !(g2 > 0.0 && g2.is_finite() && phi.is_finite()) {
                continue;
            }
            if phi.abs() / g2.sqrt() <= ON_SURFACE * diagonal {
                result[i] = Some((current[i], g));
                continue;
            }
            current[i] = sub(current[i], scale(g, phi / g2));
            still.push(i);
        }
        active = still;
    }
    result
}

/// The connected pieces of a mesh (triangles sharing a vertex): each used vertex's piece
/// label (`u32::MAX` for unused vertices) and the number of pieces.
pub fn component_labels(mesh: &Mesh) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for t in &mesh.triangles {
        let a = find(&mut parent, t[0]);
        for &v in &t[1..] {
            let b = find(&mut parent, v);
            if a != b {
                parent[b as usize] = a;
            }
        }
    }
    let mut used = vec![false; mesh.positions.len()];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut label = vec![u32::MAX; mesh.positions.len()];
    let mut root_label = vec![u32::MAX; mesh.positions.len()];
    let mut count = 0;
    for v in 0..mesh.positions.len() as u32 {
        if !used[v as usize] {
            continue;
        }
        let r = find(&mut parent, v) as usize;
        if root_label[r] == u32::MAX {
            root_label[r] = count;
            count += 1;
        }
        label[v as usize] = root_label[r];
    }
    (label, count as usize)
}

/// The number of connected pieces of a mesh (triangles sharing a vertex).
pub fn components(mesh: &Mesh) -> usize {
    component_labels(mesh).1
}

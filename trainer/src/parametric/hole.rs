//! Hole filling (§7.3): the vertices around a hole are embedded with one-ring LLE (§4.2), a
//! network is trained on them alone, new vertices are placed on a grid inside the hole's
//! boundary in the parameter plane, the boundary and the new vertices are triangulated by
//! constrained Delaunay there, and the new vertices go through the network. The boundary
//! keeps its vertices, so the filled mesh is watertight when the rest of it was. The new
//! vertices are then faired ([`fair_new_vertices`]): a network trained on the ring around a
//! hole extrapolates into it and may bulge out, where the least-bending fill continues the
//! surface around it. Where a sharp crease runs through the region, fairing would round it
//! off: the new vertices go onto the region's smooth parts extended into the hole instead,
//! meeting at the crease ([`follow_creases`]).
//!
//! The region is every vertex within [`HoleOptions::rings`] edges of the hole boundary. The
//! grid step in the parameter plane is the mean parameter-plane length of the region's
//! edges, so the new triangles match the surrounding mesh density.
//!
//! Where LLE folds the region (a crease such as fandisk's, or a strongly curved one), and the
//! region is an annulus (the hole inside, one outer loop), the hole is closed by a temporary
//! fan and the disk gets Tutte's embedding ([`super::tutte_disk`]) instead: it cannot fold,
//! and the hole's outline is star-shaped around the fan's centre, so it is a simple polygon.

use std::collections::VecDeque;

use super::crease_fill::follow_creases;
use super::embedding::{LleOptions, embed_mesh};
use super::fairing::fair_new_vertices;
use super::fit::{SurfaceFit, fit_network};
use super::grid::grid_inside;
use super::planar::triangulate_polygon;
use super::topology::TopologyOptions;
use super::tutte::tutte_disk;
use crate::error::{Error, Result};
use crate::geometry::mesh_graph::{boundary_loops, dihedral_angles, one_rings};
use crate::io::Mesh;

/// Hole-filling settings.
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HoleOptions {
    /// Rings of vertices around the hole that train the network (4).
    pub rings: usize,
    /// Embedding (its `neighbors` is unused: one-rings are the neighbourhoods).
    pub embedding: LleOptions,
    /// Regression ([`TopologyOptions::from_random_starts`]: the network extrapolates).
    pub topology: TopologyOptions,
    /// Fair the new vertices after the network placed them ([`fair_new_vertices`]), or, where
    /// a sharp crease runs through the region around the hole, put them on the region's
    /// smooth parts extended into it (`crease_fill.rs`): on by default; off keeps the
    /// network's surface everywhere.
    #[serde(default = "faired")]
    pub fairing: bool,
}

fn faired() -> bool {
    true
}

impl Default for HoleOptions {
    fn default() -> Self {
        HoleOptions {
            rings: 4,
            embedding: LleOptions::default(),
            topology: TopologyOptions::from_random_starts(),
            fairing: true,
        }
    }
}

/// A filled hole.
#[derive(Clone, Debug)]
pub struct HoleFill {
    /// The mesh with the hole closed.
    pub mesh: Mesh,
    /// Indices of the vertices created inside the hole.
    pub new_vertices: Vec<u32>,
    /// Triangles added.
    pub new_triangles: usize,
    /// Vertices that trained the network.
    pub region_vertices: usize,
    /// Rings of the region around the hole: [`HoleOptions::rings`], or fewer when the region
    /// that many rings deep could not be laid flat.
    pub region_rings: usize,
    /// The network fitted to the region.
    pub fit: SurfaceFit,
    /// Whether the region was embedded by Tutte's method because LLE folded it.
    pub tutte: bool,
    /// Whether the new vertices were faired: asked for, and no crease runs through the region.
    pub faired: bool,
    /// Whether the new vertices were put on the region's smooth parts extended into the hole
    /// (`crease_fill.rs`): fairing asked for, and a crease runs through the region.
    pub followed_creases: bool,
}

/// Fills the hole bounded by `hole` (a boundary loop of `mesh`, as [`boundary_loops`]
/// returns it).
///
/// # Errors
/// [`Error::InvalidInput`] when `hole` is not a boundary loop of the mesh, the region is too
/// small, the embedding fails or folds, or the hole's boundary is not a simple polygon in the
/// parameter plane.
pub fn fill_hole(mesh: &Mesh, hole: &[u32], options: &HoleOptions) -> Result<HoleFill> {
    let loops = boundary_loops(&mesh.triangles)?;
    if hole.len() < 3 || !loops.iter().any(|l| same_cycle(l, hole)) {
        return Err(Error::invalid(
            "the hole is not a boundary loop of the mesh",
        ));
    }
    // A region that reaches round a thin part (not an annulus) or folds may lie flat with
    // fewer rings: each is tried down to two, and the first error is the one reported.
    let mut first = None;
    for rings in (options.rings.min(2)..=options.rings).rev() {
        match fill_hole_with_rings(mesh, hole, options, rings) {
            Ok(filled) => return Ok(filled),
            Err(e) => {
                first.get_or_insert(e);
            }
        }
    }
    Err(first.unwrap_or_else(|| Error::invalid("no ring count to try")))
}

/// [`fill_hole`] with a region of `rings` rings.
fn fill_hole_with_rings(
    mesh: &Mesh,
    hole: &[u32],
    options: &HoleOptions,
    rings_asked: usize,
) -> Result<HoleFill> {
    let n = mesh.positions.len();
    let rings = one_rings(n, &mesh.triangles);
    let depth = ring_depths(&rings, hole, rings_asked);
    let mut local = vec![u32::MAX; n];
    let mut region = Mesh::default();
    for v in 0..n {
        if depth[v] != usize::MAX {
            local[v] = region.positions.len() as u32;
            region.positions.push(mesh.positions[v]);
        }
    }
    region.triangles = mesh
        .triangles
        .iter()
        .filter(|t| t.iter().all(|&v| local[v as usize] != u32::MAX))
        .map(|t| t.map(|v| local[v as usize]))
        .collect();
    // Drop region vertices that belong to no region triangle (reached only through an edge).
    let used = one_rings(region.positions.len(), &region.triangles);
    if used.iter().any(Vec::is_empty) {
        let keep: Vec<bool> = used.iter().map(|r| !r.is_empty()).collect();
        let mut remap = vec![u32::MAX; region.positions.len()];
        let mut positions = Vec::new();
        for (i, &k) in keep.iter().enumerate() {
            if k {
                remap[i] = positions.len() as u32;
                positions.push(region.positions[i]);
            }
        }
        for l in local.iter_mut().filter(|l| **l != u32::MAX) {
            *l = remap[*l as usize];
        }
        region.positions = positions;
        region.triangles = region
            .triangles
            .iter()
            .map(|t| t.map(|v| remap[v as usize]))
            .collect();
    }
    if hole.iter().any(|&v| local[v as usize] == u32::MAX) {
        return Err(Error::invalid(
            "a hole vertex belongs to no triangle of the region",
        ));
    }
    let local_hole: Vec<u32> = hole.iter().map(|&v| local[v as usize]).collect();
    // The hole's outline in the parameter plane, new vertices on a grid inside it at the
    // region's mean edge length, and their triangulation.
    let layout = |uv: &[[f64; 2]]| -> Result<(Vec<[f64; 2]>, _)> {
        let polygon: Vec<[f64; 2]> = local_hole.iter().map(|&v| uv[v as usize]).collect();
        let mut total = 0.0;
        let mut count = 0usize;
        for t in &region.triangles {
            for e in 0..3 {
                let (a, b) = (uv[t[e] as usize], uv[t[(e + 1) % 3] as usize]);
                total += ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                count += 1;
            }
        }
        let step = total / count.max(1) as f64;
        let interior = grid_inside(&polygon, step);
        let planar = triangulate_polygon(&polygon, &interior)?;
        Ok((interior, planar))
    };
    let tutte_instead = |why: Error| -> Result<_> {
        let plane = annulus_embedding(&region, &local_hole).map_err(|e| {
            Error::invalid(format!("{why}; and Tutte's embedding does not apply: {e}"))
        })?;
        let laid = layout(&plane)?;
        Ok((plane, true, laid))
    };
    // LLE first; where it folds the region, or the hole's outline crosses itself in its
    // plane, Tutte's embedding, which can do neither.
    let (parameters, tutte, (interior, planar)) = match embed_mesh(&region, &options.embedding) {
        Ok(embedding) => match layout(&embedding.parameters) {
            Ok(laid) => (embedding.parameters, false, laid),
            Err(crossing) => tutte_instead(crossing)?,
        },
        Err(folded) => tutte_instead(folded)?,
    };
    let fit = fit_network(&region.positions, &parameters, &options.topology)?;
    let uv = &parameters;

    let m = hole.len();
    let mut out = mesh.clone();
    let base = out.positions.len() as u32;
    let mut new_vertices = Vec::with_capacity(interior.len());
    for (k, p) in interior.iter().enumerate() {
        out.positions.push(fit.network.position(p[0], p[1]));
        new_vertices.push(base + k as u32);
    }
    let to_mesh = |i: u32| -> u32 {
        if (i as usize) < m {
            hole[i as usize]
        } else {
            base + (i - m as u32)
        }
    };
    let mut fill: Vec<[u32; 3]> = planar.triangles.iter().map(|t| t.map(to_mesh)).collect();
    // The mesh traverses hole[0] → hole[1]; the fill must traverse it the other way.
    let directed = |t: &[u32; 3], a: u32, b: u32| (0..3).any(|e| t[e] == a && t[(e + 1) % 3] == b);
    let mesh_forward = mesh.triangles.iter().any(|t| directed(t, hole[0], hole[1]));
    let fill_forward = fill.iter().any(|t| directed(t, hole[0], hole[1]));
    if mesh_forward == fill_forward {
        for t in fill.iter_mut() {
            t.swap(1, 2);
        }
    }
    let new_triangles = fill.len();
    out.triangles.extend(fill);
    // Fairing that cannot be solved leaves the network's fill, which is whole already.
    let creased = creased(&region);
    let faired = options.fairing && !creased && fair_new_vertices(&mut out, &new_vertices).is_ok();
    let followed_creases = options.fairing
        && creased
        && follow_creases(
            &region,
            &local_hole,
            uv,
            &interior,
            &mut out.positions[base as usize..],
        ) > 0;
    Ok(HoleFill {
        mesh: out,
        new_vertices,
        new_triangles,
        region_vertices: region.positions.len(),
        region_rings: rings_asked,
        fit,
        tutte,
        faired,
        followed_creases,
    })
}

/// An edge whose two triangles turn by more than this (60°) is sharp.
const SHARP_EDGE: f64 = std::f64::consts::FRAC_PI_3;
/// A region with this many sharp edges holds a crease (a machined part's edge), which the
/// network's surface follows and fairing would round off.
const CREASE_EDGES: usize = 3;

/// Whether a sharp crease runs through `region` ([`SHARP_EDGE`], [`CREASE_EDGES`]).
fn creased(region: &Mesh) -> bool {
    dihedral_angles(region)
        .into_iter()
        .filter(|&a| a > SHARP_EDGE)
        .count()
        >= CREASE_EDGES
}

/// How far a filled hole's new vertices lie from the surface that was removed (a punched
/// hole's triangles, [`punch_hole`]), in the mesh's units.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct FillDeviation {
    /// The farthest a new vertex lies outwards (on the side the removed triangles face).
    pub outwards: f64,
    /// The farthest either way.
    pub either: f64,
    /// The hole's diameter: the largest distance between two of its boundary vertices.
    pub diameter: f64,
}

/// Measures `filled` (a fill of `hole` in `original` less `removed`) against `removed`.
pub fn fill_deviation(
    original: &Mesh,
    hole: &[u32],
    removed: &[[u32; 3]],
    filled: &HoleFill,
) -> FillDeviation {
    use crate::geometry::vector::{cross, distance, dot, sub};
    let at = |v: u32| original.positions[v as usize];
    let diameter = hole
        .iter()
        .flat_map(|&a| hole.iter().map(move |&b| distance(at(a), at(b))))
        .fold(0.0, f64::max);
    let (mut outwards, mut either): (f64, f64) = (0.0, 0.0);
    for &v in &filled.new_vertices {
        let p = filled.mesh.positions[v as usize];
        let (d, t) = removed
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(at);
                (point_triangle_distance(p, a, b, c), [a, b, c])
            })
            .fold((f64::INFINITY, [[0.0; 3]; 3]), |x, y| {
                if y.0 < x.0 { y } else { x }
            });
        if dot(sub(p, t[0]), cross(sub(t[1], t[0]), sub(t[2], t[0]))) > 0.0 {
            outwards = outwards.max(d);
        }
        either = either.max(d);
    }
    FillDeviation {
        outwards,
        either,
        diameter,
    }
}

/// Tutte's embedding of an annulus around `hole`: the hole closed by a fan around a new
/// centre, the outer loop on the circle; scaled like LLE's (mean 0, unit variance per
/// coordinate on average).
fn annulus_embedding(region: &Mesh, hole: &[u32]) -> Result<Vec<[f64; 2]>> {
    let loops = boundary_loops(&region.triangles)?;
    let outer: Vec<&Vec<u32>> = loops.iter().filter(|l| !same_cycle(l, hole)).collect();
    let [outer] = outer.as_slice() else {
        return Err(Error::invalid(format!(
            "the region around the hole has {} other boundary loops, not one",
            outer.len()
        )));
    };
    let n = region.positions.len();
    let mut disk = region.clone();
    disk.positions.push([0.0; 3]);
    let m = hole.len();
    disk.triangles
        .extend((0..m).map(|k| [hole[k], hole[(k + 1) % m], n as u32]));
    let mut plane = tutte_disk(&disk, outer)?;
    plane.truncate(n);
    let mean = plane.iter().fold([0.0; 2], |c, p| {
        [c[0] + p[0] / n as f64, c[1] + p[1] / n as f64]
    });
    let variance = plane
        .iter()
        .map(|p| (p[0] - mean[0]).powi(2) + (p[1] - mean[1]).powi(2))
        .sum::<f64>()
        / (2.0 * n as f64);
    let scale = 1.0 / variance.sqrt().max(f64::MIN_POSITIVE);
    Ok(plane
        .iter()
        .map(|p| [(p[0] - mean[0]) * scale, (p[1] - mean[1]) * scale])
        .collect())
}

/// Edge hops from the nearest of `sources`, up to `max` (usize::MAX beyond).
pub(super) fn ring_depths(rings: &[Vec<usize>], sources: &[u32], max: usize) -> Vec<usize> {
    let mut depth = vec![usize::MAX; rings.len()];
    let mut queue = VecDeque::new();
    for &v in sources {
        depth[v as usize] = 0;
        queue.push_back(v as usize);
    }
    while let Some(v) = queue.pop_front() {
        if depth[v] >= max {
            continue;
        }
        for &w in &rings[v] {
            if depth[w] == usize::MAX {
                depth[w] = depth[v] + 1;
                queue.push_back(w);
            }
        }
    }
    depth
}

/// Whether two vertex lists are the same cycle (any rotation, either direction).
fn same_cycle(a: &[u32], b: &[u32]) -> bool {
    if a.len() != b.len() || a.is_empty() {
        return false;
    }
    let Some(start) = a.iter().position(|&v| v == b[0]) else {
        return false;
    };
    let m = a.len();
    (0..m).all(|k| a[(start + k) % m] == b[k]) || (0..m).all(|k| a[(start + m - k) % m] == b[k])
}

/// Removes every triangle with a vertex within `rings` edges of `seed` (for tests and
/// demonstrations), returning the holed mesh (same vertices) and the removed triangles.
///
/// # Errors
/// [`Error::InvalidInput`] when `seed` is not a vertex.
pub fn punch_hole(mesh: &Mesh, seed: u32, rings: usize) -> Result<(Mesh, Vec<[u32; 3]>)> {
    let n = mesh.positions.len();
    if seed as usize >= n {
        return Err(Error::invalid(format!("vertex {seed} does not exist")));
    }
    let depth = ring_depths(&one_rings(n, &mesh.triangles), &[seed], rings);
    let (removed, kept): (Vec<[u32; 3]>, Vec<[u32; 3]>) = mesh
        .triangles
        .iter()
        .partition(|t| t.iter().any(|&v| depth[v as usize] < rings));
    Ok((
        Mesh {
            positions: mesh.positions.clone(),
            triangles: kept,
        },
        removed,
    ))
}

/// Distance from `p` to triangle (a, b, c) (Ericson's closest-point regions).
pub fn point_triangle_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let sub = |x: [f64; 3], y: [f64; 3]| [x[0] - y[0], x[1] - y[1], x[2] - y[2]];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let at = |v: f64, w: f64| -> [f64; 3] { std::array::from_fn(|k| a[k] + v * ab[k] + w * ac[k]) };
    let closest = if d1 <= 0.0 && d2 <= 0.0 {
        a
    } else {
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        if d3 >= 0.0 && d4 <= d3 {
            b
        } else {
            let vc = d1 * d4 - d3 * d2;
            if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
                at(d1 / (d1 - d3), 0.0)
            } else {
                let cp = sub(p, c);
                let (d5, d6) = (dot(ab, cp), dot(ac, cp));
                if d6 >= 0.0 && d5 <= d6 {
                    c
                } else {
                    let vb = d5 * d2 - d1 * d6;
                    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
                        at(0.0, d2 / (d2 - d6))
                    } else {
                        let va = d3 * d6 - d5 * d4;
                        if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
                            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
                            std::array::from_fn(|k| b[k] + w * (c[k] - b[k]))
                        } else {
                            let denom = 1.0 / (va + vb + vc);
                            at(vb * denom, vc * denom)
                        }
                    }
                }
            }
        }
    };
    let d = sub(p, closest);
    dot(d, d).sqrt()
}

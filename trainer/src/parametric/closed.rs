//! Closed objects end to end: a closed mesh is cut into disc-shaped patches, each flattened
//! by Tutte's embedding and fitted by its own surface network, tessellated with seam vertices
//! it shares with its neighbours, and stitched (§6.1) into one watertight, consistently
//! oriented mesh.
//!
//! **Cutting.** Holes are capped first (a scan's open loops). `k` seeds are picked by
//! farthest-point sampling of edge-path distances (edges across a bend made longer by
//! [`NORMAL_PENALTY`], so regions stop at creases and rims); every vertex goes to its nearest seed
//! (multi-source Dijkstra) and every triangle to the seed most of its vertices go to; a
//! region's stray pieces join the neighbour they share most edges with. The cut is kept when
//! every region is a disc (one boundary loop, Euler characteristic 1) with [`NORMAL_SHARE`] of
//! its area facing within [`MAX_NORMAL_CONE`] of its mean normal; every other region gets one
//! more seed, at its vertex farthest from its seed, up to [`MAX_PATCHES`].
//!
//! **Seams.** Two regions meet along a chain of mesh vertices between corners (where the
//! region across changes). Every chain is thinned to the tessellation's spacing in one
//! canonical direction, so both regions keep the same vertices. Each region is fitted with one
//! ring of triangles around it ([`OVERLAP_RINGS`]), so its seams lie inside the domain its
//! network learned; its polygon is its kept loop vertices at their Tutte parameters (inside
//! the unit circle, where the ring's outer loop lies). Grid points fill it, constrained
//! Delaunay triangulates it, and its network lifts it. The copies of every kept vertex in the
//! patches around it are the seams [`stitch`] closes.

use super::fit::{SurfaceFit, fit_network};
use super::grid::grid_inside;
use super::planar::{signed_area, triangulate_polygon};
use super::stitch::{Seam, stitch};
use super::synthesis::synthesize;
use super::topology::TopologyOptions;
use super::tutte::tutte_disk;
use crate::caoen::{SurfaceDistance, cap_holes_planar, surface_distance};
use crate::error::{Error, Result};
use crate::geometry::mesh_graph::{
    boundary_loops, drop_unused_vertices, edge_faces, edge_report, one_rings,
};
use crate::geometry::vector::{cross, distance, dot, norm, scale, sub};
use crate::io::Mesh;
use rayon::prelude::*;
use std::cmp::Reverse;
use std::collections::{BTreeMap, BinaryHeap, HashMap};

/// Most patches a cut may use.
pub const MAX_PATCHES: usize = 96;
/// Largest angle (degrees) between a region's triangles and its mean normal.
pub const MAX_NORMAL_CONE: f64 = 90.0;
/// How much an edge between vertices whose normals differ costs in the cut's distances:
/// its length times 1 + this·(1 − cos).
pub const NORMAL_PENALTY: f64 = 8.0;
/// Rings of triangles a region's network is also fitted to beyond the region (while the
/// grown region stays a disc), so its seams lie inside the domain it learned.
pub const OVERLAP_RINGS: usize = 1;
/// Points each patch's network is fitted to, at least: a region with fewer vertices adds
/// points inside its triangles.
pub const FIT_SAMPLES: usize = 1500;
/// Share of a region's area that must face within [`MAX_NORMAL_CONE`] (scans have stray
/// triangles).
pub const NORMAL_SHARE: f64 = 0.9;

/// Settings of [`reconstruct_closed`].
#[derive(Copy, Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClosedOptions {
    /// Patches the first cut tries (it grows until every patch is a disc).
    pub patches: usize,
    /// About this many vertices in the output mesh.
    pub vertices: usize,
    /// Each patch's network search.
    pub topology: TopologyOptions,
}

impl Default for ClosedOptions {
    fn default() -> Self {
        ClosedOptions {
            patches: 8,
            vertices: 20_000,
            topology: TopologyOptions::default(),
        }
    }
}

/// One patch of a closed reconstruction.
#[derive(Clone, Debug)]
pub struct ClosedPatch {
    /// Its network, fitted to the region's mesh vertices at their Tutte parameters.
    pub fit: SurfaceFit,
    /// The region's polygon in the parameter plane: its kept seam vertices in order,
    /// counter-clockwise.
    pub region: Vec<[f64; 2]>,
    /// Input mesh vertices in the region.
    pub points: usize,
}

/// Where two patches meet: the same seam points in each patch's parameters, in the order of
/// their input vertices (not along the seam). Patches that only share a corner, where three
/// or more meet, have one point.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SeamCurve {
    /// First patch.
    pub patch_a: usize,
    /// Second patch.
    pub patch_b: usize,
    /// The seam points' (u, v) in the first patch.
    pub parameters_a: Vec<[f64; 2]>,
    /// The same points' (u, v) in the second patch.
    pub parameters_b: Vec<[f64; 2]>,
}

/// A closed mesh rebuilt from surface networks.
#[derive(Clone, Debug)]
pub struct ClosedReconstruction {
    /// The patches, one network each.
    pub patches: Vec<ClosedPatch>,
    /// Every pair of patches that meet.
    pub seams: Vec<SeamCurve>,
    /// The stitched mesh.
    pub mesh: Mesh,
    /// Boundary loops of the input that were capped before cutting.
    pub capped_holes: usize,
    /// Largest gap between seam copies before the stitch.
    pub gap_before: f64,
    /// Largest distance any vertex moved in the stitch.
    pub max_displacement: f64,
    /// The stitched mesh against the (capped) input, both ways, over its diagonal.
    pub distance: SurfaceDistance,
    /// Mean distance between the two networks of a seam at its points (what the blobs give
    /// there before any stitch), over the input's diagonal.
    pub seam_gap: f64,
    /// The largest such distance.
    pub max_seam_gap: f64,
}

/// Rebuilds the closed `input` mesh from patches of surface networks (see the module docs).
///
/// # Errors
/// [`Error::InvalidInput`] for an empty or non-finite mesh, option values out of range, a mesh
/// that stays open or non-manifold after capping, or one that no cut into at most
/// [`MAX_PATCHES`] discs fits.
pub fn reconstruct_closed(input: &Mesh, options: &ClosedOptions) -> Result<ClosedReconstruction> {
    if !(2..=MAX_PATCHES).contains(&options.patches) {
        return Err(Error::invalid(format!(
            "a closed object is cut into 2 to {MAX_PATCHES} patches, not {}",
            options.patches
        )));
    }
    if !(100..=2_000_000).contains(&options.vertices) {
        return Err(Error::invalid(format!(
            "the output mesh has 100 to 2 000 000 vertices, not {}",
            options.vertices
        )));
    }
    if input.triangles.is_empty() || input.positions.iter().flatten().any(|c| !c.is_finite()) {
        return Err(Error::invalid(
            "a closed object needs a mesh of finite vertices and at least one triangle; a point \
             cloud goes to `reconstruct_closed_points` (`parametric closed` takes either)",
        ));
    }
    let (mesh, _) = drop_unused_vertices(input);
    let capped_holes = boundary_loops(&mesh.triangles)?.len();
    let mesh = if capped_holes > 0 {
        cap_holes_planar(&mesh)?
    } else {
        mesh
    };
    let report = edge_report(&mesh);
    if !report.is_watertight() {
        return Err(Error::invalid(format!(
            "the mesh is not a closed manifold even with its holes capped ({} boundary, {} \
             non-manifold edges): repair it, or reconstruct its open patches with `fit`",
            report.boundary, report.non_manifold
        )));
    }
    let labels = cut_into_discs(&mesh, options.patches)?;
    let regions = regions_of(&mesh, &labels)?;
    let fits: Vec<SurfaceFit> = regions
        .par_iter()
        .map(|r| {
            let (points, parameters) = fit_samples(&mesh, r);
            fit_network(&points, &parameters, &options.topology)
        })
        .collect::<Result<_>>()?;

    // Seam vertices, thinned to the output spacing.
    let total_area: f64 = regions.iter().map(|r| r.area).sum();
    let diagonal = crate::geometry::bounding_diagonal(&mesh);
    if total_area.is_nan() || total_area <= 1e-12 * diagonal * diagonal {
        return Err(Error::invalid(
            "the mesh encloses no area: its triangles are degenerate",
        ));
    }
    let spacing = (total_area / options.vertices as f64 * 2.0 / 3f64.sqrt()).sqrt();
    let kept = seam_vertices(&mesh, &labels, &regions, spacing);

    // Each region: its kept loop as a polygon, filled, triangulated and lifted.
    let mut patches = Vec::with_capacity(regions.len());
    let mut meshes = Vec::with_capacity(regions.len());
    // Global kept vertex → (patch, local index, parameters).
    let mut copies: BTreeMap<u32, Vec<(usize, u32, [f64; 2])>> = BTreeMap::new();
    for (r, (region, fit)) in regions.iter().zip(fits).enumerate() {
        let local: HashMap<u32, usize> = region
            .vertices
            .iter()
            .enumerate()
            .map(|(i, &v)| (v, i))
            .collect();
        let corners: Vec<u32> = region
            .boundary
            .iter()
            .copied()
            .filter(|v| kept.contains_key(v))
            .collect();
        let polygon: Vec<[f64; 2]> = corners
            .iter()
            .map(|v| region.parameters[local[v]])
            .collect();
        let share = region.area / total_area;
        let target = (options.vertices as f64 * share).max(16.0);
        let h = (signed_area(&polygon).abs() / target).sqrt();
        let interior = grid_inside(&polygon, h);
        let planar = triangulate_polygon(&polygon, &interior).map_err(|e| {
            Error::invalid(format!(
                "patch {r}'s seam polygon cannot be triangulated ({e}): try more --vertices \
                 or more --patches"
            ))
        })?;
        let surface = synthesize(&fit.network, &planar);
        for (i, &v) in corners.iter().enumerate() {
            copies.entry(v).or_default().push((r, i as u32, polygon[i]));
        }
        meshes.push(surface.mesh);
        patches.push(ClosedPatch {
            fit,
            region: polygon,
            points: region.vertices.len(),
        });
    }
    let mut pairs: BTreeMap<(usize, usize), (Seam, SeamCurve)> = BTreeMap::new();
    for list in copies.values() {
        for (i, &(ra, va, ua)) in list.iter().enumerate() {
            for &(rb, vb, ub) in &list[i + 1..] {
                let (seam, curve) = pairs.entry((ra, rb)).or_insert_with(|| {
                    (
                        Seam {
                            patch_a: ra,
                            vertices_a: Vec::new(),
                            patch_b: rb,
                            vertices_b: Vec::new(),
                            whole_loop: false,
                        },
                        SeamCurve {
                            patch_a: ra,
                            patch_b: rb,
                            parameters_a: Vec::new(),
                            parameters_b: Vec::new(),
                        },
                    )
                });
                seam.vertices_a.push(va);
                seam.vertices_b.push(vb);
                curve.parameters_a.push(ua);
                curve.parameters_b.push(ub);
            }
        }
    }
    let (seams, curves): (Vec<Seam>, Vec<SeamCurve>) = pairs.into_values().unzip();
    let stitched = stitch(&meshes, &seams)?;
    let measured = surface_distance(&stitched.mesh, &mesh)?;
    // How far apart two patches' networks put the same seam point.
    let mut gaps = Vec::new();
    for curve in &curves {
        let (a, b) = (
            &patches[curve.patch_a].fit.network,
            &patches[curve.patch_b].fit.network,
        );
        for (ua, ub) in curve.parameters_a.iter().zip(&curve.parameters_b) {
            let (p, q) = (
                a.evaluate(ua[0], ua[1]).position,
                b.evaluate(ub[0], ub[1]).position,
            );
            gaps.push(distance(p, q) / measured.diagonal);
        }
    }
    let seam_gap = gaps.iter().sum::<f64>() / gaps.len().max(1) as f64;
    let max_seam_gap = gaps.iter().copied().fold(0.0, f64::max);
    Ok(ClosedReconstruction {
        seam_gap,
        max_seam_gap,
        patches,
        seams: curves,
        mesh: stitched.mesh,
        capped_holes,
        gap_before: stitched.gap_before,
        max_displacement: stitched.max_displacement,
        distance: measured,
    })
}

/// One region of a cut: the vertices it is fitted to (input indices; the region and the
/// overlap around it), their Tutte parameters, the region's own boundary loop (input indices,
/// in the triangles' direction) and its area.
struct Region {
    vertices: Vec<u32>,
    /// Triangles as indices into `vertices`.
    triangles: Vec<[u32; 3]>,
    parameters: Vec<[f64; 2]>,
    boundary: Vec<u32>,
    area: f64,
}

fn triangle_normal(mesh: &Mesh, t: &[u32; 3]) -> [f64; 3] {
    let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
    cross(sub(b, a), sub(c, a))
}

/// Edge-path distances from `seeds` and the nearest seed of every vertex. An edge counts
/// its length times 1 + [`NORMAL_PENALTY`]·(1 − cos) of the angle between its ends' normals,
/// so regions stop at creases and at the rims of thin parts.
fn nearest_seeds(
    mesh: &Mesh,
    rings: &[Vec<usize>],
    normals: &[[f64; 3]],
    seeds: &[usize],
) -> (Vec<f64>, Vec<usize>) {
    let n = mesh.positions.len();
    let mut dist = vec![f64::INFINITY; n];
    let mut label = vec![usize::MAX; n];
    let mut heap = BinaryHeap::new();
    for (s, &v) in seeds.iter().enumerate() {
        dist[v] = 0.0;
        label[v] = s;
        heap.push((Reverse(0f64.to_bits()), v));
    }
    // Distances are never negative, so their bit patterns sort as they do.
    while let Some((Reverse(bits), v)) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > dist[v] {
            continue;
        }
        for &w in &rings[v] {
            let bend = 1.0 + NORMAL_PENALTY * (1.0 - dot(normals[v], normals[w]));
            let e = d + bend * distance(mesh.positions[v], mesh.positions[w]);
            if e < dist[w] {
                dist[w] = e;
                label[w] = label[v];
                heap.push((Reverse(e.to_bits()), w));
            }
        }
    }
    (dist, label)
}

/// How many edge-connected pieces the vertices form.
fn components(rings: &[Vec<usize>]) -> usize {
    let mut seen = vec![false; rings.len()];
    let mut count = 0;
    for start in 0..rings.len() {
        if seen[start] {
            continue;
        }
        count += 1;
        seen[start] = true;
        let mut stack = vec![start];
        while let Some(v) = stack.pop() {
            for &w in &rings[v] {
                if !seen[w] {
                    seen[w] = true;
                    stack.push(w);
                }
            }
        }
    }
    count
}

/// Unit area-weighted vertex normals (zero where the triangles around cancel).
fn vertex_normals(mesh: &Mesh) -> Vec<[f64; 3]> {
    let mut sums = vec![[0.0; 3]; mesh.positions.len()];
    for t in &mesh.triangles {
        let n = triangle_normal(mesh, t);
        for &v in t {
            let s = &mut sums[v as usize];
            *s = [s[0] + n[0], s[1] + n[1], s[2] + n[2]];
        }
    }
    sums.iter()
        .map(|s| {
            let l = norm(*s);
            if l > 0.0 {
                scale(*s, 1.0 / l)
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

/// Triangle labels of the first cut whose regions are all discs facing one way (see the
/// module docs): `start` seeds by farthest-point sampling, then one more seed in every region
/// that fails, at its vertex farthest from its seed.
fn cut_into_discs(mesh: &Mesh, start: usize) -> Result<Vec<usize>> {
    let n = mesh.positions.len();
    let rings = one_rings(n, &mesh.triangles);
    let normals = vertex_normals(mesh);
    let pieces = components(&rings);
    if pieces > MAX_PATCHES / 2 {
        return Err(Error::invalid(format!(
            "the mesh has {pieces} separate pieces, each needing its own patches (at most {} \
             pieces): remove the debris or rebuild the pieces one by one",
            MAX_PATCHES / 2
        )));
    }
    let mut seeds = vec![0usize];
    let (mut dist, _) = nearest_seeds(mesh, &rings, &normals, &seeds);
    // Every component gets a seed.
    while seeds.len() < start || dist.iter().any(|d| d.is_infinite()) {
        let far = (0..n)
            .max_by(|&a, &b| dist[a].total_cmp(&dist[b]))
            .unwrap_or(0);
        seeds.push(far);
        dist = nearest_seeds(mesh, &rings, &normals, &seeds).0;
    }
    loop {
        let (distance_from_seed, vertex_label) = nearest_seeds(mesh, &rings, &normals, &seeds);
        let labels = triangle_labels(mesh, &vertex_label, seeds.len());
        let (problem, more) = check_regions(mesh, &labels, seeds.len(), &distance_from_seed);
        let Some(problem) = problem else {
            return Ok(labels);
        };
        let before = seeds.len();
        for v in more {
            if seeds.len() < MAX_PATCHES && !seeds.contains(&v) {
                seeds.push(v);
            }
        }
        if seeds.len() == before {
            return Err(Error::invalid(format!(
                "no cut into at most {MAX_PATCHES} patches gives discs: {problem}; simplify \
                 or repair the mesh"
            )));
        }
    }
}

/// Each triangle to the label most of its vertices have, then every region reduced to its
/// largest edge-connected piece (the others join the neighbour they share most edges with).
fn triangle_labels(mesh: &Mesh, vertex_label: &[usize], count: usize) -> Vec<usize> {
    let mut labels: Vec<usize> = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| vertex_label[v as usize]);
            if b == c { b } else { a }
        })
        .collect();
    let by_edge = edge_faces(&mesh.triangles);
    let neighbours = |i: usize| -> Vec<usize> {
        let t = mesh.triangles[i];
        (0..3)
            .flat_map(|e| {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                by_edge[&(a.min(b), a.max(b))].clone()
            })
            .filter(|&j| j != i)
            .collect()
    };
    for _ in 0..8 {
        // Pieces: edge-connected triangles of one label.
        let mut piece = vec![usize::MAX; labels.len()];
        let mut sizes: Vec<(usize, usize)> = Vec::new(); // (label, size)
        for start in 0..labels.len() {
            if piece[start] != usize::MAX {
                continue;
            }
            let id = sizes.len();
            piece[start] = id;
            let mut stack = vec![start];
            let mut size = 0;
            while let Some(i) = stack.pop() {
                size += 1;
                for j in neighbours(i) {
                    if piece[j] == usize::MAX && labels[j] == labels[start] {
                        piece[j] = id;
                        stack.push(j);
                    }
                }
            }
            sizes.push((labels[start], size));
        }
        let mut largest = vec![usize::MAX; count];
        for (id, &(label, size)) in sizes.iter().enumerate() {
            if largest[label] == usize::MAX || size > sizes[largest[label]].1 {
                largest[label] = id;
            }
        }
        let stray: Vec<usize> = (0..labels.len())
            .filter(|&i| largest[labels[i]] != piece[i])
            .collect();
        if stray.is_empty() {
            break;
        }
        for i in stray {
            let mut votes: HashMap<usize, usize> = HashMap::new();
            for j in neighbours(i) {
                if labels[j] != labels[i] {
                    *votes.entry(labels[j]).or_insert(0) += 1;
                }
            }
            if let Some((&label, _)) = votes.iter().max_by_key(|&(l, c)| (*c, Reverse(*l))) {
                labels[i] = label;
            }
        }
    }
    labels
}

/// The first region that is not a disc facing one way, described, and for every such region
/// the vertex to seed a new region at: its vertex farthest from its seed.
fn check_regions(
    mesh: &Mesh,
    labels: &[usize],
    count: usize,
    distance_from_seed: &[f64],
) -> (Option<String>, Vec<usize>) {
    let mut problem = None;
    let mut seeds = Vec::new();
    for (r, members) in by_label(labels, count).iter().enumerate() {
        let triangles: Vec<[u32; 3]> = members.iter().map(|&t| mesh.triangles[t]).collect();
        if triangles.is_empty() {
            continue;
        }
        let normals: Vec<[f64; 3]> = triangles.iter().map(|t| triangle_normal(mesh, t)).collect();
        let sum = normals
            .iter()
            .fold([0.0; 3], |s, n| [s[0] + n[0], s[1] + n[1], s[2] + n[2]]);
        let mean = scale(sum, 1.0 / norm(sum).max(f64::MIN_POSITIVE));
        let cosine = |n: &[f64; 3]| dot(*n, mean) / norm(*n).max(f64::MIN_POSITIVE);
        let loops = boundary_loops(&triangles);
        let mut vertices: Vec<u32> = triangles.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let edges = crate::geometry::mesh_graph::edge_uses(&triangles).len();
        let euler = vertices.len() as i64 - edges as i64 + triangles.len() as i64;
        let area: f64 = normals.iter().map(|n| norm(*n)).sum();
        let cos = MAX_NORMAL_CONE.to_radians().cos();
        let within: f64 = normals
            .iter()
            .filter(|n| cosine(n) >= cos)
            .map(|n| norm(*n))
            .sum();
        let failure = match &loops {
            Err(e) => Some(format!("patch {r}: {e}")),
            Ok(l) if l.len() != 1 || euler != 1 => Some(format!(
                "patch {r} has {} boundary loops and Euler characteristic {euler}, not a disc",
                l.len()
            )),
            Ok(_) if within < NORMAL_SHARE * area => Some(format!(
                "patch {r} turns more than {MAX_NORMAL_CONE}° from its mean normal"
            )),
            Ok(_) => None,
        };
        if let Some(f) = failure {
            problem.get_or_insert(f);
            let farthest = vertices
                .iter()
                .map(|&v| v as usize)
                .max_by(|&a, &b| distance_from_seed[a].total_cmp(&distance_from_seed[b]));
            seeds.extend(farthest);
        }
    }
    (problem, seeds)
}

/// Every non-empty region with its Tutte parameters.
fn regions_of(mesh: &Mesh, labels: &[usize]) -> Result<Vec<Region>> {
    let count = labels.iter().copied().max().map_or(0, |m| m + 1);
    let mut by_vertex: Vec<Vec<usize>> = vec![Vec::new(); mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for &v in tri {
            by_vertex[v as usize].push(t);
        }
    }
    let mut out = Vec::new();
    for core in by_label(labels, count) {
        if core.is_empty() {
            continue;
        }
        let area = core
            .iter()
            .map(|&t| 0.5 * norm(triangle_normal(mesh, &mesh.triangles[t])))
            .sum();
        // The core's boundary loop, in its triangles' direction.
        let core_triangles: Vec<[u32; 3]> = core.iter().map(|&t| mesh.triangles[t]).collect();
        let boundary = boundary_loops(&core_triangles)?.remove(0);
        // The fitted region: the core grown by up to OVERLAP_RINGS rings while it stays a disc.
        let mut grown = core.clone();
        for _ in 0..OVERLAP_RINGS {
            let mut inside = vec![false; labels.len()];
            grown.iter().for_each(|&t| inside[t] = true);
            let mut next = grown.clone();
            for &t in &grown {
                for &v in &mesh.triangles[t] {
                    for &u in &by_vertex[v as usize] {
                        if !inside[u] {
                            inside[u] = true;
                            next.push(u);
                        }
                    }
                }
            }
            if !is_disc(&next.iter().map(|&t| mesh.triangles[t]).collect::<Vec<_>>()) {
                break;
            }
            grown = next;
        }
        let triangles: Vec<[u32; 3]> = grown.iter().map(|&t| mesh.triangles[t]).collect();
        let mut vertices: Vec<u32> = triangles.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        let local: HashMap<u32, u32> = vertices
            .iter()
            .enumerate()
            .map(|(i, &v)| (v, i as u32))
            .collect();
        let patch = Mesh {
            positions: vertices
                .iter()
                .map(|&v| mesh.positions[v as usize])
                .collect(),
            triangles: triangles.iter().map(|t| t.map(|v| local[&v])).collect(),
        };
        let outer = boundary_loops(&patch.triangles)?.remove(0);
        let parameters = tutte_disk(&patch, &outer)?;
        out.push(Region {
            triangles: patch.triangles,
            boundary,
            vertices,
            parameters,
            area,
        });
    }
    Ok(out)
}

/// The triangles of every label.
fn by_label(labels: &[usize], count: usize) -> Vec<Vec<usize>> {
    let mut out = vec![Vec::new(); count];
    for (t, &l) in labels.iter().enumerate() {
        if let Some(list) = out.get_mut(l) {
            list.push(t);
        }
    }
    out
}

/// Whether `triangles` form a disc: one boundary loop and Euler characteristic 1.
fn is_disc(triangles: &[[u32; 3]]) -> bool {
    let Ok(loops) = boundary_loops(triangles) else {
        return false;
    };
    let mut vertices: Vec<u32> = triangles.iter().flatten().copied().collect();
    vertices.sort_unstable();
    vertices.dedup();
    let edges = crate::geometry::mesh_graph::edge_uses(triangles).len();
    loops.len() == 1 && vertices.len() as i64 - edges as i64 + triangles.len() as i64 == 1
}

/// The points a region's network is fitted to, with their parameters: its vertices and, so
/// that small regions still give the topology search [`FIT_SAMPLES`] points, the inner points
/// of a barycentric grid on each triangle (the same interpolation in space and in the plane).
fn fit_samples(mesh: &Mesh, region: &Region) -> (Vec<[f64; 3]>, Vec<[f64; 2]>) {
    let mut points: Vec<[f64; 3]> = region
        .vertices
        .iter()
        .map(|&v| mesh.positions[v as usize])
        .collect();
    let mut parameters = region.parameters.clone();
    // Level s has (s − 1)(s − 2)/2 inner points per triangle.
    let missing = FIT_SAMPLES.saturating_sub(points.len());
    let per_triangle = missing.div_ceil(region.triangles.len().max(1));
    let mut level = 2;
    while (level - 1) * (level - 2) / 2 < per_triangle && level < 12 {
        level += 1;
    }
    for t in &region.triangles {
        let [a, b, c] = t.map(|v| v as usize);
        for i in 1..level {
            for j in 1..level - i {
                let (wb, wc) = (i as f64 / level as f64, j as f64 / level as f64);
                let wa = 1.0 - wb - wc;
                let mix3 = |p: [f64; 3], q: [f64; 3], r: [f64; 3]| {
                    [0, 1, 2].map(|k| wa * p[k] + wb * q[k] + wc * r[k])
                };
                let mix2 = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
                    [0, 1].map(|k| wa * p[k] + wb * q[k] + wc * r[k])
                };
                let position = |v: usize| mesh.positions[region.vertices[v] as usize];
                points.push(mix3(position(a), position(b), position(c)));
                let uv = &region.parameters;
                parameters.push(mix2(uv[a], uv[b], uv[c]));
            }
        }
    }
    (points, parameters)
}

/// The seam vertices every region keeps (input index → ()), chains thinned to `spacing`.
fn seam_vertices(
    mesh: &Mesh,
    labels: &[usize],
    regions: &[Region],
    spacing: f64,
) -> BTreeMap<u32, ()> {
    // The label across every region-boundary edge, by directed edge.
    let mut label_of_edge: HashMap<(u32, u32), usize> = HashMap::new();
    for (t, &l) in mesh.triangles.iter().zip(labels) {
        for e in 0..3 {
            label_of_edge.insert((t[e], t[(e + 1) % 3]), l);
        }
    }
    let mut kept = BTreeMap::new();
    for region in regions {
        let cycle = &region.boundary;
        let m = cycle.len();
        // The region across edge k (from cycle[k] to the next) owns the reversed edge.
        let across: Vec<usize> = (0..m)
            .map(|k| {
                label_of_edge
                    .get(&(cycle[(k + 1) % m], cycle[k]))
                    .copied()
                    .unwrap_or(usize::MAX)
            })
            .collect();
        let mut breaks: Vec<usize> = (0..m)
            .filter(|&k| across[(k + m - 1) % m] != across[k])
            .collect();
        if breaks.is_empty() {
            // One neighbour all round: break where both sides will, at the smallest index.
            breaks.push((0..m).min_by_key(|&k| cycle[k]).unwrap_or(0));
        }
        for (i, &start) in breaks.iter().enumerate() {
            let end = breaks[(i + 1) % breaks.len()];
            let mut chain = vec![cycle[start]];
            let mut k = start;
            loop {
                k = (k + 1) % m;
                chain.push(cycle[k]);
                if k == end {
                    break;
                }
            }
            // Canonical direction: from the smaller end, or for a closed chain towards the
            // smaller second vertex.
            let (first, last) = (chain[0], chain[chain.len() - 1]);
            let flip = if first == last {
                chain.len() > 2 && chain[chain.len() - 2] < chain[1]
            } else {
                last < first
            };
            if flip {
                chain.reverse();
            }
            for v in thin(mesh, &chain, spacing, first == last) {
                kept.insert(v, ());
            }
        }
    }
    kept
}

/// The vertices of `chain` nearest to evenly spaced arc lengths about `spacing` apart, both
/// ends included (at least 2 segments, 3 for a closed chain).
fn thin(mesh: &Mesh, chain: &[u32], spacing: f64, closed: bool) -> Vec<u32> {
    let mut arc = vec![0.0];
    for w in chain.windows(2) {
        let d = distance(mesh.positions[w[0] as usize], mesh.positions[w[1] as usize]);
        arc.push(arc[arc.len() - 1] + d);
    }
    let total = arc[arc.len() - 1];
    let segments = ((total / spacing).round() as usize).max(if closed { 3 } else { 2 });
    let mut out = Vec::with_capacity(segments + 1);
    for j in 0..=segments {
        let target = total * j as f64 / segments as f64;
        let k = arc.partition_point(|&s| s < target).min(chain.len() - 1);
        let k = if k > 0 && (arc[k] - target) > (target - arc[k - 1]) {
            k - 1
        } else {
            k
        };
        if out.last() != Some(&chain[k]) {
            out.push(chain[k]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io;
    use crate::parametric::test_meshes::quad_triangles;

    /// A closed triangulated ellipsoid: a UV sphere with poles, scaled.
    fn ellipsoid(axes: [f64; 3], rings: usize, sectors: usize) -> Mesh {
        let mut positions = vec![[0.0, 0.0, axes[2]]];
        for i in 1..rings {
            let theta = std::f64::consts::PI * i as f64 / rings as f64;
            for j in 0..sectors {
                let phi = std::f64::consts::TAU * j as f64 / sectors as f64;
                positions.push([
                    axes[0] * theta.sin() * phi.cos(),
                    axes[1] * theta.sin() * phi.sin(),
                    axes[2] * theta.cos(),
                ]);
            }
        }
        positions.push([0.0, 0.0, -axes[2]]);
        let south = (positions.len() - 1) as u32;
        let id = |i: usize, j: usize| (1 + (i - 1) * sectors + j % sectors) as u32;
        let mut triangles = Vec::new();
        for j in 0..sectors {
            triangles.push([0, id(1, j), id(1, j + 1)]);
            triangles.push([south, id(rings - 1, j + 1), id(rings - 1, j)]);
        }
        triangles.extend(quad_triangles(0..sectors, 1..rings - 1, id));
        Mesh {
            positions,
            triangles,
        }
    }

    fn check(name: &str, mesh: &Mesh, options: &ClosedOptions) -> ClosedReconstruction {
        let result = reconstruct_closed(mesh, options).unwrap();
        let report = edge_report(&result.mesh);
        let d = result.distance;
        eprintln!(
            "{name}: {} patches, {} seams, {} vertices, {report:?}, RMS {:.4} % ({:.4} / {:.4}), \
             Hausdorff {:.3} %, gap {:.2e}, moved {:.2e}, worst fit {:.4} %",
            result.patches.len(),
            result.seams.len(),
            result.mesh.positions.len(),
            100.0 * d.rms,
            100.0 * d.rms_to_reference,
            100.0 * d.rms_to_surface,
            100.0 * d.hausdorff,
            result.gap_before,
            result.max_displacement,
            100.0
                * result
                    .patches
                    .iter()
                    .map(|p| p.fit.relative_rms_error)
                    .fold(0.0, f64::max)
        );
        assert!(report.is_watertight(), "{report:?}");
        assert_eq!((report.non_manifold, report.misoriented), (0, 0));
        result
    }

    /// A torus of radii `big` and `small`, `rings × sectors` quads.
    fn torus(big: f64, small: f64, rings: usize, sectors: usize) -> Mesh {
        let tau = std::f64::consts::TAU;
        let mut positions = Vec::new();
        for i in 0..rings {
            for j in 0..sectors {
                let (a, b) = (
                    tau * i as f64 / rings as f64,
                    tau * j as f64 / sectors as f64,
                );
                let r = big + small * b.cos();
                positions.push([r * a.cos(), r * a.sin(), small * b.sin()]);
            }
        }
        let id = |i: usize, j: usize| ((i % rings) * sectors + j % sectors) as u32;
        Mesh {
            positions,
            triangles: quad_triangles(0..sectors, 0..rings, id),
        }
    }

    /// Every seam's points, evaluated by both patches' networks, meet within `tolerance`.
    fn seams_meet(result: &ClosedReconstruction, tolerance: f64) {
        for seam in &result.seams {
            let (a, b) = (
                &result.patches[seam.patch_a].fit.network,
                &result.patches[seam.patch_b].fit.network,
            );
            for (ua, ub) in seam.parameters_a.iter().zip(&seam.parameters_b) {
                let (p, q) = (
                    a.evaluate(ua[0], ua[1]).position,
                    b.evaluate(ub[0], ub[1]).position,
                );
                assert!(distance(p, q) < tolerance, "{p:?} vs {q:?}");
            }
        }
    }

    #[test]
    fn an_ellipsoid_and_a_torus_are_rebuilt_closed_from_patches() {
        // A one-layer search and a coarser output keep the test short. Measured: ellipsoid
        // 8 patches, RMS 0.13 % of the diagonal; torus (genus 1) 16 patches, RMS 0.11 %: the
        // cut makes discs whatever the genus.
        let options = ClosedOptions {
            vertices: 6000,
            topology: TopologyOptions {
                max_layers: 1,
                restarts: 1,
                ..TopologyOptions::default()
            },
            ..ClosedOptions::default()
        };
        let mesh = ellipsoid([1.0, 0.7, 0.45], 40, 80);
        let result = check("ellipsoid", &mesh, &options);
        assert!(result.distance.rms < 0.005, "{:?}", result.distance);
        assert!(result.patches.len() >= options.patches);
        // The seam points sit inside both networks' fitted domains: they put them within
        // 2 % of the 2.5 diagonal of each other before the stitch (measured 1.7 %).
        seams_meet(&result, 0.05);
        let ring = torus(1.0, 0.35, 60, 24);
        let result = check("torus", &ring, &options);
        assert!(result.distance.rms < 0.005, "{:?}", result.distance);
        // Outward and enclosing what the input encloses.
        let volume = crate::parametric::signed_volume(&result.mesh);
        let truth = crate::parametric::signed_volume(&ring);
        assert!((volume - truth).abs() < 0.02 * truth, "{volume} vs {truth}");
    }

    #[test]
    fn bad_meshes_and_options_are_refused_by_name() {
        let mesh = ellipsoid([1.0, 1.0, 1.0], 8, 12);
        for (options, words) in [
            (
                ClosedOptions {
                    patches: 1,
                    ..ClosedOptions::default()
                },
                "2 to",
            ),
            (
                ClosedOptions {
                    vertices: 10,
                    ..ClosedOptions::default()
                },
                "100 to",
            ),
        ] {
            let e = reconstruct_closed(&mesh, &options).unwrap_err().to_string();
            assert!(e.contains(words), "{e}");
        }
        let mut broken = mesh.clone();
        broken.positions[3][1] = f64::NAN;
        assert!(reconstruct_closed(&broken, &ClosedOptions::default()).is_err());
        // Three triangles on one edge: not a manifold, capping cannot help.
        let mut fin = mesh.clone();
        fin.positions.push([0.0, 0.0, 3.0]);
        let [a, b, _] = fin.triangles[0];
        fin.triangles.push([a, b, (fin.positions.len() - 1) as u32]);
        let e = reconstruct_closed(&fin, &ClosedOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("manifold") || e.contains("boundary"), "{e}");
    }

    #[test]
    fn spot_and_woody_are_rebuilt_closed() {
        // Measured: spot 28 patches, RMS 0.09 % of the diagonal, Hausdorff 0.9 %; woody (a
        // thin plate, one hole capped) 14 patches, RMS 0.05 %, Hausdorff 1.1 %.
        for name in ["spot.obj", "woody.obj"] {
            let Ok(path) = io::data_file(name) else {
                eprintln!("{name} not found: skipped");
                continue;
            };
            let mesh = io::read_mesh(&path).unwrap();
            let result = check(name, &mesh, &ClosedOptions::default());
            assert!(result.distance.rms < 0.005, "{:?}", result.distance);
            assert!(result.distance.hausdorff < 0.03, "{:?}", result.distance);
        }
    }
}

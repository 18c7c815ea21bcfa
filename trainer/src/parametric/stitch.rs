//! Stitching patches into one watertight mesh (§6.1).
//!
//! Every patch keeps its differential coordinates δ = L·v (cotangent [`cotangent_laplacian`]);
//! all patches are solved together in least squares with one constraint row
//! w_c·(c_a − c_b) = 0 per seam vertex pair (Eq. 15) and a weak pull ε·(v − v₀) on every vertex
//! that fixes the translations the Laplacian leaves free (ε = 0.1, w_c = 10). The normal
//! equations (LᵀL + w_c²·CᵀC + ε²I)·x = Lᵀδ + ε²·v₀ are sparse SPD and go through the `faer`
//! sparse Cholesky with three right-hand sides. Then each seam pair is welded into one
//! vertex at its midpoint (so the seam gap is exactly 0), pairs of triangles that the weld put
//! on the same three vertices are dropped, and triangle orientation is made consistent across
//! the seams.
//!
//! Seams pair vertices one to one. [`boundary_seam`] builds one from two patches' boundary
//! loops, first adding vertices to the shorter loop by splitting its longest boundary edges
//! ("necessary vertex additions", Fig. 12b), then choosing the cyclic shift and direction
//! that bring the loops closest.

use super::laplacian::cotangent_laplacian;
use super::sparse::SymmetricMatrix;
use crate::error::{Error, Result};
use crate::geometry::bounding_diagonal;
use crate::geometry::mesh_graph::{boundary_loops, edge_report};
use crate::io::Mesh;

/// Weight of a seam constraint row.
pub const CONSTRAINT_WEIGHT: f64 = 10.0;
/// Weight of the pull towards the original positions.
pub const ANCHOR_WEIGHT: f64 = 1e-1;

/// The largest gap a seam accepts between its two loops, as a share of the smaller patch's
/// bounding diagonal: beyond it the loops do not meet, and stitching would drag one patch
/// across to the other.
pub const MAX_SEAM_GAP: f64 = 0.25;

/// Vertices of two patches that must coincide, pairwise.
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize)]
pub struct Seam {
    /// First patch.
    pub patch_a: usize,
    /// Its seam vertices.
    pub vertices_a: Vec<u32>,
    /// Second patch.
    pub patch_b: usize,
    /// Its seam vertices, `vertices_b[k]` paired with `vertices_a[k]`.
    pub vertices_b: Vec<u32>,
}

/// The stitched mesh and what the stitch moved.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Stitched {
    /// One mesh holding all patches, seams welded.
    #[serde(skip)]
    pub mesh: Mesh,
    /// Largest distance between paired seam vertices before stitching.
    pub gap_before: f64,
    /// Largest distance between paired seam vertices after the least squares solve, before
    /// welding.
    pub gap_solved: f64,
    /// Largest distance between paired seam vertices in the output (0: they are one vertex).
    pub gap_after: f64,
    /// Largest distance any vertex moved.
    pub max_displacement: f64,
    /// Triangles flipped to make the orientation consistent.
    pub flipped_triangles: usize,
}

/// Stitches `patches` along `seams` (see the module docs).
///
/// # Errors
/// [`Error::InvalidInput`] for no patches, a seam naming a missing patch or vertex, seam sides
/// of different lengths, or a singular system.
pub fn stitch(patches: &[Mesh], seams: &[Seam]) -> Result<Stitched> {
    if patches.is_empty() {
        return Err(Error::invalid("nothing to stitch"));
    }
    let mut offsets = Vec::with_capacity(patches.len());
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    for p in patches {
        let base = positions.len();
        offsets.push(base);
        positions.extend_from_slice(&p.positions);
        for t in &p.triangles {
            triangles.push(t.map(|v| v + base as u32));
        }
    }
    let n = positions.len();
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    for (s, seam) in seams.iter().enumerate() {
        if seam.vertices_a.len() != seam.vertices_b.len() {
            return Err(Error::invalid(format!(
                "seam {s} pairs {} vertices with {}: add vertices first (boundary_seam does)",
                seam.vertices_a.len(),
                seam.vertices_b.len()
            )));
        }
        for (side, patch, list) in [
            ("a", seam.patch_a, &seam.vertices_a),
            ("b", seam.patch_b, &seam.vertices_b),
        ] {
            let Some(mesh) = patches.get(patch) else {
                return Err(Error::invalid(format!(
                    "seam {s} side {side} names missing patch {patch}"
                )));
            };
            if let Some(v) = list.iter().find(|&&v| v as usize >= mesh.positions.len()) {
                return Err(Error::invalid(format!(
                    "seam {s} side {side} names vertex {v} of patch {patch}, which has {}",
                    mesh.positions.len()
                )));
            }
        }
        for (&a, &b) in seam.vertices_a.iter().zip(&seam.vertices_b) {
            pairs.push((
                offsets[seam.patch_a] + a as usize,
                offsets[seam.patch_b] + b as usize,
            ));
        }
    }
    let distance = |p: [f64; 3], q: [f64; 3]| {
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    let gap = |x: &[[f64; 3]]| {
        pairs
            .iter()
            .map(|&(a, b)| distance(x[a], x[b]))
            .fold(0.0, f64::max)
    };
    let gap_before = gap(&positions);

    // Normal equations of [L; w_c C; ε I] x = [δ; 0; ε v₀].
    let laplacian = cotangent_laplacian(&positions, &triangles);
    let mut system = SymmetricMatrix::new(n);
    let mut rhs = vec![vec![0.0; n]; 3];
    let mut row: Vec<(usize, f64)> = Vec::new();
    for (i, entries) in laplacian.iter().enumerate() {
        row.clear();
        row.push((i, 1.0));
        row.extend_from_slice(entries);
        let delta: [f64; 3] =
            std::array::from_fn(|c| row.iter().map(|&(j, w)| w * positions[j][c]).sum());
        for &(p, ap) in &row {
            for &(q, aq) in &row {
                system.add(p, q, ap * aq);
            }
            for c in 0..3 {
                rhs[c][p] += ap * delta[c];
            }
        }
    }
    let wc2 = CONSTRAINT_WEIGHT * CONSTRAINT_WEIGHT;
    for &(a, b) in &pairs {
        system.add(a, a, wc2);
        system.add(b, b, wc2);
        system.add(a, b, -wc2);
        system.add(b, a, -wc2);
    }
    let e2 = ANCHOR_WEIGHT * ANCHOR_WEIGHT;
    for i in 0..n {
        system.add(i, i, e2);
        for c in 0..3 {
            rhs[c][i] += e2 * positions[i][c];
        }
    }
    system.compress()?.cholesky()?.solve(&mut rhs);
    let solved: Vec<[f64; 3]> = (0..n).map(|i| [rhs[0][i], rhs[1][i], rhs[2][i]]).collect();
    if solved.iter().flatten().any(|c| !c.is_finite()) {
        return Err(Error::invalid(
            "the stitching system produced non-finite positions",
        ));
    }
    let gap_solved = gap(&solved);
    let max_displacement = solved
        .iter()
        .zip(&positions)
        .map(|(a, b)| distance(*a, *b))
        .fold(0.0, f64::max);

    // Weld pairs (union–find), each class at its mean.
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for &(a, b) in &pairs {
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut index = vec![u32::MAX; n];
    let mut sums: Vec<([f64; 3], usize)> = Vec::new();
    for i in 0..n {
        let r = find(&mut parent, i);
        if index[r] == u32::MAX {
            index[r] = sums.len() as u32;
            sums.push(([0.0; 3], 0));
        }
        let k = index[r] as usize;
        for c in 0..3 {
            sums[k].0[c] += solved[i][c];
        }
        sums[k].1 += 1;
    }
    let welded: Vec<[f64; 3]> = sums.iter().map(|(s, m)| s.map(|c| c / *m as f64)).collect();
    let welded_triangles: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| index[find(&mut parent, v as usize)]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    // Two triangles on the same three vertices (ears of both patches welded face to face)
    // enclose nothing: drop both.
    let mut count: std::collections::HashMap<[u32; 3], usize> = std::collections::HashMap::new();
    let sorted = |t: &[u32; 3]| {
        let mut s = *t;
        s.sort_unstable();
        s
    };
    for t in &welded_triangles {
        *count.entry(sorted(t)).or_insert(0) += 1;
    }
    let mut merged: Vec<[u32; 3]> = welded_triangles
        .into_iter()
        .filter(|t| count.get(&sorted(t)) == Some(&1))
        .collect();
    let flipped_triangles = orient_consistently(&mut merged);
    let mut mesh = Mesh {
        positions: welded,
        triangles: merged,
    };
    face_outward(&mut mesh);
    let gap_after = pairs
        .iter()
        .map(|&(a, b)| {
            let (ia, ib) = (index[find(&mut parent, a)], index[find(&mut parent, b)]);
            distance(mesh.positions[ia as usize], mesh.positions[ib as usize])
        })
        .fold(0.0, f64::max);
    Ok(Stitched {
        mesh,
        gap_before,
        gap_solved,
        gap_after,
        max_displacement,
        flipped_triangles,
    })
}

/// Flips triangles so every shared edge is traversed in opposite directions (breadth-first
/// from each component's first triangle); if the result is closed with negative volume, all
/// are flipped so normals face outward. Returns how many triangles were flipped.
pub fn orient_consistently(triangles: &mut [[u32; 3]]) -> usize {
    use std::collections::{HashMap, VecDeque};
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (t, tri) in triangles.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(t);
        }
    }
    let has_directed =
        |tri: &[u32; 3], a: u32, b: u32| (0..3).any(|e| tri[e] == a && tri[(e + 1) % 3] == b);
    let mut seen = vec![false; triangles.len()];
    let mut flipped = 0;
    for start in 0..triangles.len() {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        let mut queue = VecDeque::from([start]);
        while let Some(t) = queue.pop_front() {
            let tri = triangles[t];
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                let Some(list) = by_edge.get(&(a.min(b), a.max(b))) else {
                    continue;
                };
                if list.len() != 2 {
                    continue;
                }
                for &u in list {
                    if u == t || seen[u] {
                        continue;
                    }
                    seen[u] = true;
                    if has_directed(&triangles[u], a, b) {
                        triangles[u].swap(1, 2);
                        flipped += 1;
                    }
                    queue.push_back(u);
                }
            }
        }
    }
    flipped
}

/// Signed volume of a closed mesh (positive when its triangles face outward).
pub fn signed_volume(mesh: &Mesh) -> f64 {
    mesh.triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum()
}

/// Makes a closed mesh face outward (flips every triangle when its volume is negative).
pub fn face_outward(mesh: &mut Mesh) {
    if edge_report(mesh).is_watertight() && signed_volume(mesh) < 0.0 {
        for t in mesh.triangles.iter_mut() {
            t.swap(1, 2);
        }
    }
}

/// Pairs the boundary loops of `patches[a]` and `patches[b]` (each must have exactly one).
///
/// The loops are aligned first: the start vertex and direction of b's loop that minimize
/// the squared distances between points at equal arc-length fractions. Then every vertex of
/// one loop without a partner at (nearly) the same fraction on the other gets one: the other
/// loop's boundary edge is split there, its triangle becoming two. Both loops end up with the
/// same vertices at the same fractions, paired in order.
///
/// # Errors
/// [`Error::InvalidInput`] for a missing patch, a patch without exactly one boundary loop,
/// `a == b`, or loops farther apart than [`MAX_SEAM_GAP`] of the smaller patch (the patches
/// are left as they were).
pub fn boundary_seam(patches: &mut [Mesh], a: usize, b: usize) -> Result<Seam> {
    if a == b || a >= patches.len() || b >= patches.len() {
        return Err(Error::invalid(
            "a seam needs two different existing patches",
        ));
    }
    let la = single_loop(&patches[a], a)?;
    let lb0 = single_loop(&patches[b], b)?;
    let fa = arc_fractions(&patches[a].positions, &la);
    let pa = &patches[a].positions;
    let mut best = (f64::INFINITY, Vec::new());
    for reverse in [false, true] {
        for shift in 0..lb0.len() {
            let m = lb0.len();
            let lb: Vec<u32> = (0..m)
                .map(|k| {
                    lb0[if reverse {
                        (shift + m - k) % m
                    } else {
                        (shift + k) % m
                    }]
                })
                .collect();
            let pb = &patches[b].positions;
            let fb = arc_fractions(pb, &lb);
            let cost: f64 = la
                .iter()
                .zip(&fa)
                .map(|(&v, &f)| {
                    let q = point_at(pb, &lb, &fb, f).0;
                    let p = pa[v as usize];
                    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)
                })
                .sum();
            if cost < best.0 {
                best = (cost, lb);
            }
        }
    }
    // How far apart the aligned loops are, against the smaller patch.
    let gap = {
        let pb = &patches[b].positions;
        let fb = arc_fractions(pb, &best.1);
        la.iter()
            .zip(&fa)
            .map(|(&v, &f)| {
                let (q, p) = (point_at(pb, &best.1, &fb, f).0, pa[v as usize]);
                ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
            })
            .fold(0.0, f64::max)
    };
    let size = bounding_diagonal(&patches[a]).min(bounding_diagonal(&patches[b]));
    if gap > MAX_SEAM_GAP * size {
        return Err(Error::invalid(format!(
            "the boundaries of patches {a} and {b} are up to {gap:.4e} apart, {:.0} % of the \
             smaller patch's size {size:.4e} (at most {:.0} %): they do not meet, so a seam \
             would drag one patch onto the other; move the patches together or seam others",
            100.0 * gap / size,
            100.0 * MAX_SEAM_GAP
        )));
    }
    let mut loops = [la, best.1];
    let fractions = [
        arc_fractions(&patches[a].positions, &loops[0]),
        arc_fractions(&patches[b].positions, &loops[1]),
    ];
    // Merge the two fraction lists; partners closer than a quarter of the shortest step pair.
    let step = fractions
        .iter()
        .flat_map(|f| {
            f.windows(2)
                .map(|w| w[1] - w[0])
                .chain(f.last().map(|l| 1.0 - l))
        })
        .fold(1.0, f64::min);
    let tolerance = 0.25 * step;
    let (mut i, mut j) = (0, 0);
    let (na, nb) = (fractions[0].len(), fractions[1].len());
    let mut insert: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    while i < na || j < nb {
        let fi = fractions[0].get(i).copied().unwrap_or(f64::INFINITY);
        let fj = fractions[1].get(j).copied().unwrap_or(f64::INFINITY);
        if (fi - fj).abs() <= tolerance {
            i += 1;
            j += 1;
        } else if fi < fj {
            insert[1].push(fi);
            i += 1;
        } else {
            insert[0].push(fj);
            j += 1;
        }
    }
    let patch_index = [a, b];
    for side in 0..2 {
        let mesh = &mut patches[patch_index[side]];
        // Insert from the end so earlier fractions keep their edges.
        for &f in insert[side].iter().rev() {
            let fr = arc_fractions(&mesh.positions, &loops[side]);
            let (point, segment) = point_at(&mesh.positions, &loops[side], &fr, f);
            split_boundary_edge(mesh, &mut loops[side], segment, point);
        }
    }
    debug_assert_eq!(loops[0].len(), loops[1].len());
    let [vertices_a, vertices_b] = loops;
    Ok(Seam {
        patch_a: a,
        vertices_a,
        patch_b: b,
        vertices_b,
    })
}

/// Arc-length fraction of every loop vertex from the first (0) around the closed loop.
fn arc_fractions(positions: &[[f64; 3]], cycle: &[u32]) -> Vec<f64> {
    let m = cycle.len();
    let mut out = Vec::with_capacity(m);
    let mut total = 0.0;
    for k in 0..m {
        out.push(total);
        let (p, q) = (
            positions[cycle[k] as usize],
            positions[cycle[(k + 1) % m] as usize],
        );
        total += ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
    }
    if total > 0.0 {
        out.iter_mut().for_each(|f| *f /= total);
    }
    out
}

/// The point at arc fraction `f` on the closed loop and the index of the edge it lies on.
fn point_at(positions: &[[f64; 3]], cycle: &[u32], fractions: &[f64], f: f64) -> ([f64; 3], usize) {
    let m = cycle.len();
    let k = fractions
        .partition_point(|&x| x <= f)
        .saturating_sub(1)
        .min(m - 1);
    let end = if k + 1 < m { fractions[k + 1] } else { 1.0 };
    let t = if end > fractions[k] {
        ((f - fractions[k]) / (end - fractions[k])).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (p, q) = (
        positions[cycle[k] as usize],
        positions[cycle[(k + 1) % m] as usize],
    );
    (std::array::from_fn(|c| p[c] + t * (q[c] - p[c])), k)
}

fn single_loop(mesh: &Mesh, index: usize) -> Result<Vec<u32>> {
    let mut loops = boundary_loops(&mesh.triangles)?;
    if loops.len() != 1 {
        return Err(Error::invalid(format!(
            "patch {index} has {} boundary loops; a boundary seam needs exactly one",
            loops.len()
        )));
    }
    Ok(loops.remove(0))
}

/// Splits boundary edge `k` of the loop (from `cycle[k]` to the next) at `point`: its
/// triangle becomes two and the new vertex joins the loop.
fn split_boundary_edge(mesh: &mut Mesh, cycle: &mut Vec<u32>, k: usize, point: [f64; 3]) {
    let m = cycle.len();
    let (a, b) = (cycle[k], cycle[(k + 1) % m]);
    let mid = mesh.positions.len() as u32;
    mesh.positions.push(point);
    let directed =
        |t: &[u32; 3], x: u32, y: u32| (0..3).find(|&e| t[e] == x && t[(e + 1) % 3] == y);
    for (x, y) in [(a, b), (b, a)] {
        if let Some((t, e)) = mesh
            .triangles
            .iter()
            .enumerate()
            .find_map(|(t, tri)| directed(tri, x, y).map(|e| (t, e)))
        {
            let c = mesh.triangles[t][(e + 2) % 3];
            mesh.triangles[t] = [x, mid, c];
            mesh.triangles.push([mid, y, c]);
            break;
        }
    }
    cycle.insert(k + 1, mid);
}

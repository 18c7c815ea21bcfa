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
//! Seams pair vertices one to one; [`find_seams`](super::find_seams) finds them where patch
//! boundaries meet, along whole loops or stretches of them (`seams`).

use super::laplacian::cotangent_laplacian;
use super::sparse::SymmetricMatrix;
use crate::error::{Error, Result};
use crate::geometry::mesh_graph::edge_report;
use crate::io::Mesh;

/// Weight of a seam constraint row.
pub const CONSTRAINT_WEIGHT: f64 = 10.0;
/// Weight of the pull towards the original positions.
pub const ANCHOR_WEIGHT: f64 = 1e-1;

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
    /// Whether the seam is a whole boundary loop (the last pair joins the first) rather than
    /// a stretch of one.
    pub whole_loop: bool,
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
                "seam {s} pairs {} vertices with {}: add vertices first (find_seams and boundary_seam do)",
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
    use std::collections::VecDeque;
    let by_edge = crate::geometry::mesh_graph::edge_faces(triangles);
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

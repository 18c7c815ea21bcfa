//! Where patches meet (§6.1, Fig. 12): seams along whole boundary loops, and partial-edge
//! seams along stretches of them (a side that meets two neighbours, a T-junction, the faces
//! of a box, the side and caps of a can).
//!
//! A boundary vertex *touches* another patch's boundary loop when one of its own two boundary
//! edges runs parallel to an edge of that loop (|cos| ≥ [`PARALLEL`]), its foot on that edge
//! falls inside the edge, and it lies within the reach (by default the longer of the two
//! loops' median boundary edges, at most [`MAX_SEAM_GAP`] of the smaller patch). Runs of
//! touching vertices are the stretches that meet; two loops that touch each other at
//! [`WHOLE_LOOP_SHARE`] of their vertices or more make a whole-loop seam.
//!
//! A stretch's ends are carried over to the other loop: where an end's foot falls inside an
//! edge, that edge is split (the end lands on a vertex within [`SNAP`] of an edge). Then each
//! stretch gets a vertex at every arc-length fraction of the other's vertices ("necessary
//! vertex additions", Fig. 12b), and the two pair one to one. A boundary edge joins at most one
//! seam: a third patch meeting a stretch that is already seamed is refused by name, since the
//! result would not be a manifold.

use super::stitch::Seam;
use crate::error::{Error, Result};
use crate::geometry::bounding_diagonal;
use crate::geometry::mesh_graph::boundary_loops;
use crate::geometry::vector::{distance, dot, scale, sub};
use crate::io::Mesh;
use std::collections::HashMap;

/// The largest gap a seam accepts between its two loops, as a share of the smaller patch's
/// bounding diagonal: beyond it the loops do not meet, and stitching would drag one patch
/// across to the other.
pub const MAX_SEAM_GAP: f64 = 0.25;

/// How parallel (|cos| of the angle) a boundary edge must be to the other loop's edge for its
/// vertex to touch that loop: corners where the boundary turns do not reach past a seam's end.
pub const PARALLEL: f64 = 0.9;

/// A stretch's end lands on an existing vertex when it falls within this share of an edge
/// from it, instead of splitting the edge.
pub const SNAP: f64 = 0.2;

/// Share of each loop's vertices that must touch the other loop for the two to be seamed as
/// whole loops.
pub const WHOLE_LOOP_SHARE: f64 = 0.9;

/// How far outside the other loop's edge (as a share of it) a foot may fall and still count.
const FOOT_SLACK: f64 = 0.05;

/// The closest point of another loop to a boundary vertex.
#[derive(Copy, Clone, Debug)]
struct Foot {
    distance: f64,
    /// Arc length along the other loop from its first vertex.
    arc: f64,
}

/// A boundary loop with its cumulative arc lengths.
#[derive(Clone)]
struct Outline {
    cycle: Vec<u32>,
    /// `arc[k]`: arc length from `cycle[0]` to `cycle[k]`.
    arc: Vec<f64>,
    total: f64,
}

impl Outline {
    fn new(positions: &[[f64; 3]], cycle: Vec<u32>) -> Outline {
        let m = cycle.len();
        let mut arc = Vec::with_capacity(m);
        let mut total = 0.0;
        for k in 0..m {
            arc.push(total);
            total += distance(
                positions[cycle[k] as usize],
                positions[cycle[(k + 1) % m] as usize],
            );
        }
        Outline { cycle, arc, total }
    }

    fn len(&self) -> usize {
        self.cycle.len()
    }

    fn edge(&self, k: usize) -> (u32, u32) {
        (self.cycle[k], self.cycle[(k + 1) % self.len()])
    }

    fn edge_length(&self, k: usize) -> f64 {
        if k + 1 < self.len() {
            self.arc[k + 1] - self.arc[k]
        } else {
            self.total - self.arc[k]
        }
    }

    fn median_edge(&self) -> f64 {
        let mut lengths: Vec<f64> = (0..self.len()).map(|k| self.edge_length(k)).collect();
        lengths.sort_unstable_by(f64::total_cmp);
        lengths.get(lengths.len() / 2).copied().unwrap_or(0.0)
    }

    /// Unit directions of the two boundary edges at vertex `k` (zero for a zero-length edge).
    fn directions(&self, positions: &[[f64; 3]], k: usize) -> [[f64; 3]; 2] {
        let m = self.len();
        let unit = |from: u32, to: u32| {
            let d = sub(positions[to as usize], positions[from as usize]);
            let n = dot(d, d).sqrt();
            if n > 0.0 { scale(d, 1.0 / n) } else { [0.0; 3] }
        };
        [
            unit(self.cycle[(k + m - 1) % m], self.cycle[k]),
            unit(self.cycle[k], self.cycle[(k + 1) % m]),
        ]
    }

    /// The foot of `p` (whose boundary edges run along `directions`) on this loop, within
    /// `reach`, on an edge parallel to one of them (see the module docs).
    fn foot(
        &self,
        positions: &[[f64; 3]],
        p: [f64; 3],
        directions: [[f64; 3]; 2],
        reach: f64,
    ) -> Option<Foot> {
        let mut best: Option<Foot> = None;
        for k in 0..self.len() {
            let (i, j) = self.edge(k);
            let (q0, q1) = (positions[i as usize], positions[j as usize]);
            let e = sub(q1, q0);
            let length2 = dot(e, e);
            if length2 <= 0.0 {
                continue;
            }
            let t = dot(sub(p, q0), e) / length2;
            if !(-FOOT_SLACK..=1.0 + FOOT_SLACK).contains(&t) {
                continue;
            }
            let along = scale(e, 1.0 / length2.sqrt());
            if directions.iter().all(|d| dot(*d, along).abs() < PARALLEL) {
                continue;
            }
            let t = t.clamp(0.0, 1.0);
            let d = distance(p, [0, 1, 2].map(|c| q0[c] + t * e[c]));
            if d <= reach && best.is_none_or(|b| d < b.distance) {
                best = Some(Foot {
                    distance: d,
                    arc: self.arc[k] + t * length2.sqrt(),
                });
            }
        }
        best
    }

    /// The vertex at arc length `s` (taken modulo the loop), made by splitting the edge there
    /// unless `s` lies within [`SNAP`] of an edge from a vertex. On a `locked` edge (another
    /// seam's) it is the edge's end inside the stretch, which runs on from `s` forwards or not.
    fn vertex_at(
        &mut self,
        mesh: &mut Mesh,
        s: f64,
        locked: &dyn Fn(u32, u32) -> bool,
        forward: bool,
    ) -> u32 {
        let s = s.rem_euclid(self.total.max(f64::MIN_POSITIVE));
        let k = self.arc.partition_point(|&x| x <= s).saturating_sub(1);
        let length = self.edge_length(k);
        let t = if length > 0.0 {
            (s - self.arc[k]) / length
        } else {
            0.0
        };
        let (a, b) = self.edge(k);
        if locked(a, b) {
            return if forward { b } else { a };
        }
        if t <= SNAP {
            return a;
        }
        if t >= 1.0 - SNAP {
            return b;
        }
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        let point = [0, 1, 2].map(|c| p[c] + t * (q[c] - p[c]));
        let mut path = vec![a, b];
        let mid = split_path_edge(mesh, &mut path, 0, point);
        *self = Outline::new(&mesh.positions, {
            let mut cycle = std::mem::take(&mut self.cycle);
            cycle.insert(k + 1, mid);
            cycle
        });
        mid
    }

    /// The edges whose middles lie within `length` of arc length `start`, going forwards
    /// (`direction` 1) or backwards (−1).
    fn edges_within(&self, start: f64, length: f64, direction: f64) -> Vec<(u32, u32)> {
        (0..self.len())
            .filter(|&k| {
                let middle = self.arc[k] + 0.5 * self.edge_length(k);
                ((middle - start) * direction).rem_euclid(self.total) < length
            })
            .map(|k| self.edge(k))
            .collect()
    }

    /// The vertices from `from` to `to` along the loop, forwards or backwards.
    fn path(&self, from: u32, to: u32, forward: bool) -> Vec<u32> {
        let m = self.len();
        let Some(start) = self.cycle.iter().position(|&v| v == from) else {
            return Vec::new();
        };
        let mut out = vec![from];
        for step in 1..=m {
            let k = if forward {
                (start + step) % m
            } else {
                (start + m * step - step) % m
            };
            out.push(self.cycle[k]);
            if self.cycle[k] == to {
                return out;
            }
        }
        Vec::new()
    }
}

/// `x` minus `reference`, wrapped into (−total/2, total/2].
fn wrapped(x: f64, reference: f64, total: f64) -> f64 {
    let d = (x - reference).rem_euclid(total);
    if d > 0.5 * total { d - total } else { d }
}

/// Which patch each seamed boundary edge already joins: `(patch, low vertex, high vertex)`.
type Claims = HashMap<(usize, u32, u32), usize>;

fn claim_key(patch: usize, a: u32, b: u32) -> (usize, u32, u32) {
    (patch, a.min(b), a.max(b))
}

/// Finds and prepares every seam between the pairs of `patches` named in `pairs` (all pairs
/// when empty), adding the vertices each needs (see the module docs). `reach` overrides the
/// default largest gap a seam closes; neither exceeds [`MAX_SEAM_GAP`] of the smaller patch.
///
/// # Errors
/// [`Error::InvalidInput`] for a pair naming a missing patch or one patch twice, a reach that
/// is not a positive finite number, a boundary that is not a set of simple loops, or a stretch
/// where three patches meet.
pub fn find_seams(
    patches: &mut [Mesh],
    pairs: &[[usize; 2]],
    reach: Option<f64>,
) -> Result<Vec<Seam>> {
    if let Some(r) = reach
        && !(r.is_finite() && r > 0.0)
    {
        return Err(Error::invalid(format!(
            "the seam reach must be a positive distance, not {r}"
        )));
    }
    let all: Vec<[usize; 2]> = (0..patches.len())
        .flat_map(|a| (a + 1..patches.len()).map(move |b| [a, b]))
        .collect();
    let pairs = if pairs.is_empty() { &all[..] } else { pairs };
    let mut claims = Claims::new();
    let mut seams = Vec::new();
    for &[a, b] in pairs {
        if a == b || a >= patches.len() || b >= patches.len() {
            return Err(Error::invalid(format!(
                "a seam joins two different patches of the {} given, not {a} and {b}",
                patches.len()
            )));
        }
        // Every seam adds a stretch's worth of claims; a pair has at most one seam per
        // boundary edge of its first patch.
        let limit = patches[a].triangles.len() * 3 + 1;
        for _ in 0..limit {
            let Some(seam) = next_seam(patches, a, b, reach, &claims)? else {
                break;
            };
            for (patch, other, list) in [
                (seam.patch_a, seam.patch_b, &seam.vertices_a),
                (seam.patch_b, seam.patch_a, &seam.vertices_b),
            ] {
                let closing = seam.whole_loop.then(|| [list[list.len() - 1], list[0]]);
                for w in list.windows(2).chain(closing.as_ref().map(|c| &c[..])) {
                    claims.insert(claim_key(patch, w[0], w[1]), other);
                }
            }
            seams.push(seam);
        }
    }
    Ok(seams)
}

/// The next stretch (or whole loop) where patches `a` and `b` meet that no seam holds yet,
/// prepared as a seam.
fn next_seam(
    patches: &mut [Mesh],
    a: usize,
    b: usize,
    reach: Option<f64>,
    claims: &Claims,
) -> Result<Option<Seam>> {
    let size = bounding_diagonal(&patches[a]).min(bounding_diagonal(&patches[b]));
    let loops_a = boundary_loops(&patches[a].triangles)?;
    let loops_b = boundary_loops(&patches[b].triangles)?;
    for cycle_a in &loops_a {
        for cycle_b in &loops_b {
            let (pa, pb) = (&patches[a].positions, &patches[b].positions);
            let outline_a = Outline::new(pa, cycle_a.clone());
            let outline_b = Outline::new(pb, cycle_b.clone());
            let reach = reach
                .unwrap_or_else(|| outline_a.median_edge().max(outline_b.median_edge()))
                .min(MAX_SEAM_GAP * size);
            let feet = |from: &Outline, p: &[[f64; 3]], to: &Outline, q: &[[f64; 3]]| {
                (0..from.len())
                    .map(|k| to.foot(q, p[from.cycle[k] as usize], from.directions(p, k), reach))
                    .collect::<Vec<_>>()
            };
            let feet_a = feet(&outline_a, pa, &outline_b, pb);
            if feet_a.iter().all(Option::is_none) {
                continue;
            }
            let feet_b = feet(&outline_b, pb, &outline_a, pa);
            // A whole loop: all but a few vertices (a noisy boundary) of each touch the other.
            let share = |f: &[Option<Foot>]| {
                f.iter().filter(|x| x.is_some()).count() as f64 / f.len().max(1) as f64
            };
            let (share_a, share_b) = (share(&feet_a), share(&feet_b));
            if share_a.min(share_b) >= WHOLE_LOOP_SHARE {
                let edges_a = (0..outline_a.len()).map(|k| outline_a.edge(k));
                let edges_b = (0..outline_b.len()).map(|k| outline_b.edge(k));
                if !(held(claims, a, b, edges_a)? | held(claims, b, a, edges_b)?) {
                    let seam = loop_seam(patches, a, cycle_a.clone(), b, cycle_b.clone())?;
                    return Ok(Some(seam));
                }
                continue;
            }
            // Stretches of the loop that does not touch all round (a short side lying along a
            // long one touches all round; its partner's stretches are the ones to follow).
            let (first, second, outlines, all_feet) = if share_a == 1.0 {
                (b, a, [&outline_b, &outline_a], [&feet_b[..], &feet_a[..]])
            } else {
                (a, b, [&outline_a, &outline_b], [&feet_a[..], &feet_b[..]])
            };
            for run in runs(all_feet[0]) {
                let edges = run[..run.len() - 1].iter().map(|&k| outlines[0].edge(k));
                if held(claims, first, second, edges)? {
                    continue;
                }
                let owned = [outlines[0].clone(), outlines[1].clone()];
                if let Some(seam) =
                    stretch_seam(patches, [first, second], owned, &run, all_feet, claims)?
                {
                    return Ok(Some(seam));
                }
            }
        }
    }
    Ok(None)
}

/// Whether a seam of `a` and `b` already holds one of `edges` of patch `a`.
///
/// # Errors
/// When one is held by a seam with a third patch: three sheets would share the edges.
fn held(
    claims: &Claims,
    a: usize,
    b: usize,
    edges: impl Iterator<Item = (u32, u32)>,
) -> Result<bool> {
    let mut any = false;
    for (x, y) in edges {
        match claims.get(&claim_key(a, x, y)) {
            Some(&other) if other != b => {
                return Err(Error::invalid(format!(
                    "patches {other}, {a} and {b} meet along the same boundary stretch (its \
                     edge {x}–{y} in patch {a}): a seam joins two sheets, and three would not \
                     make a manifold; leave one of them out, or name the seams to make with \
                     --seam"
                )));
            }
            Some(_) => any = true,
            None => {}
        }
    }
    Ok(any)
}

/// Maximal cyclic runs of consecutive vertices with a foot, as loop indices in order, each at
/// least one edge long; empty when every vertex has one.
fn runs(feet: &[Option<Foot>]) -> Vec<Vec<usize>> {
    let m = feet.len();
    let Some(gap) = feet.iter().position(Option::is_none) else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    for step in 1..=m {
        let k = (gap + step) % m;
        if feet[k].is_some() {
            current.push(k);
        } else if !current.is_empty() {
            if current.len() >= 2 {
                out.push(std::mem::take(&mut current));
            }
            current.clear();
        }
    }
    out
}

/// The partial seam along `run` (indices of loop a touching loop b): its ends carried to the
/// other loop and extended where the other loop's touching vertices reach further, then the
/// two stretches paired. `None`, with the patches untouched, when either stretch is shorter
/// than a snap.
fn stretch_seam(
    patches: &mut [Mesh],
    [a, b]: [usize; 2],
    [mut outline_a, mut outline_b]: [Outline; 2],
    run: &[usize],
    [feet_a, feet_b]: [&[Option<Foot>]; 2],
    claims: &Claims,
) -> Result<Option<Seam>> {
    let (ta, tb) = (outline_a.total, outline_b.total);
    let foot_arc = |k: usize| feet_a[k].map_or(0.0, |f| f.arc);
    // Feet along loop b, unwrapped from the first; their trend gives b's direction.
    let mut along_b = vec![foot_arc(run[0])];
    for w in run.windows(2) {
        let last = along_b[along_b.len() - 1];
        along_b.push(last + wrapped(foot_arc(w[1]), foot_arc(w[0]), tb));
    }
    let forward = along_b[along_b.len() - 1] >= along_b[0];
    let sign = if forward { 1.0 } else { -1.0 };
    // The stretch on a, [a0, a1] in a's arc length, and on b, [b0, b1] along b's direction.
    let mut a0 = outline_a.arc[run[0]];
    let mut a1 = a0
        + run[..run.len() - 1]
            .iter()
            .map(|&k| outline_a.edge_length(k))
            .sum::<f64>();
    let (mut b0, mut b1) = (along_b[0], along_b[along_b.len() - 1]);
    // b's vertices just beyond either end that touch a near that end extend the stretch.
    let mb = outline_b.len();
    let beyond = |s: f64, outward: f64| -> Option<usize> {
        // The vertex of b nearest past arc `s` in direction `outward` (±1).
        let s = s.rem_euclid(tb);
        let mut best: Option<(f64, usize)> = None;
        for k in 0..mb {
            let d = wrapped(outline_b.arc[k], s, tb) * outward;
            if d > 1e-12 * tb && best.is_none_or(|(e, _)| d < e) {
                best = Some((d, k));
            }
        }
        best.map(|(_, k)| k)
    };
    let step_a = |k: usize| outline_a.edge_length(k);
    let ma = outline_a.len();
    for end in [-1.0, 1.0] {
        let (s_b, s_a) = if end < 0.0 { (b0, a0) } else { (b1, a1) };
        let Some(k) = beyond(s_b, end * sign) else {
            continue;
        };
        let Some(foot) = feet_b[k] else {
            continue;
        };
        let past = wrapped(foot.arc, s_a, ta) * end;
        let edge_past = if end < 0.0 {
            step_a((run[0] + ma - 1) % ma)
        } else {
            step_a(run[run.len() - 1])
        };
        if past > 0.0 && past <= edge_past * (1.0 + FOOT_SLACK) {
            let extended_b = s_b + wrapped(outline_b.arc[k], s_b, tb);
            if end < 0.0 {
                a0 -= past;
                b0 = extended_b;
            } else {
                a1 += past;
                b1 = extended_b;
            }
        }
    }
    let smallest = SNAP * outline_a.median_edge().min(outline_b.median_edge());
    if (b1 - b0).abs() <= smallest || a1 - a0 <= smallest {
        return Ok(None);
    }
    // Both stretches' edges, before anything changes: another seam may hold them already.
    let edges_a = outline_a.edges_within(a0, a1 - a0, 1.0);
    let edges_b = outline_b.edges_within(b0, (b1 - b0).abs(), sign);
    if held(claims, a, b, edges_a.into_iter())? | held(claims, b, a, edges_b.into_iter())? {
        return Ok(None);
    }
    let locked_a = |x: u32, y: u32| claims.contains_key(&claim_key(a, x, y));
    let locked_b = |x: u32, y: u32| claims.contains_key(&claim_key(b, x, y));
    let [mesh_a, mesh_b] = two_mut(patches, a, b);
    let va0 = outline_a.vertex_at(mesh_a, a0, &locked_a, true);
    let va1 = outline_a.vertex_at(mesh_a, a1, &locked_a, false);
    let vb0 = outline_b.vertex_at(mesh_b, b0, &locked_b, forward);
    let vb1 = outline_b.vertex_at(mesh_b, b1, &locked_b, !forward);
    let path_a = outline_a.path(va0, va1, true);
    let path_b = outline_b.path(vb0, vb1, forward);
    if path_a.len() < 2 || path_b.len() < 2 || va0 == va1 || vb0 == vb1 {
        return Err(Error::invalid(format!(
            "the stretch where patches {a} and {b} meet collapses to a point once its ends land \
             on vertices: pass a smaller --reach, or seam whole loops with --seam"
        )));
    }
    let [vertices_a, vertices_b] = pair_paths([mesh_a, mesh_b], [path_a, path_b]);
    Ok(Some(Seam {
        patch_a: a,
        vertices_a,
        patch_b: b,
        vertices_b,
        whole_loop: false,
    }))
}

fn two_mut(patches: &mut [Mesh], a: usize, b: usize) -> [&mut Mesh; 2] {
    if a < b {
        let (low, high) = patches.split_at_mut(b);
        [&mut low[a], &mut high[0]]
    } else {
        let (low, high) = patches.split_at_mut(a);
        [&mut high[0], &mut low[b]]
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
    let lb = single_loop(&patches[b], b)?;
    loop_seam(patches, a, la, b, lb)
}

/// [`boundary_seam`] for the given loops of `a` and `b`.
fn loop_seam(
    patches: &mut [Mesh],
    a: usize,
    la: Vec<u32>,
    b: usize,
    lb0: Vec<u32>,
) -> Result<Seam> {
    let fa = arc_fractions(&patches[a].positions, &la);
    let pa = &patches[a].positions;
    let pb = &patches[b].positions;
    let m = lb0.len();
    let mut best = (f64::INFINITY, Vec::new(), 0.0);
    for reverse in [false, true] {
        for shift in 0..m {
            let lb: Vec<u32> = (0..m)
                .map(|k| {
                    lb0[if reverse {
                        (shift + m - k) % m
                    } else {
                        (shift + k) % m
                    }]
                })
                .collect();
            let fb = arc_fractions(pb, &lb);
            let (mut cost, mut gap) = (0.0, 0.0_f64);
            for (&v, &f) in la.iter().zip(&fa) {
                let d = distance(pa[v as usize], point_at(pb, &lb, &fb, f));
                cost += d * d;
                gap = gap.max(d);
            }
            if cost < best.0 {
                best = (cost, lb, gap);
            }
        }
    }
    let (_, lb, gap) = best;
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
    // Closed paths: the first vertex again at the end, fraction 1.
    let close = |mut l: Vec<u32>| {
        l.push(l[0]);
        l
    };
    let [mesh_a, mesh_b] = two_mut(patches, a, b);
    let [mut vertices_a, mut vertices_b] = pair_paths([mesh_a, mesh_b], [close(la), close(lb)]);
    vertices_a.pop();
    vertices_b.pop();
    Ok(Seam {
        patch_a: a,
        vertices_a,
        patch_b: b,
        vertices_b,
        whole_loop: true,
    })
}

/// Gives each of two boundary paths a vertex at every arc-length fraction of the other's
/// vertices (partners closer than a quarter of the shortest step pair up), splitting boundary
/// edges; returns both paths, now paired vertex by vertex.
fn pair_paths(meshes: [&mut Mesh; 2], mut paths: [Vec<u32>; 2]) -> [Vec<u32>; 2] {
    let fractions = [
        path_fractions(&meshes[0].positions, &paths[0]),
        path_fractions(&meshes[1].positions, &paths[1]),
    ];
    let step = fractions
        .iter()
        .flat_map(|f| f.windows(2).map(|w| w[1] - w[0]))
        .filter(|&s| s > 0.0)
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
    for (side, mesh) in meshes.into_iter().enumerate() {
        // From the end, so earlier fractions keep their edges.
        for &f in insert[side].iter().rev() {
            let fr = path_fractions(&mesh.positions, &paths[side]);
            let k = segment_at(&fr, f);
            let t = ((f - fr[k]) / (fr[k + 1] - fr[k]).max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
            let (p, q) = (
                mesh.positions[paths[side][k] as usize],
                mesh.positions[paths[side][k + 1] as usize],
            );
            let point = [0, 1, 2].map(|c| p[c] + t * (q[c] - p[c]));
            split_path_edge(mesh, &mut paths[side], k, point);
        }
    }
    debug_assert_eq!(paths[0].len(), paths[1].len());
    paths
}

/// Arc-length fraction of every vertex of an open path, 0 at the first and 1 at the last.
fn path_fractions(positions: &[[f64; 3]], path: &[u32]) -> Vec<f64> {
    let mut out = Vec::with_capacity(path.len());
    let mut total = 0.0;
    for (k, &v) in path.iter().enumerate() {
        if k > 0 {
            total += distance(positions[path[k - 1] as usize], positions[v as usize]);
        }
        out.push(total);
    }
    if total > 0.0 {
        out.iter_mut().for_each(|f| *f /= total);
    }
    out
}

/// The segment (index of its first vertex) of a path holding fraction `f`.
fn segment_at(fractions: &[f64], f: f64) -> usize {
    fractions
        .partition_point(|&x| x <= f)
        .saturating_sub(1)
        .min(fractions.len().saturating_sub(2))
}

/// Arc-length fraction of every loop vertex from the first (0) around the closed loop.
fn arc_fractions(positions: &[[f64; 3]], cycle: &[u32]) -> Vec<f64> {
    let outline = Outline::new(positions, cycle.to_vec());
    let total = outline.total;
    outline
        .arc
        .into_iter()
        .map(|s| if total > 0.0 { s / total } else { s })
        .collect()
}

/// The point at arc fraction `f` on the closed loop.
fn point_at(positions: &[[f64; 3]], cycle: &[u32], fractions: &[f64], f: f64) -> [f64; 3] {
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
    std::array::from_fn(|c| p[c] + t * (q[c] - p[c]))
}

fn single_loop(mesh: &Mesh, index: usize) -> Result<Vec<u32>> {
    let mut loops = boundary_loops(&mesh.triangles)?;
    if loops.len() != 1 {
        return Err(Error::invalid(format!(
            "patch {index} has {} boundary loops; a whole-loop seam needs exactly one (without \
             --seam, seams along stretches of loops are found)",
            loops.len()
        )));
    }
    Ok(loops.remove(0))
}

/// Splits the boundary edge from `path[k]` to `path[k + 1]` at `point`: its triangle becomes
/// two and the new vertex joins the path. Returns the new vertex.
fn split_path_edge(mesh: &mut Mesh, path: &mut Vec<u32>, k: usize, point: [f64; 3]) -> u32 {
    let (a, b) = (path[k], path[k + 1]);
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
    path.insert(k + 1, mid);
    mid
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh_graph::edge_report;
    use crate::parametric::test_meshes::quad_triangles;
    use crate::parametric::{orient_consistently, signed_volume, stitch};

    /// An `n × m` grid of quads over (u, v) ∈ [0, 1]², mapped by `at`, two triangles each.
    fn grid(n: usize, m: usize, at: impl Fn(f64, f64) -> [f64; 3]) -> Mesh {
        let mut positions = Vec::new();
        for j in 0..=m {
            for i in 0..=n {
                positions.push(at(i as f64 / n as f64, j as f64 / m as f64));
            }
        }
        Mesh {
            positions,
            triangles: quad_triangles(0..m, 0..n, |i, j| (j * (n + 1) + i) as u32),
        }
    }

    /// A disc of radius `r` at height `z`: `rings` rings of `sectors` vertices and a centre.
    fn disc(r: f64, z: f64, rings: usize, sectors: usize) -> Mesh {
        let mut positions = vec![[0.0, 0.0, z]];
        for ring in 1..=rings {
            let rho = r * ring as f64 / rings as f64;
            for s in 0..sectors {
                let a = std::f64::consts::TAU * s as f64 / sectors as f64;
                positions.push([rho * a.cos(), rho * a.sin(), z]);
            }
        }
        let id = |ring: usize, s: usize| (1 + (ring - 1) * sectors + s % sectors) as u32;
        let mut triangles = Vec::new();
        for s in 0..sectors {
            triangles.push([0, id(1, s), id(1, s + 1)]);
        }
        // Rings run along the grid's rows, sectors along its columns.
        triangles.extend(quad_triangles(0..sectors, 1..rings, id));
        Mesh {
            positions,
            triangles,
        }
    }

    /// The six faces of the cube [−1, 1]³, each pushed through `shape` (identity for the box)
    /// at its own resolution, so no two faces share their edge vertices.
    fn box_faces(shape: impl Fn([f64; 3]) -> [f64; 3]) -> Vec<Mesh> {
        let faces: [([f64; 3], [f64; 3], [f64; 3]); 6] = [
            ([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
            ([-1.0, -1.0, 1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
            ([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
            ([-1.0, 1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
            ([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
            ([1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
        ];
        faces
            .iter()
            .enumerate()
            .map(|(f, (o, du, dv))| {
                grid(5 + f, 7 + 2 * f, |u, v| {
                    shape([0, 1, 2].map(|c| o[c] + u * du[c] + v * dv[c]))
                })
            })
            .collect()
    }

    fn closed_and_oriented(mesh: &Mesh) {
        let report = edge_report(mesh);
        assert!(report.is_watertight(), "{report:?}");
        assert_eq!((report.non_manifold, report.misoriented), (0, 0));
        let mut triangles = mesh.triangles.clone();
        assert_eq!(orient_consistently(&mut triangles), 0);
    }

    #[test]
    fn six_faces_of_a_box_meet_along_partial_edges() {
        let mut patches = box_faces(|p| p);
        let seams = find_seams(&mut patches, &[], None).unwrap();
        // Every face loop meets four others, a stretch each: 12 edges of the cube.
        assert_eq!(seams.len(), 12);
        for seam in &seams {
            assert_eq!(seam.vertices_a.len(), seam.vertices_b.len());
        }
        let stitched = stitch(&patches, &seams).unwrap();
        closed_and_oriented(&stitched.mesh);
        // Partners closer than a quarter of the finer step pair up without a new vertex: 0.057
        // apart at most here, welded at their midpoints on the cube's edge.
        assert!(stitched.gap_before < 0.06, "{}", stitched.gap_before);
        // The least squares solve bends the faces a little where partners slide along the
        // edge (measured 7.992).
        let volume = signed_volume(&stitched.mesh);
        assert!((volume - 8.0).abs() < 0.02, "{volume}");
    }

    #[test]
    fn a_cube_pushed_onto_a_sphere_closes_to_the_ball() {
        // Curved seams: the faces of the box projected onto the unit sphere.
        let mut patches = box_faces(|p| {
            let n = dot(p, p).sqrt();
            p.map(|c| c / n)
        });
        let seams = find_seams(&mut patches, &[], None).unwrap();
        assert_eq!(seams.len(), 12);
        let stitched = stitch(&patches, &seams).unwrap();
        closed_and_oriented(&stitched.mesh);
        // A polyhedron inscribed in the ball: a little under 4π/3 = 4.19 (measured 4.11).
        let volume = signed_volume(&stitched.mesh);
        assert!(volume > 4.05 && volume < 4.19, "{volume}");
    }

    #[test]
    fn a_can_is_a_side_and_two_caps() {
        let (r, h) = (0.7, 2.0);
        let side = grid(48, 10, |u, v| {
            let a = std::f64::consts::TAU * u;
            [r * a.cos(), r * a.sin(), h * v]
        });
        // The grid's seam column is duplicated: weld it so the side is an open cylinder.
        let side = weld(&side);
        let mut patches = vec![disc(r, 0.0, 4, 36), side, disc(r, h, 5, 60)];
        assert_eq!(boundary_loops(&patches[1].triangles).unwrap().len(), 2);
        let seams = find_seams(&mut patches, &[], None).unwrap();
        assert_eq!(seams.len(), 2);
        let stitched = stitch(&patches, &seams).unwrap();
        closed_and_oriented(&stitched.mesh);
        let volume = signed_volume(&stitched.mesh);
        let truth = std::f64::consts::PI * r * r * h;
        assert!((volume - truth).abs() < 0.02 * truth, "{volume} vs {truth}");
    }

    #[test]
    fn a_side_meeting_two_patches_makes_an_l() {
        // [0, 2] × [0, 1] below, [0, 1] × [1, 2] above: the upper patch's lower side meets half
        // of the lower patch's upper side, a T-junction where the grids do not line up.
        let mut patches = vec![
            grid(9, 4, |u, v| [2.0 * u, v, 0.0]),
            grid(6, 7, |u, v| [u, 1.0 + v, 0.0]),
        ];
        let seams = find_seams(&mut patches, &[], None).unwrap();
        assert_eq!(seams.len(), 1);
        let stitched = stitch(&patches, &seams).unwrap();
        let report = edge_report(&stitched.mesh);
        assert_eq!((report.non_manifold, report.misoriented), (0, 0));
        let loops = boundary_loops(&stitched.mesh.triangles).unwrap();
        assert_eq!(loops.len(), 1);
        // The outline is the L: 2 + 1 + 1 + 1 + 1 + 2 long.
        let outline = Outline::new(&stitched.mesh.positions, loops[0].clone());
        assert!((outline.total - 8.0).abs() < 1e-9, "{}", outline.total);
    }

    #[test]
    fn a_third_sheet_on_a_seamed_loop_is_refused() {
        let sheet = |z: f64| grid(6, 6, move |u, v| [u, v, z * u * (1.0 - u) * v * (1.0 - v)]);
        let mut patches = vec![sheet(1.0), sheet(-1.0), sheet(0.5)];
        let e = find_seams(&mut patches, &[], None).unwrap_err().to_string();
        assert!(e.contains("three") && e.contains("--seam"), "{e}");
        // Two of them are fine.
        let mut two = vec![sheet(1.0), sheet(-1.0)];
        let seams = find_seams(&mut two, &[], None).unwrap();
        assert_eq!(seams.len(), 1);
        closed_and_oriented(&stitch(&two, &seams).unwrap().mesh);
    }

    #[test]
    fn a_fin_on_a_seamed_edge_is_refused_even_when_the_pairs_are_named() {
        // A sheet, its neighbour across x = 1, and a fin standing on that same edge.
        let mut patches = vec![
            grid(4, 4, |u, v| [u, v, 0.0]),
            grid(5, 4, |u, v| [1.0 + u, v, 0.0]),
            grid(3, 4, |u, v| [1.0, v, u]),
        ];
        let e = find_seams(&mut patches, &[[0, 1], [0, 2], [1, 2]], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("three"), "{e}");
        let e = find_seams(&mut patches, &[[0, 2], [1, 2]], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("three"), "{e}");
    }

    #[test]
    fn a_loop_with_one_vertex_off_is_still_seamed_whole() {
        let mut patches = vec![
            grid(8, 8, |u, v| [u, v, u * (1.0 - u) * v * (1.0 - v)]),
            grid(8, 8, |u, v| [u, v, -u * (1.0 - u) * v * (1.0 - v)]),
        ];
        // One boundary vertex of the second pushed inwards by most of an edge.
        patches[1].positions[4][1] += 0.1;
        let seams = find_seams(&mut patches, &[], None).unwrap();
        assert_eq!(seams.len(), 1);
        assert!(seams[0].whole_loop);
        closed_and_oriented(&stitch(&patches, &seams).unwrap().mesh);
    }

    #[test]
    fn a_narrow_strip_along_a_side_is_seamed_to_it() {
        // Every vertex of the strip touches the sheet; the sheet's stretches are followed.
        let mut patches = vec![
            grid(6, 6, |u, v| [u, v, 0.0]),
            grid(9, 1, |u, v| [u, 1.0 + 0.05 * v, 0.0]),
        ];
        let seams = find_seams(&mut patches, &[], None).unwrap();
        assert_eq!(seams.len(), 1, "{seams:?}");
        let stitched = stitch(&patches, &seams).unwrap();
        let report = edge_report(&stitched.mesh);
        assert_eq!((report.non_manifold, report.misoriented), (0, 0));
        assert_eq!(boundary_loops(&stitched.mesh.triangles).unwrap().len(), 1);
    }

    #[test]
    fn patches_apart_and_bad_options_find_no_seam_or_an_error() {
        let mut patches = vec![
            grid(4, 4, |u, v| [u, v, 0.0]),
            grid(4, 4, |u, v| [u + 3.0, v, 0.0]),
        ];
        assert!(find_seams(&mut patches, &[], None).unwrap().is_empty());
        for reach in [0.0, -1.0, f64::NAN] {
            assert!(find_seams(&mut patches, &[], Some(reach)).is_err());
        }
        assert!(find_seams(&mut patches, &[[0, 0]], None).is_err());
        assert!(find_seams(&mut patches, &[[0, 2]], None).is_err());
    }

    /// Merges vertices at the same position.
    fn weld(mesh: &Mesh) -> Mesh {
        let mut index: Vec<u32> = Vec::new();
        let mut positions: Vec<[f64; 3]> = Vec::new();
        for p in &mesh.positions {
            let found = positions.iter().position(|q| distance(*p, *q) < 1e-9);
            index.push(found.unwrap_or_else(|| {
                positions.push(*p);
                positions.len() - 1
            }) as u32);
        }
        Mesh {
            positions,
            triangles: mesh
                .triangles
                .iter()
                .map(|t| t.map(|v| index[v as usize]))
                .collect(),
        }
    }
}

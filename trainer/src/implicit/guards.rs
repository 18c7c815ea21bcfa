//! Placing sign guards (`neurosurf_core::implicit::guard`) where a trained network has the
//! wrong sign away from its data.
//!
//! A grid over everything the mesher searches (the points' bounding box grown by a tenth and
//! every leaf box, inflated as rendering inflates it) is checked point by point: farther than
//! [`GUARD_CLEARANCE`] of the diagonal from the sampled surface ([`Oracle::disk_distance`]),
//! does Φ have the sign of the points' winding number? Every wrong grid point is then covered
//! by a guard: the farthest uncovered one becomes a centre; its radius reaches to within the
//! clearance of the surface and stops short of every grid point near the surface or on the
//! other side; its amplitude outweighs, twice over, Φ at every wrong point it covers. A
//! guard's ball therefore lies on one side of the surface and only adds the sign that side
//! already has, and near the data Φ is the network's own.
//!
//! The check is as good as the winding number and the distance estimate: with very sparse
//! points (a spacing of several percent of the diagonal) both are uncertain near the surface,
//! which is why nothing closer than the clearance is touched.

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;

use neurosurf_core::implicit::{FieldGradient, ImplicitModel, LANES};
use neurosurf_core::scalar::ScalarKind;

use super::blob::to_blob;
use super::network::{Guard, ImplicitNetwork};
use super::oracle::Oracle;
use crate::caoen::TriangleTree;
use crate::quality::component_labels;
use crate::render::{Aabb, Field, extract_mesh};

/// How far a guard's support keeps from the sampled surface, and how far from it the grid is
/// checked, as a fraction of the bounding diagonal.
pub const GUARD_CLEARANCE: f64 = 0.02;
/// Cells along the longest side of the grid the guards are placed on and the mesh is checked
/// on: the resolution `neurosurf mesh` uses by default.
pub const GUARD_RESOLUTION: usize = 96;
/// The guard grid has at least this many cells along every side (a flat shape's thin side
/// too): finer than the 48 points per side of [`crate::quality::stray_surface`].
pub const GUARD_MIN_CELLS: usize = 64;
/// A guard covers the wrong grid points within this fraction of its radius.
const COVER: f64 = 0.7;
/// A guard outweighs Φ at the wrong points it covers by this factor.
const MARGIN: f64 = 2.0;
/// Far from the data Φ must be at least this many cells' worth of the slope on its side
/// (Φ ≈ s·d near a zero crossing at distance d).
const FAR_PUSH: f64 = 0.5;

/// Φ as seen from a side: positive when it has that side's sign.
fn toward(inside: bool, phi: f64) -> f64 {
    if inside { phi } else { -phi }
}

/// The checked grid: `counts` points per axis from `lo`, `spacing` apart along each axis.
struct Grid {
    lo: [f64; 3],
    /// The longest side over [`GUARD_RESOLUTION`]: the largest spacing.
    step: f64,
    spacing: [f64; 3],
    counts: [usize; 3],
}

impl Grid {
    /// [`GUARD_RESOLUTION`] cells along the longest side, and at least
    /// [`GUARD_MIN_CELLS`] along the others: a stray piece thin along the short side of a flat
    /// shape is caught as surely as the 48³ stray-surface test finds it.
    fn over(domain: &Aabb) -> Option<Grid> {
        let extent = [0, 1, 2].map(|k| domain.hi[k] - domain.lo[k]);
        let step = extent.iter().copied().fold(0.0, f64::max) / GUARD_RESOLUTION as f64;
        if !(step > 0.0 && step.is_finite()) {
            return None;
        }
        let spacing = extent.map(|e| step.min(e / GUARD_MIN_CELLS as f64).max(step * 1e-3));
        Some(Grid {
            lo: domain.lo,
            step,
            spacing,
            counts: [0, 1, 2].map(|k| (extent[k] / spacing[k]).ceil() as usize + 1),
        })
    }

    fn len(&self) -> usize {
        self.counts.iter().product()
    }

    /// The index of point `i` along each axis.
    fn index(&self, i: usize) -> [usize; 3] {
        let [nx, ny, _] = self.counts;
        [i % nx, (i / nx) % ny, i / (nx * ny)]
    }

    /// Whether point `i` is on the coarse grid: every second point along each axis, and the
    /// last.
    fn is_coarse(&self, i: usize) -> bool {
        let index = self.index(i);
        (0..3).all(|k| index[k].is_multiple_of(2) || index[k] + 1 == self.counts[k])
    }

    /// The corners of the coarse cell that holds point `i` (itself when it is coarse).
    fn coarse_corners(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let index = self.index(i);
        let [nx, ny, _] = self.counts;
        let span = [0, 1, 2].map(|k| {
            if index[k].is_multiple_of(2) || index[k] + 1 == self.counts[k] {
                (index[k], index[k])
            } else {
                (index[k] - 1, index[k] + 1)
            }
        });
        (0..8_usize).filter_map(move |corner| {
            let bit = |k: usize| corner >> k & 1 == 1;
            // Each distinct corner once.
            if (0..3).any(|k| bit(k) && span[k].0 == span[k].1) {
                return None;
            }
            let c = [0, 1, 2].map(|k| if bit(k) { span[k].1 } else { span[k].0 });
            Some(c[0] + nx * (c[1] + ny * c[2]))
        })
    }

    /// The grid points next to point `i` along each axis.
    fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> {
        let index = self.index(i);
        let counts = self.counts;
        let stride = [1, counts[0], counts[0] * counts[1]];
        (0..3).flat_map(move |k| {
            let below = (index[k] > 0).then(|| i - stride[k]);
            let above = (index[k] + 1 < counts[k]).then(|| i + stride[k]);
            below.into_iter().chain(above)
        })
    }

    fn point(&self, i: usize) -> [f64; 3] {
        let index = self.index(i);
        [0, 1, 2].map(|k| self.lo[k] + self.spacing[k] * index[k] as f64)
    }
}

/// The guards that give `network` the winding number's sign at every grid point of `domain`
/// farther than [`GUARD_CLEARANCE`]·`diagonal` from the points of `oracle` (at most `limit`,
/// farthest first).
pub fn place_guards(
    network: &ImplicitNetwork,
    oracle: &Oracle,
    domain: &Aabb,
    diagonal: f64,
    slope: f64,
    limit: usize,
) -> Vec<Guard> {
    let Some(grid) = Grid::over(domain) else {
        return Vec::new();
    };
    let clearance = GUARD_CLEARANCE * diagonal;
    // Φ this close to zero far from the data means a zero crossing within half a cell: a
    // piece too small for the grid to see.
    let push = FAR_PUSH * slope * grid.step;
    let distance: Vec<f64> = (0..grid.len())
        .into_par_iter()
        .map(|i| oracle.disk_distance(grid.point(i)).1)
        .collect();
    // Only where a guard of positive radius fits: one cell beyond the clearance.
    let far: Vec<bool> = distance
        .iter()
        .map(|&d| d >= clearance + grid.step)
        .collect();
    let probe = Probe::new(network);
    let mut inside = sides(oracle, &grid, &far);
    let jets = probe.grid(&grid, &far, &inside, push);
    let mut phi: Vec<f64> = jets.iter().map(|j| j.map_or(f64::NAN, |j| j.0)).collect();
    let mut distance = distance;
    let mut wrong: Vec<usize> = (0..grid.len())
        .filter(|&i| far[i] && inside[i].is_some_and(|s| toward(s, phi[i]) < push))
        .collect();
    // Points off the grid where a steep bump of the wrong sign hides between grid points,
    // appended after them.
    let hidden = hidden_crossings(&probe, &grid, &far, &inside, &jets, push);
    let mut extra = Vec::new();
    for q in hidden {
        let d = oracle.disk_distance(q).1;
        let Some(side) = side_of(oracle.winding(q)) else {
            continue;
        };
        let (value, gradient) = probe.at(q);
        if d < clearance + grid.step || toward(side, value) >= 0.0 {
            continue;
        }
        // The bump may peak anywhere within the cell: as wrong as the slope there allows.
        let value = value - if side { 1.0 } else { -1.0 } * norm(gradient) * norm(grid.spacing);
        wrong.push(grid.len() + extra.len());
        extra.push(q);
        distance.push(d);
        inside.push(Some(side));
        phi.push(value);
    }
    let point = |i: usize| {
        if i < grid.len() {
            grid.point(i)
        } else {
            extra[i - grid.len()]
        }
    };
    if wrong.is_empty() {
        return Vec::new();
    }
    // What no guard's ball may hold: points near the surface, and far points not clearly on
    // its side.
    let tree_of = |keep: &dyn Fn(usize) -> bool| {
        let points: Vec<[f64; 3]> = (0..grid.len())
            .filter(|&i| keep(i))
            .map(|i| grid.point(i))
            .collect();
        (!points.is_empty())
            .then(|| ImmutableKdTree::<f64, 3>::new_from_slice(&points).ok())
            .flatten()
    };
    let near = tree_of(&|i| distance[i] < clearance);
    let sides_trees = [
        tree_of(&|i| far[i] && inside[i] != Some(false)),
        tree_of(&|i| far[i] && inside[i] != Some(true)),
    ];
    let nearest = |tree: &Option<ImmutableKdTree<f64, 3>>, p: &[f64; 3]| {
        tree.as_ref().map_or(f64::INFINITY, |t| {
            t.query(p)
                .nearest_one::<SquaredEuclidean<f64>>()
                .execute()
                .distance
                .sqrt()
        })
    };
    let positions: Vec<[f64; 3]> = wrong.iter().map(|&i| point(i)).collect();
    let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(&positions) else {
        return Vec::new();
    };
    // Points with the wrong sign first, then points with too weak a sign; farthest first.
    let weak = |w: usize| inside[wrong[w]].is_some_and(|s| toward(s, phi[wrong[w]]) > 0.0);
    let mut order: Vec<usize> = (0..wrong.len()).collect();
    order.sort_by(|&a, &b| {
        weak(a)
            .cmp(&weak(b))
            .then(distance[wrong[b]].total_cmp(&distance[wrong[a]]))
    });
    let mut covered = vec![false; wrong.len()];
    let mut guards = Vec::new();
    for w in order {
        if covered[w] {
            continue;
        }
        if guards.len() >= limit {
            break;
        }
        let (i, centre) = (wrong[w], positions[w]);
        // The side the guard sits on: the opposite of the network's sign there.
        let side = inside[i] == Some(true);
        let blocked =
            nearest(&near, &centre).min(nearest(&sides_trees[usize::from(side)], &centre));
        let radius = (distance[i] - clearance).min(0.95 * blocked);
        if radius.is_nan() || radius <= 0.0 {
            continue;
        }
        let reach = COVER * radius;
        let found = tree
            .query(&centre)
            .within::<SquaredEuclidean<f64>>(reach * reach)
            .unsorted()
            .execute();
        let mut need = 0.0_f64;
        for f in found {
            let j = f.item as usize;
            if inside[wrong[j]] != Some(side) {
                continue;
            }
            covered[j] = true;
            let u = 1.0 - f.distance / (radius * radius);
            let deficit = push - toward(side, phi[wrong[j]]);
            need = need.max(MARGIN * deficit.max(0.0) / (u * u * u));
        }
        let magnitude = need.max(f64::EPSILON);
        guards.push(Guard {
            center: centre,
            inverse_radius: 1.0 / radius,
            amplitude: if side { magnitude } else { -magnitude },
        });
    }
    guards
}

/// Newton steps a hidden-crossing search takes from a grid point.
const HIDDEN_STEPS: usize = 4;

/// Points within half a cell of a far grid point where Φ has the wrong side's sign although
/// the grid point has the right one by more than `push`: a steep bump narrower than a cell
/// that no grid point lands in (a network can grow one from a single neuron). A grid point
/// is searched when the tangent plane of Φ there reaches the wrong sign within a cell
/// diagonal (a bump steepens toward its top); Newton steps toward Φ = −`push` on its side,
/// kept within the cell around it, find the bump.
fn hidden_crossings(
    probe: &Probe<'_>,
    grid: &Grid,
    far: &[bool],
    inside: &[Option<bool>],
    jets: &[Option<(f64, [f64; 3])>],
    push: f64,
) -> Vec<[f64; 3]> {
    let half = grid.spacing.map(|h| 0.5 * h);
    let reach = norm(grid.spacing);
    (0..grid.len())
        .into_par_iter()
        .filter_map(|i| {
            let side = inside[i]?;
            let (value, gradient) = jets[i]?;
            let ahead = toward(side, value);
            if !far[i] || ahead < push || ahead - norm(gradient) * reach >= 0.0 {
                return None;
            }
            // Only among grid points that are all right (or settled): next to a wrong or
            // weak one, the grid's own guards cover the place.
            let healthy = |j: usize| {
                far[j]
                    && inside[j] == Some(side)
                    && jets[j].is_none_or(|(v, _)| toward(side, v) >= push)
            };
            if !grid.neighbours(i).all(healthy) {
                return None;
            }
            let origin = grid.point(i);
            let target = if side { -push } else { push };
            let (mut x, mut v, mut g) = (origin, value, gradient);
            for _ in 0..HIDDEN_STEPS {
                let g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
                if !(g2 > 0.0 && g2.is_finite()) {
                    return None;
                }
                let t = (v - target) / g2;
                x = [0, 1, 2]
                    .map(|k| (x[k] - t * g[k]).clamp(origin[k] - half[k], origin[k] + half[k]));
                (v, g) = probe.at(x);
                if toward(side, v) < 0.0 {
                    return Some(x);
                }
            }
            None
        })
        .collect()
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// How far a stray piece's guards keep from the points, as a fraction of the diagonal (the
/// off-surface offset: the network fits the points far more closely than that).
pub const PIECE_SUPPORT: f64 = 0.01;
/// A piece guard's radius is this many times the distance to the farthest point it covers.
const PIECE_REACH: f64 = 1.1;
/// A stray piece's guard reaches at least this fraction of the way to the nearest point.
const STRAY_REACH: f64 = 0.5;
/// A bridge guard's radius, as a fraction of its distance to the nearest point.
const BRIDGE_REACH: f64 = 0.9;
/// How much farther than a stray piece's guard a bridge pushes Φ: a joint as thick as a mesh
/// cell or two, not a thread between the grid points.
const BRIDGE_PUSH: f64 = 2.0;
/// Samples along a bridge, as a fraction of [`PIECE_SUPPORT`].
const BRIDGE_STEP: f64 = 0.5;

/// Guards for the pieces of `network`'s zero set that the points do not explain: `field` is
/// the network's own (the core's, or a [`super::GridCache`]'s), meshed at [`GUARD_RESOLUTION`].
///
/// Each control point belongs to the piece with the nearest triangle. A piece no control point
/// belongs to is stray: guards on the winding number's side cover its vertices, the first at
/// its centroid when one reaches past the whole piece, then at the vertices farthest from the
/// points. A piece with points of its own that is not the largest is a part the network cut
/// off (a limb at a sparsely sampled joint): when the shortest segment to the largest piece
/// is shorter than the sample spacing there and nothing on it is clearly outside (by the
/// winding number, half a spacing or more from the points), inside guards along it join
/// them. Every guard stops [`PIECE_SUPPORT`] of the diagonal short of the points and pushes Φ
/// to its side by `push` where it is meant to; what no guard fits is left alone. Returns the
/// number of pieces found and the guards.
pub fn guard_stray_pieces<F: Field + ?Sized>(
    network: &ImplicitNetwork,
    field: &F,
    oracle: &Oracle,
    diagonal: f64,
    push: f64,
) -> (usize, Vec<Guard>) {
    let Ok(extracted) = extract_mesh(field, GUARD_RESOLUTION, &|_, _| {}) else {
        return (0, Vec::new());
    };
    let mesh = extracted.mesh;
    let (labels, count) = component_labels(&mesh);
    if count <= 1 {
        return (count, Vec::new());
    }
    let mut pieces: Vec<Vec<[f64; 3]>> = vec![Vec::new(); count];
    for (p, &label) in mesh.positions.iter().zip(&labels) {
        if let Some(piece) = pieces.get_mut(label as usize) {
            piece.push(*p);
        }
    }
    // A point's piece is the one whose surface passes nearest: the network's zero set goes
    // through its points, and a small piece a cell away can hold a nearer vertex.
    let piece_of: Vec<Option<usize>> = match TriangleTree::new(&mesh) {
        Ok(tree) => oracle
            .positions()
            .par_iter()
            .map(|&q| {
                let (t, _) = tree.nearest(q);
                let vertex = mesh.triangles.get(t)?[0];
                labels.get(vertex as usize).map(|&l| l as usize)
            })
            .collect(),
        Err(_) => return (count, Vec::new()),
    };
    let mut owners = vec![0_usize; count];
    for piece in piece_of.into_iter().flatten() {
        if let Some(o) = owners.get_mut(piece) {
            *o += 1;
        }
    }
    let mut volumes = vec![0.0_f64; count];
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| mesh.positions.get(v as usize).copied().unwrap_or([0.0; 3]));
        if let Some(v) = labels
            .get(t[0] as usize)
            .and_then(|&l| volumes.get_mut(l as usize))
        {
            *v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0;
        }
    }
    let guarding = Guarding {
        network,
        oracle,
        support: PIECE_SUPPORT * diagonal,
        push,
    };
    let mut guards = Vec::new();
    let main = (0..count).max_by_key(|&i| owners[i]).unwrap_or(0);
    for (i, piece) in pieces.iter().enumerate() {
        if i == main || piece.is_empty() {
            continue;
        }
        if owners[i] == 0 {
            // A closed piece winds counter-clockwise seen from Φ < 0: a positive volume
            // encloses inside (a blob, pushed outside), a negative one outside (a cavity,
            // pushed inside). The piece goes when what it encloses takes its surroundings'
            // sign, whatever the winding number says there.
            guarding.cover_stray(piece, volumes[i] < 0.0, &mut guards);
        } else {
            guarding.bridge(piece, &pieces[main], &mut guards);
        }
    }
    (count, guards)
}

/// What the piece guards share.
#[derive(Clone, Copy)]
struct Guarding<'a> {
    network: &'a ImplicitNetwork,
    oracle: &'a Oracle,
    /// How far every guard keeps from the points.
    support: f64,
    /// How far past zero a guard pushes Φ where it is meant to.
    push: f64,
}

impl Guarding<'_> {
    /// The largest guard radius at `centre`: up to [`PIECE_SUPPORT`] short of the points, or
    /// half way to them when that is farther (a small piece just under the surface).
    fn radius(&self, centre: [f64; 3]) -> f64 {
        let nearest = self.oracle.nearest(centre).1;
        (nearest - self.support).max(STRAY_REACH * nearest)
    }

    /// A guard at `centre` of `radius` on `side` that pushes Φ there by `push` at `probes`.
    fn guard(&self, centre: [f64; 3], radius: f64, side: bool, probes: &[[f64; 3]]) -> Guard {
        let mut need = 0.0_f64;
        for &q in probes.iter().chain([&centre]) {
            let t = distance(q, centre) / radius;
            let u = 1.0 - t * t;
            let deficit = self.push - toward(side, self.network.eval(q).0);
            need = need.max(MARGIN * deficit.max(0.0) / (u * u * u));
        }
        let magnitude = need.max(f64::EPSILON);
        Guard {
            center: centre,
            inverse_radius: 1.0 / radius,
            amplitude: if side { magnitude } else { -magnitude },
        }
    }

    /// Guards on `side` over a stray piece's vertices and the points between them and each
    /// centre.
    fn cover_stray(&self, piece: &[[f64; 3]], side: bool, guards: &mut Vec<Guard>) {
        let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(piece) else {
            return;
        };
        let n = piece.len() as f64;
        let centroid = [0, 1, 2].map(|k| piece.iter().map(|p| p[k]).sum::<f64>() / n);
        let mut vertices: Vec<(f64, usize)> = piece
            .iter()
            .enumerate()
            .map(|(i, p)| (self.oracle.nearest(*p).1, i))
            .collect();
        vertices.sort_by(|a, b| b.0.total_cmp(&a.0));
        let candidates = std::iter::once((None, centroid))
            .chain(vertices.iter().map(|&(_, i)| (Some(i), piece[i])));
        let mut covered = vec![false; piece.len()];
        let mut left = piece.len();
        for (vertex, centre) in candidates {
            if left == 0 {
                break;
            }
            if vertex.is_some_and(|i| covered[i]) {
                continue;
            }
            let radius = self.radius(centre);
            if radius <= 0.0 {
                continue;
            }
            let reach = radius / PIECE_REACH;
            let members: Vec<usize> = tree
                .query(&centre)
                .within::<SquaredEuclidean<f64>>(reach * reach)
                .unsorted()
                .execute()
                .into_iter()
                .map(|f| f.item as usize)
                .filter(|&i| !covered[i])
                .collect();
            // The centroid only when it covers the whole piece.
            if members.is_empty() || (vertex.is_none() && members.len() < piece.len()) {
                continue;
            }
            let probes: Vec<[f64; 3]> = members
                .iter()
                .flat_map(|&i| {
                    let p = piece[i];
                    [p, [0, 1, 2].map(|k| 0.5 * (p[k] + centre[k]))]
                })
                .collect();
            guards.push(self.guard(centre, radius, side, &probes));
            for &i in &members {
                covered[i] = true;
            }
            left -= members.len();
        }
    }

    /// Inside guards along the shortest segment from `piece` to `main`, when the segment is
    /// shorter than the sample spacing there and no sample on it that the winding number can
    /// judge is clearly outside.
    fn bridge(&self, piece: &[[f64; 3]], main: &[[f64; 3]], guards: &mut Vec<Guard>) {
        let Ok(tree) = ImmutableKdTree::<f64, 3>::new_from_slice(main) else {
            return;
        };
        let Some((from, to)) = piece
            .iter()
            .map(|p| {
                let found = tree
                    .query(p)
                    .nearest_one::<SquaredEuclidean<f64>>()
                    .execute();
                (found.distance, *p, main[found.item as usize])
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, p, q)| (p, q))
        else {
            return;
        };
        // A gap wider than the sample spacing there is the points' to resolve.
        let length = distance(from, to);
        let (nearest, _) = self
            .oracle
            .nearest([0, 1, 2].map(|k| 0.5 * (from[k] + to[k])));
        if length > self.oracle.gap(nearest) {
            return;
        }
        let steps = (length / (BRIDGE_STEP * self.support)).ceil().max(2.0) as usize;
        let samples: Vec<[f64; 3]> = (0..=steps)
            .map(|j| {
                let t = j as f64 / steps as f64;
                [0, 1, 2].map(|k| from[k] + t * (to[k] - from[k]))
            })
            .collect();
        // Nowhere clearly outside, where the winding number can tell: within half the
        // sample spacing of a point, sparse points' winding number is noise (at a body's
        // shoulder it reads −0.25 inside the torso).
        if samples.iter().any(|&q| {
            let (i, d) = self.oracle.nearest(q);
            d >= 0.5 * self.oracle.gap(i) && self.oracle.winding(q) < CLEAR_WINDING
        }) {
            return;
        }
        let mut covered = vec![false; samples.len()];
        for j in 0..samples.len() {
            if covered[j] {
                continue;
            }
            let centre = samples[j];
            // Up to the points themselves: a bridge joins surface the points already hold.
            let radius = BRIDGE_REACH * self.oracle.nearest(centre).1;
            if radius <= 0.0 {
                continue;
            }
            let reach = radius / PIECE_REACH;
            let members: Vec<usize> = (j..samples.len())
                .filter(|&m| distance(samples[m], centre) <= reach)
                .collect();
            let probes: Vec<[f64; 3]> = members.iter().map(|&m| samples[m]).collect();
            let thick = Guarding {
                push: BRIDGE_PUSH * self.push,
                ..*self
            };
            guards.push(thick.guard(centre, radius, true, &probes));
            for m in members {
                covered[m] = true;
            }
        }
    }
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Φ and ∇Φ of a guarded network: through the core in `f32` when the network makes a blob
/// (what `mesh` and the microcontroller evaluate); else the `f64` network.
struct Probe<'a> {
    network: &'a ImplicitNetwork,
    model: Option<Box<ImplicitModel<f32>>>,
}

impl<'a> Probe<'a> {
    fn new(network: &'a ImplicitNetwork) -> Self {
        let model = to_blob(network, None, ScalarKind::F32)
            .ok()
            .and_then(|blob| ImplicitModel::<f32>::from_blob(&blob).ok().map(Box::new));
        Probe { network, model }
    }

    fn at(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        match &self.model {
            Some(model) => {
                let g = model.field_gradient(p.map(|v| v as f32));
                (f64::from(g.value), g.gradient.map(f64::from))
            }
            None => self.network.eval(p),
        }
    }

    /// Φ and ∇Φ at the `far` grid points whose side is known, in batches; `None` elsewhere
    /// and where the grid is settled. Every second point along each axis comes first (and
    /// the last); a point between them is evaluated only when a corner of its coarse cell is
    /// not on the point's side by `push` all across the cell by its tangent plane. Elsewhere
    /// Φ keeps its side through the cell, as far as first order tells.
    fn grid(
        &self,
        grid: &Grid,
        far: &[bool],
        inside: &[Option<bool>],
        push: f64,
    ) -> Vec<Option<(f64, [f64; 3])>> {
        let mut out = vec![None; grid.len()];
        let wanted = |i: usize| far[i] && inside[i].is_some();
        let coarse: Vec<usize> = (0..grid.len())
            .filter(|&i| wanted(i) && grid.is_coarse(i))
            .collect();
        for (&i, jet) in coarse.iter().zip(self.batch(grid, &coarse)) {
            out[i] = Some(jet);
        }
        let across = 2.0 * norm(grid.spacing);
        let settled = |i: usize, side: bool| {
            grid.coarse_corners(i).all(|c| {
                inside[c] == Some(side)
                    && out[c].is_some_and(|(v, g)| toward(side, v) - norm(g) * across >= push)
            })
        };
        let fine: Vec<usize> = (0..grid.len())
            .into_par_iter()
            .filter(|&i| {
                wanted(i) && !grid.is_coarse(i) && inside[i].is_some_and(|s| !settled(i, s))
            })
            .collect();
        for (&i, jet) in fine.iter().zip(self.batch(grid, &fine)) {
            out[i] = Some(jet);
        }
        out
    }

    /// Φ and ∇Φ at the grid points `indices`.
    fn batch(&self, grid: &Grid, indices: &[usize]) -> Vec<(f64, [f64; 3])> {
        indices
            .par_chunks(LANES * 64)
            .flat_map_iter(|chunk| {
                let points: Vec<[f64; 3]> = chunk.iter().map(|&i| grid.point(i)).collect();
                match &self.model {
                    Some(model) => {
                        let points: Vec<[f32; 3]> =
                            points.iter().map(|p| p.map(|v| v as f32)).collect();
                        let zero = FieldGradient {
                            value: 0.0_f32,
                            gradient: [0.0; 3],
                        };
                        let mut out = vec![zero; points.len()];
                        if model.field_gradient_batch(&points, &mut out).is_err() {
                            out.fill(zero);
                        }
                        out.into_iter()
                            .map(|g| (f64::from(g.value), g.gradient.map(f64::from)))
                            .collect::<Vec<_>>()
                    }
                    None => points.iter().map(|&p| self.network.eval(p)).collect(),
                }
            })
            .collect()
    }
}

/// Winding numbers below this are clearly outside, and above one minus this clearly inside;
/// between, a point's side is unknown and no guard covers it.
const CLEAR_WINDING: f64 = 0.3;

/// The side a winding number `w` gives: `Some(true)` inside, `Some(false)` outside, `None`
/// when it is not clear.
fn side_of(w: f64) -> Option<bool> {
    if w > 1.0 - CLEAR_WINDING {
        Some(true)
    } else if w < CLEAR_WINDING {
        Some(false)
    } else {
        None
    }
}

/// The side of each `far` grid point by the winding number: `Some(true)` inside, `Some(false)`
/// outside, `None` when the winding number is not clear. It is computed exactly on every
/// second grid point along each axis; a far point between them takes their side when all
/// eight agree clearly (a feature thin enough to slip between them would have no far points
/// inside), else it is computed exactly too.
fn sides(oracle: &Oracle, grid: &Grid, far: &[bool]) -> Vec<Option<bool>> {
    let [nx, ny, nz] = grid.counts;
    let coarse = [nx, ny, nz].map(|n| n.div_ceil(2));
    let coarse_index = |c: [usize; 3]| c[0] + coarse[0] * (c[1] + coarse[1] * c[2]);
    let coarse_sides: Vec<Option<bool>> = (0..coarse.iter().product::<usize>())
        .into_par_iter()
        .map(|i| {
            let c = [
                i % coarse[0],
                (i / coarse[0]) % coarse[1],
                i / (coarse[0] * coarse[1]),
            ];
            let p = [0, 1, 2].map(|k| grid.lo[k] + grid.spacing[k] * (2 * c[k]) as f64);
            side_of(oracle.winding(p))
        })
        .collect();
    (0..grid.len())
        .into_par_iter()
        .map(|i| {
            if !far[i] {
                return None;
            }
            let f = [i % nx, (i / nx) % ny, i / (nx * ny)];
            let lo = f.map(|v| v / 2);
            let hi = [0, 1, 2].map(|k| (f[k].div_ceil(2)).min(coarse[k] - 1));
            let mut agreed: Option<Option<bool>> = None;
            for c in [0, 1, 2, 3, 4, 5, 6, 7] {
                let pick = |k: usize| if c >> k & 1 == 0 { lo[k] } else { hi[k] };
                let s = coarse_sides[coarse_index([pick(0), pick(1), pick(2)])];
                match agreed {
                    None => agreed = Some(s),
                    Some(a) if a == s => {}
                    Some(_) => {
                        agreed = Some(None);
                        break;
                    }
                }
            }
            match agreed.flatten() {
                Some(s) => Some(s),
                None => side_of(oracle.winding(grid.point(i))),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::tests::torus_points;
    use crate::implicit::to_blob;
    use crate::implicit::{ImplicitOptions, Trained, TreeSpec, train};
    use crate::points::PointSet;
    use crate::render::{CoreField, Region};
    use neurosurf_core::implicit::ImplicitModel;
    use neurosurf_core::implicit::MAX_GUARDS;
    use neurosurf_core::scalar::ScalarKind;

    /// `count` torus points and a one-leaf network trained on them.
    fn torus(count: usize, seed: u64) -> (PointSet, Trained) {
        let points = torus_points(count, seed);
        let trained = one_leaf(&points);
        (points, trained)
    }

    /// A one-leaf network trained on `points` with the default options.
    fn one_leaf(points: &PointSet) -> Trained {
        train(
            points,
            &TreeSpec::Leaf(0),
            &ImplicitOptions::default(),
            None,
            &|_| {},
        )
        .expect("training")
    }

    /// `network` through the core in `f32`, within `regions`.
    fn core_field(network: &ImplicitNetwork, regions: Vec<Region>) -> CoreField {
        let blob = to_blob(network, None, ScalarKind::F32).expect("blob");
        CoreField::new(&blob, regions).expect("field")
    }

    /// The pieces of `network`'s mesh within `regions`, as the guards see them.
    fn count_pieces(network: &ImplicitNetwork, regions: Vec<Region>) -> usize {
        let field = core_field(network, regions);
        let mesh = extract_mesh(&field, GUARD_RESOLUTION, &|_, _| {}).expect("mesh");
        component_labels(&mesh.mesh).1
    }

    /// A torus network with a blob grown on purpose (a guard of the wrong sign, outside the
    /// torus above its hole): placing guards must remove the blob and leave the field near
    /// the points untouched.
    #[test]
    fn guards_remove_a_blob_and_leave_the_surface_alone() {
        let (points, trained) = torus(400, 3);
        let blob = Guard {
            center: [0.0, 0.0, 0.8],
            inverse_radius: 1.0 / 0.3,
            amplitude: 5.0,
        };
        let broken = trained.network.clone().with_guards(vec![blob]);
        assert!(broken.eval(blob.center).0 > 0.0, "the blob is there");
        let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
        let domain = Aabb {
            lo: [-1.8, -1.8, -1.2],
            hi: [1.8, 1.8, 1.2],
        };
        let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
        let added = place_guards(&broken, &oracle, &domain, diagonal, 5.0, MAX_GUARDS);
        assert!(!added.is_empty());
        let one = place_guards(&broken, &oracle, &domain, diagonal, 5.0, 1);
        assert_eq!(one.len(), 1, "the limit holds");
        let fixed = broken
            .clone()
            .with_guards([vec![blob], added.clone()].concat());
        // The blob is gone: outside everywhere on a line through it.
        for k in 0..=20 {
            let p = [0.0, 0.0, 0.5 + 0.03 * f64::from(k)];
            assert!(fixed.eval(p).0 < 0.0, "{p:?}: {}", fixed.eval(p).0);
        }
        // No added guard reaches a control point or its off-surface points.
        for (p, n) in points.positions.iter().zip(&points.normals) {
            for offset in [-0.01, 0.0, 0.01] {
                let q = [0, 1, 2].map(|k| p[k] + offset * diagonal * n[k]);
                for g in &added {
                    assert_eq!(g.eval(q).0, 0.0, "{g:?} reaches {q:?}");
                }
            }
        }
        // Guards keep to their side: every added guard's centre is outside, like the blob.
        assert!(added.iter().all(|g| g.amplitude < 0.0), "{added:?}");
    }

    /// A steep bump inside out between grid points (narrower than a cell, as one saturated
    /// neuron can grow) is found off the grid and guarded.
    #[test]
    fn a_bump_between_grid_points_is_found() {
        let (points, trained) = torus(400, 3);
        let domain = Aabb {
            lo: [-1.8, -1.8, -1.2],
            hi: [1.8, 1.8, 1.2],
        };
        let grid = Grid::over(&domain).expect("grid");
        // The centre of a cell above the torus's hole: every grid point is half a cell
        // diagonal away.
        let centre = [0, 1, 2].map(|k| {
            let h = grid.spacing[k];
            let near = [0.0, 0.0, 0.9][k];
            domain.lo[k] + h * ((near - domain.lo[k]) / h).floor() + 0.5 * h
        });
        let reach = norm(grid.spacing);
        let phi = trained.network.eval(centre).0;
        assert!(phi < 0.0, "outside the torus");
        let bump = Guard {
            center: centre,
            inverse_radius: 1.0 / (0.6 * reach),
            amplitude: -1.5 * phi / (1.0_f64 - 0.09).powi(3),
        };
        let own = trained.network.guards().to_vec();
        let broken = trained
            .network
            .clone()
            .with_guards([own.clone(), vec![bump]].concat());
        assert!(broken.eval(centre).0 > 0.0, "the bump is there");
        for i in 0..grid.len() {
            assert!(
                broken.eval(grid.point(i)).0 <= 0.0 || trained.network.eval(grid.point(i)).0 > 0.0,
                "no grid point lands in the bump"
            );
        }
        let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
        let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
        let added = place_guards(&broken, &oracle, &domain, diagonal, 5.0, MAX_GUARDS);
        let fixed = broken
            .clone()
            .with_guards([own, vec![bump], added].concat());
        for k in -10..=10 {
            let t = 0.1 * f64::from(k) * reach;
            for axis in 0..3 {
                let mut p = centre;
                p[axis] += t;
                assert!(fixed.eval(p).0 < 0.0, "{p:?}: {}", fixed.eval(p).0);
            }
        }
    }

    /// Guards go into the blob and come back; the core adds them as the network does.
    #[test]
    fn guards_survive_the_blob_and_the_core_adds_them() {
        let (_, trained) = torus(200, 5);
        let guard = Guard {
            center: [0.25, 0.0, 0.75],
            inverse_radius: 4.0,
            amplitude: -2.0,
        };
        let network = trained.network.with_guards(vec![guard]);
        let bytes = to_blob(&network, None, ScalarKind::F32).expect("blob");
        let back =
            crate::implicit::from_blob(&bytes, std::path::Path::new("test.nsb")).expect("decode");
        assert_eq!(back.network.guards().len(), 1);
        let core = ImplicitModel::<f32>::from_blob(&bytes).expect("the core loads it");
        assert_eq!(core.guard_count(), 1);
        for p in [[0.25, 0.0, 0.75], [0.3, 0.1, 0.7], [1.0, 0.0, 0.0]] {
            let expected = network.eval(p).0;
            let got = f64::from(core.field(p.map(|v| v as f32)));
            assert!(
                (got - expected).abs() < 1e-4,
                "{p:?}: {got} against {expected}"
            );
        }
    }

    /// A small blob just off the surface, nearer than the grid check looks, is a piece of the
    /// mesh no control point supports: it gets a guard, and the mesh is one piece again.
    #[test]
    fn a_stray_piece_near_the_surface_gets_a_guard() {
        let (points, trained) = torus(400, 3);
        let blob = Guard {
            center: [1.0, 0.0, 0.53],
            inverse_radius: 1.0 / 0.05,
            amplitude: 3.0,
        };
        let broken = trained.network.clone().with_guards(vec![blob]);
        let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
        let half = [1.8, 1.8, 1.2];
        let regions = || {
            let normalization = crate::implicit::Normalization {
                center: [0.0; 3],
                matrix: [0, 1, 2]
                    .map(|r| [0, 1, 2].map(|c| if r == c { 1.0 / half[r] } else { 0.0 })),
            };
            Region::new(normalization, 2.0, 1.0)
                .into_iter()
                .collect::<Vec<_>>()
        };
        let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
        let pieces = |network: &ImplicitNetwork| count_pieces(network, regions());
        let clean = pieces(&trained.network);
        assert!(pieces(&broken) > clean, "the blob makes pieces of its own");
        let field = core_field(&broken, regions());
        let (found, added) = guard_stray_pieces(&broken, &field, &oracle, diagonal, 0.1);
        assert_eq!(found, pieces(&broken));
        assert!(!added.is_empty());
        let fixed = broken.with_guards([vec![blob], added].concat());
        // The blob's piece is gone (and any other piece no point belongs to): one torus.
        assert_eq!(pieces(&fixed), 1);
    }

    /// A part cut off at a gap narrower than the sample spacing (a limb at a sparsely sampled
    /// joint) is joined back by inside guards along the shortest gap.
    #[test]
    fn a_part_cut_off_at_a_narrow_gap_is_joined() {
        let axes = [1.5, 0.5, 0.5];
        let shape = crate::sample::Shape::Ellipsoid { axes };
        let mut points = crate::sample::sample_shape(&shape, 200, 4).expect("points");
        points.features = Some(vec![0; points.positions.len()]);
        let trained = one_leaf(&points);
        // A slab of outside bumps across the middle (x = 0), thinnest on the axis: two
        // halves, each with points of its own.
        let mut cut = trained.network.guards().to_vec();
        let step = 0.08;
        for i in -7..=7 {
            for j in -7..=7 {
                let (y, z) = (step * f64::from(i), step * f64::from(j));
                let r = y.hypot(z);
                if r <= 0.56 {
                    cut.push(Guard {
                        center: [0.0, y, z],
                        inverse_radius: 1.0 / (0.06 + 0.05 * r / 0.56),
                        amplitude: -50.0,
                    });
                }
            }
        }
        let broken = trained.network.clone().with_guards(cut.clone());
        assert!(broken.eval([0.0; 3]).0 < 0.0, "the slab cuts the middle");
        let oracle = Oracle::new(&points.positions, &points.normals).expect("oracle");
        let (nearest, _) = oracle.nearest([0.0, 0.0, 0.5]);
        assert!(
            oracle.gap(nearest) > 0.2,
            "the slab is narrower than the spacing"
        );
        let regions = || Region::of_network(&trained.network, 2.0, crate::render::DEFAULT_INFLATE);
        let pieces = |network: &ImplicitNetwork| count_pieces(network, regions());
        assert_eq!(pieces(&broken), 2, "two halves");
        let diagonal = 2.0 * (axes[0] * axes[0] + axes[1] * axes[1] + axes[2] * axes[2]).sqrt();
        let field = core_field(&broken, regions());
        let (found, added) = guard_stray_pieces(&broken, &field, &oracle, diagonal, 0.1);
        assert_eq!(found, 2);
        assert!(!added.is_empty());
        assert!(added.iter().all(|g| g.amplitude > 0.0), "inside guards");
        let fixed = broken.with_guards([cut, added].concat());
        assert_eq!(pieces(&fixed), 1, "joined");
    }

    /// A cavity carved inside the tube (where 96 torus points cannot tell the side by the
    /// winding number) is filled from inside: what a stray piece encloses takes its
    /// surroundings' sign.
    #[test]
    fn a_cavity_no_point_explains_is_filled() {
        let (points, trained) = torus(400, 3);
        let carve = Guard {
            center: [1.0, 0.0, 0.0],
            inverse_radius: 1.0 / 0.15,
            amplitude: -20.0,
        };
        let broken = trained.network.clone().with_guards(vec![carve]);
        assert!(broken.eval(carve.center).0 < 0.0, "the cavity is there");
        // Normals turned inward: the winding number now calls the tube outside, and the side
        // must come from the piece itself.
        let inward: Vec<[f64; 3]> = points.normals.iter().map(|n| n.map(|v| -v)).collect();
        let oracle = Oracle::new(&points.positions, &inward).expect("oracle");
        assert!(oracle.winding(carve.center) < CLEAR_WINDING);
        let regions = || Region::of_network(&trained.network, 2.0, crate::render::DEFAULT_INFLATE);
        let diagonal = 2.0 * (1.4_f64 * 1.4 * 2.0 + 0.4 * 0.4).sqrt();
        let pieces = |network: &ImplicitNetwork| count_pieces(network, regions());
        assert_eq!(
            pieces(&broken),
            2,
            "the cavity's wall is a piece of its own"
        );
        let field = core_field(&broken, regions());
        let (_, added) = guard_stray_pieces(&broken, &field, &oracle, diagonal, 0.1);
        assert!(!added.is_empty());
        assert!(added.iter().all(|g| g.amplitude > 0.0), "inside guards");
        let fixed = broken.with_guards([vec![carve], added].concat());
        assert_eq!(pieces(&fixed), 1);
        assert!(fixed.eval(carve.center).0 > 0.0, "filled");
    }
}

//! Guards for the pieces of the mesh the points do not explain, and bridges for the parts
//! the network cut off.

use super::*;

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
/// the network's own (the core's, or a [`crate::implicit::GridCache`]'s), meshed at [`GUARD_RESOLUTION`].
///
/// Each control point belongs to the piece with the nearest triangle. A piece no control point
/// belongs to is stray: guards on the winding number's side cover its vertices, the first at
/// its centroid when one reaches past the whole piece, then at the vertices farthest from the
/// points. A piece with points of its own that is not the largest is a part the network cut
/// off (a limb at a sparsely sampled joint): when the shortest segment to the largest piece
/// is shorter than the sample spacing there and nothing on it is clearly outside (by the
/// winding number, half a spacing or more from the points; not asked of a segment shorter
/// than a mesh cell), inside guards along it join them. Every guard stops [`PIECE_SUPPORT`] of the diagonal short of the points and pushes Φ
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
        cell: extracted.stats.cell_size,
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
    /// The mesh's cell side.
    cell: f64,
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
        // shoulder it reads −0.25 inside the torso). Pieces that meet within a mesh cell
        // touch at the mesh's resolution: a thin part pinched there (a scanned ear's tip)
        // reads outside by its few points' winding number, and is joined all the same.
        if length >= self.cell
            && samples.iter().any(|&q| {
                let (i, d) = self.oracle.nearest(q);
                d >= 0.5 * self.oracle.gap(i) && self.oracle.winding(q) < CLEAR_WINDING
            })
        {
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

//! The grid check: guards wherever Φ has the wrong sign away from the data.

use super::*;

/// A guard covers the wrong grid points within this fraction of its radius.
const COVER: f64 = 0.7;
/// A guard outweighs Φ at the wrong points it covers by this factor.
pub(super) const MARGIN: f64 = 2.0;
/// Far from the data Φ must be at least this many cells' worth of the slope on its side
/// (Φ ≈ s·d near a zero crossing at distance d).
const FAR_PUSH: f64 = 0.5;

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
    // Only where a guard of positive radius fits: one cell beyond the clearance. Most grid
    // points are surely that far (NaN here: distance not computed yet); the exact distance is
    // needed only below that, and for the points that get a guard (filled in below).
    let far_from = clearance + grid.step;
    let mut distance = grid.disk_distances_below(oracle, far_from);
    let far: Vec<bool> = distance
        .iter()
        .map(|&d| d.is_nan() || d >= far_from)
        .collect();
    let probe = Probe::new(network);
    let mut inside = sides(oracle, &grid, &far);
    let jets = probe.grid(&grid, &far, &inside, push);
    let mut phi: Vec<f64> = jets.iter().map(|j| j.map_or(f64::NAN, |j| j.0)).collect();
    let mut wrong: Vec<usize> = (0..grid.len())
        .filter(|&i| far[i] && inside[i].is_some_and(|s| toward(s, phi[i]) < push))
        .collect();
    for &i in &wrong {
        if distance[i].is_nan() {
            distance[i] = oracle.disk_distance(grid.point(i)).1;
        }
    }
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
    let near = GridSet::new(&grid, |i| distance[i] < clearance);
    let sides_sets = [
        GridSet::new(&grid, |i| far[i] && inside[i] != Some(false)),
        GridSet::new(&grid, |i| far[i] && inside[i] != Some(true)),
    ];
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
        let blocked = near
            .nearest(&grid, centre)
            .min(sides_sets[usize::from(side)].nearest(&grid, centre));
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

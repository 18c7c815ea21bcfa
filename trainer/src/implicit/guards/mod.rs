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

mod grid;
mod grid_set;
mod pieces;
mod place;
mod probe;
#[cfg(test)]
mod tests;

pub use pieces::{PIECE_SUPPORT, guard_stray_pieces};
pub use place::place_guards;

use grid::Grid;
use grid_set::GridSet;
use place::MARGIN;
use probe::Probe;

/// How far a guard's support keeps from the sampled surface, and how far from it the grid is
/// checked, as a fraction of the bounding diagonal.
pub const GUARD_CLEARANCE: f64 = 0.01;
/// Cells along the longest side of the grid the guards are placed on and the mesh is checked
/// on: the resolution the stray-surface and mesh-piece figures are measured at (`neurosurf
/// mesh --resolution 96`; its default, 128, is finer).
pub const GUARD_RESOLUTION: usize = 96;
/// The guard grid has at least this many cells along every side (a flat shape's thin side
/// too): finer than the 48 points per side of [`crate::quality::stray_surface`].
pub const GUARD_MIN_CELLS: usize = 64;

/// Φ as seen from a side: positive when it has that side's sign.
fn toward(inside: bool, phi: f64) -> f64 {
    if inside { phi } else { -phi }
}

fn norm(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
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

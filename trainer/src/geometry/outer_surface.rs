//! Which points of several triangle meshes lie on the outer surface of the whole: the part an
//! observer outside can reach.
//!
//! A shape built from overlapping closed parts (a teapot's body, lid, spout and handle) has
//! surface inside itself: the spout's root within the body, two caps pressed on each other.
//! Its outer surface is what bounds the space outside. It is found on a voxel grid: every cell
//! a triangle passes through is a wall, the cells reachable from the grid's border without
//! crossing a wall are outside, and a point is on the outer surface when a cell next to its
//! own (or its own) is outside. Gaps narrower than a cell are closed, and a point up to about
//! a cell and a half under the outer surface still counts as on it: the cell is the
//! tolerance, and callers state it.

use std::collections::VecDeque;

use crate::error::{Error, Result};
use crate::geometry::point_bounds;
use crate::io::Mesh;

/// The most cells along the grid's longest side (bounds memory: at most 512³ bytes).
pub const MAX_CELLS_PER_SIDE: usize = 512;

/// The outside of a set of meshes on a voxel grid (see the module documentation).
#[derive(Clone, Debug)]
pub struct OuterSurface {
    origin: [f64; 3],
    cell: f64,
    size: [usize; 3],
    /// Per cell: 0 free but enclosed, 1 wall, 2 outside.
    state: Vec<u8>,
}

const ENCLOSED: u8 = 0;
const WALL: u8 = 1;
const OUTSIDE: u8 = 2;

impl OuterSurface {
    /// Builds the grid over `meshes` with cells of side `cell` (two free cells of margin on
    /// every side).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when no mesh has a vertex, a coordinate is not finite, `cell`
    /// is not positive, or the grid would need more than [`MAX_CELLS_PER_SIDE`] cells a side.
    pub fn new(meshes: &[&Mesh], cell: f64) -> Result<OuterSurface> {
        if !(cell > 0.0 && cell.is_finite()) {
            return Err(Error::invalid(format!(
                "the outer-surface cell must be positive, got {cell}"
            )));
        }
        let bounds = point_bounds(meshes.iter().flat_map(|m| m.positions.iter()));
        if !(bounds.lo.iter().chain(&bounds.hi)).all(|v| v.is_finite()) {
            return Err(Error::invalid(
                "the meshes have no vertices, or a coordinate that is not finite",
            ));
        }
        let origin = bounds.lo.map(|v| v - 2.0 * cell);
        let size = [0, 1, 2].map(|k| ((bounds.hi[k] - bounds.lo[k]) / cell).ceil() as usize + 5);
        if size.iter().any(|&n| n > MAX_CELLS_PER_SIDE) {
            return Err(Error::invalid(format!(
                "an outer-surface cell of {cell} needs {size:?} cells; at most \
                 {MAX_CELLS_PER_SIDE} a side: use a larger cell"
            )));
        }
        let mut grid = OuterSurface {
            origin,
            cell,
            size,
            state: vec![ENCLOSED; size[0] * size[1] * size[2]],
        };
        for mesh in meshes {
            for t in &mesh.triangles {
                let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
                grid.wall_triangle(a, b, c);
            }
        }
        grid.flood();
        Ok(grid)
    }

    /// Whether `p` is on the outer surface: its cell or one of the 26 around it is outside.
    pub fn is_outer(&self, p: [f64; 3]) -> bool {
        let Some(centre) = self.cell_of(p) else {
            return true;
        };
        for dx in -1..=1_isize {
            for dy in -1..=1_isize {
                for dz in -1..=1_isize {
                    let at = [
                        centre[0] as isize + dx,
                        centre[1] as isize + dy,
                        centre[2] as isize + dz,
                    ];
                    if at
                        .iter()
                        .zip(&self.size)
                        .any(|(&v, &n)| v < 0 || v >= n as isize)
                    {
                        return true;
                    }
                    let at = at.map(|v| v as usize);
                    if self.state[self.index(at)] == OUTSIDE {
                        return true;
                    }
                }
            }
        }
        false
    }

    fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        (z * self.size[1] + y) * self.size[0] + x
    }

    fn cell_of(&self, p: [f64; 3]) -> Option<[usize; 3]> {
        let mut at = [0; 3];
        for k in 0..3 {
            let v = ((p[k] - self.origin[k]) / self.cell).floor();
            if !(v >= 0.0 && v < self.size[k] as f64) {
                return None;
            }
            at[k] = v as usize;
        }
        Some(at)
    }

    /// Marks every cell the triangle passes through, by samples a quarter cell apart.
    fn wall_triangle(&mut self, a: [f64; 3], b: [f64; 3], c: [f64; 3]) {
        let length =
            |u: [f64; 3], v: [f64; 3]| (0..3).map(|k| (u[k] - v[k]).powi(2)).sum::<f64>().sqrt();
        let longest = length(a, b).max(length(b, c)).max(length(c, a));
        let steps = ((4.0 * longest / self.cell).ceil() as usize).max(1);
        for i in 0..=steps {
            for j in 0..=steps - i {
                let (u, v) = (i as f64 / steps as f64, j as f64 / steps as f64);
                let p = [0, 1, 2].map(|k| a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]));
                if let Some(at) = self.cell_of(p) {
                    let i = self.index(at);
                    self.state[i] = WALL;
                }
            }
        }
    }

    /// Marks the free cells reachable from the border (six neighbours) as outside.
    fn flood(&mut self) {
        let [nx, ny, nz] = self.size;
        let mut queue = VecDeque::new();
        let visit = |grid: &mut OuterSurface, at: [usize; 3], queue: &mut VecDeque<[usize; 3]>| {
            let i = grid.index(at);
            if grid.state[i] == ENCLOSED {
                grid.state[i] = OUTSIDE;
                queue.push_back(at);
            }
        };
        for x in 0..nx {
            for y in 0..ny {
                for z in 0..nz {
                    if x == 0 || y == 0 || z == 0 || x == nx - 1 || y == ny - 1 || z == nz - 1 {
                        visit(self, [x, y, z], &mut queue);
                    }
                }
            }
        }
        while let Some([x, y, z]) = queue.pop_front() {
            if x > 0 {
                visit(self, [x - 1, y, z], &mut queue);
            }
            if x + 1 < nx {
                visit(self, [x + 1, y, z], &mut queue);
            }
            if y > 0 {
                visit(self, [x, y - 1, z], &mut queue);
            }
            if y + 1 < ny {
                visit(self, [x, y + 1, z], &mut queue);
            }
            if z > 0 {
                visit(self, [x, y, z - 1], &mut queue);
            }
            if z + 1 < nz {
                visit(self, [x, y, z + 1], &mut queue);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::caoen::icosphere;

    /// A unit sphere's mesh scaled by `r` and moved to `c`.
    fn ball(r: f64, c: [f64; 3]) -> Mesh {
        let mut m = icosphere(4).unwrap();
        for p in &mut m.positions {
            *p = [0, 1, 2].map(|k| c[k] + r * p[k]);
        }
        m
    }

    /// Two overlapping balls: the part of each inside the other is hidden, the rest is outer;
    /// a ball inside a hollow one is hidden whole.
    #[test]
    fn overlapping_and_nested_parts_hide_what_is_inside() {
        let (a, b) = (ball(1.0, [0.0; 3]), ball(1.0, [1.2, 0.0, 0.0]));
        let outer = OuterSurface::new(&[&a, &b], 0.02).unwrap();
        for p in &a.positions {
            let inside_b = ((p[0] - 1.2).powi(2) + p[1] * p[1] + p[2] * p[2]).sqrt();
            // Beyond the tolerance (1.5 cells each side), the answer is certain.
            if inside_b < 1.0 - 0.04 {
                assert!(!outer.is_outer(*p), "{p:?} is inside the other ball");
            } else if inside_b > 1.0 + 0.04 {
                assert!(outer.is_outer(*p), "{p:?} is outside the other ball");
            }
        }
        let (shell, core) = (ball(1.0, [0.0; 3]), ball(0.5, [0.1, 0.0, 0.0]));
        let outer = OuterSurface::new(&[&shell, &core], 0.02).unwrap();
        assert!(core.positions.iter().all(|&p| !outer.is_outer(p)));
        assert!(shell.positions.iter().all(|&p| outer.is_outer(p)));
    }

    /// An axis-aligned box from `lo` to `hi` (12 triangles).
    fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Mesh {
        let positions = (0..8)
            .map(|i| [0, 1, 2].map(|k| if i >> k & 1 == 1 { hi[k] } else { lo[k] }))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Mesh {
            positions,
            triangles,
        }
    }

    /// Two boxes stacked face to face: the faces pressed on each other are hidden, the rest
    /// of both is outer; a point inside either is hidden.
    #[test]
    fn faces_pressed_on_each_other_are_hidden() {
        let (a, b) = (
            cuboid([0.0; 3], [1.0; 3]),
            cuboid([0.0, 1.0, 0.0], [1.0, 2.0, 1.0]),
        );
        let outer = OuterSurface::new(&[&a, &b], 0.02).unwrap();
        for i in 1..10 {
            for j in 1..10 {
                let (u, v) = (f64::from(i) / 10.0, f64::from(j) / 10.0);
                assert!(!outer.is_outer([u, 1.0, v]), "shared face at {u}, {v}");
                assert!(outer.is_outer([u, 0.0, v]) && outer.is_outer([u, 2.0, v]));
                assert!(outer.is_outer([0.0, 2.0 * u, v]) && outer.is_outer([1.0, 2.0 * u, v]));
                assert!(!outer.is_outer([u, 0.5, v]) && !outer.is_outer([u, 1.5, v]));
            }
        }
    }

    #[test]
    fn bad_cells_and_empty_input_are_named() {
        let a = ball(1.0, [0.0; 3]);
        for cell in [0.0, -1.0, f64::NAN] {
            let e = OuterSurface::new(&[&a], cell).unwrap_err().to_string();
            assert!(e.contains("cell"), "{e}");
        }
        let e = OuterSurface::new(&[&a], 1e-4).unwrap_err().to_string();
        assert!(e.contains("larger cell"), "{e}");
        let e = OuterSurface::new(&[&Mesh::default()], 0.1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no vertices"), "{e}");
    }
}

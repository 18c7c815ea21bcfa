//! The octree of §6: the scene's bounding cube subdivided where the surface may be, and the
//! front-to-back walk of a ray through its leaf voxels.
//!
//! Two ways to decide where the surface may be:
//! - [`Octree::regions`] (the paper's): a voxel is kept while it meets an inflated leaf box
//!   and split until it is smaller than `ratio` × the smallest box it meets;
//!   [`Octree::regions_probed`] also drops leaf voxels where samples of Φ stay away from 0
//!   (the punctual renderer's tree: rays then skip empty space);
//! - [`Octree::bounded`] (guaranteed): a voxel is kept only if it meets a box *and* the interval
//!   bound of Φ over it contains 0, split to a fixed depth.

use rayon::prelude::*;

use super::field::Field;
use super::region::{Aabb, Region, bounds_of};

/// Deepest subdivision accepted.
pub const MAX_DEPTH: u32 = 10;

#[derive(Clone, Debug)]
struct Node {
    bounds: Aabb,
    /// Kept children (empty for a leaf voxel).
    children: Vec<u32>,
}

/// An octree of kept voxels.
#[derive(Clone, Debug)]
pub struct Octree {
    nodes: Vec<Node>,
    leaves: usize,
}

impl Octree {
    /// The paper's octree over `regions`: voxels meeting a region, split while larger than
    /// `ratio` times the smallest side of the regions they meet (and at most [`MAX_DEPTH`]
    /// times). `None` without regions.
    pub fn regions(regions: &[Region], ratio: f64) -> Option<Octree> {
        let cube = cube_around(&bounds_of(regions)?);
        Some(Octree::build(cube, &|voxel: &Aabb, depth: u32| {
            let meeting: Vec<&Region> = regions.iter().filter(|r| r.may_overlap(voxel)).collect();
            let smallest = meeting
                .iter()
                .map(|r| r.smallest_side())
                .fold(f64::INFINITY, f64::min);
            if meeting.is_empty() {
                Decision::Drop
            } else if depth < MAX_DEPTH && voxel.longest_side() > ratio * smallest {
                Decision::Split
            } else {
                Decision::Leaf
            }
        }))
    }

    /// [`Octree::regions`] without the voxels the surface does not seem to cross: Φ is
    /// sampled on a [`PROBE_GRID`]³ grid over each leaf voxel (the core's batches, voxels in
    /// parallel), and a voxel is kept when the samples change sign or when the smallest |Φ|
    /// is within [`PROBE_REACH`] grid steps of zero at the largest change of Φ between
    /// neighbouring samples. Like the punctual search this may miss surface thinner than a grid
    /// step; the guaranteed octree never does.
    pub fn regions_probed<F: Field + ?Sized>(field: &F, ratio: f64) -> Option<Octree> {
        let mut tree = Octree::regions(field.regions(), ratio)?;
        let leaves: Vec<usize> = (0..tree.nodes.len())
            .filter(|&i| {
                tree.nodes[i].children.is_empty() && tree.nodes[i].bounds.lo[0].is_finite()
            })
            .collect();
        let dropped: Vec<usize> = leaves
            .into_par_iter()
            .filter(|&i| !may_hold_surface(field, &tree.nodes[i].bounds))
            .collect();
        for i in dropped {
            tree.nodes[i].bounds = EMPTY;
            tree.leaves -= 1;
        }
        Some(tree)
    }

    /// The guaranteed octree: voxels meeting a region whose interval bound of Φ contains 0,
    /// split `depth` times. Fields without interval bounds keep every voxel meeting a region.
    pub fn bounded<F: Field + ?Sized>(field: &F, depth: u32) -> Option<Octree> {
        let regions = field.regions();
        let cube = cube_around(&bounds_of(regions)?);
        let depth = depth.min(MAX_DEPTH);
        Some(Octree::build(cube, &|voxel: &Aabb, level: u32| {
            let meets = regions.iter().any(|r| r.may_overlap(voxel));
            let may_cross = field
                .box_bounds(voxel.center(), voxel.half())
                .is_none_or(|b| b.contains_zero());
            if !(meets && may_cross) {
                Decision::Drop
            } else if level < depth {
                Decision::Split
            } else {
                Decision::Leaf
            }
        }))
    }

    fn build(cube: Aabb, decide: &dyn Fn(&Aabb, u32) -> Decision) -> Octree {
        let mut tree = Octree {
            nodes: vec![Node {
                bounds: cube,
                children: Vec::new(),
            }],
            leaves: 0,
        };
        match decide(&cube, 0) {
            Decision::Drop => tree.nodes.clear(),
            Decision::Leaf => tree.leaves = 1,
            Decision::Split => tree.split(0, 0, decide),
        }
        tree
    }

    fn split(&mut self, index: usize, depth: u32, decide: &dyn Fn(&Aabb, u32) -> Decision) {
        let parent = self.nodes[index].bounds;
        let mid = parent.center();
        for octant in 0..8 {
            let pick = |k: usize| octant >> k & 1 == 1;
            let child = Aabb {
                lo: std::array::from_fn(|k| if pick(k) { mid[k] } else { parent.lo[k] }),
                hi: std::array::from_fn(|k| if pick(k) { parent.hi[k] } else { mid[k] }),
            };
            let decision = decide(&child, depth + 1);
            if decision == Decision::Drop {
                continue;
            }
            let id = self.nodes.len();
            self.nodes.push(Node {
                bounds: child,
                children: Vec::new(),
            });
            self.nodes[index].children.push(id as u32);
            match decision {
                Decision::Split => self.split(id, depth + 1, decide),
                _ => self.leaves += 1,
            }
        }
        if self.nodes[index].children.is_empty() {
            // Every child was dropped: the node holds nothing; make it an empty interior node
            // by giving it no leaf status (walks skip it).
            self.nodes[index].bounds = EMPTY;
        }
    }

    /// Number of leaf voxels.
    pub fn leaf_count(&self) -> usize {
        self.leaves
    }

    /// The leaf voxels' boxes.
    pub fn leaf_boxes(&self) -> Vec<Aabb> {
        self.nodes
            .iter()
            .filter(|n| n.children.is_empty() && n.bounds.lo[0].is_finite())
            .map(|n| n.bounds)
            .collect()
    }

    /// Walks the leaf voxels the ray `origin + t·direction` (t ≥ 0) crosses, front to back,
    /// calling `search(voxel, [t_in, t_out])`; returns the first hit `search` reports. Leaves
    /// are disjoint, so when `search` only reports hits inside `[t_in, t_out]` the first is
    /// the nearest.
    pub fn first_hit<T>(
        &self,
        origin: [f64; 3],
        direction: [f64; 3],
        search: &mut dyn FnMut(&Aabb, [f64; 2]) -> Option<T>,
    ) -> Option<T> {
        let root = self.nodes.first()?;
        let span = root.bounds.ray_span(origin, direction, 0.0)?;
        let ray = Ray {
            origin,
            direction,
            inverse: direction.map(|d| 1.0 / d),
        };
        self.walk(0, span, &ray, search)
    }

    fn walk<T>(
        &self,
        index: usize,
        span: [f64; 2],
        ray: &Ray,
        search: &mut dyn FnMut(&Aabb, [f64; 2]) -> Option<T>,
    ) -> Option<T> {
        let node = &self.nodes[index];
        if node.children.is_empty() {
            return if node.bounds.lo[0].is_finite() {
                search(&node.bounds, span)
            } else {
                None
            };
        }
        // At most 8 children: sorted by entry on the stack, no allocation per ray.
        let mut order = [(0_usize, [0.0_f64; 2]); 8];
        let mut count = 0;
        for &c in &node.children {
            let c = c as usize;
            if let Some(s) =
                self.nodes[c]
                    .bounds
                    .ray_span_inverse(ray.origin, ray.direction, ray.inverse, 0.0)
                && let Some(slot) = order.get_mut(count)
            {
                *slot = (c, s);
                count += 1;
            }
        }
        let order = &mut order[..count];
        order.sort_unstable_by(|a, b| a.1[0].total_cmp(&b.1[0]));
        order
            .iter()
            .find_map(|&(c, s)| self.walk(c, s, ray, search))
    }
}

/// A ray with the reciprocals of its direction, computed once for its whole walk.
struct Ray {
    origin: [f64; 3],
    direction: [f64; 3],
    inverse: [f64; 3],
}

/// Samples per axis of a voxel's probe grid ([`Octree::regions_probed`]).
pub const PROBE_GRID: usize = 4;
/// How many grid steps away from zero a probed voxel may be and still be kept.
pub const PROBE_REACH: f64 = 1.5;

/// The bounds of a node that holds nothing (walks skip it).
const EMPTY: Aabb = Aabb {
    lo: [f64::NAN; 3],
    hi: [f64::NAN; 3],
};

/// Whether Φ sampled over `voxel` changes sign or comes within reach of zero.
fn may_hold_surface<F: Field + ?Sized>(field: &F, voxel: &Aabb) -> bool {
    const G: usize = PROBE_GRID;
    let at =
        |k: usize, i: usize| voxel.lo[k] + (voxel.hi[k] - voxel.lo[k]) * i as f64 / (G - 1) as f64;
    let points: Vec<[f64; 3]> = (0..G * G * G)
        .map(|i| [at(0, i % G), at(1, i / G % G), at(2, i / (G * G))])
        .collect();
    let mut phi = vec![f64::NAN; points.len()];
    field.values(&points, &mut phi);
    if phi.iter().any(|v| !v.is_finite()) {
        return true;
    }
    let (lo, hi) = phi
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if lo <= 0.0 && hi >= 0.0 {
        return true;
    }
    let mut largest_step = 0.0_f64;
    for i in 0..phi.len() {
        for stride in [1, G, G * G] {
            let neighbour = i + stride;
            let same_line = match stride {
                1 => i % G + 1 < G,
                s if s == G => i / G % G + 1 < G,
                _ => neighbour < phi.len(),
            };
            if same_line {
                largest_step = largest_step.max((phi[i] - phi[neighbour]).abs());
            }
        }
    }
    lo.abs().min(hi.abs()) <= PROBE_REACH * largest_step
}

#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum Decision {
    Drop,
    Leaf,
    Split,
}

/// The cube sharing `b`'s center whose side is `b`'s longest side.
fn cube_around(b: &Aabb) -> Aabb {
    let c = b.center();
    let h = 0.5 * b.longest_side();
    Aabb {
        lo: c.map(|v| v - h),
        hi: c.map(|v| v + h),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::field::SphereField;

    #[test]
    fn leaves_cover_the_region_and_walk_in_order() {
        let sphere = SphereField::new([0.5, 0.0, 0.0], 1.0, 5.0).unwrap();
        let tree = Octree::regions(sphere.regions(), 0.25).unwrap();
        assert!(tree.leaf_count() >= 64, "{}", tree.leaf_count());
        let mut entries = Vec::new();
        let hit = tree.first_hit([-5.0, 0.1, 0.05], [1.0, 0.0, 0.0], &mut |_, span| {
            entries.push(span[0]);
            None::<f64>
        });
        assert!(hit.is_none());
        assert!(entries.len() >= 4);
        assert!(entries.windows(2).all(|w| w[0] <= w[1]), "{entries:?}");
        // Interval pruning keeps only voxels near the sphere: fewer than the regions' tree
        // at the same depth.
        let bounded = Octree::bounded(&sphere, 4).unwrap();
        assert!(
            bounded.leaf_count() < 8_usize.pow(4) / 2,
            "{}",
            bounded.leaf_count()
        );
    }
}

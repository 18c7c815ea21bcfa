//! Where the surface is assumed to lie: the leaf modules' normalization boxes, inflated
//! (Carcenac §6, Fig. 5), and the axis-aligned boxes the octree and the mesher work with.

use crate::geometry::vector::{add, scale, sub};
use crate::implicit::{ImplicitNetwork, Normalization};

/// An axis-aligned box `[lo, hi]`.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub lo: [f64; 3],
    /// Upper corner.
    pub hi: [f64; 3],
}

impl Aabb {
    /// The box's center.
    pub fn center(&self) -> [f64; 3] {
        scale(add(self.lo, self.hi), 0.5)
    }

    /// Half the side lengths.
    pub fn half(&self) -> [f64; 3] {
        scale(sub(self.hi, self.lo), 0.5)
    }

    /// The longest side.
    pub fn longest_side(&self) -> f64 {
        let s = sub(self.hi, self.lo);
        s[0].max(s[1]).max(s[2])
    }

    /// Whether the two boxes overlap (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        (0..3).all(|k| self.lo[k] <= other.hi[k] && other.lo[k] <= self.hi[k])
    }

    /// The smallest box containing both.
    pub fn union(&self, other: &Aabb) -> Aabb {
        Aabb {
            lo: [0, 1, 2].map(|k| self.lo[k].min(other.lo[k])),
            hi: [0, 1, 2].map(|k| self.hi[k].max(other.hi[k])),
        }
    }

    /// The ray parameters `[t_in, t_out]` (t ≥ `t_min`) where `origin + t·direction` is inside,
    /// `None` when the ray misses (slab method; exact up to rounding).
    pub fn ray_span(&self, origin: [f64; 3], direction: [f64; 3], t_min: f64) -> Option<[f64; 2]> {
        self.ray_span_inverse(origin, direction, direction.map(|d| 1.0 / d), t_min)
    }

    /// [`Aabb::ray_span`] with each `1 / direction[k]` computed once per ray by the caller
    /// (`inverse`): the same result, without three divisions per box.
    pub fn ray_span_inverse(
        &self,
        origin: [f64; 3],
        direction: [f64; 3],
        inverse: [f64; 3],
        t_min: f64,
    ) -> Option<[f64; 2]> {
        let mut t_in = t_min;
        let mut t_out = f64::INFINITY;
        for k in 0..3 {
            if direction[k] == 0.0 {
                if origin[k] < self.lo[k] || origin[k] > self.hi[k] {
                    return None;
                }
                continue;
            }
            let inv = inverse[k];
            let a = (self.lo[k] - origin[k]) * inv;
            let b = (self.hi[k] - origin[k]) * inv;
            t_in = t_in.max(a.min(b));
            t_out = t_out.min(a.max(b));
        }
        (t_in <= t_out).then_some([t_in, t_out])
    }
}

/// A parallelepiped `{x : |A·(x − c)|∞ ≤ h}`: a leaf's normalization box `[−H/2, H/2]³`
/// mapped back to world space and grown by an inflation factor.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Region {
    /// The leaf's normalization (c and A).
    pub normalization: Normalization,
    /// Half side h in normalized coordinates (H/2 · inflation).
    pub half: f64,
    /// The world-space bounding box of the parallelepiped.
    pub bounds: Aabb,
}

impl Region {
    /// The region of a normalization box of side `box_size`, inflated by `inflate`; `None`
    /// when A is singular or not finite.
    pub fn new(normalization: Normalization, box_size: f64, inflate: f64) -> Option<Region> {
        let corners = normalization.world_corners(box_size, inflate)?;
        let mut bounds = Aabb {
            lo: corners[0],
            hi: corners[0],
        };
        for c in &corners[1..] {
            bounds = bounds.union(&Aabb { lo: *c, hi: *c });
        }
        let finite = bounds.lo.iter().chain(&bounds.hi).all(|v| v.is_finite());
        (finite && box_size > 0.0 && inflate > 0.0).then_some(Region {
            normalization,
            half: 0.5 * box_size * inflate,
            bounds,
        })
    }

    /// The inflated boxes of every leaf of `network`, for its normalization side `box_size`
    /// (the trainer's default is 2) grown by `inflate` (e.g. 1.2). Leaves whose
    /// normalization is singular are skipped.
    ///
    /// With several leaves, their common bounding box is one more region: the leaf boxes
    /// need not cover the inside of the shape between them, and an uncovered pocket would
    /// read as outside and close a cavity wall around itself. The trainer checks Φ's sign in
    /// that whole box ([`crate::implicit::place_guards`]).
    pub fn of_network(network: &ImplicitNetwork, box_size: f64, inflate: f64) -> Vec<Region> {
        let mut regions: Vec<Region> = (0..network.module_count())
            .filter(|&i| network.kinds()[i] == neurosurf_core::implicit::ModuleKind::Leaf)
            .filter_map(|i| network.normalization(i))
            .filter_map(|n| Region::new(n, box_size, inflate))
            .collect();
        if regions.len() > 1
            && let Some(around) = bounds_of(&regions).and_then(|b| Region::of_box(&b))
        {
            regions.push(around);
        }
        regions
    }

    /// The axis-aligned box `aabb` as a region; `None` when it has no extent.
    pub fn of_box(aabb: &Aabb) -> Option<Region> {
        let half = aabb.half();
        if half.iter().any(|&h| h.is_nan() || h <= 0.0) {
            return None;
        }
        let normalization = Normalization {
            center: aabb.center(),
            matrix: [0, 1, 2].map(|r| [0, 1, 2].map(|c| if r == c { 1.0 / half[r] } else { 0.0 })),
        };
        Region::new(normalization, 2.0, 1.0)
    }

    /// The shortest world-space side, 2h/|row| minimized over the rows of A (rows are
    /// orthogonal for the trainer's PCA boxes).
    pub fn smallest_side(&self) -> f64 {
        self.normalization
            .matrix
            .iter()
            .map(|row| {
                2.0 * self.half / (row[0] * row[0] + row[1] * row[1] + row[2] * row[2]).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether `p` is inside (boundary included).
    pub fn contains(&self, p: [f64; 3]) -> bool {
        self.normalization
            .apply(p)
            .iter()
            .all(|u| u.abs() <= self.half)
    }

    /// Whether the axis-aligned box may meet the region: its image under A is bounded by a
    /// box that must meet `[−h, h]³`, and its world box must meet [`Region::bounds`].
    /// Conservative: never false for boxes that meet the region.
    pub fn may_overlap(&self, b: &Aabb) -> bool {
        if !self.bounds.overlaps(b) {
            return false;
        }
        let center = self.normalization.apply(b.center());
        let half = b.half();
        self.normalization
            .matrix
            .iter()
            .zip(center)
            .all(|(row, c)| {
                let radius: f64 = (0..3).map(|k| row[k].abs() * half[k]).sum();
                c.abs() - radius <= self.half
            })
    }

    /// The ray parameters `[t_in, t_out]` (t ≥ `t_min`) inside the region, by the slab
    /// method in normalized coordinates.
    pub fn ray_span(&self, origin: [f64; 3], direction: [f64; 3], t_min: f64) -> Option<[f64; 2]> {
        let local = self.normalization.apply(origin);
        let m = &self.normalization.matrix;
        let slope: [f64; 3] = std::array::from_fn(|i| {
            m[i][0] * direction[0] + m[i][1] * direction[1] + m[i][2] * direction[2]
        });
        let cube = Aabb {
            lo: [-self.half; 3],
            hi: [self.half; 3],
        };
        cube.ray_span(local, slope, t_min)
    }
}

/// The box containing every region (`None` when there is none).
pub fn bounds_of(regions: &[Region]) -> Option<Aabb> {
    let first = regions.first()?.bounds;
    Some(regions.iter().fold(first, |b, r| b.union(&r.bounds)))
}

/// The sorted, merged spans `[t_in, t_out]` of a ray inside the union of `regions`.
pub fn ray_spans(regions: &[Region], origin: [f64; 3], direction: [f64; 3]) -> Vec<[f64; 2]> {
    let mut spans: Vec<[f64; 2]> = regions
        .iter()
        .filter_map(|r| r.ray_span(origin, direction, 0.0))
        .collect();
    spans.sort_by(|a, b| a[0].total_cmp(&b[0]));
    let mut merged: Vec<[f64; 2]> = Vec::with_capacity(spans.len());
    for s in spans {
        match merged.last_mut() {
            Some(last) if s[0] <= last[1] => last[1] = last[1].max(s[1]),
            _ => merged.push(s),
        }
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rotated() -> Region {
        let (c, s) = (0.5_f64.cos(), 0.5_f64.sin());
        // Rows: axes times scale 2 (a box of world side 1 for H = 2).
        let normalization = Normalization {
            center: [1.0, 2.0, 3.0],
            matrix: [
                [2.0 * c, 2.0 * s, 0.0],
                [-2.0 * s, 2.0 * c, 0.0],
                [0.0, 0.0, 2.0],
            ],
        };
        Region::new(normalization, 2.0, 1.0).unwrap()
    }

    #[test]
    fn spans_agree_with_membership() {
        let r = rotated();
        let origin = [-2.0, 0.5, 3.1];
        let direction = [3.0, 1.5, -0.1];
        let [a, b] = r.ray_span(origin, direction, 0.0).unwrap();
        let at = |t: f64| add(origin, scale(direction, t));
        assert!(r.contains(at(a + 1e-9)) && r.contains(at(b - 1e-9)));
        assert!(!r.contains(at(a - 1e-6)) && !r.contains(at(b + 1e-6)));
        assert!(r.may_overlap(&Aabb {
            lo: at(a + 0.01),
            hi: add(at(a + 0.01), [0.01; 3])
        }));
        assert!(!r.may_overlap(&Aabb {
            lo: [5.0; 3],
            hi: [6.0; 3]
        }));
    }

    #[test]
    fn overlapping_spans_merge() {
        let r = rotated();
        let mut shifted = r;
        shifted.normalization.center[0] += 0.5;
        let spans = ray_spans(&[shifted, r], [-5.0, 2.0, 3.0], [1.0, 0.0, 0.0]);
        assert_eq!(spans.len(), 1);
        assert!(spans[0][1] > spans[0][0]);
    }
}

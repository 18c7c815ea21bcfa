//! What the renderer and the mesher evaluate: a field Φ (> 0 inside, < 0 outside), its
//! gradient, the regions the surface is assumed to lie in, and optionally interval bounds.
//!
//! Four fields implement [`Field`]:
//! - [`CoreField`]: the core in `f32` — what a microcontroller computes, and the fastest
//!   (reverse-mode gradient, batches of 8 for the mesher). The punctual renderer uses it.
//! - [`NetworkField`]: the trainer's `f64` reference, with interval bounds through the module
//!   tree ([`super::interval`]); the guaranteed renderer needs those bounds, so it uses it.
//! - [`RbfField`]: the RBF baseline ([`RbfModel`]) in `f64` on the host, searched in its
//!   centres' grown bounding box, batches in parallel; no interval bounds.
//! - [`SphereField`]: Φ = s·(r − |x − c|), analytic, for tests.

use neurosurf_core::implicit::ImplicitModel;
use neurosurf_core::scalar::{Q16, Scalar};
use rayon::prelude::*;

use super::interval::{self, Interval};
use super::region::Region;
use crate::error::{Error, Result};
use crate::geometry::vector::{dot, norm, sub};
use crate::implicit::ImplicitNetwork;
use crate::rbf::RbfModel;

/// The normalization box side H the trainer uses by default (`ImplicitOptions::box_size`).
pub const DEFAULT_BOX_SIZE: f64 = 2.0;
/// How much the leaf boxes are grown for rendering (Carcenac: "slightly inflated").
pub const DEFAULT_INFLATE: f64 = 1.25;

/// A scalar field whose zero set is a surface.
pub trait Field: Sync {
    /// Φ at `p`.
    fn value(&self, p: [f64; 3]) -> f64;

    /// Φ and ∇Φ at `p`.
    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]);

    /// Where the surface is assumed to lie; nothing outside is searched.
    fn regions(&self) -> &[Region];

    /// Φ at many points (the core's batch API where available).
    fn values(&self, points: &[[f64; 3]], out: &mut [f64]) {
        for (p, o) in points.iter().zip(out) {
            *o = self.value(*p);
        }
    }

    /// Φ and ∇Φ at many points.
    fn value_gradients(&self, points: &[[f64; 3]], out: &mut [(f64, [f64; 3])]) {
        for (p, o) in points.iter().zip(out) {
            *o = self.value_gradient(*p);
        }
    }

    /// Bounds of Φ and dΦ/dt over the segment `origin + t·direction`, t ∈ `t`; `None` when
    /// the field has no interval evaluation.
    fn segment_bounds(
        &self,
        _origin: [f64; 3],
        _direction: [f64; 3],
        _t: Interval,
    ) -> Option<(Interval, Interval)> {
        None
    }

    /// Bounds of Φ over the box `center ± half`; `None` without interval evaluation.
    fn box_bounds(&self, _center: [f64; 3], _half: [f64; 3]) -> Option<Interval> {
        None
    }
}

/// The core's `f32` evaluation of a blob.
#[derive(Debug)]
pub struct CoreField {
    model: Box<ImplicitModel<f32>>,
    regions: Vec<Region>,
}

impl CoreField {
    /// Loads `blob` into the core (any stored scalar; parameters become `f32`) with the
    /// regions `regions` (see [`Region::of_network`]).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the core rejects the blob or there is no region.
    pub fn new(blob: &[u8], regions: Vec<Region>) -> Result<Self> {
        let model = ImplicitModel::<f32>::from_blob(blob)
            .map_err(|e| Error::invalid(format!("the core rejects the blob: {e}")))?;
        check_regions(&regions)?;
        Ok(CoreField {
            model: Box::new(model),
            regions,
        })
    }
}

/// Points per call of the core's batch API.
const BATCH: usize = neurosurf_core::implicit::LANES;

fn check_regions(regions: &[Region]) -> Result<()> {
    if regions.is_empty() {
        return Err(Error::invalid(
            "the model has no usable leaf normalization box to render in",
        ));
    }
    Ok(())
}

fn to_f32(p: [f64; 3]) -> [f32; 3] {
    p.map(|v| v as f32)
}

impl Field for CoreField {
    fn value(&self, p: [f64; 3]) -> f64 {
        f64::from(self.model.field(to_f32(p)))
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let fg = self.model.field_gradient(to_f32(p));
        (f64::from(fg.value), fg.gradient.map(f64::from))
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }

    fn values(&self, points: &[[f64; 3]], out: &mut [f64]) {
        for (points, out) in points.chunks(BATCH).zip(out.chunks_mut(BATCH)) {
            let mut input = [[0.0_f32; 3]; BATCH];
            let mut result = [0.0_f32; BATCH];
            let n = points.len().min(out.len());
            for (i, p) in input.iter_mut().zip(points) {
                *i = to_f32(*p);
            }
            if self
                .model
                .field_batch(&input[..n], &mut result[..n])
                .is_ok()
            {
                for (o, r) in out.iter_mut().zip(result) {
                    *o = f64::from(r);
                }
            }
        }
    }

    fn value_gradients(&self, points: &[[f64; 3]], out: &mut [(f64, [f64; 3])]) {
        let input: Vec<[f32; 3]> = points.iter().map(|&p| to_f32(p)).collect();
        let mut result = vec![Default::default(); input.len()];
        if self.model.field_gradient_batch(&input, &mut result).is_ok() {
            for (o, r) in out.iter_mut().zip(result) {
                *o = (f64::from(r.value), r.gradient.map(f64::from));
            }
        }
    }
}

/// The core's Q16.16 evaluation of a blob (points saturated into Q16.16 as the target takes
/// them), for measuring what fixed point does to a surface; one point at a time.
#[derive(Debug)]
pub struct Q16Field {
    model: Box<ImplicitModel<Q16>>,
    regions: Vec<Region>,
}

impl Q16Field {
    /// Loads `blob` into the core in Q16.16 with the regions `regions`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the core rejects the blob in Q16.16 or there is no region.
    pub fn new(blob: &[u8], regions: Vec<Region>) -> Result<Self> {
        let model = ImplicitModel::<Q16>::from_blob(blob)
            .map_err(|e| Error::invalid(format!("the core rejects the blob in Q16.16: {e}")))?;
        check_regions(&regions)?;
        Ok(Q16Field {
            model: Box::new(model),
            regions,
        })
    }
}

fn to_q16(p: [f64; 3]) -> [Q16; 3] {
    p.map(|v| Q16::from_f32_saturating(v as f32))
}

impl Field for Q16Field {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.model.field(to_q16(p)).to_f64()
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let fg = self.model.field_gradient(to_q16(p));
        (fg.value.to_f64(), fg.gradient.map(Scalar::to_f64))
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }
}

/// The trainer's `f64` network, with interval bounds.
#[derive(Debug)]
pub struct NetworkField<'a> {
    network: &'a ImplicitNetwork,
    regions: Vec<Region>,
}

impl<'a> NetworkField<'a> {
    /// The network with its leaf boxes of side `box_size` inflated by `inflate`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when no leaf has a usable box.
    pub fn new(network: &'a ImplicitNetwork, box_size: f64, inflate: f64) -> Result<Self> {
        let regions = Region::of_network(network, box_size, inflate);
        check_regions(&regions)?;
        Ok(NetworkField { network, regions })
    }
}

impl Field for NetworkField<'_> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.network.eval(p).0
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.network.eval(p)
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }

    fn segment_bounds(
        &self,
        origin: [f64; 3],
        direction: [f64; 3],
        t: Interval,
    ) -> Option<(Interval, Interval)> {
        Some(interval::segment_bounds(self.network, origin, direction, t))
    }

    fn box_bounds(&self, center: [f64; 3], half: [f64; 3]) -> Option<Interval> {
        Some(interval::box_bounds(self.network, center, half))
    }
}

/// Φ = s·(r − |x − c|): a sphere of radius r, slope s at the surface, region a cube of side
/// 2.5·r around it.
#[derive(Clone, Debug)]
pub struct SphereField {
    center: [f64; 3],
    radius: f64,
    slope: f64,
    regions: Vec<Region>,
}

impl SphereField {
    /// The sphere; `None` unless radius and slope are positive and everything is finite.
    pub fn new(center: [f64; 3], radius: f64, slope: f64) -> Option<Self> {
        let ok = radius > 0.0 && slope > 0.0 && center.iter().all(|c| c.is_finite());
        let normalization = crate::implicit::Normalization {
            center,
            matrix: [
                [1.0 / radius, 0.0, 0.0],
                [0.0, 1.0 / radius, 0.0],
                [0.0, 0.0, 1.0 / radius],
            ],
        };
        let region = Region::new(normalization, 2.0, 1.25)?;
        ok.then(|| SphereField {
            center,
            radius,
            slope,
            regions: vec![region],
        })
    }

    /// The exact first intersection of a ray (unit `direction`) with the sphere, t ≥ 0.
    pub fn exact_hit(&self, origin: [f64; 3], direction: [f64; 3]) -> Option<f64> {
        let oc = sub(origin, self.center);
        let b = dot(oc, direction);
        let c = dot(oc, oc) - self.radius * self.radius;
        let disc = b * b - c;
        if disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        [-b - root, -b + root].into_iter().find(|&t| t >= 0.0)
    }
}

impl Field for SphereField {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.slope * (self.radius - norm(sub(p, self.center)))
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let d = sub(p, self.center);
        let r = norm(d);
        let g = if r > 0.0 {
            d.map(|v| -self.slope * v / r)
        } else {
            [0.0; 3]
        };
        (self.slope * (self.radius - r), g)
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }

    fn segment_bounds(
        &self,
        origin: [f64; 3],
        direction: [f64; 3],
        t: Interval,
    ) -> Option<(Interval, Interval)> {
        // |x(t) − c| over a segment: the endpoints bound the maximum, the closest point of
        // the segment the minimum.
        let oc = sub(origin, self.center);
        let dd = dot(direction, direction);
        let closest = if dd > 0.0 {
            -dot(oc, direction) / dd
        } else {
            t.lo
        };
        let at = |s: f64| norm([0, 1, 2].map(|k| oc[k] + s * direction[k]));
        let near = at(closest.clamp(t.lo, t.hi));
        let far = at(t.lo).max(at(t.hi));
        let speed = dd.sqrt() * self.slope;
        Some((
            Interval::new(
                self.slope * (self.radius - far),
                self.slope * (self.radius - near),
            )
            .widen(interval::ROUNDING_MARGIN),
            Interval::new(-speed, speed),
        ))
    }

    fn box_bounds(&self, center: [f64; 3], half: [f64; 3]) -> Option<Interval> {
        let gap: [f64; 3] = std::array::from_fn(|k| (center[k] - self.center[k]).abs());
        let near = norm(std::array::from_fn(|k| (gap[k] - half[k]).max(0.0)));
        let far = norm(std::array::from_fn(|k| gap[k] + half[k]));
        Some(
            Interval::new(
                self.slope * (self.radius - far),
                self.slope * (self.radius - near),
            )
            .widen(interval::ROUNDING_MARGIN),
        )
    }
}

/// How much an RBF's centres' bounding box is grown for rendering and meshing by default:
/// each half-side × 1.1.
pub const DEFAULT_RBF_INFLATE: f64 = 1.1;

/// Points per task of [`RbfField`]'s parallel batches (one point costs O(centres): about
/// 10 µs for the 4 500 centres of a 1 500-point fit).
const RBF_CHUNK: usize = 16;

/// The RBF baseline ([`RbfModel`]), evaluated in `f64` on the host (the no-std core does not
/// evaluate RBFs): its one region is the centres' bounding box — control points and their
/// off-surface points — grown by an inflation factor, each half-side at least 1 % of the
/// box's diagonal. No interval bounds (the guaranteed renderer cannot use it); batches run
/// in parallel.
#[derive(Debug)]
pub struct RbfField<'a> {
    model: &'a RbfModel,
    regions: Vec<Region>,
}

impl<'a> RbfField<'a> {
    /// The model with its centres' bounding box scaled by `inflate` (≥ 1, e.g.
    /// [`DEFAULT_RBF_INFLATE`]) about its centre.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the centres span no volume or `inflate` is not a finite
    /// number of at least 1.
    pub fn new(model: &'a RbfModel, inflate: f64) -> Result<Self> {
        if !(inflate.is_finite() && inflate >= 1.0) {
            return Err(Error::invalid(format!(
                "the RBF's box inflation must be at least 1, got {inflate}"
            )));
        }
        let (lo, hi) = model.bounds();
        let floor = 0.01 * norm(sub(hi, lo));
        let half: [f64; 3] = std::array::from_fn(|k| (0.5 * (hi[k] - lo[k])).max(floor));
        let normalization = crate::implicit::Normalization {
            center: std::array::from_fn(|k| 0.5 * (lo[k] + hi[k])),
            matrix: std::array::from_fn(|r| {
                std::array::from_fn(|c| if r == c { 1.0 / half[r] } else { 0.0 })
            }),
        };
        let regions: Vec<Region> = Region::new(normalization, 2.0, inflate)
            .into_iter()
            .filter(|_| floor > 0.0)
            .collect();
        if regions.is_empty() {
            return Err(Error::invalid(
                "the RBF's centres span no volume to search its surface in",
            ));
        }
        Ok(RbfField { model, regions })
    }
}

impl Field for RbfField<'_> {
    fn value(&self, p: [f64; 3]) -> f64 {
        self.model.field(p)
    }

    fn value_gradient(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.model.field_gradient(p)
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }

    fn values(&self, points: &[[f64; 3]], out: &mut [f64]) {
        points
            .par_chunks(RBF_CHUNK)
            .zip(out.par_chunks_mut(RBF_CHUNK))
            .for_each(|(points, out)| {
                for (p, o) in points.iter().zip(out) {
                    *o = self.model.field(*p);
                }
            });
    }

    fn value_gradients(&self, points: &[[f64; 3]], out: &mut [(f64, [f64; 3])]) {
        points
            .par_chunks(RBF_CHUNK)
            .zip(out.par_chunks_mut(RBF_CHUNK))
            .for_each(|(points, out)| {
                for (p, o) in points.iter().zip(out) {
                    *o = self.model.field_gradient(*p);
                }
            });
    }
}

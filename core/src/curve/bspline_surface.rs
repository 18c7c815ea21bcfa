//! The validated B-spline tensor-product surface: loading and evaluation of position,
//! partial derivatives and unit normal.

use heapless::Vec;

use super::bspline_curve::at;
use super::control::{self, POINT_BYTES};
use super::direction::{Direction, MAX_ORDER};
use super::payload::SurfacePayload;
use crate::blob::ModelKind;
use crate::error::BlobError;
use crate::scalar::{Scalar, ScalarKind, normalize3};

/// Default control-point capacity of [`BSplineSurface`]: 1024 points (a 32 × 32 net, 12 KiB
/// in `f32`).
pub const DEFAULT_SURFACE_POINTS: usize = 1024;

/// Position and partial derivatives of a surface at one parameter pair.
#[derive(Copy, Clone, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SurfacePoint<S> {
    /// S(u, v).
    pub position: [S; 3],
    /// ∂S/∂u (including the factor `segments_u`; saturated in Q16.16).
    pub du: [S; 3],
    /// ∂S/∂v (including the factor `segments_v`; saturated in Q16.16).
    pub dv: [S; 3],
}

/// The 4 × 4 control points of one patch, as differences from its anchor P₁₁: `[j][k]` is
/// row v + j, column u + k.
type Patch<S> = [[[S; 3]; 4]; 4];

/// The control points of one patch of any degree, as differences from its anchor.
type WidePatch<S> = [[[S; 3]; MAX_ORDER]; MAX_ORDER];

/// A uniform tensor-product B-spline surface of degree 2 to 5 along each direction (bicubic
/// by default), loaded from a blob and validated (see
/// [`crate::curve`] for the contract and the payload).
///
/// `C` is the control-point capacity (count_u·count_v) reserved inline. Evaluation after a
/// successful load cannot fail. Parameters are `[u, v]`, each clamped to [0, 1] (NaN counts
/// as 0).
///
/// # Accuracy
///
/// Against an `f64` evaluation at the same parameters, with Δ the largest coordinate
/// difference between the patch's 16 control points and its anchor P₁₁, M their largest
/// coordinate magnitude, g the segment count of the direction, ε = 2⁻²⁴, LSB = 2⁻¹⁶, and for
/// normals κ = (Δ/|S_u| + Δ/|S_v| + 1)/sin θ (S_u, S_v the partials of the local parameters, θ
/// the angle between them). Bounds asserted by `core/tests/curve_surface.rs` on random nets of
/// 4 to 12 points per direction, open and closed, coordinates up to ±300; the largest measured
/// error over 5 × 600 nets in parentheses:
///
/// - `f32`: position within 3·ε·(M + Δ) (2.3), partials within 5·ε·g·Δ (3.1), normal within
///   4·ε·κ radians (1.2; at most 6·10⁻⁷ rad where κ < 10).
/// - Q16.16: position within 6 LSB·Δ + ½ LSB (3.5); partials within 5 LSB·g·Δ + ½ LSB (3.6),
///   saturating at ±32 768 (unlike a curve's tangent their error grows with g: the tensor
///   weights g·Bⱼ′(v)·Bₖ(u) carry Bₖ's rounding times g); normal within 5 LSB·κ radians (3.0;
///   at most 2.8·10⁻⁴ rad where κ < 10).
///
/// Surfaces of other degrees (2 to 5 along each direction) evaluate by the curves' any-degree
/// recurrence, within the bounds of `core/tests/curve_degree.rs` (Q16.16 position within
/// 8 LSB·(Δ + 1), partials within 8 LSB·g·(Δ + 1)).
///
/// A constant net gives its constant, zero partials and no normal, exactly; a net in the plane
/// z = 0 gives the normal (0, 0, ±1) (exactly, at every point the tests try).
///
/// ```
/// # use neurosurf_core::curve::{BSplineSurface, SurfacePayload};
/// # use neurosurf_core::scalar::{Q16, Scalar, ScalarKind};
/// # fn main() -> Result<(), neurosurf_core::BlobError> {
/// # let blob = example_blob();
/// let surface = BSplineSurface::<f32>::from_blob(&blob)?;
/// let fixed = BSplineSurface::<Q16>::from_blob(&blob)?;
/// let n = surface.normal([0.5, 0.5]).unwrap();
/// assert!((n[2] - 1.0).abs() < 1e-6); // a plane z = 0 facing +z
/// let q = fixed.normal([Q16::from_num(0.5); 2]).unwrap();
/// assert!((q[2].to_f32() - 1.0).abs() < 1e-3);
/// assert_eq!(surface.segments(), [1, 2]);
/// # Ok(())
/// # }
/// # fn example_blob() -> Vec<u8> {
/// #     let mut control = Vec::new();
/// #     for v in 0..5 { for u in 0..4 { for c in [f64::from(u), f64::from(v), 0.0] {
/// #         control.extend_from_slice(&ScalarKind::Q16_16.encode(c).unwrap());
/// #     } } }
/// #     let payload = SurfacePayload {
/// #         closed_u: false, closed_v: false, degree_u: 3, degree_v: 3, count_u: 4, count_v: 5,
/// #         frame: neurosurf_core::frame::IDENTITY_PAYLOAD, control: &control, metadata: &[] };
/// #     let mut out = vec![0_u8; 512];
/// #     let n = payload.write(ScalarKind::Q16_16, &mut out).unwrap();
/// #     out.truncate(n);
/// #     out
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct BSplineSurface<S: Scalar, const C: usize = DEFAULT_SURFACE_POINTS> {
    pub(crate) u: Direction<S>,
    pub(crate) v: Direction<S>,
    pub(crate) control: Vec<[S; 3], C>,
    pub(crate) stored_as: ScalarKind,
}

impl<S: Scalar, const C: usize> BSplineSurface<S, C> {
    /// An empty surface (no control points: every evaluation gives 0 and no normal), to be
    /// filled by [`BSplineSurface::load`]. `const`, so firmware can keep it in a `static`.
    pub const fn new() -> Self {
        BSplineSurface {
            u: Direction::EMPTY,
            v: Direction::EMPTY,
            control: Vec::new(),
            stored_as: S::KIND,
        }
    }

    crate::blob::loader_methods!(
        SurfacePayload,
        "spline surface",
        "Framing errors ([`crate::blob::parse`]); [`BlobError::WrongModelKind`]; \
         [`BlobError::MalformedPayload`]; [`BlobError::UnsupportedStorage`] for `f64` \
         storage; [`BlobError::ShapeMismatch`] for a degree outside 2 to 5 (`Degree`) or no \
         more points than the degree along a direction (`ControlPoints`), u checked first, \
         or a control byte string that does not hold \
         exactly count_u·count_v points (`Parameters`, in words); \
         [`BlobError::CapacityExceeded`] beyond [`MAX_SEGMENTS`](super::MAX_SEGMENTS) \
         segments along a direction (`Segments`) or `C` points in total \
         (`ControlPoints`); [`BlobError::NonFiniteParameter`] / \
         [`BlobError::ParameterOutOfRange`] (|x| > 1024 for Q16.16, in the frame's \
         coordinates) naming the first bad coordinate word; the frame's own errors \
         ([`crate::frame::Frame::from_payload`])."
    );

    fn fill(&mut self, payload: &SurfacePayload<'_>, stored: ScalarKind) -> Result<(), BlobError> {
        self.clear();
        control::check_storage(ModelKind::SplineSurface, stored)?;
        let u = Direction::new(
            usize::from(payload.count_u),
            payload.closed_u,
            usize::from(payload.degree_u),
        )?;
        let v = Direction::new(
            usize::from(payload.count_v),
            payload.closed_v,
            usize::from(payload.degree_v),
        )?;
        // At most 65 535² points: checked anyway, for 16-bit `usize`.
        let count = u
            .count
            .checked_mul(v.count)
            .ok_or(control::over_capacity(usize::MAX, C))?;
        if count > C {
            return Err(control::over_capacity(count, C));
        }
        if count.checked_mul(POINT_BYTES) != Some(payload.control.len()) {
            return Err(control::length_mismatch(count, payload.control.len()));
        }
        control::decode(&mut self.control, payload.control, stored, false)?;
        control::fold_frame(&mut self.control, &payload.frame, stored, false)?;
        self.u = u;
        self.v = v;
        self.stored_as = stored;
        Ok(())
    }

    /// Control points per row and rows: `[count_u, count_v]` (zeros when empty).
    pub fn counts(&self) -> [usize; 2] {
        [self.u.count, self.v.count]
    }

    /// Whether the u and v directions wrap around.
    pub fn is_closed(&self) -> [bool; 2] {
        [self.u.closed, self.v.closed]
    }

    /// Segments along u and v.
    pub fn segments(&self) -> [usize; 2] {
        [self.u.segments, self.v.segments]
    }

    /// Control point (u index, v index), if it exists.
    pub fn control_point(&self, u: usize, v: usize) -> Option<[S; 3]> {
        if u >= self.u.count {
            return None;
        }
        let index = v.checked_mul(self.u.count)?.checked_add(u)?;
        self.control.get(index).copied()
    }

    /// The scalar kind the blob stored its control points in.
    pub fn stored_as(&self) -> ScalarKind {
        self.stored_as
    }

    /// Multiplications (scalar products and accumulator multiply–adds) of one evaluation:
    /// 82 for [`BSplineSurface::position`], 212 for [`BSplineSurface::eval`] (position and
    /// both partials). Independent of the number of control points.
    /// Other degrees p_u, p_v: each direction's basis (1 + 2p(p + 1) + 4p, and
    /// 2p(p − 1) + 4(p − 1) more for a derivative), then per output t = (p_u + 1)(p_v + 1) − 1
    /// tensor weights and 3t multiply–adds.
    pub fn mac_count(&self, derivatives: bool) -> usize {
        if !self.is_bicubic() && self.u.degree > 0 {
            let [basis, slopes, output] = self.any_degree_counts();
            return if derivatives {
                basis + slopes + 3 * output
            } else {
                basis + output
            };
        }
        // Per output: 15 tensor weights, then 15 multiply–adds per coordinate.
        const OUTPUT: usize = 15 + 3 * 15;
        let basis = 2 * Direction::<S>::VALUE_MULS;
        if derivatives {
            basis + 2 * Direction::<S>::SLOPE_MULS + 3 * OUTPUT
        } else {
            basis + OUTPUT
        }
    }

    /// Multiplications of one [`BSplineSurface::normal`]: 185 (two unscaled partials, their
    /// cross product and three normalizations, each of which also takes a square root and a
    /// reciprocal).
    pub fn normal_mac_count(&self) -> usize {
        if !self.is_bicubic() && self.u.degree > 0 {
            let [basis, slopes, output] = self.any_degree_counts();
            return basis + slopes + 2 * output + 6 + 27;
        }
        2 * (Direction::<S>::VALUE_MULS + Direction::<S>::SLOPE_MULS) + 2 * (15 + 3 * 15) + 6 + 27
    }

    /// Multiplications of both directions' bases, of their derivative weights, and of one
    /// output, for degrees other than bicubic.
    fn any_degree_counts(&self) -> [usize; 3] {
        let basis = |p: usize| 1 + 2 * p * (p + 1) + 4 * p;
        let slopes = |p: usize| 2 * p * p.saturating_sub(1) + 4 * p.saturating_sub(1);
        let (pu, pv) = (self.u.degree, self.v.degree);
        let terms = (pu + 1) * (pv + 1) - 1;
        [basis(pu) + basis(pv), slopes(pu) + slopes(pv), 4 * terms]
    }

    /// S(u, v).
    pub fn position(&self, uv: [S; 2]) -> [S; 3] {
        let [point] = if self.is_bicubic() {
            self.lanes::<1, false>(&[uv])
        } else {
            self.any_degree_point::<false>(uv)
        };
        point.position
    }

    /// S(u, v), ∂S/∂u and ∂S/∂v (including the segment factors).
    pub fn eval(&self, uv: [S; 2]) -> SurfacePoint<S> {
        let [point] = if self.is_bicubic() {
            self.lanes::<1, true>(&[uv])
        } else {
            self.any_degree_point::<true>(uv)
        };
        point
    }

    /// The polynomial degrees along u and v, 2 to 5 each (0 for an empty surface).
    pub fn degrees(&self) -> [usize; 2] {
        [self.u.degree, self.v.degree]
    }

    /// Whether both directions are cubic: each entry point picks the bicubic path or the
    /// any-degree one once, outside its loops, so that the bicubic path compiles as it did
    /// before other degrees existed.
    #[inline(always)]
    pub(crate) fn is_bicubic(&self) -> bool {
        self.u.degree == 3 && self.v.degree == 3
    }

    /// One point of a surface of other degrees, out of line (see [`Self::is_bicubic`]).
    #[inline(never)]
    fn any_degree_point<const DERIVATIVES: bool>(&self, uv: [S; 2]) -> [SurfacePoint<S>; 1] {
        self.any_degree_lanes::<1, DERIVATIVES>(&[uv])
    }

    /// The unit normal (∂S/∂u × ∂S/∂v)/|…|, `None` where the cross product vanishes.
    ///
    /// Computed from dS/du and dS/dv of the local parameters (the same direction, without the
    /// segment factors), so it never saturates in Q16.16; there it is reliable where the
    /// partials are not nearly parallel and not within a few LSB of zero.
    pub fn normal(&self, uv: [S; 2]) -> Option<[S; 3]> {
        let [normal] = if self.is_bicubic() {
            self.normal_lanes::<1>(&[uv])
        } else {
            self.any_degree_normal::<1>(&[uv])
        };
        normal
    }

    /// Segment indices and local parameters of `L` parameter pairs.
    #[inline]
    fn locate_lanes<const L: usize>(&self, uv: &[[S; 2]; L]) -> ([[usize; 2]; L], [[S; 2]; L]) {
        let mut first = [[0; 2]; L];
        let mut local = [[S::ZERO; 2]; L];
        for ((&[u, v], first), local) in uv.iter().zip(&mut first).zip(&mut local) {
            let (iu, u) = self.u.locate(u);
            let (iv, v) = self.v.locate(v);
            *first = [iu, iv];
            *local = [u, v];
        }
        (first, local)
    }

    /// `L` parameter pairs at once: segments and bases of every lane, then every lane's
    /// patch. The single-point calls are `L = 1`, so batches give the same bits.
    #[inline]
    pub(crate) fn lanes<const L: usize, const DERIVATIVES: bool>(
        &self,
        uv: &[[S; 2]; L],
    ) -> [SurfacePoint<S>; L] {
        let (first, local) = self.locate_lanes(uv);
        let mut bases = [[[S::ZERO; 4]; 2]; L];
        let mut slopes = [[[S::ZERO; 4]; 2]; L];
        for ((&[u, v], bases), slopes) in local.iter().zip(&mut bases).zip(&mut slopes) {
            *bases = [self.u.values(u), self.v.values(v)];
            if DERIVATIVES {
                *slopes = [self.u.slopes(u), self.v.slopes(v)];
            }
        }
        let mut out = [SurfacePoint::default(); L];
        for (((out, &first), &[bu, bv]), &[su, sv]) in
            out.iter_mut().zip(&first).zip(&bases).zip(&slopes)
        {
            let (anchor, patch) = self.patch(first);
            out.position = tensor(anchor, bv, bu, &patch);
            if DERIVATIVES {
                out.du = tensor([S::ZERO; 3], bv, su, &patch);
                out.dv = tensor([S::ZERO; 3], sv, bu, &patch);
            }
        }
        out
    }

    /// Unit normals of `L` parameter pairs (see [`BSplineSurface::normal`]).
    #[inline]
    pub(crate) fn normal_lanes<const L: usize>(&self, uv: &[[S; 2]; L]) -> [Option<[S; 3]>; L] {
        let (first, local) = self.locate_lanes(uv);
        let mut bases = [[[S::ZERO; 4]; 4]; L];
        for (&[u, v], bases) in local.iter().zip(&mut bases) {
            *bases = [
                self.u.values(u),
                self.v.values(v),
                self.u.unit_slopes(u),
                self.v.unit_slopes(v),
            ];
        }
        let mut out = [None; L];
        for ((out, &first), &[bu, bv, su, sv]) in out.iter_mut().zip(&first).zip(&bases) {
            let (_, patch) = self.patch(first);
            let du = tensor([S::ZERO; 3], bv, su, &patch);
            let dv = tensor([S::ZERO; 3], sv, bu, &patch);
            *out = unit_cross(du, dv);
        }
        out
    }

    /// [`Self::lanes`] for a surface of other degrees (p_u along u, p_v along v): the
    /// recurrence's weights ([`Direction::any_degree`]) around the anchor P at
    /// (⌊p_v/2⌋, ⌊p_u/2⌋), each tensor weight wv[j]·wu[k] rounded once, each coordinate one
    /// accumulation with one rounding.
    #[inline]
    pub(crate) fn any_degree_lanes<const L: usize, const DERIVATIVES: bool>(
        &self,
        uv: &[[S; 2]; L],
    ) -> [SurfacePoint<S>; L] {
        let (first, local) = self.locate_lanes(uv);
        let mut out = [SurfacePoint::default(); L];
        for ((out, &first), &[u, v]) in out.iter_mut().zip(&first).zip(&local) {
            let slope = |d: &Direction<S>| DERIVATIVES.then(|| d.scale());
            let (bu, su) = self.u.any_degree(u, slope(&self.u));
            let (bv, sv) = self.v.any_degree(v, slope(&self.v));
            let (anchor, patch) = self.wide_patch(first);
            out.position = self.wide_tensor(anchor, &bv, &bu, &patch);
            if DERIVATIVES {
                out.du = self.wide_tensor([S::ZERO; 3], &bv, &su, &patch);
                out.dv = self.wide_tensor([S::ZERO; 3], &sv, &bu, &patch);
            }
        }
        out
    }

    /// [`Self::normal_lanes`] for a surface of other degrees (partials of the local
    /// parameters, as for the bicubic).
    #[inline]
    pub(crate) fn any_degree_normal<const L: usize>(
        &self,
        uv: &[[S; 2]; L],
    ) -> [Option<[S; 3]>; L] {
        let (first, local) = self.locate_lanes(uv);
        let mut out = [None; L];
        for ((out, &first), &[u, v]) in out.iter_mut().zip(&first).zip(&local) {
            let (bu, su) = self.u.any_degree(u, Some(S::ONE));
            let (bv, sv) = self.v.any_degree(v, Some(S::ONE));
            let (_, patch) = self.wide_patch(first);
            let du = self.wide_tensor([S::ZERO; 3], &bv, &su, &patch);
            let dv = self.wide_tensor([S::ZERO; 3], &sv, &bu, &patch);
            *out = unit_cross(du, dv);
        }
        out
    }

    /// The anchor of the patch of any degree whose first control point is `first`, and
    /// every point's difference from it (`[j][k]`: row v + j, column u + k; unused entries 0).
    #[inline]
    fn wide_patch(&self, [iu, iv]: [usize; 2]) -> ([S; 3], WidePatch<S>) {
        let (pu, pv) = (self.u.degree, self.v.degree);
        let point = |j: usize, k: usize| {
            let row = self.v.index(iv, j);
            let column = self.u.index(iu, k);
            self.control
                .get(row * self.u.count + column)
                .copied()
                .unwrap_or([S::ZERO; 3])
        };
        let anchor = point(pv / 2, pu / 2);
        let mut patch = [[[S::ZERO; 3]; MAX_ORDER]; MAX_ORDER];
        for (j, row) in patch.iter_mut().enumerate().take(pv + 1) {
            for (k, difference) in row.iter_mut().enumerate().take(pu + 1) {
                let p = point(j, k);
                *difference = [0, 1, 2].map(|axis| at(&p, axis).sub(at(&anchor, axis)));
            }
        }
        (anchor, patch)
    }

    /// `start + Σ_{(j,k) ≠ anchor} (wv[j]·wu[k])·patch[j][k]` over the patch's
    /// (p_v + 1) × (p_u + 1) points, per coordinate with one rounding.
    #[inline]
    fn wide_tensor(
        &self,
        start: [S; 3],
        wv: &[S; MAX_ORDER],
        wu: &[S; MAX_ORDER],
        patch: &WidePatch<S>,
    ) -> [S; 3] {
        let (pu, pv) = (self.u.degree, self.v.degree);
        let anchor = (pv / 2, pu / 2);
        let mut acc = start.map(S::to_acc);
        for (j, (points, &a)) in patch.iter().zip(wv).enumerate().take(pv + 1) {
            for (k, (p, &b)) in points.iter().zip(wu).enumerate().take(pu + 1) {
                if (j, k) == anchor {
                    continue;
                }
                let w = a.mul(b);
                for (acc, &d) in acc.iter_mut().zip(p) {
                    *acc = S::mac(*acc, w, d);
                }
            }
        }
        acc.map(S::from_acc)
    }

    /// The anchor P₁₁ of the patch whose first control point is `first` = [u index, v index],
    /// and every point's difference from it.
    #[inline]
    fn patch(&self, [iu, iv]: [usize; 2]) -> ([S; 3], Patch<S>) {
        let columns = [0, 1, 2, 3].map(|k| self.u.index(iu, k));
        let point = |j: usize, column: usize| {
            let row = self.v.index(iv, j);
            self.control
                .get(row * self.u.count + column)
                .copied()
                .unwrap_or([S::ZERO; 3])
        };
        let anchor = point(1, at_index(&columns, 1));
        let patch = [0, 1, 2, 3].map(|j| {
            columns.map(|column| {
                let p = point(j, column);
                [0, 1, 2].map(|axis| at(&p, axis).sub(at(&anchor, axis)))
            })
        });
        (anchor, patch)
    }
}

impl<S: Scalar, const C: usize> Default for BSplineSurface<S, C> {
    fn default() -> Self {
        Self::new()
    }
}

/// `start + Σ_{(j,k) ≠ (1,1)} (wv[j]·wu[k])·patch[j][k]`, per coordinate with one rounding.
/// (The anchor's own difference is zero, so leaving it out changes nothing.)
#[inline]
fn tensor<S: Scalar>(start: [S; 3], wv: [S; 4], wu: [S; 4], patch: &Patch<S>) -> [S; 3] {
    let mut weights = [[S::ZERO; 4]; 4];
    for (j, (row, &a)) in weights.iter_mut().zip(&wv).enumerate() {
        for (k, (weight, &b)) in row.iter_mut().zip(&wu).enumerate() {
            if (j, k) != (1, 1) {
                *weight = a.mul(b);
            }
        }
    }
    [0, 1, 2].map(|axis| {
        let mut acc = at(&start, axis).to_acc();
        for (j, (weights, points)) in weights.iter().zip(patch).enumerate() {
            for (k, (&w, p)) in weights.iter().zip(points).enumerate() {
                if (j, k) != (1, 1) {
                    acc = S::mac(acc, w, at(p, axis));
                }
            }
        }
        S::from_acc(acc)
    })
}

/// (a × b)/|a × b| from a/|a| and b/|b| (so that no product saturates in fixed point).
#[inline]
fn unit_cross<S: Scalar>(a: [S; 3], b: [S; 3]) -> Option<[S; 3]> {
    let [ax, ay, az] = normalize3(a)?;
    let [bx, by, bz] = normalize3(b)?;
    let det =
        |p: S, q: S, r: S, s: S| S::from_acc(S::mac(S::mac(S::ZERO.to_acc(), p, q), r.neg(), s));
    normalize3([
        det(ay, bz, az, by),
        det(az, bx, ax, bz),
        det(ax, by, ay, bx),
    ])
}

#[inline(always)]
fn at_index(v: &[usize; 4], k: usize) -> usize {
    v.get(k).copied().unwrap_or(0)
}

impl<S: Scalar, const C: usize> crate::model::Model<S> for BSplineSurface<S, C> {
    const KIND: ModelKind = ModelKind::SplineSurface;

    fn load_blob(&mut self, blob: &[u8]) -> Result<(), BlobError> {
        self.load(blob)
    }

    fn input_len(&self) -> usize {
        2
    }

    fn output_len(&self, full: bool) -> usize {
        if full { 6 } else { 3 }
    }

    fn evaluate(&self, input: &[S], full: bool, out: &mut [S]) {
        let uv = crate::model::point(input);
        let position = self.position(uv);
        if full {
            let normal = crate::model::normal_or_zero(self.normal(uv));
            crate::model::write(out, crate::model::pair(position, normal));
        } else {
            crate::model::write(out, position);
        }
    }

    fn evaluate_batch(
        &self,
        inputs: &[[S; crate::model::MAX_INPUTS]],
        full: bool,
        out: &mut [[S; crate::model::MAX_OUTPUTS]],
    ) {
        let uv = |input: &[S; crate::model::MAX_INPUTS]| crate::model::point::<S, 2>(input);
        if full {
            crate::model::batch(
                inputs,
                out,
                uv,
                |uv, points: &mut [([S; 3], Option<[S; 3]>)]| {
                    let mut positions = [[S::ZERO; 3]; crate::model::BATCH_CHUNK];
                    let mut normals = [None; crate::model::BATCH_CHUNK];
                    let (Some(positions), Some(normals)) =
                        (positions.get_mut(..uv.len()), normals.get_mut(..uv.len()))
                    else {
                        return;
                    };
                    // Lengths agree by construction: nothing to report.
                    let _ = self.position_batch(uv, positions);
                    let _ = self.normal_batch(uv, normals);
                    for ((slot, &p), &n) in
                        points.iter_mut().zip(positions.iter()).zip(normals.iter())
                    {
                        *slot = (p, n);
                    }
                },
                |&(p, n), out| {
                    let normal = crate::model::normal_or_zero(n);
                    crate::model::write(out, crate::model::pair(p, normal));
                },
            );
        } else {
            crate::model::positions(inputs, out, uv, |uv, positions| {
                self.position_batch(uv, positions)
            });
        }
    }

    fn mac_count(&self, full: bool) -> usize {
        if full {
            BSplineSurface::mac_count(self, false) + self.normal_mac_count()
        } else {
            BSplineSurface::mac_count(self, false)
        }
    }

    fn describe(&self, f: &mut dyn core::fmt::Write) -> core::fmt::Result {
        let ([count_u, count_v], [closed_u, closed_v]) = (self.counts(), self.is_closed());
        write!(
            f,
            "{count_u} × {count_v} control points, degree {} × {}, {} × {}",
            self.u.degree,
            self.v.degree,
            crate::model::open_or_closed(closed_u),
            crate::model::open_or_closed(closed_v)
        )
    }
}

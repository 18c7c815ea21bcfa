//! Shared helpers of the curve and surface tests: a seeded PRNG, random control nets on the
//! Q16.16 grid, blob builders, and an independent `f64` reference evaluator written from the
//! mathematical contract in `core/src/curve/mod.rs` (not from the core's code: plain
//! Σ Bₖ(u)·Pₖ with the textbook basis, modulo for wrapping, `floor` for the segment).
#![allow(dead_code)]

use neurosurf_core::blob;
use neurosurf_core::curve::{CurvePayload, SurfacePayload};
use neurosurf_core::scalar::{Q16, ScalarKind};

#[allow(unused_imports)]
pub use common::{LSB, Rng, to_grid};

/// The PRNG, test constants and grid rounding shared with the implicit-model tests.
#[path = "../common/mod.rs"]
mod common;
pub use common::{cross, norm};

/// The unit roundoff of `f32` (half an ulp of 1).
pub const F32_EPS: f64 = 1.0 / 16_777_216.0;

/// Curve-test draws on top of the shared PRNG.
pub trait CurveDraws {
    /// A parameter in [0, 1] on the Q16.16 grid.
    fn parameter(&mut self) -> f64;
    /// `n` points with coordinates in [−scale, scale] on the grid (z = 0 when `flat`).
    fn points(&mut self, n: usize, scale: f64, flat: bool) -> Vec<[f64; 3]>;
}

impl CurveDraws for Rng {
    fn parameter(&mut self) -> f64 {
        self.grid(0.0, 1.0 + LSB)
    }

    fn points(&mut self, n: usize, scale: f64, flat: bool) -> Vec<[f64; 3]> {
        (0..n)
            .map(|_| {
                let mut p = [(); 3].map(|()| self.grid(-scale, scale));
                if flat {
                    p[2] = 0.0;
                }
                p
            })
            .collect()
    }
}

// ---------------------------------------------------------------------------------------------
// Blobs

/// x, y, z of every point in `kind`.
pub fn encode_points(points: &[[f64; 3]], kind: ScalarKind) -> Vec<u8> {
    points
        .iter()
        .flatten()
        .flat_map(|&c| kind.encode(c).expect("encodable coordinate"))
        .collect()
}

pub fn curve_blob_raw(kind: ScalarKind, dimension: u8, closed: bool, control: &[u8]) -> Vec<u8> {
    curve_blob_of_degree(kind, dimension, closed, 3, control)
}

/// [`curve_blob_raw`] of any `degree`.
pub fn curve_blob_of_degree(
    kind: ScalarKind,
    dimension: u8,
    closed: bool,
    degree: u8,
    control: &[u8],
) -> Vec<u8> {
    let payload = CurvePayload {
        dimension,
        closed,
        degree,
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        control,
        metadata: b"test curve",
    };
    let mut out = vec![0_u8; 64 + control.len()];
    let len = payload.write(kind, &mut out).unwrap();
    out.truncate(len);
    out
}

pub fn curve_blob(kind: ScalarKind, dimension: u8, closed: bool, points: &[[f64; 3]]) -> Vec<u8> {
    curve_blob_raw(kind, dimension, closed, &encode_points(points, kind))
}

pub fn surface_blob_raw(
    kind: ScalarKind,
    closed: [bool; 2],
    counts: [u16; 2],
    control: &[u8],
) -> Vec<u8> {
    let payload = SurfacePayload {
        closed_u: closed[0],
        closed_v: closed[1],
        degree_u: 3,
        degree_v: 3,
        count_u: counts[0],
        count_v: counts[1],
        frame: neurosurf_core::frame::IDENTITY_PAYLOAD,
        control,
        metadata: b"test surface",
    };
    let mut out = vec![0_u8; 64 + control.len()];
    let len = payload.write(kind, &mut out).unwrap();
    out.truncate(len);
    out
}

pub fn surface_blob(kind: ScalarKind, reference: &RefSurface) -> Vec<u8> {
    surface_blob_raw(
        kind,
        [reference.u.closed, reference.v.closed],
        [reference.u.count as u16, reference.v.count as u16],
        &encode_points(&reference.points, kind),
    )
}

/// Frames arbitrary payload bytes by hand (header, payload, CRC) with arbitrary kind codes, in
/// the current format version.
pub fn frame(model: u8, scalar: u8, payload: &[u8]) -> Vec<u8> {
    common::frame(blob::FORMAT_VERSION, model, scalar, payload)
}

/// [`frame`] in format `version`.
pub fn frame_version(version: u16, model: u8, scalar: u8, payload: &[u8]) -> Vec<u8> {
    common::frame(version, model, scalar, payload)
}

#[allow(unused_imports)]
pub use common::fix_crc;

pub fn q16(x: f64) -> Q16 {
    Q16::from_num(x)
}

pub fn f64s_q16(v: [Q16; 3]) -> [f64; 3] {
    v.map(|c| c.to_num::<f64>())
}

pub fn f64s_f32(v: [f32; 3]) -> [f64; 3] {
    v.map(f64::from)
}

pub fn max_abs_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}

/// Angle between two vectors, in radians (robust near 0).
pub fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    norm(cross(a, b)).atan2(a.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>())
}

// ---------------------------------------------------------------------------------------------
// The f64 reference

/// The textbook uniform cubic B-spline basis and its first and second derivatives.
pub fn basis(u: f64) -> [[f64; 4]; 3] {
    let (u2, u3) = (u * u, u * u * u);
    [
        [
            (1.0 - u).powi(3) / 6.0,
            (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0,
            (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0,
            u3 / 6.0,
        ],
        [
            -(1.0 - u).powi(2) / 2.0,
            (9.0 * u2 - 12.0 * u) / 6.0,
            (-9.0 * u2 + 6.0 * u + 3.0) / 6.0,
            u2 / 2.0,
        ],
        [1.0 - u, 3.0 * u - 2.0, 1.0 - 3.0 * u, u],
    ]
}

/// One direction of the reference.
#[derive(Clone, Copy, Debug)]
pub struct RefDirection {
    pub count: usize,
    pub closed: bool,
}

impl RefDirection {
    pub fn segments(&self) -> usize {
        if self.closed {
            self.count
        } else {
            self.count - 3
        }
    }

    /// (segment, local parameter) of t, t clamped to [0, 1].
    pub fn locate(&self, t: f64) -> (usize, f64) {
        let g = self.segments();
        let s = t.clamp(0.0, 1.0) * g as f64;
        let i = (s.floor() as usize).min(g - 1);
        (i, s - i as f64)
    }

    /// Index of the k-th control point of segment i.
    pub fn index(&self, i: usize, k: usize) -> usize {
        (i + k) % self.count
    }
}

/// A reference curve: value, first and second derivative with respect to t.
#[derive(Clone, Debug)]
pub struct RefCurve {
    pub direction: RefDirection,
    pub points: Vec<[f64; 3]>,
}

impl RefCurve {
    pub fn new(closed: bool, points: Vec<[f64; 3]>) -> Self {
        RefCurve {
            direction: RefDirection {
                count: points.len(),
                closed,
            },
            points,
        }
    }

    pub fn segments(&self) -> usize {
        self.direction.segments()
    }

    /// [C, dC/dt, d²C/dt²] at t.
    pub fn eval(&self, t: f64) -> [[f64; 3]; 3] {
        let (i, u) = self.direction.locate(t);
        self.eval_segment(i, u)
    }

    /// [C, dC/dt, d²C/dt²] of segment i at local u (any u, for one-sided limits).
    pub fn eval_segment(&self, i: usize, u: f64) -> [[f64; 3]; 3] {
        let g = self.segments() as f64;
        let b = basis(u);
        let scale = [1.0, g, g * g];
        std::array::from_fn(|order| {
            std::array::from_fn(|axis| {
                (0..4)
                    .map(|k| b[order][k] * self.points[self.direction.index(i, k)][axis])
                    .sum::<f64>()
                    * scale[order]
            })
        })
    }

    /// The points of segment i.
    pub fn span(&self, i: usize) -> [[f64; 3]; 4] {
        std::array::from_fn(|k| self.points[self.direction.index(i, k)])
    }
}

/// Largest coordinate difference from the second point (the core's anchor) and largest
/// coordinate magnitude, over `points`.
pub fn span_scales<'a>(
    points: impl IntoIterator<Item = &'a [f64; 3]> + Clone,
    anchor: [f64; 3],
) -> (f64, f64) {
    let delta = points
        .clone()
        .into_iter()
        .map(|p| max_abs_diff(*p, anchor))
        .fold(0.0, f64::max);
    let magnitude = points
        .into_iter()
        .flat_map(|p| p.iter().map(|c| c.abs()))
        .fold(0.0, f64::max);
    (delta, magnitude)
}

/// A reference tensor-product surface.
#[derive(Clone, Debug)]
pub struct RefSurface {
    pub u: RefDirection,
    pub v: RefDirection,
    /// P[v·count_u + u].
    pub points: Vec<[f64; 3]>,
}

impl RefSurface {
    pub fn new(closed: [bool; 2], counts: [usize; 2], points: Vec<[f64; 3]>) -> Self {
        assert_eq!(points.len(), counts[0] * counts[1]);
        RefSurface {
            u: RefDirection {
                count: counts[0],
                closed: closed[0],
            },
            v: RefDirection {
                count: counts[1],
                closed: closed[1],
            },
            points,
        }
    }

    pub fn random(rng: &mut Rng, closed: [bool; 2], counts: [usize; 2], scale: f64) -> Self {
        Self::new(
            closed,
            counts,
            rng.points(counts[0] * counts[1], scale, false),
        )
    }

    pub fn point(&self, iu: usize, iv: usize) -> [f64; 3] {
        self.points[iv * self.u.count + iu]
    }

    /// The 16 points of the patch at (u, v), and its anchor P₁₁.
    pub fn patch(&self, u: f64, v: f64) -> (Vec<[f64; 3]>, [f64; 3]) {
        let (iu, _) = self.u.locate(u);
        let (iv, _) = self.v.locate(v);
        let mut points = Vec::new();
        for j in 0..4 {
            for k in 0..4 {
                points.push(self.point(self.u.index(iu, k), self.v.index(iv, j)));
            }
        }
        let anchor = self.point(self.u.index(iu, 1), self.v.index(iv, 1));
        (points, anchor)
    }

    /// [S, ∂S/∂u, ∂S/∂v] at (u, v).
    pub fn eval(&self, u: f64, v: f64) -> [[f64; 3]; 3] {
        let (iu, lu) = self.u.locate(u);
        let (iv, lv) = self.v.locate(v);
        let (bu, bv) = (basis(lu), basis(lv));
        let (gu, gv) = (self.u.segments() as f64, self.v.segments() as f64);
        let mut out = [[0.0; 3]; 3];
        for j in 0..4 {
            for k in 0..4 {
                let p = self.point(self.u.index(iu, k), self.v.index(iv, j));
                let w = [
                    bv[0][j] * bu[0][k],
                    bv[0][j] * bu[1][k] * gu,
                    bv[1][j] * bu[0][k] * gv,
                ];
                for (o, &w) in out.iter_mut().zip(&w) {
                    for axis in 0..3 {
                        o[axis] += w * p[axis];
                    }
                }
            }
        }
        out
    }

    pub fn segments(&self) -> [usize; 2] {
        [self.u.segments(), self.v.segments()]
    }
}

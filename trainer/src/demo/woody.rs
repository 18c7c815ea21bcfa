//! A body from a mesh with automatic features: `woody.obj` (a flat gingerbread man) made into
//! a cookie, decomposed into 17 features and blended by a balanced tree.
//!
//! The mesh is planar (every z is 0), so it has no inside: it is extruded into a slab (top and
//! bottom copies, a wall on every boundary edge), a closed surface an implicit model can learn,
//! stood upright (its y becomes z) and scaled to the synthetic body's height. Control points
//! are spread evenly on the slab ([`Spread::Even`]) with its face normals; the held-out points
//! that measure it are independent draws.
//!
//! Features come from [`decompose`](crate::implicit::decompose): recursive principal-axis
//! bisection into equal groups, then capacity-constrained k-means — spatially compact groups
//! of neighbouring points, which is what a leaf learns easily; positions alone suffice here
//! because the slab's parts (head, arms, legs, body) are separated in space, and normals would
//! only split a limb's front from its back. The tree is
//! [`TreeSpec::balanced`](crate::implicit::TreeSpec::balanced) over the feature centroids
//! (neighbours blended first, as shallow as possible: the rationale of the paper's Fig. 8).

use serde::Serialize;

use crate::error::{Error, Result};
use crate::fidelity::{Fidelity, diameter};
use crate::implicit::{self, FitRequest, ImplicitOptions, Outcome, Progress, Trained};
use crate::io::{Mesh, data_file, read_mesh};
use crate::points::PointSet;
use crate::quality::{MEASURE_RESOLUTION, STRAY_RESOLUTION, Truth, TwoSided, two_sided};
use crate::render::{DEFAULT_BOX_SIZE, DEFAULT_INFLATE, NetworkField};
use crate::sample::{BODY_FEATURES, Spread, sample_mesh};

/// Height of the cookie, as the synthetic body's.
const HEIGHT: f64 = 14.0;
/// Thickness of the slab.
const THICKNESS: f64 = 1.6;
/// Control points on the cookie.
pub const WOODY_POINTS: usize = 400;
/// LM iterations per module: the slab's sharp edges keep E_s above the 10⁻⁵ threshold (its
/// normals jump by 90°; measured: 7149 iterations, 33 s, not converged, with the default
/// cap of 2000), so the demo stops every module after this many.
pub const WOODY_ITERATIONS: usize = 100;

/// What the woody demo did.
#[derive(Clone, Debug, Serialize)]
pub struct WoodyDemo {
    /// Control points.
    pub control_points: usize,
    /// Automatic features.
    pub features: usize,
    /// The balanced tree.
    pub tree: String,
    /// Learning time, seconds.
    pub seconds: f64,
    /// LM iterations over all modules.
    pub iterations: usize,
    /// How the training ended: converged, stalled at E_s = …, or cut by the iteration cap.
    pub outcome: Outcome,
    /// Against held-out points of the slab.
    pub fidelity: Fidelity,
    /// Against the slab both ways, with stray surface and mesh pieces.
    pub two_sided: TwoSided,
}

/// Extrudes a planar mesh (z = const, triangles wound consistently) into a closed slab of
/// `thickness`, stood up (x, y, z) ↦ (x, −z, y) and scaled so its height is `height`.
///
/// # Errors
/// [`Error::InvalidInput`] when the mesh is not planar in z or has no boundary.
pub fn extrude(mesh: &Mesh, thickness: f64, height: f64) -> Result<Mesh> {
    let z0 = mesh.positions.first().map_or(0.0, |p| p[2]);
    if mesh.positions.iter().any(|p| (p[2] - z0).abs() > 1e-9) {
        return Err(Error::invalid(
            "only a mesh in a plane z = const can be extruded",
        ));
    }
    let (lo, hi) = mesh.positions.iter().fold(
        ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
        |(lo, hi), p| {
            (
                [lo[0].min(p[0]), lo[1].min(p[1])],
                [hi[0].max(p[0]), hi[1].max(p[1])],
            )
        },
    );
    let scale = height / (hi[1] - lo[1]).max(f64::MIN_POSITIVE);
    let cx = 0.5 * (lo[0] + hi[0]);
    let n = mesh.positions.len() as u32;
    // Vertex v on the front (toward −y after standing up: the top copy) is v, on the back v + n.
    let half = 0.5 * thickness;
    let stand = |p: &[f64; 3], z: f64| [(p[0] - cx) * scale, -z, (p[1] - lo[1]) * scale];
    let mut positions: Vec<[f64; 3]> = mesh.positions.iter().map(|p| stand(p, half)).collect();
    positions.extend(mesh.positions.iter().map(|p| stand(p, -half)));
    // Orient every triangle counter-clockwise seen from +z (the top side).
    let up = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) >= 0.0
    };
    let top: Vec<[u32; 3]> = mesh
        .triangles
        .iter()
        .map(|t| if up(t) { *t } else { [t[0], t[2], t[1]] })
        .collect();
    let mut edges: std::collections::HashMap<(u32, u32), (u32, u32, u32)> =
        std::collections::HashMap::new();
    for t in &top {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges
                .entry((a.min(b), a.max(b)))
                .and_modify(|e| e.0 += 1)
                .or_insert((1, a, b));
        }
    }
    let mut triangles = top.clone();
    triangles.extend(top.iter().map(|t| [t[0] + n, t[2] + n, t[1] + n]));
    let mut boundary: Vec<(u32, u32)> = edges
        .values()
        .filter(|e| e.0 == 1)
        .map(|e| (e.1, e.2))
        .collect();
    if boundary.is_empty() {
        return Err(Error::invalid("the planar mesh has no boundary to extrude"));
    }
    boundary.sort_unstable();
    for (a, b) in boundary {
        // Wall of edge a → b (interior on its left): outward is to its right.
        triangles.push([a + n, b + n, b]);
        triangles.push([a + n, b, a]);
    }
    Mesh {
        positions,
        triangles,
    }
    .validated()
}

/// The cookie mesh from `woody.obj` (see [`data_file`]).
///
/// # Errors
/// The data file is missing or unreadable.
pub fn woody_mesh() -> Result<Mesh> {
    extrude(&read_mesh(&data_file("woody.obj")?)?, THICKNESS, HEIGHT)
}

/// Samples the cookie, decomposes it into 17 features, trains the balanced tree.
///
/// # Errors
/// Missing data file, training errors.
pub fn woody(
    seed: u64,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(WoodyDemo, Trained, PointSet)> {
    let mesh = woody_mesh()?;
    let points = sample_mesh(&mesh, WOODY_POINTS, seed, Spread::Even)?;
    let labels = implicit::decompose(&points.positions, BODY_FEATURES.len(), 4)?;
    let points = PointSet {
        features: Some(labels),
        ..points
    };
    let mut options = ImplicitOptions {
        seed,
        ..ImplicitOptions::default()
    };
    options.lm.max_iterations = WOODY_ITERATIONS;
    let trained = implicit::fit(points.clone(), &FitRequest::default(), &options, progress)?;
    let held_out = sample_mesh(
        &mesh,
        super::HELD_OUT,
        seed.wrapping_add(1_000_003),
        Spread::Random,
    )?;
    let fidelity = Fidelity::measure(&held_out, diameter(&held_out.positions), |p| {
        trained.network.eval(p)
    })
    .ok_or_else(|| Error::invalid("the cookie model has a vanishing gradient"))?;
    let demo = WoodyDemo {
        control_points: points.len(),
        features: BODY_FEATURES.len(),
        tree: trained.summary.tree.clone(),
        seconds: trained.summary.seconds,
        iterations: trained.summary.iterations(),
        outcome: trained.summary.outcome(),
        fidelity,
        two_sided: two_sided(
            &NetworkField::new(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE)?,
            &Truth::from_mesh(&mesh)?,
            MEASURE_RESOLUTION,
            STRAY_RESOLUTION,
        )?,
    };
    Ok((demo, trained, points))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_extruded_cookie_is_closed_and_upright() {
        let mesh = woody_mesh().unwrap();
        // Every edge is shared by exactly two triangles, in opposite directions.
        let mut directed = std::collections::HashSet::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                assert!(directed.insert((t[k], t[(k + 1) % 3])), "edge used twice");
            }
        }
        for &(a, b) in &directed {
            assert!(directed.contains(&(b, a)), "open edge {a}-{b}");
        }
        let zs = mesh.positions.iter().map(|p| p[2]);
        let (lo, hi) = zs.fold((f64::MAX, f64::MIN), |(l, h), z| (l.min(z), h.max(z)));
        assert!(lo.abs() < 1e-9 && (hi - HEIGHT).abs() < 1e-9, "{lo} {hi}");
        // Outward: the signed volume is positive.
        let volume: f64 = mesh
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| mesh.positions[v as usize]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum();
        assert!(volume > 0.0, "{volume}");
    }
}

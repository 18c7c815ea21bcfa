//! Shapes and measurements the implicit benches share: analytic test shapes meshed from
//! their signed distance, a blob measured both ways as a user runs it, and flag parsing.

// Each bench uses a part of this module.
#![allow(dead_code)]

use neurosurf_trainer::implicit;
use neurosurf_trainer::io::Mesh;
use neurosurf_trainer::quality::{
    MEASURE_RESOLUTION, STRAY_RESOLUTION, Truth, TwoSided, signed_distance_mesh, two_sided,
};
use neurosurf_trainer::render::{Aabb, CoreField, DEFAULT_BOX_SIZE, DEFAULT_INFLATE, Region};

/// The surface of a signed distance inside the box ±`half`, meshed finely.
pub fn analytic_mesh(distance: impl Fn([f64; 3]) -> f64 + Sync, half: [f64; 3]) -> Mesh {
    let bounds = Aabb {
        lo: half.map(|h| -h),
        hi: half,
    };
    signed_distance_mesh(distance, bounds, 160).expect("mesh")
}

/// Signed distance to a torus around the z axis, centred at `c`.
pub fn torus(p: [f64; 3], c: [f64; 3], big: f64, small: f64) -> f64 {
    let q = [p[0] - c[0], p[1] - c[1], p[2] - c[2]];
    ((q[0] * q[0] + q[1] * q[1]).sqrt() - big).hypot(q[2]) - small
}

/// Carcenac's torus (R = 1, r = 0.4), as Table 5 samples it.
pub fn table5_torus() -> Mesh {
    analytic_mesh(|p| torus(p, [0.0; 3], 1.0, 0.4), [1.5, 1.5, 0.5])
}

/// Two tori (R = 1, r = 0.35) side by side, centres x = ±0.9: genus 2.
pub fn double_torus() -> Mesh {
    analytic_mesh(
        |p| torus(p, [-0.9, 0.0, 0.0], 1.0, 0.35).min(torus(p, [0.9, 0.0, 0.0], 1.0, 0.35)),
        [2.4, 1.5, 0.5],
    )
}

/// A cube of side 2 with edges rounded to radius 0.2.
pub fn rounded_cube() -> Mesh {
    analytic_mesh(
        |p| {
            let q = p.map(|v| v.abs() - 0.8);
            let outside = q.map(|v| v.max(0.0));
            (outside[0].hypot(outside[1]).hypot(outside[2])) + q[0].max(q[1]).max(q[2]).min(0.0)
                - 0.2
        },
        [1.2; 3],
    )
}

/// `blob` (of `network`) measured as a user runs it: in the core, in f32, inside the leaf boxes
/// `mesh` and `render` search.
pub fn measure_core(blob: &[u8], network: &implicit::ImplicitNetwork, truth: &Truth) -> TwoSided {
    let regions = Region::of_network(network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
    let field = CoreField::new(blob, regions).expect("the core loads the blob");
    two_sided(&field, truth, MEASURE_RESOLUTION, STRAY_RESOLUTION).expect("measure")
}

/// The value after `name` on the command line (`--seeds 5`), if any.
pub fn flag(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .cloned()
}

/// `path` relative to the workspace root (cargo runs benches in the package's folder).
pub fn in_workspace(path: &str) -> std::path::PathBuf {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    root.join(path)
}

/// The bench's own arguments as typed after `--` (cargo adds `--bench`), for the "written by"
/// line of an `--out` file.
pub fn arguments(args: &[String]) -> String {
    let own: Vec<&str> = args
        .iter()
        .skip(1)
        .map(String::as_str)
        .filter(|a| *a != "--bench")
        .collect();
    own.join(" ")
}

//! Axis-aligned bounds of points and meshes, the yardstick of every relative distance.

use crate::io::Mesh;
use crate::render::Aabb;

/// The axis-aligned bounds of some points.
pub fn point_bounds<'a>(points: impl IntoIterator<Item = &'a [f64; 3]>) -> Aabb {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    Aabb { lo, hi }
}

/// The length of the diagonal of a mesh's axis-aligned bounding box.
pub fn bounding_diagonal(mesh: &Mesh) -> f64 {
    let (low, high) = mesh.positions.iter().fold(
        ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]),
        |(low, high), p| {
            (
                [0, 1, 2].map(|k| low[k].min(p[k])),
                [0, 1, 2].map(|k| high[k].max(p[k])),
            )
        },
    );
    (0..3)
        .map(|k| (high[k] - low[k]).powi(2))
        .sum::<f64>()
        .sqrt()
}

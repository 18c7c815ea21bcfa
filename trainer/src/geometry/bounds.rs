//! Axis-aligned bounds of meshes, the yardstick of every relative distance.

use crate::io::Mesh;

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

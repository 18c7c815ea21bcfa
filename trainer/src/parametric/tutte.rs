//! Tutte's embedding of a disk-shaped mesh: the boundary loop on the unit circle (spaced by
//! arc length) and every other vertex at the mean of its neighbours, one sparse Cholesky solve
//! per coordinate. By Tutte's theorem the result has no fold whatever the mesh looks like in
//! space, which is what [`super::fill_hole`] falls back on when LLE folds a hole's region.

use super::sparse::SymmetricMatrix;
use crate::error::{Error, Result};
use crate::io::Mesh;

/// The planar embedding of `mesh` (a topological disk) with `boundary` (its boundary loop,
/// in order) on the unit circle.
///
/// # Errors
/// [`Error::InvalidInput`] for a boundary of fewer than three vertices, a vertex outside the
/// mesh, or a solve that fails (a vertex not connected to the boundary).
pub fn tutte_disk(mesh: &Mesh, boundary: &[u32]) -> Result<Vec<[f64; 2]>> {
    let n = mesh.positions.len();
    if boundary.len() < 3 || boundary.iter().any(|&v| v as usize >= n) {
        return Err(Error::invalid(
            "a disk embedding needs a boundary loop of at least three mesh vertices",
        ));
    }
    let length = |a: u32, b: u32| {
        let (p, q) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
    };
    let m = boundary.len();
    let perimeter: f64 = (0..m)
        .map(|k| length(boundary[k], boundary[(k + 1) % m]))
        .sum();
    let mut plane = vec![[0.0; 2]; n];
    let mut arc = 0.0;
    for k in 0..m {
        let angle = if perimeter > 0.0 {
            std::f64::consts::TAU * arc / perimeter
        } else {
            std::f64::consts::TAU * k as f64 / m as f64
        };
        plane[boundary[k] as usize] = [angle.cos(), angle.sin()];
        arc += length(boundary[k], boundary[(k + 1) % m]);
    }
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| (0..3).map(move |e| (t[e].min(t[(e + 1) % 3]), t[e].max(t[(e + 1) % 3]))))
        .filter(|&(a, b)| (b as usize) < n && a != b)
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let fixed: Vec<(usize, [f64; 2])> = boundary
        .iter()
        .map(|&v| (v as usize, plane[v as usize]))
        .collect();
    weighted_means(n, &edges, &vec![1.0; edges.len()], &fixed)
}

/// The plane positions of `n` vertices where those in `fixed` are placed and every other one
/// is at the mean of its neighbours along `edges` (a < b), weighted by `weights` (positive):
/// one sparse Cholesky solve per coordinate.
///
/// # Errors
/// [`Error::InvalidInput`] when the solve fails or is not finite (a free vertex not connected
/// to a fixed one, or degenerate weights).
pub(crate) fn weighted_means(
    n: usize,
    edges: &[(u32, u32)],
    weights: &[f64],
    fixed: &[(usize, [f64; 2])],
) -> Result<Vec<[f64; 2]>> {
    let mut plane = vec![[0.0; 2]; n];
    let mut unknown = vec![usize::MAX; n];
    let mut is_fixed = vec![false; n];
    for &(v, at) in fixed {
        plane[v] = at;
        is_fixed[v] = true;
    }
    let mut count = 0;
    for v in 0..n {
        if !is_fixed[v] {
            unknown[v] = count;
            count += 1;
        }
    }
    if count == 0 {
        return Ok(plane);
    }
    let mut matrix = SymmetricMatrix::new(count);
    let mut rhs = vec![vec![0.0; count], vec![0.0; count]];
    for (&(a, b), &w) in edges.iter().zip(weights) {
        let (a, b) = (a as usize, b as usize);
        for (i, j) in [(a, b), (b, a)] {
            let ui = unknown[i];
            if ui == usize::MAX {
                continue;
            }
            matrix.add(ui, ui, w);
            match unknown[j] {
                usize::MAX => {
                    for k in 0..2 {
                        rhs[k][ui] += w * plane[j][k];
                    }
                }
                uj => matrix.add(ui, uj, -w),
            }
        }
    }
    matrix.compress()?.cholesky()?.solve(&mut rhs);
    for (v, &u) in unknown.iter().enumerate() {
        if u != usize::MAX {
            plane[v] = [rhs[0][u], rhs[1][u]];
        }
    }
    if plane.iter().flatten().any(|c| !c.is_finite()) {
        return Err(Error::invalid(
            "the disk embedding is not finite: a vertex is not connected to the boundary, or \
             the edge weights degenerated",
        ));
    }
    Ok(plane)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan around one centre: the rim on the circle, the centre at the mean of the rim.
    #[test]
    fn a_fan_centre_lands_at_the_mean_of_its_rim() {
        let rim = 7;
        let mut mesh = Mesh::default();
        for k in 0..rim {
            let a = std::f64::consts::TAU * k as f64 / rim as f64;
            mesh.positions
                .push([a.cos(), a.sin(), 0.3 * (3.0 * a).sin()]);
        }
        mesh.positions.push([0.0, 0.0, 2.0]);
        mesh.triangles = (0..rim as u32)
            .map(|k| [k, (k + 1) % rim as u32, rim as u32])
            .collect();
        let boundary: Vec<u32> = (0..rim as u32).collect();
        let plane = tutte_disk(&mesh, &boundary).unwrap();
        let centre = plane[rim];
        let mean = plane[..rim].iter().fold([0.0; 2], |c, p| {
            [c[0] + p[0] / rim as f64, c[1] + p[1] / rim as f64]
        });
        assert!((centre[0] - mean[0]).abs() < 1e-9 && (centre[1] - mean[1]).abs() < 1e-9);
        for p in &plane[..rim] {
            assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-12);
        }
        assert!(tutte_disk(&mesh, &[0, 1]).is_err());
    }
}

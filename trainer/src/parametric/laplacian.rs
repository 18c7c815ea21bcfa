//! The cotangent Laplacian of §6.1 (Eq. 14): row i has wᵢᵢ = 1 and wᵢⱼ = −cᵢⱼ/Σₖcᵢₖ over the
//! one-ring, cᵢⱼ = (cot α + cot β)/2 with α, β the angles opposite edge ij.
//!
//! Obtuse triangles give negative cotangents; each cᵢⱼ is clamped to at least 10⁻³ of the
//! mean |c| of its row so a row's weights stay positive and sum to one (the uniform Laplacian
//! is used for a vertex whose weights all vanish).

use std::collections::HashMap;

/// Rows of the Laplacian: for each vertex, (neighbour, −weight) pairs; the diagonal is 1.
pub fn cotangent_laplacian(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Vec<Vec<(usize, f64)>> {
    let n = positions.len();
    let mut cot: Vec<HashMap<usize, f64>> = vec![HashMap::new(); n];
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    for t in triangles {
        for k in 0..3 {
            let (o, i, j) = (
                t[k] as usize,
                t[(k + 1) % 3] as usize,
                t[(k + 2) % 3] as usize,
            );
            if o >= n || i >= n || j >= n {
                continue;
            }
            let (u, v) = (
                sub(positions[i], positions[o]),
                sub(positions[j], positions[o]),
            );
            let dot = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
            let cross = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let area2 = (cross[0].powi(2) + cross[1].powi(2) + cross[2].powi(2)).sqrt();
            let c = if area2 > 0.0 { 0.5 * dot / area2 } else { 0.0 };
            *cot[i].entry(j).or_insert(0.0) += c;
            *cot[j].entry(i).or_insert(0.0) += c;
        }
    }
    cot.into_iter()
        .map(|row| {
            let mut entries: Vec<(usize, f64)> = row.into_iter().collect();
            entries.sort_by_key(|e| e.0);
            let mean = entries.iter().map(|e| e.1.abs()).sum::<f64>() / entries.len().max(1) as f64;
            for e in entries.iter_mut() {
                e.1 = e.1.max(1e-3 * mean);
            }
            let sum: f64 = entries.iter().map(|e| e.1).sum();
            let uniform = 1.0 / entries.len().max(1) as f64;
            entries
                .into_iter()
                .map(|(j, w)| (j, if sum > 0.0 { -w / sum } else { -uniform }))
                .collect()
        })
        .collect()
}

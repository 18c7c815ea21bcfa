//! Machined shapes of our own for the hole benches: a box and a capped cylinder, meshed
//! watertight and facing outwards, with sharp edges where their faces meet.

use std::f64::consts::TAU;

use neurosurf_trainer::io::Mesh;

/// Appends the vertices of `grid` (rows of points) and its cells cut into two triangles
/// each, alternating the diagonal, facing along `(row step) × (column step)`.
fn push_grid(mesh: &mut Mesh, grid: &[Vec<[f64; 3]>]) {
    let base = mesh.positions.len() as u32;
    let width = grid[0].len() as u32;
    for row in grid {
        mesh.positions.extend(row);
    }
    for j in 0..grid.len() as u32 - 1 {
        for i in 0..width - 1 {
            let a = base + j * width + i;
            let (b, c, d) = (a + 1, a + width + 1, a + width);
            if (i + j) % 2 == 0 {
                mesh.triangles.extend([[a, b, c], [a, c, d]]);
            } else {
                mesh.triangles.extend([[a, b, d], [b, c, d]]);
            }
        }
    }
}

/// Merges vertices at the same place (faces meeting at an edge) and drops unused ones.
fn welded(mesh: Mesh) -> Mesh {
    let mut index = std::collections::HashMap::new();
    let mut out = Mesh::default();
    let remap: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = p.map(|x| (x * 1e6).round() as i64);
            *index.entry(key).or_insert_with(|| {
                out.positions.push(*p);
                out.positions.len() as u32 - 1
            })
        })
        .collect();
    out.triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|v| remap[v as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    out
}

/// A 2 × 1.5 × 1 box, its faces gridded at 0.1.
pub fn box_mesh() -> Mesh {
    let face = |origin: [f64; 3], u: [f64; 3], v: [f64; 3]| -> Vec<Vec<[f64; 3]>> {
        let length = |a: [f64; 3]| a.iter().map(|x| x * x).sum::<f64>().sqrt();
        let (nu, nv) = (
            (length(u) / 0.1).round() as usize,
            (length(v) / 0.1).round() as usize,
        );
        (0..=nv)
            .map(|j| {
                (0..=nu)
                    .map(|i| {
                        let (s, t) = (i as f64 / nu as f64, j as f64 / nv as f64);
                        [0, 1, 2].map(|k| origin[k] + u[k] * s + v[k] * t)
                    })
                    .collect()
            })
            .collect()
    };
    let (x, y, z) = (2.0, 1.5, 1.0);
    let mut mesh = Mesh::default();
    for grid in [
        face([0.0; 3], [0.0, y, 0.0], [x, 0.0, 0.0]),
        face([0.0, 0.0, z], [x, 0.0, 0.0], [0.0, y, 0.0]),
        face([0.0; 3], [x, 0.0, 0.0], [0.0, 0.0, z]),
        face([0.0, y, 0.0], [0.0, 0.0, z], [x, 0.0, 0.0]),
        face([0.0; 3], [0.0, 0.0, z], [0.0, y, 0.0]),
        face([x, 0.0, 0.0], [0.0, y, 0.0], [0.0, 0.0, z]),
    ] {
        push_grid(&mut mesh, &grid);
    }
    welded(mesh)
}

/// A cylinder of radius 1 and height 1.5 with flat caps: 48 vertices round, 12 rows up, each
/// cap in 6 rings of 8, 16, …, 48 vertices round a centre.
pub fn can_mesh() -> Mesh {
    const ROUND: usize = 48;
    const RINGS: usize = 6;
    let height = 1.5;
    let at = |k: usize, count: usize, r: f64, z: f64| {
        let a = TAU * k as f64 / count as f64;
        [r * a.cos(), r * a.sin(), z]
    };
    let mut mesh = Mesh::default();
    let side: Vec<Vec<[f64; 3]>> = (0..=12)
        .map(|j| {
            (0..=ROUND)
                .map(|i| at(i % ROUND, ROUND, 1.0, height * j as f64 / 12.0))
                .collect()
        })
        .collect();
    push_grid(&mut mesh, &side);
    for (z, up) in [(height, true), (0.0, false)] {
        let centre = mesh.positions.len() as u32;
        mesh.positions.push([0.0, 0.0, z]);
        let mut inner = vec![centre];
        for ring in 1..=RINGS {
            let count = ROUND * ring / RINGS;
            let base = mesh.positions.len() as u32;
            mesh.positions
                .extend((0..count).map(|k| at(k, count, ring as f64 / RINGS as f64, z)));
            let outer: Vec<u32> = (0..count as u32).map(|k| base + k).collect();
            // Walk both rings by angle, each step a triangle on the ring that is behind.
            let (mut i, mut o) = (0, 0);
            while i < inner.len() || o < outer.len() {
                let angle = |k: usize, n: usize| k as f64 / n as f64;
                let take_outer = i == inner.len()
                    || (o < outer.len() && angle(o + 1, outer.len()) <= angle(i + 1, inner.len()));
                let triangle = if take_outer {
                    o += 1;
                    [inner[i % inner.len()], outer[o - 1], outer[o % outer.len()]]
                } else {
                    i += 1;
                    [inner[i - 1], outer[o % outer.len()], inner[i % inner.len()]]
                };
                mesh.triangles.push(if up {
                    triangle
                } else {
                    [triangle[0], triangle[2], triangle[1]]
                });
            }
            inner = outer;
        }
    }
    welded(mesh)
}

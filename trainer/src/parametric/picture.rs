//! A wireframe picture of a mesh and, optionally, the points it was made from: edges drawn in
//! an oblique view (turned 30° about z, tilted 55°), shaded by depth; points as dots.

use crate::io::Mesh;
use crate::plot::{Dot, Rgb, Scene, Stroke};

/// The scene of `mesh`'s edges (and `points` as dots) in a `size` × `size` picture.
pub fn wireframe(mesh: &Mesh, points: &[[f64; 3]], size: u32) -> Scene {
    let (turn, tilt) = (30f64.to_radians(), 55f64.to_radians());
    let view = |p: [f64; 3]| {
        let x = p[0] * turn.cos() - p[1] * turn.sin();
        let y = p[0] * turn.sin() + p[1] * turn.cos();
        // Screen right, screen up, depth (towards the viewer).
        [
            x,
            y * tilt.cos() + p[2] * tilt.sin(),
            -y * tilt.sin() + p[2] * tilt.cos(),
        ]
    };
    let projected: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .chain(points)
        .map(|&p| view(p))
        .collect();
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in &projected {
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let margin = 0.06 * f64::from(size);
    let scale = (f64::from(size) - 2.0 * margin) / (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12);
    let pixel = |p: [f64; 3]| {
        [
            margin + (p[0] - lo[0]) * scale,
            f64::from(size) - margin - (p[1] - lo[1]) * scale,
        ]
    };
    let shade = |depth: f64| {
        let t = ((depth - lo[2]) / (hi[2] - lo[2]).max(1e-12)).clamp(0.0, 1.0);
        let c = |far: f64, near: f64| (far + (near - far) * t) as u8;
        Rgb(c(190.0, 20.0), c(200.0, 70.0), c(215.0, 160.0))
    };
    let mut edges: Vec<(u32, u32)> = mesh
        .triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let depth = |e: &(u32, u32)| projected[e.0 as usize][2] + projected[e.1 as usize][2];
    edges.sort_by(|a, b| depth(a).total_cmp(&depth(b)));
    let mut scene = Scene::new(size, size);
    for e in &edges {
        let (a, b) = (projected[e.0 as usize], projected[e.1 as usize]);
        scene.strokes.push(Stroke::new(
            vec![pixel(a), pixel(b)],
            shade(0.5 * (a[2] + b[2])),
            1.0,
        ));
    }
    for &p in &projected[mesh.positions.len()..] {
        scene.dots.push(Dot {
            center: pixel(p),
            radius: 1.6,
            color: Rgb(0xd9, 0x5f, 0x0e),
        });
    }
    scene
}

//! The part of a sampled surface its samples reach, for the benches that measure a rebuilt
//! surface against the truth: the convex hull of the samples' parameters, and the surface
//! meshed on a grid of its parameters within it.

use neurosurf_trainer::io::Mesh;

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
pub fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let turn = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f64; 2]> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &[f64; 2]>> = if pass == 0 {
            Box::new(sorted.iter())
        } else {
            Box::new(sorted.iter().rev())
        };
        for &p in ordered {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Whether `p` lies inside (or on) the counter-clockwise convex polygon `hull`.
pub fn inside_convex(p: [f64; 2], hull: &[[f64; 2]]) -> bool {
    (0..hull.len()).all(|i| {
        let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= 0.0
    })
}

/// The surface `position` triangulated on a `side × side` grid of the parameter rectangle
/// `domain`; cells with a corner where `keep` is false are left out.
pub fn grid_mesh(
    side: usize,
    domain: [[f64; 2]; 2],
    position: impl Fn(f64, f64) -> [f64; 3],
    keep: impl Fn([f64; 2]) -> bool,
) -> Mesh {
    let [s, t] = domain;
    let at = |i: usize, j: usize| {
        [
            s[0] + (s[1] - s[0]) * i as f64 / side as f64,
            t[0] + (t[1] - t[0]) * j as f64 / side as f64,
        ]
    };
    let positions = (0..=side)
        .flat_map(|j| (0..=side).map(move |i| (i, j)))
        .map(|(i, j)| {
            let [s, t] = at(i, j);
            position(s, t)
        })
        .collect();
    let index = |i: usize, j: usize| (j * (side + 1) + i) as u32;
    let mut triangles = Vec::new();
    for j in 0..side {
        for i in 0..side {
            let corners = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            if corners.iter().all(|&(i, j)| keep(at(i, j))) {
                triangles.push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
                triangles.push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
            }
        }
    }
    Mesh {
        positions,
        triangles,
    }
}

//! The Cao En depth buffer against meshing the same network, in the same run: spot fitted
//! with 200 and 256 keys (`caoen fit-mesh`'s defaults), rendered at 400 × 400 from the
//! starting icosphere of level 3, and meshed on the level-6 icosphere (40 962 vertices, what
//! `caoen mesh --subdivisions 6` writes).
//!
//! Run: `cargo bench -p neurosurf-trainer --bench caoen_render`; `-- --out FILE` also writes
//! the table as Markdown.

use std::time::Instant;

use neurosurf_trainer::caoen::{
    MeshFitOptions, View, depth_buffer_image, fit_parameterized, sphere_mesh,
    spherical_parameterization,
};
use neurosurf_trainer::io::{data_file, read_mesh};
use neurosurf_trainer::plot::Rgb;

/// Median seconds of 5 runs of `f`.
fn median(mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..5)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1));
    let mesh = read_mesh(&data_file("spot.obj").expect("spot.obj")).expect("spot");
    let map = spherical_parameterization(&mesh).expect("map");
    let mut table = String::from(
        "| network | depth buffer 400² | pixels drawn | mesh, 40 962 vertices | depth buffer / mesh |\n\
         |---|---:|---:|---:|---:|\n",
    );
    for keys in [200, 256] {
        let fit =
            fit_parameterized(&mesh, &map.points, keys, &MeshFitOptions::default()).expect("fit");
        let network = fit.network;
        // Framed like `caoen render`: the bounding sphere of the meshed surface.
        let surface = sphere_mesh(&network, 3).expect("mesh").mesh.positions;
        let view = View::framing_points(&surface, [-1.0, -0.3, -0.5], [0.0, 1.0, 0.0], 400, 400)
            .expect("view");
        let mut drawn = 0;
        let render = median(|| {
            let picture =
                depth_buffer_image(&[(&network, Rgb(200, 110, 60))], &view, 3).expect("render");
            drawn = picture.covered();
        });
        let meshing = median(|| {
            sphere_mesh(&network, 6).expect("mesh");
        });
        table += &format!(
            "| spot, {keys} keys | {:.3} s | {drawn} | {:.3} s | {:.2} |\n",
            render,
            meshing,
            render / meshing
        );
    }
    print!("{table}");
    if let Some(path) = out {
        let text = format!(
            "# Cao En depth buffer\n\nWritten by `cargo bench -p neurosurf-trainer --bench \
             caoen_render -- --out {path}`. Median of 5 runs each, one after the other on this \
             machine; the ratio compares the two in the same run.\n\n{table}"
        );
        std::fs::write(path, text).expect("write the table");
    }
}

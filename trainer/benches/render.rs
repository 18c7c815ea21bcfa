//! Carcenac's Table 2 render column on this machine: the 3-feature head (tree ((0,1),2),
//! 99 control points, seed 1 as in `neurosurf demo`), 256×256 pixels, 4 rays per pixel. The
//! paper took 229 s on a 500 MHz Pentium III.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench render`. Prints the punctual render (core
//! f32, the paper's method) and the guaranteed render (f64 intervals), each the median of 3
//! runs on all cores, writes both PNGs under `target/tmp/`, then the mesh at resolution 128 and
//! the punctual-vs-guaranteed comparison on a 96×96 hit map.

use std::time::Instant;

use neurosurf_core::scalar::ScalarKind;
use neurosurf_trainer::implicit::{self, FitRequest, ImplicitOptions, TreeSpec};
use neurosurf_trainer::render::{
    Camera, CoreField, DEFAULT_BOX_SIZE, DEFAULT_INFLATE, Field, Method, NetworkField, Region,
    RenderOptions, View, bounds_of, compare_methods, extract_mesh, render, write_png,
};
use neurosurf_trainer::sample::{Shape, sample_shape};

/// The paper's 256×256 render of the head (Table 2), seconds.
const PAPER_SECONDS: f64 = 229.0;

fn main() {
    let start = Instant::now();
    let points = sample_shape(&Shape::Head, 99, 1).expect("head samples");
    let request = FitRequest {
        tree: Some("((0,1),2)".parse::<TreeSpec>().expect("tree")),
        ..FitRequest::default()
    };
    let trained =
        implicit::fit(points, &request, &ImplicitOptions::default(), &|_| {}).expect("training");
    println!("head trained in {:.2} s", start.elapsed().as_secs_f64());
    let blob = implicit::to_blob(&trained.network, None, ScalarKind::F32).expect("blob");
    let regions = Region::of_network(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE);
    let core = CoreField::new(&blob, regions).expect("core field");
    let network =
        NetworkField::new(&trained.network, DEFAULT_BOX_SIZE, DEFAULT_INFLATE).expect("field");
    let view = View {
        azimuth: 50.0,
        elevation: 10.0,
        ..View::default()
    };
    let camera =
        Camera::orbit(&bounds_of(core.regions()).expect("bounds"), &view, 256, 256).expect("cam");
    println!(
        "threads: {}; paper: {PAPER_SECONDS} s (500 MHz Pentium III)",
        rayon::current_num_threads()
    );
    for (name, method, field) in [
        ("punctual, core f32", Method::Punctual, &core as &dyn Field),
        (
            "guaranteed, f64 intervals",
            Method::Guaranteed,
            &network as &dyn Field,
        ),
    ] {
        let options = RenderOptions {
            method,
            ..RenderOptions::default()
        };
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..3 {
            let r = render(field, &camera, &options, &|_, _| {}).expect("render");
            times.push(r.stats.seconds);
            last = Some(r);
        }
        times.sort_by(f64::total_cmp);
        let r = last.expect("rendered");
        let file = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join(format!("head-{}.png", format!("{method:?}").to_lowercase()));
        write_png(&file, &r.image).expect("png");
        let file = file.display();
        println!(
            "render 256×256 ×4 rays ({name}): median {:.3} s (min {:.3}), {:.0}× faster than the \
             paper; {} of {} rays hit, {} voxels; wrote {file}",
            times[1],
            times[0],
            PAPER_SECONDS / times[1],
            r.stats.hits,
            r.stats.rays,
            r.stats.voxels
        );
    }
    let mesh = extract_mesh(&core, 128, &|_, _| {}).expect("mesh");
    println!("mesh at resolution 128: {:?}", mesh.stats);
    let small =
        Camera::orbit(&bounds_of(core.regions()).expect("bounds"), &view, 96, 96).expect("camera");
    let c = compare_methods(&network, &small, &RenderOptions::default(), 0.002).expect("compare");
    println!("punctual vs guaranteed (f64 network, 96×96, dense step 0.002): {c:?}");
}

//! Carcenac's Table 2 render column on this machine: the 3-feature head (tree ((0,1),2),
//! 99 control points, seed 1 as in `neurosurf demo`), 256×256 pixels, 4 rays per pixel. The
//! paper took 229 s on a 500 MHz Pentium III.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench render`. Prints a table of the punctual
//! render (core f32, the paper's method) over every voxel with 4 rays through every pixel (the
//! baseline), then with probed voxels (empty ones dropped), then with adaptive anti-aliasing, and the
//! guaranteed render (f64 intervals): the median of 3 runs on all cores each, the speed-up
//! over the baseline and how far each picture is from the baseline's; writes the PNGs under
//! `target/tmp/`, then the mesh at resolution 128 and the punctual-vs-guaranteed comparison on
//! a 96×96 hit map.

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
    let full = RenderOptions {
        adaptive: false,
        probe: false,
        ..RenderOptions::default()
    };
    let probed = RenderOptions {
        adaptive: false,
        ..RenderOptions::default()
    };
    let adaptive = RenderOptions::default();
    let guaranteed = RenderOptions {
        method: Method::Guaranteed,
        ..RenderOptions::default()
    };
    let runs: [(&str, &str, &dyn Field, &RenderOptions); 4] = [
        (
            "punctual, all voxels, 4 rays everywhere",
            "full",
            &core,
            &full,
        ),
        (
            "punctual, probed voxels, 4 rays everywhere",
            "probed",
            &core,
            &probed,
        ),
        (
            "punctual, probed voxels, adaptive 4 rays",
            "adaptive",
            &core,
            &adaptive,
        ),
        (
            "guaranteed (f64 intervals), adaptive",
            "guaranteed",
            &network,
            &guaranteed,
        ),
    ];
    println!(
        "| search (256×256, 4 rays/pixel) | median s | vs first row | vs paper | rays | hits | \
         voxels |"
    );
    println!("|---|---|---|---|---|---|---|");
    let mut baseline = None;
    let mut first_image = None;
    // `cargo bench --bench render -- adaptive` runs that row alone (for profiling).
    let only = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    for (name, file_name, field, options) in runs {
        if only.as_deref().is_some_and(|o| o != file_name) {
            continue;
        }
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..3 {
            let r = render(field, &camera, options, &|_, _| {}).expect("render");
            times.push(r.stats.seconds);
            last = Some(r);
        }
        times.sort_by(f64::total_cmp);
        let r = last.expect("rendered");
        let file =
            std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("head-{file_name}.png"));
        write_png(&file, &r.image).expect("png");
        let base = *baseline.get_or_insert(times[1]);
        println!(
            "| {name} | {:.3} | {:.2}× faster | {:.0}× faster | {} | {} | {} |",
            times[1],
            base / times[1],
            PAPER_SECONDS / times[1],
            r.stats.rays,
            r.stats.hits,
            r.stats.voxels
        );
        // How far each picture is from the first (every voxel, every ray): mean and worst
        // per-channel difference in 8-bit levels.
        let first = first_image.get_or_insert_with(|| r.image.clone());
        let differences: Vec<i32> = first
            .as_raw()
            .iter()
            .zip(r.image.as_raw())
            .map(|(&a, &b)| (i32::from(a) - i32::from(b)).abs())
            .collect();
        println!(
            "|  ↳ image vs first row: mean {:.3}, worst {} levels; {} |||||||",
            differences.iter().sum::<i32>() as f64 / differences.len() as f64,
            differences.iter().max().copied().unwrap_or(0),
            file.display()
        );
    }
    if only.is_some() {
        return;
    }
    let mesh = extract_mesh(&core, 128, &|_, _| {}).expect("mesh");
    println!("mesh at resolution 128: {:?}", mesh.stats);
    let small =
        Camera::orbit(&bounds_of(core.regions()).expect("bounds"), &view, 96, 96).expect("camera");
    let c = compare_methods(&network, &small, &RenderOptions::default(), 0.002).expect("compare");
    println!("punctual vs guaranteed (f64 network, 96×96, dense step 0.002): {c:?}");
}

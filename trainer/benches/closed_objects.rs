//! Closed meshes rebuilt from surface-network patches (`parametric closed`), measured both ways
//! against the (capped) input: RMS and largest distance over its bounding diagonal, the gap
//! between two patches' networks at their seam points, and the wall time. Then closed point
//! clouds (a mesh's vertices, area-uniform random samples of it, and those samples with noise)
//! rebuilt the same way, measured both ways against the points and against the mesh they came
//! from.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench closed_objects`, with after `--`:
//! `--markdown FILE` to write the tables as well (`docs/performance/closed-objects.md`),
//! `--mesh NAME` (repeatable) for other meshes in `data/` (their vertices and samples are the
//! clouds then), `--samples N` for the sampled clouds' size (20 000).

mod arguments;
use arguments::{given, in_workspace, option};

use std::fmt::Write as _;
use std::time::Instant;

use neurosurf_trainer::caoen::surface_distance;
use neurosurf_trainer::geometry::mesh_graph::edge_report;
use neurosurf_trainer::io::{Mesh, data_file, read_mesh};
use neurosurf_trainer::parametric::{
    ClosedOptions, ClosedReconstruction, reconstruct_closed, reconstruct_closed_points,
};
use neurosurf_trainer::sample::{Spread, sample_mesh};
use rand::{Rng, SeedableRng};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut names: Vec<&str> = args
        .windows(2)
        .filter(|w| w[0] == "--mesh")
        .map(|w| w[1].as_str())
        .collect();
    if names.is_empty() {
        names = vec!["stanford-bunny.obj", "spot.obj", "fandisk.obj", "woody.obj"];
    }
    let samples: usize = option(&args, "--samples").map_or(20_000, |v| v.parse().expect("a count"));
    let options = ClosedOptions::default();
    let meshes: Vec<(&str, Mesh)> = names
        .iter()
        .map(|&name| {
            let mesh = read_mesh(&data_file(name).expect("a mesh in data/")).expect("a mesh");
            (name, mesh)
        })
        .collect();
    let mut table = String::from(
        "| mesh | patches | holes capped | output vertices | watertight | RMS | largest | seam \
         gap (mean / max) | time |\n|---|---:|---:|---:|---|---:|---:|---:|---:|\n",
    );
    for (name, mesh) in &meshes {
        let started = Instant::now();
        let result = match reconstruct_closed(mesh, &options) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("{name}: {e}");
                continue;
            }
        };
        let seconds = started.elapsed().as_secs_f64();
        let row = format!(
            "| `{name}` | {} | {} | {} | {} | {:.2} % | {:.1} % | {:.2} / {:.1} % | {seconds:.0} s |",
            result.patches.len(),
            result.capped_holes,
            result.mesh.positions.len(),
            watertight(&result),
            100.0 * result.distance.rms,
            100.0 * result.distance.hausdorff,
            100.0 * result.seam_gap,
            100.0 * result.max_seam_gap,
        );
        println!("{row}");
        let _ = writeln!(table, "{row}");
    }
    let mut clouds = String::from(
        "| points | count | patches | watertight | RMS / largest to the points | RMS / largest \
         to the mesh | time |\n|---|---:|---:|---|---:|---:|---:|\n",
    );
    for (name, mesh) in &meshes {
        let sampled = sample_mesh(mesh, samples, 1, Spread::Random).expect("samples");
        let diagonal = neurosurf_trainer::geometry::bounding_diagonal(mesh);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let noisy: Vec<[f64; 3]> = sampled
            .positions
            .iter()
            .map(|p| p.map(|c| c + NOISE * diagonal * gaussian(&mut rng)))
            .collect();
        for (what, points) in [
            (format!("`{name}` vertices"), mesh.positions.clone()),
            (format!("`{name}`, random samples"), sampled.positions),
            (format!("`{name}`, random samples, noise"), noisy),
        ] {
            let started = Instant::now();
            let result = match reconstruct_closed_points(&points, &options) {
                Ok((r, _)) => r,
                Err(e) => {
                    eprintln!("{what}: {e}");
                    let _ = writeln!(
                        clouds,
                        "| {what} | {} | refused: {e} | | | | |",
                        points.len()
                    );
                    continue;
                }
            };
            let seconds = started.elapsed().as_secs_f64();
            let truth = surface_distance(&result.mesh, mesh).expect("distances");
            let row = format!(
                "| {what} | {} | {} | {} | {:.2} / {:.1} % | {:.2} / {:.1} % | {seconds:.0} s |",
                points.len(),
                result.patches.len(),
                watertight(&result),
                100.0 * result.distance.rms,
                100.0 * result.distance.hausdorff,
                100.0 * truth.rms,
                100.0 * truth.hausdorff,
            );
            println!("{row}");
            let _ = writeln!(clouds, "{row}");
        }
    }
    if let Some(path) = option(&args, "--markdown") {
        let text = format!(
            "# Closed objects\n\nWritten by `cargo bench -p neurosurf-trainer --bench \
             closed_objects -- {}` on {} threads: each mesh rebuilt by `parametric closed` \
             with default options. RMS and largest: distances both ways between the output \
             and the capped input, over its bounding diagonal; seam gap: the distance between \
             two patches' networks at their shared seam points, over the same diagonal (the \
             stitch closes it in the mesh).\n\n{table}\n## Point clouds\n\nThe same meshes' \
             vertices alone, {samples} random area-uniform samples of them (seed 1), and \
             the same samples with Gaussian noise of σ = {:.2} % of the diagonal, rebuilt by \
             `parametric closed` from the points. To the points: from every point to \
             the output, and from every output vertex to the points' tangent disks. To the \
             mesh: both ways against the mesh the points came from; where that mesh has holes \
             (the bunny), the output closes them and the largest distance is across a hole.\n\n\
             {clouds}",
            given(&args),
            rayon::current_num_threads(),
            100.0 * NOISE
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

/// The noise of the third cloud of every mesh: σ as a share of the diagonal.
const NOISE: f64 = 0.0025;

/// A standard Gaussian (Box–Muller).
fn gaussian(rng: &mut impl Rng) -> f64 {
    let (a, b) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
    (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
}

fn watertight(result: &ClosedReconstruction) -> &'static str {
    if edge_report(&result.mesh).is_watertight() {
        "yes"
    } else {
        "no"
    }
}

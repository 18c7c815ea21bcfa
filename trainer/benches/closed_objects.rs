//! Closed meshes rebuilt from surface-network patches (`parametric closed`), measured both ways
//! against the (capped) input: RMS and largest distance over its bounding diagonal, the gap
//! between two patches' networks at their seam points, and the wall time.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench closed_objects`, with after `--`:
//! `--markdown FILE` to write the table as well (`docs/performance/closed-objects.md`),
//! `--mesh NAME` (repeatable) for other meshes in `data/`.

mod arguments;
use arguments::{given, in_workspace, option};

use std::fmt::Write as _;
use std::time::Instant;

use neurosurf_trainer::geometry::mesh_graph::edge_report;
use neurosurf_trainer::io::{data_file, read_mesh};
use neurosurf_trainer::parametric::{ClosedOptions, reconstruct_closed};

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
    let options = ClosedOptions::default();
    let mut table = String::from(
        "| mesh | patches | holes capped | output vertices | watertight | RMS | largest | seam \
         gap (mean / max) | time |\n|---|---:|---:|---:|---|---:|---:|---:|---:|\n",
    );
    for name in names {
        let mesh = read_mesh(&data_file(name).expect("a mesh in data/")).expect("a mesh");
        let started = Instant::now();
        let result = match reconstruct_closed(&mesh, &options) {
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
            if edge_report(&result.mesh).is_watertight() {
                "yes"
            } else {
                "no"
            },
            100.0 * result.distance.rms,
            100.0 * result.distance.hausdorff,
            100.0 * result.seam_gap,
            100.0 * result.max_seam_gap,
        );
        println!("{row}");
        let _ = writeln!(table, "{row}");
    }
    if let Some(path) = option(&args, "--markdown") {
        let text = format!(
            "# Closed objects\n\nWritten by `cargo bench -p neurosurf-trainer --bench \
             closed_objects -- {}` on {} threads: each mesh rebuilt by `parametric closed` \
             with default options. RMS and largest: distances both ways between the output \
             and the capped input, over its bounding diagonal; seam gap: the distance between \
             two patches' networks at their shared seam points, over the same diagonal (the \
             stitch closes it in the mesh).\n\n{table}",
            given(&args),
            rayon::current_num_threads()
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

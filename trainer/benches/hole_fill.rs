//! Filled holes against the surface they replace: holes punched `--rings` deep (3) at
//! `--holes` (40) spread-out vertices of each mesh, filled with the network's surface alone
//! (`fairing: false`) and with the default options (faired unless a crease runs through the
//! region, else put on the smooth parts' own surfaces), and measured by their new vertices' distance from the removed triangles, as a
//! share of the hole's diameter: how many bulge outwards by more than 2 %, the worst bulge and
//! the median distance either way.
//!
//! Run: `cargo bench -p neurosurf-trainer --bench hole_fill`, with after `--`:
//! `--meshes spot.obj,fandisk.obj,box,can` for meshes from the data folder and the machined
//! shapes of our own (`box`: 2 × 1.5 × 1; `can`: a capped cylinder), `--rings 3,5`,
//! `--holes 40`, `--markdown FILE` to write the table as well
//! (`docs/performance/hole-fill.md`).

mod arguments;
mod machined;
use arguments::{given, in_workspace, option};

use std::fmt::Write as _;

use neurosurf_trainer::geometry::mesh_graph::boundary_loops;
use neurosurf_trainer::io::{self, Mesh};
use neurosurf_trainer::parametric::{
    FillDeviation, HoleOptions, fill_deviation, fill_hole, punch_hole,
};
use rayon::prelude::*;

/// A bulge larger than this share of the hole's diameter counts.
const BULGE: f64 = 0.02;

/// A fill's deviation as shares of its hole's diameter: (outwards, either way).
type Share = (f64, f64);
type Shares = Vec<Share>;

/// The holes punched at `holes` vertices spread over `mesh` (by a multiplicative hash), each
/// filled both ways; holes that do not open as one new boundary loop, or that either way
/// cannot fill, are counted and left out.
fn measure(mesh: &Mesh, rings: usize, holes: u64) -> (Shares, Shares, usize) {
    let n = mesh.positions.len() as u64;
    let before = boundary_loops(&mesh.triangles).map_or(0, |l| l.len());
    let results: Vec<Option<(Share, Share)>> = (0..holes)
        .into_par_iter()
        .map(|k| {
            let seed = (k * 2_654_435_761 % n) as u32;
            let (holed, removed) = punch_hole(mesh, seed, rings).ok()?;
            let loops = boundary_loops(&holed.triangles).ok()?;
            if loops.len() != before + 1 {
                return None;
            }
            let touched: std::collections::HashSet<u32> =
                removed.iter().flatten().copied().collect();
            let hole = loops
                .iter()
                .find(|l| l.iter().all(|v| touched.contains(v)))?;
            let share = |d: FillDeviation| (d.outwards / d.diameter, d.either / d.diameter);
            let mut shares = [false, true].into_iter().map(|fairing| {
                let options = HoleOptions {
                    fairing,
                    ..HoleOptions::default()
                };
                let filled = fill_hole(&holed, hole, &options).ok()?;
                Some(share(fill_deviation(mesh, hole, &removed, &filled)))
            });
            Some((shares.next()??, shares.next()??))
        })
        .collect();
    let skipped = results.iter().filter(|r| r.is_none()).count();
    let (network, default) = results.into_iter().flatten().unzip();
    (network, default, skipped)
}

fn summary(shares: &Shares) -> (usize, f64, f64) {
    let bulges = shares.iter().filter(|s| s.0 > BULGE).count();
    let worst = shares.iter().map(|s| s.0).fold(0.0, f64::max);
    let mut either: Vec<f64> = shares.iter().map(|s| s.1).collect();
    either.sort_by(f64::total_cmp);
    let median = either.get(either.len() / 2).copied().unwrap_or(0.0);
    (bulges, worst, median)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let meshes: Vec<&str> = option(&args, "--meshes")
        .unwrap_or("spot.obj,fandisk.obj,stanford-bunny.obj,box,can")
        .split(',')
        .collect();
    let rings: Vec<usize> = option(&args, "--rings")
        .unwrap_or("3")
        .split(',')
        .map(|s| s.parse().expect("--rings: ring counts separated by commas"))
        .collect();
    let holes: u64 = option(&args, "--holes")
        .unwrap_or("40")
        .parse()
        .expect("--holes: a count");
    let mut table = String::from(
        "| mesh | rings | holes | bulging > 2 % | worst bulge | median either way |\n\
         |---|---:|---:|---:|---:|---:|\n",
    );
    for name in &meshes {
        let mesh = match *name {
            "box" => machined::box_mesh(),
            "can" => machined::can_mesh(),
            _ => {
                let path = io::data_file(name).expect("a mesh in the data folder");
                io::read_mesh(&path).expect("a readable mesh")
            }
        };
        for &r in &rings {
            let (network, default, skipped) = measure(&mesh, r, holes);
            let (nb, nw, nm) = summary(&network);
            let (db, dw, dm) = summary(&default);
            let row = format!(
                "| {name} | {r} | {}{} | {nb} → {db} | {:.1} → {:.1} % | {:.1} → {:.1} % |",
                network.len(),
                if skipped > 0 {
                    format!(" ({skipped} skipped)")
                } else {
                    String::new()
                },
                100.0 * nw,
                100.0 * dw,
                100.0 * nm,
                100.0 * dm,
            );
            println!("{row}");
            let _ = writeln!(table, "{row}");
        }
    }
    if let Some(path) = option(&args, "--markdown") {
        let text = format!(
            "# Filled holes\n\nWritten by `cargo bench -p neurosurf-trainer --bench hole_fill -- \
             {}`: holes punched at spread-out vertices, filled with the network's surface alone \
             → with the default options (faired where no sharp crease runs through the region, \
             else on the smooth parts' own surfaces); `box` and `can` are a 2 × 1.5 × 1 box \
             and a capped cylinder (radius 1, height 1.5) meshed by the bench; \
             the new vertices' distance from the removed triangles, % of the hole's diameter \
             (a bulge is a distance outwards).\n\n{table}",
            given(&args)
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

//! `neurosurf`: train neural freeform surfaces on a desktop, write blobs for microcontrollers,
//! evaluate them in f64, f32 and Q16.16. Run `neurosurf --help`.
//!
//! The command line: one module per command, each a thin layer over the `neurosurf-trainer`
//! library.

mod caoen;
mod compare;
mod curve;
mod demo;
mod eval;
mod implicit;
mod info;
mod mesh;
mod output;
mod parametric;
mod progress;
mod render;
mod sample;
mod sim;
mod sim_bench;
mod target;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Neural freeform surfaces: train on a desktop, evaluate on microcontrollers.
#[derive(Debug, Parser)]
#[command(name = "neurosurf", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Sample oriented control points from a built-in shape or a mesh file.
    Sample(sample::Args),
    /// Implicit surfaces (Carcenac): fit a module tree, or the RBF baseline, to oriented
    /// points and write its blob. (`implicit fit` and `implicit rbf` are the same commands.)
    #[command(subcommand, alias = "train")]
    Implicit(implicit::Command),
    /// Cao En surfaces (Wyvill, Cao & Trotman): fit a network to key and target points, mesh
    /// it.
    #[command(subcommand)]
    Caoen(caoen::Command),
    /// Curves and surfaces from scattered points (Hoffmann & Várady): sample, fit, plot,
    /// bench.
    #[command(subcommand)]
    Curve(curve::Command),
    /// Parametric surfaces from point sets (Yumer & Kara): sample, embed, fit a surface
    /// network, tessellate, stitch patches, fill holes, bench.
    /// (`patch` is the same command.)
    #[command(subcommand, alias = "patch")]
    Parametric(parametric::Command),
    /// Evaluate a model at query points; CSV `x,y,z,phi,gx,gy,gz` on stdout.
    ///
    /// Curves read one parameter t ∈ [0, 1] per line and print `t,x,y,z,tx,ty,tz` (position
    /// and tangent dC/dt); spline surfaces read `u v` and print `u,v,x,y,z,nx,ny,nz` (position
    /// and unit normal, 0,0,0 where it does not exist), and so do surface networks; Cao En
    /// networks read their m source
    /// coordinates and print `s1..sm`, their outputs (`x,y,z`, or `y1..yp`) and `nx,ny,nz`.
    Eval(eval::Args),
    /// Describe a blob: kind, tree, parameters, size, training summary.
    Info(info::Args),
    /// The main job on built-in data: train a torus and a 3-feature head, write their blobs,
    /// and print their accuracy in f64, f32 and Q16.16.
    Demo(demo::Args),
    /// Evaluate a model on the simulated Cortex-M4F (QEMU); the same CSV as `eval`, or the
    /// run's cost with `--json`.
    ///
    /// The unmodified core runs on a Cortex-M4F under QEMU (`mps2-an386`); the CSV is exactly
    /// what `neurosurf eval` prints for the same scalar. `--json` prints instead the run's
    /// cost: instructions per point, multiply–accumulates, flash, static RAM, stack, and the
    /// target's log. The target has no f64 and does not run host-only models (RBF).
    Sim(sim::Args),
    /// Fixed point against float: f32 and Q16.16, on the host and on the simulated target,
    /// against the f64 reference.
    ///
    /// For every evaluation (f32 host, f32 target, q16.16 host, q16.16 target) the report gives
    /// the max and RMS field error |Φ − Φ_f64|, the max and median angle between the normals
    /// −∇Φ/|∇Φ| and the f64 normals (points where either gradient is zero are skipped and
    /// counted), and for the target rows whether every value equals the host's bit for bit,
    /// with the largest difference in ulps (f32 ulps; 2⁻¹⁶ steps in Q16.16).
    ///
    /// Every point is first rounded to f32, which is what the core receives, so the f64
    /// reference sees the same inputs (Q16.16 then rounds them to 2⁻¹⁶ itself).
    ///
    /// Without --points the points come from the model itself: 1000 points uniform in the
    /// leaves' normalization boxes (fixed seed, so the same model gives the same points), each
    /// pushed onto the surface by up to 8 Newton steps x ← x − Φ∇Φ/|∇Φ|² in f64 and kept if
    /// |Φ| < 1e-6 and it stays near a box. If fewer than 50 survive, the box samples are used
    /// unprojected and the report says so.
    Compare(compare::Args),
    /// The cost table on the simulated Cortex-M4F: instructions per evaluation against
    /// multiply–accumulates, f32 against Q16.16, with flash, static RAM and stack.
    ///
    /// Trains two models with fixed seeds (a torus, one leaf of width 9; the 3-feature head
    /// with tree ((0,1),2)), stores each as f32 and as Q16.16, and runs 64 points on its
    /// surface for each scalar × op (field, field+gradient) × mode (single, batch); then a
    /// spiral B-spline curve (position, position+tangent at 64 parameters) and a surface
    /// network fitted to a wavy patch (position, position+normal at 64 (u, v)). Blob paths
    /// given as arguments are measured too (implicit models and every parametric kind).
    SimBench(sim_bench::Args),
    /// Ray-cast an implicit model to a PNG: octree over the leaf boxes, Newton per voxel on
    /// the core in f32 (Carcenac §6), or `--guaranteed` interval search in f64.
    Render(render::Args),
    /// Extract a watertight triangle mesh (OBJ, PLY or STL) of an implicit model.
    Mesh(mesh::Args),
}

/// Parses the arguments, runs the command, and turns an error into a message and exit code 1.
fn main() -> ExitCode {
    restore_default_sigpipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Sample(args) => sample::run(&args),
        Command::Implicit(command) => implicit::run(&command),
        Command::Caoen(command) => caoen::run(&command),
        Command::Curve(command) => curve::run(&command),
        Command::Parametric(command) => parametric::run(&command),
        Command::Eval(args) => eval::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Demo(args) => demo::run(&args),
        Command::Sim(args) => sim::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::SimBench(args) => sim_bench::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Mesh(args) => mesh::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", describe(&error));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes, each cause added only if the message so far does not already
/// say it (the library's errors often quote their source).
fn describe(error: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in error.chain() {
        let part = cause.to_string();
        if !text.contains(&part) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&part);
        }
    }
    text
}

/// Rust ignores SIGPIPE, so `neurosurf eval … | head` would panic on the closed pipe; a
/// command-line tool should end quietly instead, as `cat` does.
#[cfg(unix)]
fn restore_default_sigpipe() {
    // SAFETY: called first thing in `main`, before any thread exists; setting a signal's
    // disposition to its default has no other effect on the program.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn restore_default_sigpipe() {}

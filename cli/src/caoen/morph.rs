//! `neurosurf caoen morph`: metamorphosis between two networks (paper §12.1).

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use neurosurf_core::caoen::Domain;
use serde::Serialize;

use neurosurf_trainer::caoen::{self, MAX_FRAMES, Morph};
use neurosurf_trainer::io::write_mesh;
use neurosurf_trainer::render::write_png;

use super::super::output;
use super::read_network;
use super::render::{Camera, depth_picture_framed};

#[derive(Debug, clap::Args)]
pub struct Args {
    /// The network at t = 0.
    from: PathBuf,
    /// The network at t = 1 (same domain, blending and form; any key count — unpaired keys
    /// become empty key points).
    to: PathBuf,
    /// Frames, t = k/(frames − 1).
    #[arg(long, default_value_t = 5)]
    frames: usize,
    /// Icosphere subdivisions of each frame's mesh (torus: a 10·2ˢ × 5·2ˢ grid).
    #[arg(long, default_value_t = 3)]
    subdivisions: usize,
    /// Folder for `frame_000.obj`, … (and `frame_000.png`, … with --png).
    #[arg(long)]
    out_dir: PathBuf,
    /// Also render every frame (depth buffer, one camera framing both ends).
    #[arg(long)]
    png: bool,
    #[command(flatten)]
    camera: Camera,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct Report {
    frames: usize,
    keys_from: usize,
    keys_to: usize,
    /// Keys of the in-between network (paired keys once, unpaired ones as empty keys).
    keys_between: usize,
    meshes: Vec<PathBuf>,
    pictures: Vec<PathBuf>,
}

pub fn run(args: &Args) -> Result<()> {
    if !(2..=MAX_FRAMES).contains(&args.frames) {
        bail!("--frames must be 2 to {MAX_FRAMES}, got {}", args.frames);
    }
    let from = read_network(&args.from, "morph")?;
    let to = read_network(&args.to, "morph")?;
    let morph = Morph::new(&from, &to)?;
    std::fs::create_dir_all(&args.out_dir)?;
    let mut report = Report {
        frames: args.frames,
        keys_from: from.key_count(),
        keys_to: to.key_count(),
        keys_between: morph.key_count(),
        meshes: Vec::new(),
        pictures: Vec::new(),
    };
    let ends = [from.clone(), to.clone()];
    for k in 0..args.frames {
        let t = k as f64 / (args.frames - 1) as f64;
        let network = morph.at(t)?;
        let mapped = if network.domain == Domain::Torus.code() {
            caoen::torus_mesh(
                &network,
                10 << args.subdivisions.min(8),
                5 << args.subdivisions.min(8),
            )?
        } else {
            caoen::sphere_mesh(&network, args.subdivisions)?
        };
        let path = frame_path(&args.out_dir, k, "obj");
        write_mesh(&path, &mapped.mesh, Some(&mapped.normals))?;
        report.meshes.push(path);
        if args.png {
            let picture = depth_picture_framed(
                std::slice::from_ref(&network),
                &ends,
                &args.camera,
                args.subdivisions.min(6),
            )?;
            let path = frame_path(&args.out_dir, k, "png");
            write_png(&path, &picture.image)?;
            report.pictures.push(path);
        }
    }
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} frames from {} keys to {} keys ({} in between); wrote {} meshes{} to {}",
        report.frames,
        report.keys_from,
        report.keys_to,
        report.keys_between,
        report.meshes.len(),
        if args.png { " and pictures" } else { "" },
        args.out_dir.display()
    );
    Ok(())
}

fn frame_path(dir: &Path, k: usize, extension: &str) -> PathBuf {
    dir.join(format!("frame_{k:03}.{extension}"))
}

//! `neurosurf caoen image`: pictures as Cao En networks on a 5-D hypersphere (paper §12.5).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Subcommand;
use serde::Serialize;

use neurosurf_trainer::caoen::{CompressedImage, compress_image, psnr, smooth_test_image};
use neurosurf_trainer::evaluate::Precision;
use neurosurf_trainer::render::write_png;

use super::super::output::{self, blob_scalar, comma_list};

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Compress a PNG into a Cao En blob (key points on S⁴, V fitted to every pixel).
    Compress(CompressArgs),
    /// Reconstruct the PNG from the blob alone.
    Decompress(DecompressArgs),
    /// Write the smooth synthetic test picture.
    Sample(SampleArgs),
}

pub fn run(command: &Command) -> Result<()> {
    match command {
        Command::Compress(args) => compress(args),
        Command::Decompress(args) => decompress(args),
        Command::Sample(args) => sample(args),
    }
}

#[derive(Debug, clap::Args)]
pub struct CompressArgs {
    /// The picture (PNG, or any format the `image` crate reads with its enabled features).
    input: PathBuf,
    /// Key points (rounded down to a grid close to the picture's aspect; 4 … 256).
    #[arg(long)]
    keys: usize,
    /// Weight γ of the luminance in the source point, 0 … 1 (0: position only).
    #[arg(long, default_value_t = 0.3)]
    gamma: f64,
    /// Luminance refinements when decoding (with γ > 0).
    #[arg(long, default_value_t = 3)]
    iterations: u8,
    /// How the blob stores the network: `f32` or `q16.16`.
    #[arg(long, default_value = "f32")]
    scalar: Precision,
    /// Output blob.
    #[arg(long)]
    out: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct CompressReport<'a> {
    out: &'a Path,
    width: u32,
    height: u32,
    key_points: usize,
    stored_as: &'static str,
    blob_bytes: usize,
    /// Bytes of the picture as raw 8-bit RGB.
    raw_bytes: usize,
    /// PSNR of the picture decoded from the blob as written, dB.
    psnr_db: f64,
}

fn compress(args: &CompressArgs) -> Result<()> {
    let scalar = blob_scalar(args.scalar)?;
    neurosurf_trainer::io::check_output(&args.out)?;
    let picture = neurosurf_trainer::io::read_picture(&args.input)?;
    neurosurf_trainer::caoen::check_key_count(args.keys, "--keys")?;
    let compressed = compress_image(&picture, args.keys, args.gamma, args.iterations)?;
    let blob = compressed.to_blob(scalar)?;
    // Measure what a reader of the blob gets (the words rounded to the scalar).
    let decoded = CompressedImage::from_blob(&blob, &args.out)?.decode();
    neurosurf_trainer::blob::write_checked(&args.out, &blob)?;
    let report = CompressReport {
        out: &args.out,
        width: picture.width(),
        height: picture.height(),
        key_points: compressed.network.key_count(),
        stored_as: scalar.name(),
        blob_bytes: blob.len(),
        raw_bytes: picture.as_raw().len(),
        psnr_db: psnr(&picture, &decoded)?,
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} × {} pixels, {} key points: {} bytes ({} raw), PSNR {:.2} dB; wrote {}",
        report.width,
        report.height,
        report.key_points,
        report.blob_bytes,
        report.raw_bytes,
        report.psnr_db,
        args.out.display()
    );
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct DecompressArgs {
    /// A blob written by `caoen image compress`.
    blob: PathBuf,
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
    /// The original picture, to report the PSNR against.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct DecompressReport<'a> {
    out: &'a Path,
    width: u32,
    height: u32,
    key_points: usize,
    blob_bytes: usize,
    psnr_db: Option<f64>,
}

fn decompress(args: &DecompressArgs) -> Result<()> {
    let bytes = std::fs::read(&args.blob)
        .with_context(|| format!("cannot read {}", args.blob.display()))?;
    let compressed = CompressedImage::from_blob(&bytes, &args.blob)?;
    let picture = compressed.decode();
    let psnr_db = match &args.reference {
        Some(path) => Some(psnr(&neurosurf_trainer::io::read_picture(path)?, &picture)?),
        None => None,
    };
    write_png(&args.out, &picture)?;
    let report = DecompressReport {
        out: &args.out,
        width: picture.width(),
        height: picture.height(),
        key_points: compressed.network.key_count(),
        blob_bytes: bytes.len(),
        psnr_db,
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} × {} pixels from {} key points ({} bytes){}; wrote {}",
        report.width,
        report.height,
        report.key_points,
        report.blob_bytes,
        psnr_db.map_or(String::new(), |p| format!(", PSNR {p:.2} dB")),
        args.out.display()
    );
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// Picture size, `WIDTH,HEIGHT`.
    #[arg(long, value_parser = comma_list::<u32, 2>, default_value = "64,64")]
    size: [u32; 2],
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
}

fn sample(args: &SampleArgs) -> Result<()> {
    let [width, height] = args.size;
    if width == 0 || height == 0 || width > 4096 || height > 4096 {
        anyhow::bail!("--size: each side must be 1 to 4096, got {width} × {height}");
    }
    write_png(&args.out, &smooth_test_image(width, height))?;
    println!("wrote {}", args.out.display());
    Ok(())
}

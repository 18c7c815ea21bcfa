//! `neurosurf caoen image`: pictures as Cao En networks on a 5-D hypersphere (paper §12.5),
//! one per 8 × 8 tile, with key points placed where the picture changes.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Subcommand;
use serde::Serialize;

use neurosurf_trainer::caoen::{
    CompressedImage, ImageOptions, compress_image, edge_test_image, psnr, smooth_test_image,
    thumbnail,
};
use neurosurf_trainer::render::write_png;

use super::super::output::{self, comma_list};

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Compress a PNG into at most `--bytes` bytes (key points on S⁴, V fitted to every pixel).
    Compress(CompressArgs),
    /// Reconstruct the PNG from the compressed file alone.
    Decompress(DecompressArgs),
    /// Write a synthetic test picture (smooth shading, or flat shapes with hard edges).
    Sample(SampleArgs),
}

pub fn run(command: &Command) -> Result<()> {
    match command {
        Command::Compress(args) => compress(args),
        Command::Decompress(args) => decompress(args),
        Command::Sample(args) => sample(args),
    }
}

/// `auto` (the compressor chooses) or a number.
#[derive(Copy, Clone, Debug)]
struct AutoOr(Option<f64>);

fn auto_or_number(text: &str) -> Result<AutoOr, String> {
    if text.eq_ignore_ascii_case("auto") {
        return Ok(AutoOr(None));
    }
    text.parse::<f64>()
        .map(|v| AutoOr(Some(v)))
        .map_err(|_| format!("'{text}' is neither `auto` nor a number"))
}

#[derive(Debug, clap::Args)]
pub struct CompressArgs {
    /// The picture (PNG).
    input: PathBuf,
    /// The most bytes the compressed file may take (header and checksum included).
    #[arg(long)]
    bytes: usize,
    /// Weight γ of the luminance in the source point, 0 … 1, or `auto` (tries 0 and 1).
    #[arg(long, default_value = "auto", value_parser = auto_or_number)]
    gamma: AutoOr,
    /// How far each key's blending reaches, in sides of its quadtree cell (0.1 … 2.5), or
    /// `auto` (tries 0.6 and 1).
    #[arg(long, default_value = "auto", value_parser = auto_or_number)]
    reach: AutoOr,
    /// Luminance refinements when decoding (with γ > 0).
    #[arg(long, default_value_t = 3)]
    iterations: u8,
    /// The compressed file to write.
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
    gamma: f64,
    reach: f64,
    bytes: usize,
    /// Bytes of the picture as raw 8-bit RGB.
    raw_bytes: usize,
    /// PSNR of the picture decoded from the file as written, dB.
    psnr_db: f64,
    /// PSNR of a box thumbnail whose raw RGB fits in the same bytes, upscaled bicubically.
    thumbnail_psnr_db: Option<f64>,
}

fn compress(args: &CompressArgs) -> Result<()> {
    neurosurf_trainer::io::check_output(&args.out)?;
    let picture = neurosurf_trainer::io::read_picture(&args.input)?;
    let options = ImageOptions {
        bytes: args.bytes,
        gamma: args.gamma.0,
        reach: args.reach.0,
        iterations: args.iterations,
    };
    let compressed = compress_image(&picture, &options)?;
    let bytes = compressed.to_bytes();
    // Measure what a reader of the file gets.
    let decoded = CompressedImage::from_bytes(&bytes, &args.out)?.decode();
    neurosurf_trainer::io::write_atomic(&args.out, &bytes)?;
    let report = CompressReport {
        out: &args.out,
        width: picture.width(),
        height: picture.height(),
        key_points: compressed.key_count(),
        gamma: compressed.codec.gamma(),
        reach: compressed.codec.reach(),
        bytes: bytes.len(),
        raw_bytes: picture.as_raw().len(),
        psnr_db: psnr(&picture, &decoded)?,
        thumbnail_psnr_db: thumbnail(&picture, bytes.len())
            .map(|(t, _)| psnr(&picture, &t))
            .transpose()?,
    };
    if args.json {
        return output::json(&report);
    }
    println!(
        "{} × {} pixels, {} key points (γ {:.2}, reach {:.2}): {} bytes ({} raw), PSNR {:.2} dB{}; \
         wrote {}",
        report.width,
        report.height,
        report.key_points,
        report.gamma,
        report.reach,
        report.bytes,
        report.raw_bytes,
        report.psnr_db,
        report.thumbnail_psnr_db.map_or(String::new(), |t| format!(
            " (a thumbnail of the same bytes: {t:.2} dB)"
        )),
        args.out.display()
    );
    Ok(())
}

#[derive(Debug, clap::Args)]
pub struct DecompressArgs {
    /// A file written by `caoen image compress`.
    input: PathBuf,
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
    bytes: usize,
    psnr_db: Option<f64>,
}

fn decompress(args: &DecompressArgs) -> Result<()> {
    let bytes = std::fs::read(&args.input)
        .with_context(|| format!("cannot read {}", args.input.display()))?;
    let compressed = CompressedImage::from_bytes(&bytes, &args.input)?;
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
        key_points: compressed.key_count(),
        bytes: bytes.len(),
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
        report.bytes,
        psnr_db.map_or(String::new(), |p| format!(", PSNR {p:.2} dB")),
        args.out.display()
    );
    Ok(())
}

/// Which synthetic picture `caoen image sample` writes.
#[derive(Copy, Clone, Debug, clap::ValueEnum)]
pub enum SampleKind {
    /// Colour ramps, a soft disc and a slow wave.
    Smooth,
    /// Flat shapes and stripes with hard, unsmoothed edges.
    Edges,
}

#[derive(Debug, clap::Args)]
pub struct SampleArgs {
    /// Picture size, `WIDTH,HEIGHT`.
    #[arg(long, value_parser = comma_list::<u32, 2>, default_value = "64,64")]
    size: [u32; 2],
    /// Which picture.
    #[arg(long, value_enum, default_value = "smooth")]
    kind: SampleKind,
    /// The PNG to write.
    #[arg(long)]
    out: PathBuf,
}

fn sample(args: &SampleArgs) -> Result<()> {
    let [width, height] = args.size;
    if width == 0 || height == 0 || width > 4096 || height > 4096 {
        anyhow::bail!("--size: each side must be 1 to 4096, got {width} × {height}");
    }
    let picture = match args.kind {
        SampleKind::Smooth => smooth_test_image(width, height),
        SampleKind::Edges => edge_test_image(width, height),
    };
    write_png(&args.out, &picture)?;
    println!("wrote {}", args.out.display());
    Ok(())
}

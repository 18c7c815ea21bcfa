//! Cao En image coding (`caoen image compress`) against a box thumbnail upscaled bicubically
//! and against JPEG, at equal bytes: for each picture and budget, the codec's stream, then the
//! largest thumbnail whose raw RGB fits in the stream's bytes, and the best JPEG quality that
//! fits in them too (the `image` crate's encoder, baseline, 4:2:0).
//!
//! Pictures: a hard-edged and a smooth synthetic picture, and the photographs in
//! `data/pictures/` (128 × 128, and the same box-halved to 64 × 64).
//!
//! Run: `cargo bench -p neurosurf-trainer --bench image_coding`, with after `--`:
//! `--markdown FILE` to write the table as well (`docs/performance/image-coding.md`),
//! `--picture FILE` (repeatable) for other PNG pictures, `--budgets 5,10,20` for other shares
//! of the raw size (percent), `--figure FILE` to write a strip of
//! the last picture at 10 %: the original, Cao En, the thumbnail and JPEG, each doubled.

mod arguments;
use arguments::{given, in_workspace, option};

use std::fmt::Write as _;
use std::time::Instant;

use image::RgbImage;
use neurosurf_trainer::caoen::{
    ImageOptions, compress_image, edge_test_image, psnr, smooth_test_image, thumbnail,
};
use neurosurf_trainer::io::{data_dir, read_picture};

/// Shares of the raw RGB size each picture is compressed to.
const BUDGETS: [f64; 3] = [0.05, 0.1, 0.2];

/// The JPEG with the highest quality whose file fits in `bytes`: its size and the picture it
/// decodes to.
fn jpeg(picture: &RgbImage, bytes: usize) -> Option<(usize, RgbImage)> {
    (1..=100u8).rev().find_map(|quality| {
        let mut out = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality)
            .encode_image(picture)
            .ok()?;
        if out.len() > bytes {
            return None;
        }
        Some((out.len(), image::load_from_memory(&out).ok()?.to_rgb8()))
    })
}

/// Each 2 × 2 block averaged.
fn halve(picture: &RgbImage) -> RgbImage {
    RgbImage::from_fn(picture.width() / 2, picture.height() / 2, |x, y| {
        let mut sum = [0u32; 3];
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let p = picture.get_pixel(2 * x + dx, 2 * y + dy).0;
            for k in 0..3 {
                sum[k] += u32::from(p[k]);
            }
        }
        image::Rgb(sum.map(|s| ((s + 2) / 4) as u8))
    })
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut pictures: Vec<(String, RgbImage)> = vec![
        ("edges (synthetic)".into(), edge_test_image(64, 64)),
        ("edges (synthetic)".into(), edge_test_image(128, 128)),
        ("smooth (synthetic)".into(), smooth_test_image(64, 64)),
    ];
    let given_pictures: Vec<&str> = args
        .windows(2)
        .filter(|w| w[0] == "--picture")
        .map(|w| w[1].as_str())
        .collect();
    let files: Vec<std::path::PathBuf> = if given_pictures.is_empty() {
        let mut found: Vec<_> = std::fs::read_dir(data_dir().join("pictures"))
            .expect("data/pictures")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "png"))
            .collect();
        found.sort();
        found
    } else {
        given_pictures
            .iter()
            .map(std::path::PathBuf::from)
            .collect()
    };
    for path in files {
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let picture = read_picture(&path).expect("a PNG picture");
        if given_pictures.is_empty() {
            pictures.push((name.clone(), halve(&picture)));
        }
        pictures.push((name, picture));
    }
    let mut table = String::from(
        "| picture | size | budget | Cao En bytes | keys | γ | reach | PSNR | thumbnail | PSNR | \
         JPEG bytes | PSNR | Cao En − thumbnail | encode |\n|---|---|---:|---:|---:|---:|---:|---:|\
         ---|---:|---:|---:|---:|---:|\n",
    );
    println!("{table}");
    let mut strip = None;
    let budgets: Vec<f64> = option(&args, "--budgets").map_or(BUDGETS.to_vec(), |v| {
        v.split(',')
            .map(|b| b.trim().parse::<f64>().expect("--budgets: percentages") / 100.0)
            .collect()
    });
    for (name, picture) in &pictures {
        let (w, h) = picture.dimensions();
        for &share in &budgets {
            let budget = (share * f64::from(3 * w * h)) as usize;
            let started = Instant::now();
            let options = ImageOptions {
                bytes: budget,
                ..ImageOptions::default()
            };
            let compressed = match compress_image(picture, &options) {
                Ok(c) => c,
                Err(e) => {
                    let row = format!("| {name} | {w} × {h} | {budget} | refused: {e} ||||||||||");
                    println!("{row}");
                    let _ = writeln!(table, "{row}");
                    continue;
                }
            };
            let seconds = started.elapsed().as_secs_f64();
            let bytes = compressed.to_bytes().len();
            let ours = psnr(picture, &compressed.decode()).expect("same size");
            let (thumb, thumb_bytes) = thumbnail(picture, bytes).expect("a thumbnail fits");
            let theirs = psnr(picture, &thumb).expect("same size");
            let side = (thumb_bytes as f64 / 3.0 * f64::from(w) / f64::from(h))
                .sqrt()
                .round();
            let jpeg = jpeg(picture, bytes);
            let jpeg_cells = jpeg.as_ref().map_or("— | —".into(), |(b, p)| {
                format!("{b} | {:.2}", psnr(picture, p).expect("same size"))
            });
            if (share - 0.1).abs() < 1e-9 {
                strip = Some(vec![
                    picture.clone(),
                    compressed.decode(),
                    thumb.clone(),
                    jpeg.map_or_else(|| RgbImage::new(w, h), |(_, p)| p),
                ]);
            }
            let row = format!(
                "| {name} | {w} × {h} | {:.0} % | {bytes} | {} | {:.0} | {:.1} | {ours:.2} | \
                 ≈{side}² in {thumb_bytes} | {theirs:.2} | {jpeg_cells} | {:+.2} dB | {seconds:.2} s |",
                100.0 * share,
                compressed.key_count(),
                compressed.codec.gamma(),
                compressed.codec.reach(),
                ours - theirs,
            );
            println!("{row}");
            let _ = writeln!(table, "{row}");
        }
    }
    if let (Some(path), Some(strip)) = (option(&args, "--figure"), strip) {
        let (w, h) = strip[0].dimensions();
        let mut figure = RgbImage::from_pixel(4 * 2 * w + 3 * 4, 2 * h, image::Rgb([255; 3]));
        for (i, part) in strip.iter().enumerate() {
            let big =
                image::imageops::resize(part, 2 * w, 2 * h, image::imageops::FilterType::Nearest);
            image::imageops::replace(&mut figure, &big, i as i64 * i64::from(2 * w + 4), 0);
        }
        figure.save(in_workspace(path)).expect("the figure");
    }
    if let Some(path) = option(&args, "--markdown") {
        let text = format!(
            "# Image coding\n\nWritten by `cargo bench -p neurosurf-trainer --bench image_coding \
             -- {}`. Each picture is compressed by `caoen image compress --bytes B` (defaults: \
             γ chosen between 0 and 1 and the key reach between 0.6 and 1 cell sides by the \
             better PSNR, 3 decoding iterations) with B the share of its raw RGB \
             bytes in the budget column; the stream's own size is the Cao En bytes. At those \
             bytes: the largest box-filtered thumbnail of the picture's aspect whose raw RGB fits, \
             upscaled with Catmull–Rom bicubic interpolation, and the highest-quality JPEG (the \
             `image` crate's encoder) whose file fits. PSNR over the three 8-bit channels. \
             The photographs are in `data/pictures/` (their sources are in `data/README.md`); \
             the 64 × 64 rows are them halved by 2 × 2 averaging.\n\n{table}",
            given(&args)
        );
        std::fs::write(in_workspace(path), text).expect("the markdown file");
    }
}

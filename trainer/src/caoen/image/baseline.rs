//! What a compressed picture is measured with: PSNR, the box thumbnail of the same bytes
//! upscaled bicubically, and two synthetic test pictures.

use image::RgbImage;
use image::imageops::FilterType;

use crate::error::{Error, Result};

/// Peak signal-to-noise ratio of `b` against `a`, in dB (8-bit channels; +∞ when equal).
///
/// # Errors
/// [`Error::InvalidInput`] when the sizes differ.
pub fn psnr(a: &RgbImage, b: &RgbImage) -> Result<f64> {
    if a.dimensions() != b.dimensions() {
        return Err(Error::invalid(format!(
            "cannot compare a {:?} picture with a {:?} one",
            a.dimensions(),
            b.dimensions()
        )));
    }
    let squares: f64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(&p, &q)| (f64::from(p) - f64::from(q)).powi(2))
        .sum();
    let mse = squares / a.as_raw().len().max(1) as f64;
    Ok(10.0 * (255.0 * 255.0 / mse).log10())
}

/// The baseline at `bytes`: the largest thumbnail of the picture's aspect whose raw 8-bit RGB
/// fits in `bytes`, each of its pixels the area-weighted mean of the pixels it covers, upscaled
/// back with Catmull–Rom bicubic interpolation. Returns the upscaled picture and the
/// thumbnail's bytes (`None` when not even one pixel fits).
pub fn thumbnail(image: &RgbImage, bytes: usize) -> Option<(RgbImage, usize)> {
    let (w, h) = image.dimensions();
    let (tw, th) = (1..=w)
        .map(|tw| {
            let th = ((f64::from(tw) * f64::from(h) / f64::from(w)).round() as u32).clamp(1, h);
            (tw, th)
        })
        .rfind(|&(tw, th)| 3 * tw as usize * th as usize <= bytes)?;
    let small = RgbImage::from_fn(tw, th, |i, j| {
        let span = |k: u32, n: u32, full: u32| {
            let scale = f64::from(full) / f64::from(n);
            (f64::from(k) * scale, f64::from(k + 1) * scale)
        };
        let (a0, a1) = span(i, tw, w);
        let (b0, b1) = span(j, th, h);
        let mut sum = [0.0; 3];
        let mut total = 0.0;
        for y in b0.floor() as u32..(b1.ceil() as u32).min(h) {
            let wy = (b1.min(f64::from(y + 1)) - b0.max(f64::from(y))).max(0.0);
            for x in a0.floor() as u32..(a1.ceil() as u32).min(w) {
                let wx = (a1.min(f64::from(x + 1)) - a0.max(f64::from(x))).max(0.0);
                let p = image.get_pixel(x, y).0;
                for k in 0..3 {
                    sum[k] += wx * wy * f64::from(p[k]);
                }
                total += wx * wy;
            }
        }
        image::Rgb(sum.map(|s| (s / total).round().clamp(0.0, 255.0) as u8))
    });
    let up = image::imageops::resize(&small, w, h, FilterType::CatmullRom);
    Some((up, 3 * tw as usize * th as usize))
}

/// A smooth synthetic picture: two colour ramps, a soft bright disc and a slow wave.
pub fn smooth_test_image(width: u32, height: u32) -> RgbImage {
    RgbImage::from_fn(width, height, |x, y| {
        let u = (f64::from(x) + 0.5) / f64::from(width);
        let v = (f64::from(y) + 0.5) / f64::from(height);
        let disc = (-((u - 0.62).powi(2) + (v - 0.4).powi(2)) / 0.03).exp();
        let wave = 0.5 + 0.5 * (std::f64::consts::TAU * (u + 0.5 * v)).sin();
        let r = 0.2 + 0.5 * u + 0.3 * disc;
        let g = 0.15 + 0.35 * wave + 0.4 * disc;
        let b = 0.7 - 0.4 * v + 0.2 * disc;
        image::Rgb([r, g, b].map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8))
    })
}

/// A picture with hard edges: flat-coloured shapes (a disc, a square, a wedge, thin stripes)
/// on a light ground, no anti-aliasing.
pub fn edge_test_image(width: u32, height: u32) -> RgbImage {
    RgbImage::from_fn(width, height, |x, y| {
        let u = (f64::from(x) + 0.5) / f64::from(width);
        let v = (f64::from(y) + 0.5) / f64::from(height);
        let c = if (u - 0.33).powi(2) + (v - 0.36).powi(2) < 0.05 {
            [200, 30, 30]
        } else if (0.55..0.9).contains(&u) && (0.48..0.85).contains(&v) {
            [25, 75, 200]
        } else if v > 0.5 * u + 0.62 {
            [30, 150, 50]
        } else if (0.62..0.95).contains(&u) && v < 0.3 && ((u * 40.0) as i32) % 2 == 0 {
            [40, 40, 40]
        } else {
            [230, 215, 180]
        };
        image::Rgb(c)
    })
}

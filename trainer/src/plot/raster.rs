//! Scenes as pixels: every stroke and dot is drawn with exact-area-like anti-aliasing (the
//! coverage of a pixel is one minus its centre's distance beyond the shape's edge, clamped to
//! [0, 1]), then the image is encoded as PNG.

use image::{ImageEncoder, RgbImage};

use super::scene::{Rgb, Scene, Stroke};
use crate::error::{Error, Result};

/// Most dashes one stroke is cut into.
const MAX_DASHES: f64 = 1e6;

/// Largest side of a rasterized scene.
pub const MAX_SIDE: u32 = 16_384;

/// The scene's pixels.
///
/// # Errors
/// [`Error::InvalidInput`] when a side is zero or above [`MAX_SIDE`].
pub fn rasterize(scene: &Scene) -> Result<RgbImage> {
    let (w, h) = (scene.width, scene.height);
    if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
        return Err(Error::invalid(format!(
            "a picture of {w} × {h} pixels: each side must be 1 to {MAX_SIDE}"
        )));
    }
    let white = image::Rgb([0xff; 3]);
    let mut image = RgbImage::from_pixel(w, h, white);
    let mut coverage = Coverage::new(w as usize, h as usize);
    for stroke in &scene.strokes {
        coverage.clear();
        for (a, b) in dashed(stroke) {
            coverage.segment(a, b, 0.5 * stroke.width.max(0.5));
        }
        coverage.blend_into(&mut image, stroke.color);
    }
    for dot in &scene.dots {
        coverage.clear();
        coverage.segment(dot.center, dot.center, dot.radius.max(0.5));
        coverage.blend_into(&mut image, dot.color);
    }
    Ok(image)
}

/// The scene as a PNG file's bytes.
///
/// # Errors
/// As [`rasterize`].
pub fn to_png(scene: &Scene) -> Result<Vec<u8>> {
    png_bytes(&rasterize(scene)?)
}

/// An RGB image as a PNG file's bytes.
///
/// # Errors
/// [`Error::InvalidInput`] when the encoder fails.
pub fn png_bytes(image: &RgbImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(
            image.as_raw(),
            image.width(),
            image.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| Error::invalid(format!("cannot encode the PNG: {e}")))?;
    Ok(bytes)
}

/// The segments of a stroke, cut into dashes when it is dashed.
fn dashed(stroke: &Stroke) -> Vec<([f64; 2], [f64; 2])> {
    let Some([on, off]) = stroke.dash.filter(|[on, off]| *on > 0.0 && *off >= 0.0) else {
        return stroke.segments().collect();
    };
    let period = on + off;
    // A stroke far longer than any canvas (absurd coordinates) is drawn solid rather than cut
    // into unbounded dashes; the rasterizer clips each segment to the canvas anyway.
    let length: f64 = stroke
        .segments()
        .map(|(a, b)| (b[0] - a[0]).hypot(b[1] - a[1]))
        .sum();
    let dashes = length / period;
    if dashes.is_nan() || dashes > MAX_DASHES {
        return stroke.segments().collect();
    }
    let mut out = Vec::new();
    let mut phase = 0.0_f64;
    for (a, b) in stroke.segments() {
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        let at = |s: f64| {
            let t = if length > 0.0 { s / length } else { 0.0 };
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        };
        let mut s = 0.0;
        while s < length {
            let within = phase % period;
            let step = if within < on {
                on - within
            } else {
                period - within
            };
            let end = (s + step).min(length);
            if within < on {
                out.push((at(s), at(end)));
            }
            phase += end - s;
            s = end;
        }
    }
    out
}

/// One shape's coverage of every pixel, so overlapping segments of a polyline blend once.
struct Coverage {
    width: usize,
    height: usize,
    alpha: Vec<f32>,
    touched: Vec<usize>,
}

impl Coverage {
    fn new(width: usize, height: usize) -> Self {
        Coverage {
            width,
            height,
            alpha: vec![0.0; width * height],
            touched: Vec::new(),
        }
    }

    fn clear(&mut self) {
        for &i in &self.touched {
            self.alpha[i] = 0.0;
        }
        self.touched.clear();
    }

    /// Covers the capsule of radius `r` around segment `a`–`b` (a disc when `a == b`).
    fn segment(&mut self, a: [f64; 2], b: [f64; 2], r: f64) {
        if !(a.iter().chain(&b).all(|c| c.is_finite()) && r.is_finite()) {
            return;
        }
        let reach = r + 1.0;
        let bound = |lo: f64, hi: f64, size: usize| {
            let first = (lo - reach).floor().max(0.0);
            let last = (hi + reach).ceil().min(size as f64 - 1.0);
            (first as usize, last as usize, first <= last)
        };
        let (x0, x1, x_ok) = bound(a[0].min(b[0]), a[0].max(b[0]), self.width);
        let (y0, y1, y_ok) = bound(a[1].min(b[1]), a[1].max(b[1]), self.height);
        if !(x_ok && y_ok) {
            return;
        }
        let d = [b[0] - a[0], b[1] - a[1]];
        let length2 = d[0] * d[0] + d[1] * d[1];
        for y in y0..=y1 {
            for x in x0..=x1 {
                let p = [x as f64 + 0.5 - a[0], y as f64 + 0.5 - a[1]];
                let t = if length2 > 0.0 {
                    ((p[0] * d[0] + p[1] * d[1]) / length2).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                let distance = (p[0] - t * d[0]).hypot(p[1] - t * d[1]);
                let cover = (r + 0.5 - distance).clamp(0.0, 1.0) as f32;
                if cover > 0.0 {
                    let i = y * self.width + x;
                    if self.alpha[i] == 0.0 {
                        self.touched.push(i);
                    }
                    self.alpha[i] = self.alpha[i].max(cover);
                }
            }
        }
    }

    fn blend_into(&self, image: &mut RgbImage, color: Rgb) {
        let color = [color.0, color.1, color.2];
        for &i in &self.touched {
            let (x, y) = ((i % self.width) as u32, (i / self.width) as u32);
            let alpha = self.alpha[i];
            let pixel = image.get_pixel_mut(x, y);
            for (channel, &c) in pixel.0.iter_mut().zip(&color) {
                let mixed = f32::from(*channel) * (1.0 - alpha) + f32::from(c) * alpha;
                *channel = mixed.round().clamp(0.0, 255.0) as u8;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::{Dot, Stroke};

    #[test]
    fn strokes_and_dots_cover_what_they_should() {
        let mut scene = Scene::new(40, 20);
        scene.strokes.push(Stroke::new(
            vec![[0.0, 10.0], [40.0, 10.0]],
            Rgb(0, 0, 255),
            2.0,
        ));
        scene.dots.push(Dot {
            center: [30.5, 4.5],
            radius: 2.0,
            color: Rgb(255, 0, 0),
        });
        let image = rasterize(&scene).unwrap();
        // On the line (pixel rows 9 and 10 straddle y = 10): blue.
        assert_eq!(image.get_pixel(5, 9).0, [0, 0, 255]);
        assert_eq!(image.get_pixel(5, 10).0, [0, 0, 255]);
        // Far from everything: white.
        assert_eq!(image.get_pixel(5, 2).0, [255; 3]);
        // The dot's centre: red; its edge: a blend.
        assert_eq!(image.get_pixel(30, 4).0, [255, 0, 0]);
        let edge = image.get_pixel(32, 4).0;
        assert!(edge[0] == 255 && edge[1] > 0 && edge[1] < 255, "{edge:?}");
        assert!(to_png(&scene).unwrap().starts_with(b"\x89PNG\r\n\x1a\n"));
    }

    #[test]
    fn dashes_leave_gaps_and_bad_sizes_are_refused() {
        let mut stroke = Stroke::new(vec![[0.0, 5.5], [40.0, 5.5]], Rgb(0, 0, 0), 1.0);
        stroke.dash = Some([4.0, 4.0]);
        let dashes = dashed(&stroke);
        assert_eq!(dashes.len(), 5);
        assert_eq!(dashes[1], ([8.0, 5.5], [12.0, 5.5]));
        assert!(rasterize(&Scene::new(0, 10)).is_err());
        assert!(rasterize(&Scene::new(MAX_SIDE + 1, 10)).is_err());
        let mut scene = Scene::new(10, 10);
        scene.strokes.push(Stroke::new(
            vec![[f64::NAN, 0.0], [5.0, 5.0]],
            Rgb(0, 0, 0),
            1.0,
        ));
        assert!(rasterize(&scene).is_ok());
        let mut huge = Stroke::new(vec![[-1e300, 5.0], [1e300, 5.0]], Rgb(0, 0, 0), 1.0);
        huge.dash = Some([4.0, 4.0]);
        assert_eq!(
            dashed(&huge).len(),
            1,
            "drawn solid, not cut into 1e300 dashes"
        );
    }
}

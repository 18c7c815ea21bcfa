//! Image compression with a Cao En network (paper §12.5): key points (x, y, R, G, B) on a
//! 5-D hypersphere, the network maps a pixel's source point back to its colour.
//!
//! **The source point.** S⁴ (the unit sphere of ℝ⁵) has four free coordinates, so a pixel's
//! five numbers cannot all be placed on it one to one; this codec places position and
//! luminance L (0.299 R + 0.587 G + 0.114 B, in [0, 1]):
//!
//! s(x, y, L) = (√(1 − h²)/√2 · (cos α, sin α, cos β, sin β), h),  h = γ·(L − ½),
//!
//! with α, β the pixel centre's column and row scaled by [`SPAN`]/max(width, height) around
//! the picture's centre. Then s·s′ = √(1−h²)√(1−h′²)·½(cos Δα + cos Δβ) + h h′, which near a
//! key is ≈ 1 − (Δα² + Δβ²)/4 − (h − h′)²/2: the blending falls off with the distance in the
//! picture *and* with the difference in luminance — each key speaks mostly for the pixels
//! that look like it (an edge-preserving, bilateral-like interpolation), and γ sets how much.
//! [`SPAN`] = 1.5π keeps the two ends of a row 90° apart on their circle, far outside every
//! key's reach, so the picture does not wrap around.
//!
//! **Decodable from the blob alone.** The decoder knows (x, y) but not L. It evaluates
//! y(s(x, y, ½)), takes that colour's luminance, and re-evaluates, a fixed number of times
//! ([`ImageCodec::iterations`]); with γ = 0 the colour never enters and one pass is exact.
//! Width, height, γ and the iteration count travel in the blob's metadata, so decoding needs
//! nothing else. (Storing colour only through L keeps the map from colour to the source a
//! known, fixed function; the fitted V carries R, G and B.)
//!
//! **Keys and fit.** K keys on a gx × gy grid of pixel centres (gx·gy ≤ K, the grid's aspect
//! near the picture's), each with its pixel's luminance; normalized exponential blending with
//! q from the grid spacing (the blending falls to 0.3 at the nearest key, at most the core's
//! 64); V (K × 3) by least squares against every pixel (at most 16 384, evenly strided),
//! using the source points the decoder converges to: the fit is run once with the true
//! luminance, decoded, and refitted with the decoder's luminance, so encoder and decoder
//! agree on where each pixel sits.
//!
//! Measured (64 × 64 [`smooth_test_image`], f32 blob; the CLI test and the README's table):
//! PSNR rises with K; the unit test asserts > 30 dB at K = 64 on a 32 × 32 crop.

use image::RgbImage;
use neurosurf_core::caoen::{Blending, Domain, MAX_SHARPNESS};
use neurosurf_core::scalar::ScalarKind;

use super::blob::{from_blob, to_blob};
use super::fit::fit_shape;
use super::network::CaoEnNetwork;
use crate::error::{Error, Result};
use crate::plot::MAX_SIDE;

/// The angle the longer side of the picture spans on its circle.
pub const SPAN: f64 = 1.5 * std::f64::consts::PI;
/// Most decoding iterations a blob may ask for.
pub const MAX_ITERATIONS: u8 = 16;
/// Most pixels the least-squares fit uses (more are strided).
const MAX_FIT_PIXELS: usize = 16_384;
/// The blending value at a key's nearest grid neighbour.
const OVERLAP: f64 = 0.3;
/// Marks a Cao En blob as an image (the metadata's first bytes).
const MAGIC: &[u8; 8] = b"NSIMAGE1";

/// How pixels become source points (see the module documentation).
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ImageCodec {
    /// Picture width in pixels.
    pub width: u32,
    /// Picture height in pixels.
    pub height: u32,
    /// Weight of the luminance in the source point, in [0, 1].
    pub gamma: f64,
    /// Luminance refinements when decoding (0 … [`MAX_ITERATIONS`]).
    pub iterations: u8,
}

impl ImageCodec {
    /// The source point of pixel (`x`, `y`) with luminance `luminance`.
    pub fn source(&self, x: u32, y: u32, luminance: f64) -> Vec<f64> {
        let scale = SPAN / f64::from(self.width.max(self.height));
        let alpha = scale * (f64::from(x) + 0.5 - 0.5 * f64::from(self.width));
        let beta = scale * (f64::from(y) + 0.5 - 0.5 * f64::from(self.height));
        let h = self.gamma * (luminance.clamp(0.0, 1.0) - 0.5);
        let r = (1.0 - h * h).sqrt() / std::f64::consts::SQRT_2;
        vec![
            r * alpha.cos(),
            r * alpha.sin(),
            r * beta.cos(),
            r * beta.sin(),
            h,
        ]
    }

    fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 || self.width > MAX_SIDE || self.height > MAX_SIDE {
            return Err(Error::invalid(format!(
                "an image of {} × {} pixels: each side must be 1 to {MAX_SIDE}",
                self.width, self.height
            )));
        }
        if !(0.0..=1.0).contains(&self.gamma) {
            return Err(Error::invalid(format!(
                "the luminance weight γ must be in [0, 1], got {}",
                self.gamma
            )));
        }
        if self.iterations > MAX_ITERATIONS {
            return Err(Error::invalid(format!(
                "at most {MAX_ITERATIONS} decoding iterations, got {}",
                self.iterations
            )));
        }
        Ok(())
    }
}

/// A picture as a network and the codec that places its pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressedImage {
    /// m = 5 (the source point), p = 3 (R, G, B in [0, 1]).
    pub network: CaoEnNetwork,
    /// Size, γ and decoding iterations.
    pub codec: ImageCodec,
}

/// Luminance of a colour with channels in [0, 1].
fn luminance(c: &[f64]) -> f64 {
    0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]
}

/// The channels of a pixel in [0, 1].
fn channels(image: &RgbImage, x: u32, y: u32) -> Vec<f64> {
    image
        .get_pixel(x, y)
        .0
        .iter()
        .map(|&c| f64::from(c) / 255.0)
        .collect()
}

/// Compresses `image` into a network of at most `keys` key points (a gx × gy grid, see the
/// module documentation), with luminance weight `gamma` and `iterations` decoding passes.
///
/// # Errors
/// [`Error::InvalidInput`] for an empty or oversized picture, fewer than 4 keys or more
/// than the picture's pixels or the core's limit, γ outside [0, 1], too many iterations, or
/// a failed solve.
pub fn compress_image(
    image: &RgbImage,
    keys: usize,
    gamma: f64,
    iterations: u8,
) -> Result<CompressedImage> {
    let codec = ImageCodec {
        width: image.width(),
        height: image.height(),
        gamma,
        iterations,
    };
    codec.validate()?;
    let (w, h) = (f64::from(codec.width), f64::from(codec.height));
    let pixels = codec.width as usize * codec.height as usize;
    if keys < 4 || keys > pixels {
        return Err(Error::invalid(format!(
            "{keys} key points for {pixels} pixels: need 4 to {pixels}"
        )));
    }
    let gx = ((keys as f64 * w / h).sqrt().round() as usize).clamp(1, keys);
    let gy = (keys / gx).max(1);
    let gx = gx.min(codec.width as usize);
    let gy = gy.min(codec.height as usize);
    let at = |i: usize, g: usize, side: f64| ((i as f64 + 0.5) * side / g as f64) as u32;
    let mut weights = Vec::with_capacity(gx * gy);
    for j in 0..gy {
        for i in 0..gx {
            let (x, y) = (at(i, gx, w), at(j, gy, h));
            weights.push(codec.source(x, y, luminance(&channels(image, x, y))));
        }
    }
    let spacing = SPAN / w.max(h) * (w / gx as f64).max(h / gy as f64);
    let similarity = 0.5 * (spacing.cos() + 1.0);
    let q = (-OVERLAP.ln() / (1.0 - similarity).max(1e-12)).clamp(0.5, MAX_SHARPNESS);
    let n = weights.len();
    let network = CaoEnNetwork {
        domain: Domain::Sphere.code(),
        blending: Blending::Exponential.code(),
        normalized: true,
        weights,
        targets: vec![vec![0.0; 3]; n],
        sharpness: vec![q; n],
    };
    network.validate()?;
    let stride = pixels.div_ceil(MAX_FIT_PIXELS);
    let sample: Vec<(u32, u32)> = (0..pixels)
        .step_by(stride)
        .map(|i| {
            (
                (i % codec.width as usize) as u32,
                (i / codec.width as usize) as u32,
            )
        })
        .collect();
    let values: Vec<Vec<f64>> = sample.iter().map(|&(x, y)| channels(image, x, y)).collect();
    let truth: Vec<Vec<f64>> = sample
        .iter()
        .zip(&values)
        .map(|(&(x, y), c)| codec.source(x, y, luminance(c)))
        .collect();
    let mut compressed = CompressedImage {
        network: fit_shape(&network, &truth, &values)?,
        codec,
    };
    if gamma > 0.0 {
        let decoded: Vec<Vec<f64>> = sample
            .iter()
            .map(|&(x, y)| {
                let c = compressed.pixel(x, y);
                codec.source(x, y, luminance(&c))
            })
            .collect();
        compressed.network = fit_shape(&network, &decoded, &values)?;
    }
    Ok(compressed)
}

impl CompressedImage {
    /// The colour (channels in [0, 1], unclamped) the decoder gives pixel (`x`, `y`).
    pub fn pixel(&self, x: u32, y: u32) -> Vec<f64> {
        let mut c = self.network.position(&self.codec.source(x, y, 0.5));
        if self.codec.gamma > 0.0 {
            for _ in 0..self.codec.iterations {
                c = self
                    .network
                    .position(&self.codec.source(x, y, luminance(&c)));
            }
        }
        c
    }

    /// The decoded picture.
    pub fn decode(&self) -> RgbImage {
        RgbImage::from_fn(self.codec.width, self.codec.height, |x, y| {
            let c = self.pixel(x, y);
            image::Rgb([0, 1, 2].map(|k| (c[k] * 255.0).round().clamp(0.0, 255.0) as u8))
        })
    }

    /// The blob: the network in `scalar`, the codec in its metadata.
    ///
    /// # Errors
    /// As [`to_blob`].
    pub fn to_blob(&self, scalar: ScalarKind) -> Result<Vec<u8>> {
        let mut metadata = MAGIC.to_vec();
        metadata.extend(self.codec.width.to_le_bytes());
        metadata.extend(self.codec.height.to_le_bytes());
        metadata.extend(self.codec.gamma.to_le_bytes());
        metadata.push(self.codec.iterations);
        to_blob(&self.network, scalar, &metadata)
    }

    /// Reads a blob written by [`CompressedImage::to_blob`] (`path` names it in errors).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a blob that is not a valid Cao En blob, or one whose
    /// metadata does not describe an image of a 5-D → 3-D sphere network.
    pub fn from_blob(bytes: &[u8], path: &std::path::Path) -> Result<CompressedImage> {
        let (network, metadata, _) = from_blob(bytes, path)?;
        let not_image = |why: &str| {
            Error::invalid(format!(
                "{}: not a Cao En image blob ({why})",
                path.display()
            ))
        };
        let rest = metadata
            .strip_prefix(MAGIC.as_slice())
            .ok_or_else(|| not_image("its metadata lacks the image header"))?;
        let [
            w0,
            w1,
            w2,
            w3,
            h0,
            h1,
            h2,
            h3,
            g0,
            g1,
            g2,
            g3,
            g4,
            g5,
            g6,
            g7,
            iterations,
        ] = *rest
        else {
            return Err(not_image("its image header has the wrong length"));
        };
        let codec = ImageCodec {
            width: u32::from_le_bytes([w0, w1, w2, w3]),
            height: u32::from_le_bytes([h0, h1, h2, h3]),
            gamma: f64::from_le_bytes([g0, g1, g2, g3, g4, g5, g6, g7]),
            iterations,
        };
        codec.validate()?;
        if network.domain != Domain::Sphere.code()
            || network.source_dimension() != 5
            || network.target_dimension() != 3
        {
            return Err(not_image(&format!(
                "an image network maps S⁴ to R, G, B; this one has m = {}, p = {}",
                network.source_dimension(),
                network.target_dimension()
            )));
        }
        Ok(CompressedImage { network, codec })
    }
}

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

/// A smooth synthetic picture for tests and the README: two colour ramps, a soft bright
/// disc and a slow wave.
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

#[cfg(test)]
mod tests {
    use super::*;

    /// 64 keys reconstruct a 32 × 32 smooth picture above 30 dB, with γ = 0 and with the
    /// luminance in the source (decoded iteratively), from the blob alone in f32 and Q16.16;
    /// more keys give a better picture.
    #[test]
    fn smooth_pictures_survive_compression() {
        let picture = smooth_test_image(32, 32);
        let path = std::path::Path::new("test.nsb");
        for gamma in [0.0, 0.3] {
            let mut last = 0.0;
            for keys in [16, 64] {
                let compressed = compress_image(&picture, keys, gamma, 3).unwrap();
                assert_eq!(compressed.network.key_count(), keys);
                for scalar in [ScalarKind::F32, ScalarKind::Q16_16] {
                    let blob = compressed.to_blob(scalar).unwrap();
                    let back = CompressedImage::from_blob(&blob, path).unwrap();
                    assert_eq!(back.codec, compressed.codec);
                    let quality = psnr(&picture, &back.decode()).unwrap();
                    println!(
                        "γ {gamma} K {keys} {}: {quality:.2} dB, {} bytes",
                        scalar.name(),
                        blob.len()
                    );
                    assert!(quality > last, "γ {gamma}, K {keys}: {quality} dB");
                    if keys == 64 {
                        assert!(quality > 30.0, "γ {gamma}: {quality} dB");
                    }
                }
                last = psnr(&picture, &compressed.decode()).unwrap();
            }
        }
    }

    /// Damaged or foreign blobs, and impossible requests, are named errors.
    #[test]
    fn bad_blobs_and_requests_are_errors() {
        let picture = smooth_test_image(16, 16);
        let path = std::path::Path::new("bad.nsb");
        let blob = compress_image(&picture, 16, 0.0, 0)
            .unwrap()
            .to_blob(ScalarKind::F32)
            .unwrap();
        assert!(CompressedImage::from_blob(&blob[..blob.len() - 7], path).is_err());
        let mut flipped = blob.clone();
        let middle = flipped.len() / 2;
        flipped[middle] ^= 0x5a;
        assert!(CompressedImage::from_blob(&flipped, path).is_err());
        // A valid Cao En blob that is not an image.
        let shape = crate::caoen::support::fitted(
            &crate::caoen::support::fibonacci(12),
            &crate::caoen::support::fibonacci(12),
            Blending::Exponential,
            true,
            4.0,
        );
        let other = to_blob(&shape, ScalarKind::F32, b"shape").unwrap();
        let e = CompressedImage::from_blob(&other, path)
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a Cao En image blob"), "{e}");
        assert!(compress_image(&picture, 3, 0.0, 0).is_err());
        assert!(compress_image(&picture, 16, 1.5, 0).is_err());
        assert!(compress_image(&picture, 16, 0.2, 17).is_err());
        assert!(compress_image(&RgbImage::new(0, 0), 16, 0.0, 0).is_err());
        assert!(psnr(&picture, &smooth_test_image(8, 8)).is_err());
    }
}

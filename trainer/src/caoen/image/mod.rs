//! Image compression with Cao En networks (paper §12.5): key points (x, y, L) on the 5-D
//! hypersphere S⁴, each network mapping a pixel's source point back to its colour.
//!
//! **Tiles.** The blending's sharpness is bounded (q ≤ [`MAX_SHARPNESS`]), so one sphere
//! cannot hold keys a pixel apart across a whole picture. The picture is cut into
//! [`TILE`]-pixel tiles, each with its own network whose source circles span the tile and a
//! [`MARGIN`](tiles::MARGIN) around it ([`tiles`]); a pixel's colour is the average of the networks whose
//! windows hold it, weighted by linear fades that add up to 1, so no seam shows.
//!
//! **The source point.** For pixel (x, y) with luminance L (0.299 R + 0.587 G + 0.114 B):
//!
//! s = (√(1 − h²)/√2 · (cos α, sin α, cos β, sin β), h),  h = γ·(L − ½),
//!
//! α, β the position relative to the tile. Near a key, 1 − s·s′ ≈ (Δα² + Δβ²)/4 + (h − h′)²/2:
//! the blending falls off with the distance in the picture *and*, when γ > 0, with the
//! difference in luminance, so each key speaks mostly for the pixels that look like it (an
//! edge-preserving interpolation). The decoder knows (x, y) but not L: it evaluates at L = ½
//! and re-evaluates with its own answer's luminance [`ImageCodec::iterations`] times.
//!
//! **Adaptive keys** ([`keys`]): each tile is a quadtree; the cell whose pixels stray most from
//! their mean is split while the stream fits the byte budget, so keys crowd at edges and
//! texture and a flat tile costs one key. A key sits at its cell's centre, with the sharpness
//! that makes its blending fall to 0.3 at [`ImageCodec::reach`] cell sides (for one-pixel
//! cells that would need q > [`MAX_SHARPNESS`], so they blend more broadly).
//!
//! **Fit.** V (normalized exponential blending) by least squares against every pixel, tile by
//! tile in three Gauss–Seidel sweeps over the faded sum, with a small pull towards each cell's
//! mean colour; with γ > 0 it is refitted at the luminance the decoder's last pass evaluates
//! each pixel at, so encoder and decoder nearly agree on where each pixel sits (the refit
//! moves those luminances a little in turn). V is stored in 8 bits per channel
//! ([`stream`]). Left open, γ (0 or 1) and the reach ([`REACHES`]) are chosen by compressing
//! with each and keeping the picture with the higher PSNR.
//!
//! Each tile's network is an ordinary Cao En network (m = 5, p = 3, at most 64 keys):
//! [`CompressedImage::networks`] gives them for [`to_blob`](super::to_blob) and the core.
//!
//! Measured: `cargo bench -p neurosurf-trainer --bench image_coding` writes
//! `docs/performance/image-coding.md`, PSNR at equal bytes against a box thumbnail upscaled
//! bicubically and against JPEG.

mod baseline;
pub mod keys;
pub mod stream;
pub mod tiles;

use image::RgbImage;
use neurosurf_core::caoen::{Blending, Domain, MAX_SHARPNESS};
use rayon::prelude::*;

use super::network::CaoEnNetwork;
use crate::error::{Error, Result};
use crate::plot::MAX_SIDE;
pub use baseline::{edge_test_image, psnr, smooth_test_image, thumbnail};
use keys::{Cell, Quadtrees, place_keys};
use tiles::{TILE, Tile, sharpness_for};

/// Most pixels a compressed picture may have (4096 × 4096): the encoder keeps a few f64
/// buffers of the whole picture, about 100 bytes a pixel.
pub const MAX_PIXELS: u64 = 4096 * 4096;
/// Most decoding iterations a picture may ask for.
pub const MAX_ITERATIONS: u8 = 16;
/// The key reaches the encoder tries when none is given: sharp keys suit edges and texture,
/// broad ones smooth shading.
pub const REACHES: [f64; 2] = [0.6, 1.0];
/// The blending value at a key's reach.
const OVERLAP: f64 = 0.3;
/// Pull of each key's V towards its cell's mean colour (keeps keys that see few pixels tame).
const RIDGE: f64 = 1e-4;
/// Gauss–Seidel sweeps over the tiles.
const SWEEPS: usize = 3;

/// How pixels become source points (see the module documentation).
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct ImageCodec {
    /// Picture width in pixels.
    pub width: u32,
    /// Picture height in pixels.
    pub height: u32,
    /// Weight γ of the luminance in the source point, in 255ths.
    pub gamma_byte: u8,
    /// How far a key's blending reaches before it falls to 0.3, in hundredths of its cell's
    /// side.
    pub reach_percent: u8,
    /// Luminance refinements when decoding (0 … [`MAX_ITERATIONS`]).
    pub iterations: u8,
}

impl ImageCodec {
    /// γ in [0, 1].
    pub fn gamma(&self) -> f64 {
        f64::from(self.gamma_byte) / 255.0
    }

    /// A key's reach in cell sides.
    pub fn reach(&self) -> f64 {
        f64::from(self.reach_percent) / 100.0
    }

    pub(crate) fn validate(&self) -> Result<()> {
        let side = MAX_SIDE.min(u32::from(u16::MAX));
        if self.width == 0 || self.height == 0 || self.width > side || self.height > side {
            return Err(Error::invalid(format!(
                "a picture of {} × {} pixels: each side must be 1 to {side}",
                self.width, self.height
            )));
        }
        if u64::from(self.width) * u64::from(self.height) > MAX_PIXELS {
            return Err(Error::invalid(format!(
                "a picture of {} × {} pixels: at most {MAX_PIXELS} pixels (4096 × 4096); \
                 scale it down first",
                self.width, self.height
            )));
        }
        if !(10..=250).contains(&self.reach_percent) {
            return Err(Error::invalid(format!(
                "a key reach of {} % of its cell: it must be 10 to 250 %",
                self.reach_percent
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

/// What [`compress_image`] aims for.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct ImageOptions {
    /// The most bytes the compressed picture may take (header and checksum included).
    pub bytes: usize,
    /// The luminance weight γ in [0, 1]; `None` tries 0 and 1 and keeps the better picture.
    pub gamma: Option<f64>,
    /// How far a key's blending reaches before it falls to 0.3, in sides of its cell (0.1 …
    /// 2.5); `None` tries each of [`REACHES`] and keeps the better picture.
    pub reach: Option<f64>,
    /// Luminance refinements when decoding (used when γ > 0).
    pub iterations: u8,
}

impl Default for ImageOptions {
    fn default() -> Self {
        ImageOptions {
            bytes: 2048,
            gamma: None,
            reach: None,
            iterations: 3,
        }
    }
}

/// A picture as quadtrees of key points and their quantized V: what the stream holds.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressedImage {
    /// Size, γ, reach and decoding iterations.
    pub codec: ImageCodec,
    /// Where the keys sit.
    pub trees: Quadtrees,
    /// Each key's V (R, G, B) as bytes ([`stream::dequantize`]), in stream order.
    pub values: Vec<[u8; 3]>,
    /// Each key's luminance in 255ths (empty when γ = 0).
    pub luminances: Vec<u8>,
}

/// Luminance of a colour with channels in [0, 1].
fn luminance(c: &[f64]) -> f64 {
    0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]
}

/// The least bytes a `width` × `height` picture takes: one key per tile.
pub fn least_bytes(width: u32, height: u32, gamma: f64) -> usize {
    // Counted, not built: the reader calls this before trusting a header's size.
    let tiles = width.div_ceil(TILE) as usize * height.div_ceil(TILE) as usize;
    let per_key = stream::key_bytes((gamma.clamp(0.0, 1.0) * 255.0).round() as u8);
    stream::HEADER_BYTES + stream::TRAILER_BYTES + tiles.div_ceil(8) + tiles * per_key
}

/// Compresses `image` into at most `options.bytes` bytes (see the module documentation).
///
/// # Errors
/// [`Error::InvalidInput`] for an empty picture or one over [`MAX_PIXELS`], a budget below
/// one key per tile (the message gives the least), γ outside [0, 1], a reach outside 0.1 …
/// 2.5 or too many iterations.
pub fn compress_image(image: &RgbImage, options: &ImageOptions) -> Result<CompressedImage> {
    if options.gamma.is_none() || options.reach.is_none() {
        let gammas = options.gamma.map_or(vec![0.0, 1.0], |g| vec![g]);
        let reaches = options.reach.map_or(REACHES.to_vec(), |r| vec![r]);
        let candidates: Vec<(f64, f64)> = gammas
            .iter()
            .flat_map(|&g| reaches.iter().map(move |&r| (g, r)))
            .collect();
        // Independent encodings: one per core.
        let results: Vec<Result<(f64, CompressedImage)>> = candidates
            .par_iter()
            .map(|&(gamma, reach)| {
                let fixed = ImageOptions {
                    gamma: Some(gamma),
                    reach: Some(reach),
                    ..*options
                };
                let c = compress_image(image, &fixed)?;
                Ok((psnr(image, &c.decode())?, c))
            })
            .collect();
        let mut best: Option<(f64, CompressedImage)> = None;
        let mut first_error = None;
        for result in results {
            match result {
                Ok((score, c)) => {
                    if best.as_ref().is_none_or(|(s, _)| score > *s) {
                        best = Some((score, c));
                    }
                }
                Err(e) => {
                    first_error.get_or_insert(e);
                }
            }
        }
        return match (best, first_error) {
            (Some((_, c)), _) => Ok(c),
            (None, Some(e)) => Err(e),
            (None, None) => Err(Error::invalid("no γ and reach to try")),
        };
    }
    let (gamma, reach) = (options.gamma.unwrap_or(0.0), options.reach.unwrap_or(0.6));
    if !(0.1..=2.5).contains(&reach) || reach.is_nan() {
        return Err(Error::invalid(format!(
            "a key reach of {reach} cell sides: it must be 0.1 to 2.5"
        )));
    }
    if !(0.0..=1.0).contains(&gamma) {
        return Err(Error::invalid(format!(
            "the luminance weight γ must be in [0, 1], got {gamma}"
        )));
    }
    let gamma_byte = (gamma * 255.0).round() as u8;
    let codec = ImageCodec {
        width: image.width(),
        height: image.height(),
        gamma_byte,
        reach_percent: (100.0 * reach).round() as u8,
        iterations: options.iterations,
    };
    codec.validate()?;
    let (w, h) = (codec.width, codec.height);
    let least = least_bytes(w, h, codec.gamma());
    let Some(budget) = options
        .bytes
        .checked_sub(stream::HEADER_BYTES + stream::TRAILER_BYTES)
        .filter(|_| options.bytes >= least)
    else {
        return Err(Error::invalid(format!(
            "{} bytes cannot hold a {w} × {h} picture: it takes at least {least} (one key per \
             {TILE} × {TILE} tile); give --bytes {least} or more",
            options.bytes
        )));
    };
    let pixels: Vec<[f64; 3]> = image
        .pixels()
        .map(|p| p.0.map(|c| f64::from(c) / 255.0))
        .collect();
    let tiles = Tile::cover(w, h);
    let per_key = stream::key_bytes(gamma_byte);
    let bits = budget.saturating_mul(8);
    let trees = place_keys(&pixels, w, h, &tiles, bits, per_key * 8).ok_or_else(|| {
        Error::invalid(format!(
            "{} bytes cannot hold a {w} × {h} picture; give --bytes {least} or more",
            options.bytes
        ))
    })?;
    let means: Vec<[f64; 3]> = trees
        .leaves
        .iter()
        .flatten()
        .map(|c| cell_mean(&pixels, w, h, c))
        .collect();
    let mut compressed = CompressedImage {
        codec,
        values: means.iter().map(|m| m.map(stream::quantize)).collect(),
        luminances: if gamma_byte > 0 {
            means
                .iter()
                .map(|m| (luminance(m) * 255.0).round() as u8)
                .collect()
        } else {
            Vec::new()
        },
        trees,
    };
    let truth: Vec<f64> = pixels.iter().map(|p| luminance(p)).collect();
    compressed.fit(&pixels, &means, &truth);
    if gamma_byte > 0 {
        // Where the decoder's last pass places each pixel.
        let decoded: Vec<f64> = compressed
            .decode_colours()
            .iter()
            .map(|&(_, l)| l)
            .collect();
        compressed.fit(&pixels, &means, &decoded);
    }
    Ok(compressed)
}

/// The mean colour of a cell.
fn cell_mean(pixels: &[[f64; 3]], width: u32, height: u32, cell: &Cell) -> [f64; 3] {
    let (x0, y0, x1, y1) = cell.rect(width, height);
    let mut sum = [0.0; 3];
    for y in y0..y1 {
        for x in x0..x1 {
            let c = pixels[(y * width + x) as usize];
            for k in 0..3 {
                sum[k] += c[k];
            }
        }
    }
    let n = f64::from((x1 - x0) * (y1 - y0));
    sum.map(|s| s / n)
}

impl CompressedImage {
    /// The picture's Cao En networks, one per tile (row by row): m = 5, p = 3, normalized
    /// exponential blending, V dequantized.
    pub fn networks(&self) -> Vec<CaoEnNetwork> {
        let c = &self.codec;
        let tiles = Tile::cover(c.width, c.height);
        let mut k = 0;
        tiles
            .iter()
            .zip(&self.trees.leaves)
            .map(|(tile, leaves)| {
                let mut network = CaoEnNetwork {
                    domain: Domain::Sphere.code(),
                    blending: Blending::Exponential.code(),
                    normalized: true,
                    weights: Vec::with_capacity(leaves.len()),
                    targets: Vec::with_capacity(leaves.len()),
                    sharpness: Vec::with_capacity(leaves.len()),
                };
                for cell in leaves {
                    let l = self
                        .luminances
                        .get(k)
                        .map_or(0.5, |&b| f64::from(b) / 255.0);
                    let (x0, y0, x1, y1) = cell.rect(c.width, c.height);
                    let centre = (0.5 * f64::from(x0 + x1), 0.5 * f64::from(y0 + y1));
                    network
                        .weights
                        .push(tile.source(centre.0, centre.1, l, c.gamma()).to_vec());
                    network.targets.push(
                        self.values[k]
                            .iter()
                            .map(|&b| stream::dequantize(b))
                            .collect(),
                    );
                    network.sharpness.push(
                        sharpness_for(c.reach() * f64::from(cell.size), OVERLAP)
                            .clamp(0.5, MAX_SHARPNESS),
                    );
                    k += 1;
                }
                network
            })
            .collect()
    }

    /// Number of key points.
    pub fn key_count(&self) -> usize {
        self.values.len()
    }

    /// The stream (see [`stream`]).
    pub fn to_bytes(&self) -> Vec<u8> {
        stream::write(self)
    }

    /// Reads a stream written by [`CompressedImage::to_bytes`] (`path` names it in errors).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming what is wrong with the bytes.
    pub fn from_bytes(bytes: &[u8], path: &std::path::Path) -> Result<CompressedImage> {
        stream::read(bytes, path)
    }

    /// The decoded colours (channels in [0, 1], unclamped), row-major, each with the
    /// luminance its last pass was evaluated at (½ with γ = 0 or no iterations).
    fn decode_colours(&self) -> Vec<([f64; 3], f64)> {
        let c = &self.codec;
        let networks = self.networks();
        let tiles = Tile::cover(c.width, c.height);
        let weights = Fades::new(&tiles, c.width, c.height);
        let passes = if c.gamma_byte > 0 {
            1 + usize::from(c.iterations)
        } else {
            1
        };
        (0..c.width * c.height)
            .into_par_iter()
            .map(|i| (i % c.width, i / c.width))
            .map(|(x, y)| {
                let mut colour = [0.0; 3];
                let mut l = 0.5;
                let mut used = l;
                for _ in 0..passes {
                    colour = [0.0; 3];
                    used = l;
                    for (t, fade) in weights.at(&tiles, x, y) {
                        let s =
                            tiles[t].source(f64::from(x) + 0.5, f64::from(y) + 0.5, l, c.gamma());
                        let v = networks[t].position(&s);
                        for k in 0..3 {
                            colour[k] += fade * v[k];
                        }
                    }
                    l = luminance(&colour);
                }
                (colour, used)
            })
            .collect()
    }

    /// The decoded picture.
    pub fn decode(&self) -> RgbImage {
        let colours = self.decode_colours();
        RgbImage::from_fn(self.codec.width, self.codec.height, |x, y| {
            let (c, _) = colours[(y * self.codec.width + x) as usize];
            image::Rgb(c.map(|v| (v * 255.0).round().clamp(0.0, 255.0) as u8))
        })
    }

    /// Fits V against `pixels`, the decoder placing each pixel at luminance `lum`, then
    /// quantizes it. `means` are the cells' mean colours (the ridge's anchor).
    fn fit(&mut self, pixels: &[[f64; 3]], means: &[[f64; 3]], lum: &[f64]) {
        let c = self.codec;
        let (w, h) = (c.width, c.height);
        let tiles = Tile::cover(w, h);
        let fades = Fades::new(&tiles, w, h);
        let networks = self.networks();
        let offsets: Vec<usize> = self
            .trees
            .leaves
            .iter()
            .scan(0, |k, l| {
                let start = *k;
                *k += l.len();
                Some(start)
            })
            .collect();
        let mut values: Vec<[f64; 3]> = means.to_vec();
        // The faded prediction of every pixel from the current V.
        let mut prediction = vec![[0.0; 3]; pixels.len()];
        let rows = |t: usize| -> Vec<(usize, f64, Vec<f64>)> {
            let (x0, y0, x1, y1) = tiles[t].window(w, h);
            let mut rows = Vec::new();
            for y in y0..y1 {
                for x in x0..x1 {
                    let i = (y * w + x) as usize;
                    let fade = fades.weight(&tiles, t, x, y);
                    if fade <= 0.0 {
                        continue;
                    }
                    let s =
                        tiles[t].source(f64::from(x) + 0.5, f64::from(y) + 0.5, lum[i], c.gamma());
                    rows.push((i, fade, blend_row(&networks[t], &s)));
                }
            }
            rows
        };
        for t in 0..tiles.len() {
            let start = offsets[t];
            for (i, fade, b) in rows(t) {
                for (j, bj) in b.iter().enumerate() {
                    for k in 0..3 {
                        prediction[i][k] += fade * bj * values[start + j][k];
                    }
                }
            }
        }
        for _ in 0..SWEEPS {
            for t in 0..tiles.len() {
                let start = offsets[t];
                let n = networks[t].weights.len();
                let rows = rows(t);
                let mut lhs = nalgebra::DMatrix::<f64>::identity(n, n) * RIDGE;
                let mut rhs = nalgebra::DMatrix::<f64>::zeros(n, 3);
                for j in 0..n {
                    for k in 0..3 {
                        rhs[(j, k)] = RIDGE * means[start + j][k];
                    }
                }
                for (i, fade, b) in &rows {
                    // The pixel without this tile's share.
                    let mut residual = [0.0; 3];
                    for k in 0..3 {
                        let own: f64 = b
                            .iter()
                            .enumerate()
                            .map(|(j, bj)| bj * values[start + j][k])
                            .sum();
                        residual[k] = pixels[*i][k] - prediction[*i][k] + fade * own;
                    }
                    for (a, ba) in b.iter().enumerate() {
                        let fa = fade * ba;
                        for (bb_i, bb) in b.iter().enumerate().skip(a) {
                            lhs[(a, bb_i)] += fa * fade * bb;
                        }
                        for k in 0..3 {
                            rhs[(a, k)] += fa * residual[k];
                        }
                    }
                }
                lhs.fill_lower_triangle_with_upper_triangle();
                let Some(solved) = lhs.cholesky().map(|ch| ch.solve(&rhs)) else {
                    continue;
                };
                for (i, fade, b) in &rows {
                    for (j, bj) in b.iter().enumerate() {
                        for k in 0..3 {
                            prediction[*i][k] +=
                                fade * bj * (solved[(j, k)] - values[start + j][k]);
                        }
                    }
                }
                for j in 0..n {
                    values[start + j] = [solved[(j, 0)], solved[(j, 1)], solved[(j, 2)]];
                }
            }
        }
        self.values = values.iter().map(|v| v.map(stream::quantize)).collect();
    }
}

/// The normalized blending weights of `network`'s keys at source point `s` (what V is
/// multiplied by).
fn blend_row(network: &CaoEnNetwork, s: &[f64]) -> Vec<f64> {
    let mut row: Vec<f64> = network
        .weights
        .iter()
        .zip(&network.sharpness)
        .map(|(w, q)| (q * (w.iter().zip(s).map(|(a, b)| a * b).sum::<f64>() - 1.0)).exp())
        .collect();
    let sum: f64 = row.iter().sum();
    if sum > 0.0 {
        row.iter_mut().for_each(|v| *v /= sum);
    }
    row
}

/// Each pixel's sum of tile fades, to normalize them.
struct Fades {
    width: u32,
    sums: Vec<f64>,
}

impl Fades {
    fn new(tiles: &[Tile], width: u32, height: u32) -> Fades {
        let mut sums = vec![0.0; (width * height) as usize];
        for t in tiles {
            let (x0, y0, x1, y1) = t.window(width, height);
            for y in y0..y1 {
                for x in x0..x1 {
                    sums[(y * width + x) as usize] += t.fade(x, y);
                }
            }
        }
        Fades { width, sums }
    }

    /// Tile `t`'s normalized weight at (`x`, `y`).
    fn weight(&self, tiles: &[Tile], t: usize, x: u32, y: u32) -> f64 {
        let sum = self.sums[(y * self.width + x) as usize];
        if sum > 0.0 {
            tiles[t].fade(x, y) / sum
        } else {
            0.0
        }
    }

    /// The tiles whose windows hold (`x`, `y`), with their normalized weights.
    fn at<'a>(
        &'a self,
        tiles: &'a [Tile],
        x: u32,
        y: u32,
    ) -> impl Iterator<Item = (usize, f64)> + 'a {
        let columns = self.width.div_ceil(TILE) as usize;
        let rows = tiles.len() / columns.max(1);
        let (tx, ty) = ((x / TILE) as usize, (y / TILE) as usize);
        let near = |i: usize| [i.wrapping_sub(1), i, i + 1];
        near(ty)
            .into_iter()
            .flat_map(move |j| near(tx).into_iter().map(move |i| (i, j)))
            .filter(move |&(i, j)| i < columns && j < rows)
            .map(move |(i, j)| j * columns + i)
            .map(move |t| (t, self.weight(tiles, t, x, y)))
            .filter(|&(_, w)| w > 0.0)
    }
}

#[cfg(test)]
mod tests;

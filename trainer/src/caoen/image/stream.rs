//! The compressed picture as bytes: a 15-byte header, the quadtrees' split flags (one bit per
//! cell larger than a pixel), each key's quantized V (and its luminance when γ > 0), and a
//! CRC-32 of everything before it.
//!
//! | bytes | field |
//! |---|---|
//! | 8 | `NSIMAGE2` |
//! | 2 + 2 | width, height (little endian) |
//! | 1 | γ · 255 |
//! | 1 | key reach, in hundredths of its cell's side |
//! | 1 | decoding iterations |
//! | ⌈flags / 8⌉ | split flags, tile by tile, depth first, least significant bit first |
//! | 3 or 4 per key | R, G, B of V on [`V_LOW`, `V_HIGH`] in 255 steps; the key's luminance |
//! | 4 | CRC-32 (IEEE) |

use std::path::Path;

use super::keys::Quadtrees;
use super::tiles::Tile;
use super::{CompressedImage, ImageCodec};
use crate::error::{Error, Result};

/// The first bytes of a compressed picture.
pub const MAGIC: &[u8; 8] = b"NSIMAGE2";
/// Header bytes before the flags.
pub const HEADER_BYTES: usize = 15;
/// Bytes after the keys (the checksum).
pub const TRAILER_BYTES: usize = 4;
/// The least value a stored V channel can take (V overshoots [0, 1] beside edges, where it
/// undoes the blending's blur).
pub const V_LOW: f64 = -0.5;
/// The greatest value a stored V channel can take.
pub const V_HIGH: f64 = 1.5;

/// A V channel as its byte.
pub fn quantize(v: f64) -> u8 {
    ((v - V_LOW) / (V_HIGH - V_LOW) * 255.0)
        .round()
        .clamp(0.0, 255.0) as u8
}

/// The V channel a byte stands for.
pub fn dequantize(b: u8) -> f64 {
    V_LOW + f64::from(b) / 255.0 * (V_HIGH - V_LOW)
}

/// Bytes per key: V's three channels, and the luminance when γ > 0.
pub fn key_bytes(gamma_byte: u8) -> usize {
    if gamma_byte > 0 { 4 } else { 3 }
}

/// The stream of `image` (its codec as [`compress_image`](super::compress_image) made it:
/// sides up to 16 384 fit the 16-bit fields).
pub fn write(image: &CompressedImage) -> Vec<u8> {
    let c = &image.codec;
    let mut out = MAGIC.to_vec();
    out.extend((c.width as u16).to_le_bytes());
    out.extend((c.height as u16).to_le_bytes());
    out.extend([c.gamma_byte, c.reach_percent, c.iterations]);
    let mut byte = 0u8;
    for (i, &f) in image.trees.flags.iter().enumerate() {
        byte |= u8::from(f) << (i % 8);
        if i % 8 == 7 {
            out.push(byte);
            byte = 0;
        }
    }
    if !image.trees.flags.len().is_multiple_of(8) {
        out.push(byte);
    }
    for (k, v) in image.values.iter().enumerate() {
        out.extend(v);
        if c.gamma_byte > 0 {
            // `compress_image` stores one luminance per key; mid-grey stands in for a missing one.
            out.push(image.luminances.get(k).copied().unwrap_or(128));
        }
    }
    let crc = crc32fast::hash(&out);
    out.extend(crc.to_le_bytes());
    out
}

/// Reads a stream written by [`write()`] (`path` names it in errors).
///
/// # Errors
/// [`Error::InvalidInput`] naming what is wrong: not a compressed picture, a damaged one (the
/// checksum), a header out of range, or flags and keys that do not match the length.
pub fn read(bytes: &[u8], path: &Path) -> Result<CompressedImage> {
    let bad = |why: String| {
        Error::invalid(format!(
            "{}: not a Cao En picture this version reads ({why})",
            path.display()
        ))
    };
    if !bytes.starts_with(MAGIC) {
        return Err(bad(format!(
            "it does not start with {:?}; `caoen image compress` writes these",
            std::str::from_utf8(MAGIC).unwrap_or_default()
        )));
    }
    if bytes.len() < HEADER_BYTES + TRAILER_BYTES {
        return Err(bad(format!(
            "{} bytes are shorter than its header and checksum ({}): the file is truncated",
            bytes.len(),
            HEADER_BYTES + TRAILER_BYTES
        )));
    }
    let (body, crc) = bytes.split_at(bytes.len() - TRAILER_BYTES);
    let stored = u32::from_le_bytes([crc[0], crc[1], crc[2], crc[3]]);
    if crc32fast::hash(body) != stored {
        return Err(bad(
            "its checksum does not match: the file is damaged or truncated".into(),
        ));
    }
    let codec = ImageCodec {
        width: u32::from(u16::from_le_bytes([body[8], body[9]])),
        height: u32::from(u16::from_le_bytes([body[10], body[11]])),
        gamma_byte: body[12],
        reach_percent: body[13],
        iterations: body[14],
    };
    codec.validate().map_err(|e| bad(e.to_string()))?;
    let rest = &body[HEADER_BYTES..];
    // One key per tile at least: refuse a header the bytes cannot back before building tiles.
    let least = super::least_bytes(codec.width, codec.height, codec.gamma());
    if bytes.len() < least {
        return Err(bad(format!(
            "a {} × {} picture takes at least {least} bytes, the file has {}: it is truncated",
            codec.width,
            codec.height,
            bytes.len()
        )));
    }
    let tiles = Tile::cover(codec.width, codec.height);
    let mut bits = rest
        .iter()
        .flat_map(|&b| (0..8).map(move |i| b >> i & 1 == 1));
    let trees = Quadtrees::from_flags(&tiles, codec.width, codec.height, &mut bits)
        .ok_or_else(|| bad("its split flags end early".into()))?;
    let flag_bytes = trees.flags.len().div_ceil(8);
    let per_key = key_bytes(codec.gamma_byte);
    let keys = &rest[flag_bytes.min(rest.len())..];
    if keys.len() != trees.key_count() * per_key {
        return Err(bad(format!(
            "its flags name {} keys of {per_key} bytes, but {} bytes follow them",
            trees.key_count(),
            keys.len()
        )));
    }
    let mut values = Vec::with_capacity(trees.key_count());
    let mut luminances = Vec::new();
    for chunk in keys.chunks_exact(per_key) {
        values.push([chunk[0], chunk[1], chunk[2]]);
        if per_key == 4 {
            luminances.push(chunk[3]);
        }
    }
    Ok(CompressedImage {
        codec,
        trees,
        values,
        luminances,
    })
}

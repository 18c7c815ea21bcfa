//! Tests of the image codec: quality against the bytes, the thumbnail baseline, the stream's
//! refusals, and the tiles' networks in the core.

use std::path::Path;

use neurosurf_core::caoen::CaoEnModel;
use neurosurf_core::scalar::{Q16, ScalarKind};

use super::*;

fn options(bytes: usize, gamma: Option<f64>) -> ImageOptions {
    ImageOptions {
        bytes,
        gamma,
        reach: None,
        iterations: 3,
    }
}

/// More bytes give a better picture, the stream stays within its budget and decodes to the
/// same picture, for γ = 0, γ = 1 and the automatic choice.
#[test]
fn quality_rises_with_bytes_and_the_stream_round_trips() {
    let picture = smooth_test_image(40, 28);
    let path = Path::new("test.nsi");
    for gamma in [Some(0.0), Some(1.0), None] {
        let mut last = 0.0;
        for bytes in [700, 1400, 2800] {
            let compressed = compress_image(&picture, &options(bytes, gamma)).unwrap();
            let stream = compressed.to_bytes();
            assert!(stream.len() <= bytes, "{} > {bytes}", stream.len());
            let back = CompressedImage::from_bytes(&stream, path).unwrap();
            assert_eq!(back, compressed);
            let quality = psnr(&picture, &back.decode()).unwrap();
            println!(
                "γ {gamma:?} {bytes} bytes ({} used, {} keys): {quality:.2} dB",
                stream.len(),
                back.key_count()
            );
            assert!(
                quality > last + 0.5,
                "γ {gamma:?}, {bytes} bytes: {quality} dB"
            );
            last = quality;
        }
        assert!(last > 35.0, "γ {gamma:?}: {last} dB");
    }
}

/// At equal bytes the codec beats a box thumbnail upscaled bicubically, on hard edges and on a
/// photograph.
#[test]
fn beats_the_thumbnail_at_equal_bytes() {
    let photo =
        crate::io::read_picture(&crate::io::data_file("pictures/chelsea.png").unwrap()).unwrap();
    for (name, picture, bytes) in [
        ("edges", edge_test_image(48, 48), 1200),
        ("photograph", photo, 2500),
    ] {
        let compressed = compress_image(&picture, &options(bytes, None)).unwrap();
        let stream = compressed.to_bytes();
        let ours = psnr(&picture, &compressed.decode()).unwrap();
        let (thumb, thumb_bytes) = thumbnail(&picture, stream.len()).unwrap();
        let theirs = psnr(&picture, &thumb).unwrap();
        println!(
            "{name}: {ours:.2} dB in {} bytes (γ {}), thumbnail {theirs:.2} dB in {thumb_bytes}",
            stream.len(),
            compressed.codec.gamma()
        );
        assert!(thumb_bytes <= stream.len());
        assert!(ours > theirs + 1.0, "{name}: {ours} against {theirs} dB");
    }
}

/// Each tile's network is an ordinary Cao En network: the core loads it in f32 and Q16.16 and
/// gives the host's colours.
#[test]
fn the_tiles_networks_run_in_the_core() {
    let picture = edge_test_image(24, 17);
    let compressed = compress_image(&picture, &options(900, Some(1.0))).unwrap();
    let networks = compressed.networks();
    let tiles = Tile::cover(24, 17);
    assert_eq!(networks.len(), tiles.len());
    for (tile, network) in tiles.iter().zip(&networks) {
        assert!(network.key_count() <= (TILE * TILE) as usize);
        for kind in [ScalarKind::F32, ScalarKind::Q16_16] {
            let blob = super::super::to_blob(network, kind, b"tile").unwrap();
            let f = CaoEnModel::<f32>::from_blob(&blob).unwrap();
            let q = CaoEnModel::<Q16>::from_blob(&blob).unwrap();
            for (x, y) in [(tile.x0, tile.y0), (tile.x1 - 1, tile.y1 - 1)] {
                let s = tile.source(f64::from(x) + 0.5, f64::from(y) + 0.5, 0.4, 1.0);
                let exact = network.position(&s);
                let a: [f32; 3] = f.eval(&s.map(|v| v as f32));
                let b: [Q16; 3] = q.eval(&s.map(Q16::from_num));
                for k in 0..3 {
                    assert!((f64::from(a[k]) - exact[k]).abs() < 1e-4);
                    assert!((b[k].to_num::<f64>() - exact[k]).abs() < 1e-2);
                }
            }
        }
    }
}

/// A flat picture takes one key per tile, however many bytes it is given, and pictures a
/// pixel wide or tall work.
#[test]
fn flat_and_thin_pictures() {
    for (w, h) in [(1, 1), (1, 37), (200, 1), (20, 20)] {
        let picture = RgbImage::from_pixel(w, h, image::Rgb([10, 200, 30]));
        let compressed = compress_image(&picture, &options(100_000, None)).unwrap();
        assert_eq!(compressed.key_count(), Tile::cover(w, h).len(), "{w} × {h}");
        assert!(psnr(&picture, &compressed.decode()).unwrap() > 45.0);
    }
}

/// Damaged or foreign streams, and impossible requests, are errors that say what is wrong.
#[test]
fn bad_streams_and_requests_are_named() {
    let picture = smooth_test_image(16, 16);
    let path = Path::new("bad.nsi");
    let stream = compress_image(&picture, &options(300, Some(0.0)))
        .unwrap()
        .to_bytes();
    let message = |bytes: &[u8]| {
        CompressedImage::from_bytes(bytes, path)
            .unwrap_err()
            .to_string()
    };
    assert!(message(&stream[..stream.len() - 3]).contains("checksum"));
    let mut flipped = stream.clone();
    flipped[20] ^= 0x10;
    assert!(message(&flipped).contains("checksum"));
    assert!(message(b"NSIMAGE1 an older picture").contains("NSIMAGE2"));
    assert!(message(&stream[..12]).contains("truncated"));
    // Headers with a valid checksum that the bytes cannot back, or too many pixels.
    let forged = |w: u16, h: u16| {
        let mut bytes = stream::MAGIC.to_vec();
        bytes.extend(w.to_le_bytes());
        bytes.extend(h.to_le_bytes());
        bytes.extend([0, 60, 3]);
        bytes.extend(crc32fast::hash(&bytes).to_le_bytes());
        bytes
    };
    assert!(message(&forged(16_000, 16_000)).contains("at most"));
    assert!(message(&forged(4000, 4000)).contains("truncated"));
    assert!(message(&[]).contains("NSIMAGE2"));
    let small = compress_image(&picture, &options(20, Some(0.0)))
        .unwrap_err()
        .to_string();
    assert!(
        small.contains("at least 32") && small.contains("--bytes"),
        "{small}"
    );
    assert!(compress_image(&picture, &options(300, Some(1.5))).is_err());
    let mut many = options(300, Some(0.5));
    many.iterations = 17;
    assert!(compress_image(&picture, &many).is_err());
    assert!(compress_image(&RgbImage::new(0, 0), &options(300, None)).is_err());
    assert!(psnr(&picture, &smooth_test_image(8, 8)).is_err());
    assert!(thumbnail(&picture, 2).is_none());
}

/// No γ makes the decoder's luminance iteration run away: every γ and iteration count decodes
/// within 6 dB of γ = 0 at the same bytes (γ > 0 stores a fourth byte per key, so fewer keys),
/// and 16 iterations are never worse than 3 by more than 0.5 dB.
#[test]
fn no_gamma_diverges() {
    for picture in [edge_test_image(40, 40), smooth_test_image(40, 40)] {
        let quality = |gamma: f64, iterations: u8| {
            let options = ImageOptions {
                bytes: 1000,
                gamma: Some(gamma),
                reach: Some(0.6),
                iterations,
            };
            psnr(
                &picture,
                &compress_image(&picture, &options).unwrap().decode(),
            )
            .unwrap()
        };
        let plain = quality(0.0, 0);
        for gamma in [0.1, 0.5, 1.0] {
            let three = quality(gamma, 3);
            for iterations in [0, 3, 16] {
                let q = quality(gamma, iterations);
                assert!(
                    q > plain - 6.0,
                    "γ {gamma}, {iterations}: {q} against {plain} dB"
                );
                if iterations == 16 {
                    assert!(q > three - 0.5, "γ {gamma}: {q} after 16, {three} after 3");
                }
            }
        }
    }
}

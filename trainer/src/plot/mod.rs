//! Flat pictures: a [`Scene`] of strokes and dots in pixel coordinates, written as SVG
//! ([`to_svg`]) or rasterized with anti-aliasing into a PNG ([`to_png`]).
//!
//! The model families build scenes (the curve plots of [`crate::curve`]); this module only
//! draws them, so every picture gets both formats from one description.
//!
//! ```
//! use neurosurf_trainer::plot::{Dot, Rgb, Scene, Stroke, to_png, to_svg};
//! let mut scene = Scene::new(64, 48);
//! scene.strokes.push(Stroke::new(vec![[4.0, 4.0], [60.0, 44.0]], Rgb(0x22, 0x55, 0xcc), 2.0));
//! scene.dots.push(Dot { center: [32.0, 24.0], radius: 3.0, color: Rgb(0, 0, 0) });
//! assert!(to_svg(&scene).contains("<polyline"));
//! assert!(to_png(&scene)?.starts_with(b"\x89PNG"));
//! # Ok::<(), neurosurf_trainer::Error>(())
//! ```

mod raster;
mod scene;
mod svg;

use std::path::Path;

pub use raster::{MAX_SIDE, png_bytes, rasterize, to_png};
pub use scene::{Dot, Rgb, Scene, Stroke};
pub use svg::to_svg;

use crate::error::{Error, Result};
use crate::io::write_atomic;

/// Writes `scene` to `path` atomically, as PNG when the extension is `.png` (any case) and as
/// SVG when it is `.svg`.
///
/// # Errors
/// [`Error::InvalidInput`] for another extension, or an empty or oversized scene;
/// [`Error::Io`] when writing fails.
pub fn write_picture(path: &Path, scene: &Scene) -> Result<()> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let bytes = match extension.as_deref() {
        Some("png") => to_png(scene)?,
        Some("svg") => to_svg(scene).into_bytes(),
        _ => {
            return Err(Error::invalid(format!(
                "{}: pictures are written as .svg or .png",
                path.display()
            )));
        }
    };
    write_atomic(path, &bytes)
}

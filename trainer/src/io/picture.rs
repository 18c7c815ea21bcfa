//! Pictures in: PNG (the `image` crate), as 8-bit RGB.

use std::path::Path;

use crate::error::{Error, Result};

/// Reads a PNG picture as 8-bit RGB (grey, alpha and 16-bit pictures are converted).
///
/// # Errors
/// [`Error::Io`] when the file cannot be read; [`Error::Format`] naming the file when it is
/// not a PNG the decoder accepts.
pub fn read_picture(path: &Path) -> Result<image::RgbImage> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .map(|picture| picture.to_rgb8())
        .map_err(|e| Error::format(path, format!("not a PNG picture this reader accepts: {e}")))
}

//! Host images in and out: PNG (8- and 16-bit) and OpenEXR (32-bit float).

use std::path::Path;

use crate::imaging::Raster;
use crate::Result;

impl Raster {
    /// Reads a PNG (8- or 16-bit; grey, grey+alpha, RGB, RGBA) or OpenEXR image; errors
    /// name the file.
    pub fn load(path: impl AsRef<Path>) -> Result<Raster> {
        crate::imaging::file::load(path.as_ref())
    }

    /// Writes a `.png` (keeping 8 or 16 bits) or `.exr` (32-bit float) image, atomically: a
    /// failure leaves no partial file behind.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        crate::imaging::file::save(self, path.as_ref())
    }
}

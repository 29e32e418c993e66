//! Writing rendered images: PNG (8-bit sRGB) and EXR (32-bit float, linear).

use std::path::Path;

use anyhow::{Context, bail};
use volgraph_core::runtime::Image;

/// The image file kinds `-o` accepts, told by the extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageKind {
    /// 8-bit sRGB PNG.
    Png,
    /// 32-bit float linear EXR.
    Exr,
}

impl ImageKind {
    /// The kind of `path`, checked before any GPU work so a typo costs nothing.
    pub fn from_path(path: &Path) -> anyhow::Result<ImageKind> {
        let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("png") => Ok(ImageKind::Png),
            Some("exr") => Ok(ImageKind::Exr),
            Some(other) => bail!(
                "-o {}: volgraph writes .png (8-bit sRGB) or .exr (32-bit float, linear), not .{other}; \
                 change the extension",
                path.display()
            ),
            None => bail!(
                "-o {}: the file name has no extension; end it in .png (8-bit sRGB) or .exr (32-bit float, linear)",
                path.display()
            ),
        }
    }
}

/// The sRGB transfer function.
fn srgb_encode(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// Writes `image` as PNG. `already_srgb`: the values are display-encoded (a `present` output);
/// otherwise they are linear premultiplied colour, composited over black and sRGB-encoded.
pub fn write_png(path: &Path, image: &Image, already_srgb: bool) -> anyhow::Result<()> {
    let mut bytes = Vec::with_capacity((image.width * image.height * 4) as usize);
    for y in 0..image.height {
        for x in 0..image.width {
            let p = image.rgba(x, y);
            for v in &p[..3] {
                let v = if already_srgb { *v } else { srgb_encode(*v) };
                bytes.push((v.clamp(0.0, 1.0) * 255.0).round() as u8);
            }
            bytes.push(255);
        }
    }
    let Some(buffer) = image::RgbaImage::from_raw(image.width, image.height, bytes) else {
        bail!("internal: image buffer size mismatch");
    };
    buffer.save(path).with_context(|| format!("{}: cannot write PNG", path.display()))
}

/// Writes `image` as a 32-bit float RGBA EXR (linear, premultiplied).
pub fn write_exr(path: &Path, image: &Image) -> anyhow::Result<()> {
    let (w, h) = (image.width as usize, image.height as usize);
    exr::prelude::write_rgba_file(path, w, h, |x, y| {
        let p = image.rgba(x as u32, y as u32);
        (p[0], p[1], p[2], p[3])
    })
    .with_context(|| format!("{}: cannot write EXR", path.display()))
}

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
    /// The kind of `path` (given with `flag`, for the message), checked before any GPU work
    /// so a typo costs nothing.
    pub fn from_path(flag: &str, path: &Path) -> anyhow::Result<ImageKind> {
        let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("png") => Ok(ImageKind::Png),
            Some("exr") => Ok(ImageKind::Exr),
            Some(other) => bail!(
                "{flag} {}: volgraph writes .png (8-bit sRGB) or .exr (32-bit float, linear), not .{other}; \
                 change the extension",
                path.display()
            ),
            None => bail!(
                "{flag} {}: the file name has no extension; end it in .png (8-bit sRGB) or .exr (32-bit float, linear)",
                path.display()
            ),
        }
    }
}

/// The sRGB transfer function (IEC 61966-2-1), through the workspace's one definition.
fn srgb_encode(c: f32) -> f32 {
    volgraph_accel::srgb::encode(f64::from(c)) as f32
}

/// The inverse of [`srgb_encode`].
fn srgb_decode(c: f32) -> f32 {
    volgraph_accel::srgb::decode(f64::from(c)) as f32
}

/// Writes `bytes` to `path` and waits until the file system has them: a full disk or a
/// failing device is an error here, never a reported success (a buffered writer dropped
/// without a flush, as image encoders use, loses that error).
fn write_fully(path: &Path, bytes: &[u8], what: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let context = || format!("{}: cannot write {what}", path.display());
    let mut file = std::fs::File::create(path).with_context(context)?;
    file.write_all(bytes).with_context(context)?;
    file.flush().with_context(context)?;
    // Regular files only: a device such as /dev/stdout cannot be synced, and needs not be.
    if file.metadata().is_ok_and(|m| m.is_file()) {
        file.sync_all().with_context(context)?;
    }
    Ok(())
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
    let mut encoded = std::io::Cursor::new(Vec::new());
    buffer.write_to(&mut encoded, image::ImageFormat::Png).context("internal: PNG encoding failed")?;
    write_fully(path, encoded.get_ref(), "PNG")
}

/// Writes `image` as a 32-bit float RGBA EXR (linear, premultiplied). EXR is linear by
/// definition, so display-encoded values (`already_srgb`: the `display` output) are decoded
/// back to linear first.
pub fn write_exr(path: &Path, image: &Image, already_srgb: bool) -> anyhow::Result<()> {
    use exr::prelude::{Image as ExrImage, SpecificChannels, Vec2, WritableImage};
    let (w, h) = (image.width as usize, image.height as usize);
    let linear = |v: f32| if already_srgb { srgb_decode(v) } else { v };
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let p = image.rgba(x as u32, y as u32);
        (linear(p[0]), linear(p[1]), linear(p[2]), p[3])
    });
    let mut encoded = std::io::Cursor::new(Vec::new());
    ExrImage::from_channels((w, h), channels)
        .write()
        .to_buffered(&mut encoded)
        .map_err(|e| anyhow::anyhow!("internal: EXR encoding failed: {e}"))?;
    write_fully(path, encoded.get_ref(), "EXR")
}

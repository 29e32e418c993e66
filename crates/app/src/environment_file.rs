//! Reads a scene's environment map (`--environment sky.exr`, a scene's `environment:`): an
//! OpenEXR file of linear radiance, equirectangular (`volgraph_accel::environment`). Checked
//! before the GPU opens: a missing file, an image that is not HDR, a map too large or holding
//! NaN, infinite or negative radiance is an error naming the file and how to fix it.

use std::path::Path;

use anyhow::{Context as _, anyhow, bail};
use volgraph_accel::environment::{EnvironmentMap, MAX_SIDE};

/// The map in `path`.
pub fn load_environment(path: &Path) -> anyhow::Result<EnvironmentMap> {
    let shown = path.display();
    let meta = std::fs::metadata(path)
        .with_context(|| format!("environment map {shown}: cannot read it; give an OpenEXR file (.exr)"))?;
    if !meta.is_file() {
        bail!("environment map {shown}: not a regular file; give an OpenEXR file (.exr)");
    }
    let is_exr = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if !is_exr {
        bail!(
            "environment map {shown}: not an HDR image; volgraph reads OpenEXR (.exr) with linear radiance — an 8-bit \
             image (PNG, JPEG) holds no light above 1 (convert a .hdr with e.g. `oiiotool sky.hdr -o sky.exr`)"
        );
    }
    // The header first: a map too large is refused before its pixels are decoded.
    let header = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| anyhow!("environment map {shown}: not a readable OpenEXR file ({e})"))?;
    let size =
        header.headers.first().map(|h| h.layer_size).ok_or_else(|| anyhow!("environment map {shown}: no layer"))?;
    if size.0 == 0 || size.1 == 0 || size.0 > MAX_SIDE as usize || size.1 > MAX_SIDE as usize {
        bail!("environment map {shown}: {}×{} pixels; an environment map's sides are 1..={MAX_SIDE}", size.0, size.1);
    }
    let width = size.0;
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| vec![[0.0f32; 4]; resolution.width() * resolution.height()],
        move |texels: &mut Vec<[f32; 4]>, position, (r, g, b, a): (f32, f32, f32, f32)| {
            texels[position.y() * width + position.x()] = [r, g, b, a];
        },
    )
    .map_err(|e| anyhow!("environment map {shown}: not an RGB(A) OpenEXR image ({e})"))?;
    let texels = image.layer_data.channel_data.pixels;
    EnvironmentMap::new(size.0 as u32, size.1 as u32, texels).map_err(|e| anyhow!("environment map {shown}: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_exr(path: &Path, (w, h): (usize, usize), pixel: impl Fn(usize, usize) -> (f32, f32, f32, f32) + Sync) {
        use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
        let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| pixel(x, y));
        Image::from_channels((w, h), channels).write().to_file(path).expect("writes");
    }

    /// An EXR map reads back texel for texel, row 0 on top.
    #[test]
    fn an_exr_map_reads_back() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("sky.exr");
        write_exr(&path, (4, 2), |x, y| (x as f32, y as f32 * 10.0, 0.5, 1.0));
        let map = load_environment(&path).expect("loads");
        assert_eq!((map.width, map.height), (4, 2));
        assert_eq!(map.texels[4 + 3], [3.0, 10.0, 0.5, 1.0]);
    }

    /// Missing, not HDR, NaN radiance: errors naming the file and the fix.
    #[test]
    fn a_map_that_is_not_hdr_light_is_refused_by_name() {
        let dir = tempfile::tempdir().expect("temp dir");
        let missing = dir.path().join("nope.exr");
        let e = format!("{:#}", load_environment(&missing).expect_err("missing"));
        assert!(e.contains("nope.exr: cannot read it"), "{e}");
        let png = dir.path().join("sky.png");
        std::fs::write(&png, b"\x89PNG\r\n\x1a\n").expect("writes");
        let e = format!("{:#}", load_environment(&png).expect_err("png"));
        assert!(e.contains("sky.png: not an HDR image"), "{e}");
        let nan = dir.path().join("nan.exr");
        write_exr(&nan, (2, 1), |x, _| (if x == 0 { f32::NAN } else { 1.0 }, 0.0, 0.0, 1.0));
        let e = format!("{:#}", load_environment(&nan).expect_err("NaN"));
        assert!(e.contains("nan.exr: 1 texels hold a NaN"), "{e}");
        let junk = dir.path().join("junk.exr");
        std::fs::write(&junk, b"not an exr at all").expect("writes");
        let e = format!("{:#}", load_environment(&junk).expect_err("junk"));
        assert!(e.contains("junk.exr: not a readable OpenEXR file"), "{e}");
    }
}

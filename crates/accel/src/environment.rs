//! An environment map: the radiance a path tracer's paths see when they leave the volume
//! (issue "light that scatters", item 2: `--environment sky.exr`, a scene's `environment:`).
//! Equirectangular, linear radiance: row 0 looks up (+y, the orbit camera's up), the column at
//! u = atan2(x, −z) / 2π + ½ (the middle column along −z, three quarters along +x, the edges
//! along +z); the GPU reads it with the same nearest lookup
//! (`shaders/path_trace.wgsl`, `environment_radiance`), the f64 path tracer with
//! [`EnvironmentMap::radiance`].

use glam::DVec3;

/// The largest side a map may have (a 16k × 8k map is 2 GiB as RGBA f32).
pub const MAX_SIDE: u32 = 16_384;

/// An equirectangular map of linear radiance, RGBA f32 (alpha unused).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentMap {
    /// Texels per row (azimuth).
    pub width: u32,
    /// Rows (elevation, top first).
    pub height: u32,
    /// Row-major texels.
    pub texels: Vec<[f32; 4]>,
}

impl EnvironmentMap {
    /// A checked map: sides within 1..=[`MAX_SIDE`], one texel per pixel, every colour finite and
    /// not negative (radiance); the error says what is wrong.
    pub fn new(width: u32, height: u32, texels: Vec<[f32; 4]>) -> Result<Self, String> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(format!("{width}×{height} texels: an environment map's sides are 1..={MAX_SIDE}"));
        }
        if texels.len() != width as usize * height as usize {
            return Err(format!("{} texels for {width}×{height}", texels.len()));
        }
        let bad = texels.iter().filter(|t| t[..3].iter().any(|c| !c.is_finite() || *c < 0.0)).count();
        if bad > 0 {
            return Err(format!(
                "{bad} texels hold a NaN, infinite or negative radiance; an environment map is light (≥ 0 and finite)"
            ));
        }
        Ok(Self { width, height, texels })
    }

    /// The same radiance everywhere.
    pub fn uniform(radiance: [f32; 3]) -> Self {
        Self { width: 1, height: 1, texels: vec![[radiance[0], radiance[1], radiance[2], 1.0]] }
    }

    /// The texel a unit world direction `w` looks at.
    pub fn texel_of(&self, w: DVec3) -> (u32, u32) {
        let u = w.x.atan2(-w.z) / std::f64::consts::TAU + 0.5;
        let v = w.y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI;
        let x = ((u * f64::from(self.width)).floor() as i64).rem_euclid(i64::from(self.width)) as u32;
        let y = ((v * f64::from(self.height)).floor().max(0.0) as u32).min(self.height - 1);
        (x, y)
    }

    /// The radiance along unit direction `w` (nearest texel).
    pub fn radiance(&self, w: DVec3) -> DVec3 {
        let (x, y) = self.texel_of(w);
        let t = self.texels[(y * self.width + x) as usize];
        DVec3::new(f64::from(t[0]), f64::from(t[1]), f64::from(t[2]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Up is row 0, down the last row; the four horizontal axes fall in four columns.
    #[test]
    fn directions_map_to_their_texels() {
        let map = EnvironmentMap::uniform([1.0; 3]);
        assert_eq!(map.texel_of(DVec3::Y), (0, 0));
        let wide = EnvironmentMap::new(4, 2, vec![[0.0; 4]; 8]).expect("valid");
        assert_eq!(wide.texel_of(DVec3::Y).1, 0);
        assert_eq!(wide.texel_of(-DVec3::Y).1, 1);
        let columns: Vec<u32> =
            [-DVec3::Z, DVec3::X, DVec3::Z, -DVec3::X].iter().map(|w| wide.texel_of(*w).0).collect();
        assert_eq!(columns, [2, 3, 0, 1]);
    }

    /// NaN, infinite and negative radiance, empty and oversized maps are refused, saying why.
    #[test]
    fn a_map_that_is_not_light_is_refused() {
        let e = EnvironmentMap::new(2, 1, vec![[f32::NAN, 0.0, 0.0, 1.0], [1.0; 4]]).expect_err("NaN");
        assert!(e.contains("1 texels hold a NaN"), "{e}");
        assert!(EnvironmentMap::new(1, 1, vec![[-1.0, 0.0, 0.0, 1.0]]).is_err());
        assert!(EnvironmentMap::new(0, 1, vec![]).expect_err("empty").contains("sides are 1..="));
        assert!(EnvironmentMap::new(MAX_SIDE + 1, 1, vec![]).is_err());
        assert!(EnvironmentMap::new(2, 2, vec![[0.0; 4]; 3]).expect_err("short").contains("3 texels for 2×2"));
    }
}

//! The sRGB transfer function (IEC 61966-2-1) in f64: the exact curve ParaView colour maps are
//! read and written with, and what `shaders/present.wgsl`'s fitted encoding is tested against
//! (crates/passes/tests/present.rs).

/// Linear channel → sRGB-encoded, clamped to [0, 1].
pub fn encode(linear: f64) -> f64 {
    let c = linear.clamp(0.0, 1.0);
    if c <= 0.0031308 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// sRGB-encoded channel → linear, clamped to [0, 1]; the inverse of [`encode`].
pub fn decode(encoded: f64) -> f64 {
    let c = encoded.clamp(0.0, 1.0);
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

#[cfg(test)]
mod tests {
    /// Each inverts the other across the whole range, the linear segment and the power one.
    #[test]
    fn decode_inverts_encode() {
        for i in 0..=1000 {
            let x = f64::from(i) / 1000.0;
            assert!((super::decode(super::encode(x)) - x).abs() < 1e-12, "{x}");
        }
        // Out-of-range input clamps; 1.055 · 1 − 0.055 is one ulp under 1 in f64.
        assert_eq!(super::encode(-1.0), 0.0);
        assert!((super::encode(2.0) - 1.0).abs() < 1e-15);
        assert_eq!(super::decode(-1.0), 0.0);
        assert!((super::decode(2.0) - 1.0).abs() < 1e-15);
    }
}

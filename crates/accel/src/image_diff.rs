//! The one image-difference metric: a rendered image against a reference (the f64 CPU reference,
//! or another rendering), premultiplied linear RGBA, all four channels. Tests assert on it and
//! benchmarks report it, so a figure in a table and a threshold in a test mean the same thing.
//!
//! A NaN (or infinite) channel in either image is never a small error: it makes `max_abs`
//! infinite and is counted in `non_finite`, so a tolerance check fails and a report shows it.

use serde::Serialize;

/// How far an image is from a reference.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImageDiff {
    /// Largest absolute channel difference (infinite when a channel is not finite).
    pub max_abs: f64,
    /// Mean absolute channel difference (infinite when a channel is not finite).
    pub mean_abs: f64,
    /// Root-mean-square channel difference (infinite when a channel is not finite).
    pub rms: f64,
    /// PSNR in dB for a peak of 1; `None` when the images are identical or a channel is not
    /// finite.
    pub psnr_db: Option<f64>,
    /// Channels that are NaN or infinite in either image.
    pub non_finite: usize,
}

impl ImageDiff {
    /// True when every channel is finite and within `tolerance` of the reference.
    pub fn within(&self, tolerance: f64) -> bool {
        self.non_finite == 0 && self.max_abs <= tolerance
    }

    /// The PSNR as a table shows it: dB to one decimal, `∞` for identical images, and the
    /// count of non-finite channels where there are any.
    pub fn psnr_label(&self) -> String {
        match (self.non_finite, self.psnr_db) {
            (0, None) => "∞".to_string(),
            (0, Some(db)) => format!("{db:.1}"),
            (n, _) => format!("{n} non-finite"),
        }
    }
}

/// Why two images cannot be compared.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the images differ in size: {image} pixels against a reference of {reference}")]
pub struct SizeMismatch {
    /// Pixels of the image.
    pub image: usize,
    /// Pixels of the reference.
    pub reference: usize,
}

/// Compares `image` with `reference`, pixel by pixel in the same order.
pub fn image_diff(image: &[[f64; 4]], reference: &[[f64; 4]]) -> Result<ImageDiff, SizeMismatch> {
    if image.len() != reference.len() {
        return Err(SizeMismatch { image: image.len(), reference: reference.len() });
    }
    let (mut max_abs, mut sum_abs, mut sum_sq, mut finite, mut non_finite) = (0.0f64, 0.0, 0.0, 0usize, 0usize);
    for (a, b) in image.iter().zip(reference) {
        for c in 0..4 {
            let d = (a[c] - b[c]).abs();
            if !a[c].is_finite() || !b[c].is_finite() {
                non_finite += 1;
                max_abs = f64::INFINITY;
                continue;
            }
            max_abs = max_abs.max(d);
            sum_abs += d;
            sum_sq += d * d;
            finite += 1;
        }
    }
    if non_finite > 0 {
        // Every summary says it: a reader of the mean alone (a Pareto front, a test of the
        // mean) must not see a NaN image as a small error.
        let inf = f64::INFINITY;
        return Ok(ImageDiff { max_abs: inf, mean_abs: inf, rms: inf, psnr_db: None, non_finite });
    }
    let n = finite.max(1) as f64;
    let mse = sum_sq / n;
    let psnr_db = (mse > 0.0).then(|| 10.0 * (1.0 / mse).log10());
    Ok(ImageDiff { max_abs, mean_abs: sum_abs / n, rms: mse.sqrt(), psnr_db, non_finite })
}

/// The share of pixels with a channel more than `threshold` from the reference; a pixel with a
/// non-finite channel counts as off. (How much of an image is wrong, where [`image_diff`] says
/// by how much.)
pub fn fraction_over(image: &[[f64; 4]], reference: &[[f64; 4]], threshold: f64) -> Result<f64, SizeMismatch> {
    if image.len() != reference.len() {
        return Err(SizeMismatch { image: image.len(), reference: reference.len() });
    }
    let off_by = |d: f64| d.is_nan() || d > threshold;
    let off = image.iter().zip(reference).filter(|(a, b)| (0..4).any(|c| off_by((a[c] - b[c]).abs()))).count();
    Ok(off as f64 / image.len().max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_have_zero_error_and_no_psnr() {
        let d = image_diff(&[[0.5; 4]; 2], &[[0.5; 4]; 2]).expect("same size");
        assert_eq!((d.max_abs, d.mean_abs, d.rms, d.psnr_db, d.non_finite), (0.0, 0.0, 0.0, None, 0));
        let d = image_diff(&[[0.5; 4]; 2], &[[0.4; 4]; 2]).expect("same size");
        assert!((d.psnr_db.expect("differs") - 20.0).abs() < 1e-4);
        assert!((d.rms - 0.1).abs() < 1e-12);
        assert!(d.within(0.1 + 1e-12) && !d.within(0.05));
    }

    /// A NaN is a failure, never a zero difference (`NaN > tol` is false, which is how a NaN
    /// image used to pass a `max_abs > tol` check).
    #[test]
    fn nan_fails_every_tolerance() {
        let d = image_diff(&[[f64::NAN, 0.0, 0.0, 0.0]], &[[0.0; 4]]).expect("same size");
        assert_eq!(d.non_finite, 1);
        assert!(d.max_abs.is_infinite() && d.mean_abs.is_infinite() && d.rms.is_infinite());
        assert!(!d.within(1e9));
        assert_eq!(d.psnr_db, None);
    }

    #[test]
    fn fraction_over_counts_pixels_and_nan() {
        let image = [[0.0; 4], [0.5, 0.0, 0.0, 0.0], [f64::NAN, 0.0, 0.0, 0.0], [0.1, 0.0, 0.0, 0.0]];
        assert_eq!(fraction_over(&image, &[[0.0; 4]; 4], 0.2), Ok(0.5));
    }

    #[test]
    fn sizes_must_match() {
        assert_eq!(image_diff(&[[0.0; 4]], &[]), Err(SizeMismatch { image: 1, reference: 0 }));
    }
}

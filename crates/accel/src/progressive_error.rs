//! The error of a progressive (Monte Carlo) image estimated from the image itself, with no
//! reference: what the viewer and `volgraph render --spp` report for a path tracer (issue
//! "light that scatters", item 3: "the viewer shows spp and the view's estimated error").
//!
//! A pixel's running mean of n independent samples of variance σ² has error variance σ²/n. The
//! mean m_n and the mean m_{n/2} of its first half differ by half the difference of the two
//! halves' means, (m′ − m)/2, whose variance is (σ²/(n/2) + σ²/(n/2))/4 = σ²/n: the same. So the
//! RMS difference between the images at n/2 and n samples per pixel estimates the RMSE of the
//! image at n against the converged one — without bias in the mean square, pixel by pixel, for
//! any σ per pixel. Between powers of two the error falls as 1/√n: the estimate at n scales by
//! √(n/m) to m samples. It sees the noise only: a biased estimator's bias (none here: delta and
//! ratio tracking are unbiased) is invisible to it.
//!
//! Where each pixel holds its own count (a reprojected mean: n₁ samples in the first image, n₂
//! in the second, after the frames between added n₂ − n₁), the difference has variance
//! σ²(1/n₁ − 1/n₂) = σ²(n₂ − n₁)/(n₁n₂), so d²·n₁/(n₂ − n₁) estimates σ²/n₂ pixel by pixel
//! ([`estimated_rmse_counted`]); with n₁ = n/2, n₂ = n that is the plain estimate.

/// Root-mean-square difference over every channel of two premultiplied RGBA images (the
/// project's RMSE: `bench cinematic`'s and the path tracer's tests').
pub fn rmse(a: &[[f64; 4]], b: &[[f64; 4]]) -> f64 {
    let sum: f64 = a.iter().zip(b).flat_map(|(x, y)| (0..4).map(move |c| (x[c] - y[c]).powi(2))).sum();
    (sum / (a.len().max(1) * 4) as f64).sqrt()
}

/// The estimated RMSE of `mean` (n samples per pixel) from the image at n/2, `half_mean`.
pub fn estimated_rmse(half_mean: &[[f64; 4]], mean: &[[f64; 4]]) -> f64 {
    rmse(half_mean, mean)
}

/// The estimated RMSE of `mean`, whose pixels hold `counts` samples (`.x` of a graph's `samples`
/// output), from `earlier` with `earlier_counts`: per pixel d²·n₁/(n₂ − n₁); a pixel that took
/// no sample between the two (or started over: fewer now) counts as its own mean's noise
/// unknown and is left out.
pub fn estimated_rmse_counted(earlier: (&[[f64; 4]], &[f64]), now: (&[[f64; 4]], &[f64])) -> f64 {
    let (mut sum, mut values) = (0.0, 0usize);
    for ((a, &n1), (b, &n2)) in earlier.0.iter().zip(earlier.1).zip(now.0.iter().zip(now.1)) {
        if !(n2 > n1 && n1 > 0.0) {
            continue;
        }
        let weight = n1 / (n2 - n1);
        sum += (0..4).map(|c| (a[c] - b[c]).powi(2) * weight).sum::<f64>();
        values += 4;
    }
    (sum / values.max(1) as f64).sqrt()
}

/// An estimate at `spp` samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorEstimate {
    /// The samples per pixel it was made at (a power of two, at least 2).
    pub spp: u64,
    /// The estimated RMSE of the image at `spp`, per channel of premultiplied linear RGBA.
    pub rmse: f64,
}

impl ErrorEstimate {
    /// The estimated RMSE at `spp` samples (1/√n from this estimate).
    pub fn at(&self, spp: u64) -> f64 {
        self.rmse * (self.spp as f64 / spp.max(1) as f64).sqrt()
    }

    /// The samples per pixel at which the RMSE falls to `target` (at least this estimate's).
    pub fn spp_for(&self, target: f64) -> Option<u64> {
        if !(target > 0.0 && self.rmse.is_finite()) {
            return None;
        }
        let n = (self.spp as f64 * (self.rmse / target).powi(2)).ceil();
        (n < u64::MAX as f64).then_some(n as u64)
    }

    /// A panel's line for a mean whose pixels keep their own counts (a reprojected one), made
    /// `self.spp` frames after the view came to rest: not scaled, since a pixel's count is not
    /// the frames.
    pub fn line_resting(&self) -> String {
        format!(
            "estimated error {:.2}/255 RMS (noise from the images {} and {} frames after the view rested)",
            self.rmse * 255.0,
            self.spp / 2,
            self.spp
        )
    }

    /// A panel's or a log's line, at `spp` samples now.
    pub fn line(&self, spp: u64) -> String {
        let target = 2.0 / 255.0;
        let to_target = match self.spp_for(target) {
            Some(n) if n > spp => format!("; 2/255 at about {n} spp"),
            Some(_) => "; under 2/255".to_string(),
            None => String::new(),
        };
        format!(
            "estimated error {:.2}/255 RMS at {spp} spp (noise from the means at {} and {} spp){to_target}",
            self.at(spp) * 255.0,
            self.spp / 2,
            self.spp
        )
    }
}

/// Keeps the image at each power of two of samples of one accumulation and estimates the error
/// at the next. The accumulation is named by a key that changes when it starts over (the
/// runtime's restart count): a new key forgets what was kept.
#[derive(Clone, Debug, Default)]
pub struct ErrorTracker {
    key: u64,
    kept: Option<Kept>,
    last: Option<ErrorEstimate>,
}

/// The image kept at a power of two, with its per-pixel counts where the graph has them.
#[derive(Clone, Debug)]
struct Kept {
    step: u64,
    mean: Vec<[f64; 4]>,
    counts: Option<Vec<f64>>,
}

impl ErrorTracker {
    /// Whether the image at `spp` of accumulation `key` is wanted: a power of two.
    pub fn wants(&self, spp: u64) -> bool {
        spp.is_power_of_two()
    }

    /// Offers the image `mean` at `spp` samples of accumulation `key` (read when
    /// [`Self::wants`] said so); estimates the error when the image at `spp / 2` was kept.
    /// A count that does not grow is taken as an accumulation that started over unseen.
    pub fn offer(&mut self, key: u64, spp: u64, mean: Vec<[f64; 4]>) {
        self.offer_counted(key, spp, mean, None);
    }

    /// [`Self::offer`] where `spp` counts frames and each pixel holds its own count of samples
    /// (`counts`, a reprojected mean's): estimated with [`estimated_rmse_counted`].
    pub fn offer_counted(&mut self, key: u64, spp: u64, mean: Vec<[f64; 4]>, counts: Option<Vec<f64>>) {
        if key != self.key || self.kept.as_ref().is_some_and(|k| spp <= k.step) {
            self.restart(key);
        }
        if let Some(kept) = &self.kept
            && kept.step * 2 == spp
            && kept.mean.len() == mean.len()
        {
            let rmse = match (&kept.counts, &counts) {
                (Some(n1), Some(n2)) if n1.len() == mean.len() && n2.len() == mean.len() => {
                    estimated_rmse_counted((&kept.mean, n1), (&mean, n2))
                }
                _ => estimated_rmse(&kept.mean, &mean),
            };
            self.last = Some(ErrorEstimate { spp, rmse });
        }
        self.kept = Some(Kept { step: spp, mean, counts });
    }

    /// Forgets the accumulation: a new one, `key`, began.
    pub fn restart(&mut self, key: u64) {
        *self = Self { key, ..Self::default() };
    }

    /// The latest estimate of accumulation `key`, if any.
    pub fn last(&self, key: u64) -> Option<ErrorEstimate> {
        self.last.filter(|_| key == self.key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Standard normal values (Box–Muller over the f64 path tracer's SplitMix64).
    struct Normal(crate::path_trace::SplitMix64);

    impl Normal {
        fn next(&mut self) -> f64 {
            let (u, v) = (1.0 - self.0.uniform(), self.0.uniform());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        }
    }

    /// Pixels with their own truth and noise level (σ from 0 to 0.5, as a path tracer's dark and
    /// bright pixels): the estimate from the images at 32 and 64 samples is the true RMSE at
    /// 64 within a few percent (over 4,096 values the RMS of either has a spread of ~2 %).
    #[test]
    fn the_doubling_estimate_is_the_true_error() {
        let mut rng = Normal(crate::path_trace::SplitMix64(7));
        let pixels = 1024;
        let truth: Vec<[f64; 4]> = (0..pixels).map(|i| [i as f64 / pixels as f64; 4]).collect();
        let sigma: Vec<f64> = (0..pixels).map(|i| 0.5 * ((i * 37) % pixels) as f64 / pixels as f64).collect();
        let mut tracker = ErrorTracker::default();
        let mut sum = vec![[0.0; 4]; pixels];
        for n in 1..=64u64 {
            for (p, s) in sum.iter_mut().enumerate() {
                for c in s.iter_mut().enumerate() {
                    *c.1 += truth[p][c.0] + sigma[p] * rng.next();
                }
            }
            if tracker.wants(n) {
                tracker.offer(3, n, sum.iter().map(|s| s.map(|v| v / n as f64)).collect());
            }
        }
        let mean: Vec<[f64; 4]> = sum.iter().map(|s| s.map(|v| v / 64.0)).collect();
        let actual = rmse(&mean, &truth);
        let estimate = tracker.last(3).expect("an estimate at 64");
        assert_eq!(estimate.spp, 64);
        let ratio = estimate.rmse / actual;
        assert!((0.9..=1.1).contains(&ratio), "estimated {} against the true {actual}", estimate.rmse);
        // The true RMSE is σ_rms/√64.
        let sigma_rms = (sigma.iter().map(|s| s * s).sum::<f64>() / pixels as f64).sqrt();
        assert!((actual / (sigma_rms / 8.0) - 1.0).abs() < 0.1);
        // Scaled: at 256 samples a half; 2/255 needs n·(e/target)² samples.
        assert!((estimate.at(256) - estimate.rmse / 2.0).abs() < 1e-12);
        let n = estimate.spp_for(estimate.rmse / 4.0).expect("finite");
        assert!((1024..=1025).contains(&n), "{n}");
    }

    /// A restart forgets the kept image: no estimate mixes two accumulations.
    #[test]
    fn a_restart_forgets_the_kept_image() {
        let mut tracker = ErrorTracker::default();
        tracker.offer(1, 1, vec![[0.0; 4]]);
        tracker.offer(2, 2, vec![[1.0; 4]]);
        assert_eq!(tracker.last(2), None, "the image at 1 sample was another accumulation's");
        tracker.offer(2, 4, vec![[0.5; 4]]);
        assert_eq!(tracker.last(2).map(|e| e.rmse), Some(0.5));
        assert_eq!(tracker.last(1), None);
        // Sizes that disagree (a resized view) estimate nothing.
        tracker.offer(2, 8, vec![[0.5; 4]; 2]);
        assert_eq!(tracker.last(2).map(|e| e.spp), Some(4));
        // A count that went back started over: the last estimate was another accumulation's.
        tracker.offer(2, 1, vec![[0.5; 4]]);
        assert_eq!(tracker.last(2), None);
    }

    /// Pixels that kept 32 samples from before the view rested and then took k more: the plain
    /// doubling estimate undershoots (the difference holds only the new samples' share), the
    /// counted one is the true error.
    #[test]
    fn with_per_pixel_counts_the_estimate_is_the_true_error() {
        let mut rng = Normal(crate::path_trace::SplitMix64(11));
        let pixels = 2048;
        let truth = vec![[0.5; 4]; pixels];
        let sigma = 0.2;
        let kept = 32.0;
        let mut sum: Vec<[f64; 4]> = vec![[0.0; 4]; pixels];
        let mut draw = |sum: &mut Vec<[f64; 4]>, n: usize| {
            for s in sum.iter_mut() {
                for _ in 0..n {
                    for c in s.iter_mut() {
                        *c += 0.5 + sigma * rng.next();
                    }
                }
            }
        };
        let mean = |sum: &[[f64; 4]], n: f64| sum.iter().map(|s| s.map(|v| v / n)).collect::<Vec<_>>();
        draw(&mut sum, kept as usize + 16);
        let first = mean(&sum, kept + 16.0);
        draw(&mut sum, 16);
        let second = mean(&sum, kept + 32.0);
        let actual = rmse(&second, &truth);
        let counted =
            estimated_rmse_counted((&first, &vec![kept + 16.0; pixels]), (&second, &vec![kept + 32.0; pixels]));
        let plain = estimated_rmse(&first, &second);
        // Each RMS is over 8,192 values: its own spread is ~1 % for the truth, ~2 % for the
        // estimate (a difference of two noisy images), so 10 % is a wide margin.
        assert!((counted / actual - 1.0).abs() < 0.1, "counted {counted} against {actual}");
        // The plain estimate sees σ²(1/48 − 1/64) = σ²/192 where the truth is σ²/64: √(1/3) ≈
        // 0.58 of it.
        assert!(plain < 0.8 * actual, "the plain estimate undershoots: {plain} against {actual}");
        // Through the tracker, keyed by frames since the view rested (16, 32).
        let mut tracker = ErrorTracker::default();
        tracker.offer_counted(5, 16, first, Some(vec![kept + 16.0; pixels]));
        tracker.offer_counted(5, 32, second, Some(vec![kept + 32.0; pixels]));
        assert_eq!(tracker.last(5).map(|e| e.rmse), Some(counted));
    }

    #[test]
    fn the_line_says_how_far_the_target_is() {
        let e = ErrorEstimate { spp: 64, rmse: 4.0 / 255.0 };
        let line = e.line(64);
        assert!(line.contains("4.00/255") && line.contains("2/255 at about 256 spp"), "{line}");
        assert!(e.line(1024).contains("under 2/255"), "{}", e.line(1024));
        assert_eq!(e.spp_for(0.0), None);
    }
}

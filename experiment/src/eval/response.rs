//! The robot's response to a terrain that changes by itself (the `switch`
//! terrain's springs): how far the base dips past its new level, and how
//! long it takes to settle there.
//!
//! The signal is the base's height above the ground at rest below it, z_b
//! (the task's own h_b is measured from the sunk tile under each hip, so a
//! softer spring does not show in it), at every physics step from 3 s
//! before the change to 6 s after it. With `at` the change's time:
//!
//! - level before, L0: mean z_b over [at - 3 s, at); level after, L1: mean
//!   over [at + 3 s, at + 6 s) (the gait's own oscillation averaged out);
//! - excess dip: (min(L0, L1) - min z_b over [at, at + 3 s)) - (L0 - min
//!   z_b over [at - 3 s, at)): how much further below the lower of the two
//!   levels the base goes after the change than it goes below its level in
//!   the walk before (positive: a dip beyond the gait's own; the lower
//!   level, so that a base rising to a higher level after a stiffening is
//!   not counted as dipping below it on its way up);
//! - recovery time: with m(t) the moving mean of z_b over the last phase
//!   (0.75 s: the base's swing with each step averages out) and the band
//!   B = max |m(t) - L0| over [at - 3 s, at) + 5 mm (the walk's own wander
//!   of m, and a tolerance), the last time in [at, at + 3 s) at which
//!   |m(t) - L1| > B, less at; 0 when m never leaves L1's band. The moving
//!   mean lags by up to a phase, so a base that settles at once scores up
//!   to ~0.75 s.
//!
//! - profile: z_b - L0 in bins of [`PROFILE_BIN_SECS`] over the whole
//!   window, for plotting responses beside each other (the summary averages
//!   it over the episodes).
//!
//! An episode that falls or ends before at + 6 s has no response (its fall
//! is in its record).

use serde::{Deserialize, Serialize};

use super::summary::Spread;

/// Seconds of the window before the change (the walk's own level and band).
pub const BEFORE_SECS: f64 = 3.0;
/// Seconds after the change in which the dip and the recovery are looked for.
pub const SETTLE_SECS: f64 = 3.0;
/// Seconds after [`SETTLE_SECS`] over which the new level is averaged.
pub const LEVEL_SECS: f64 = 3.0;
/// The moving mean's window for the recovery time, s (one phase).
pub const SMOOTHING_SECS: f64 = 0.75;
/// What the recovery band adds to the walk's own wander, m.
pub const TOLERANCE_M: f64 = 0.005;
/// The width of a profile's bins, s (12 physics steps).
pub const PROFILE_BIN_SECS: f64 = 0.05;

/// The number of bins of a profile: the window from `at - BEFORE_SECS` to
/// `at + SETTLE_SECS + LEVEL_SECS`.
pub fn profile_bins() -> usize {
    ((BEFORE_SECS + SETTLE_SECS + LEVEL_SECS) / PROFILE_BIN_SECS).round() as usize
}

/// The time of bin `i`'s centre, s from the change.
pub fn profile_bin_secs(i: usize) -> f64 {
    -BEFORE_SECS + (i as f64 + 0.5) * PROFILE_BIN_SECS
}

/// One episode's response to the terrain's change.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChangeResponse {
    /// when the terrain changed, s after its reset
    pub at_secs: f64,
    /// L0: the base's mean height over the 3 s before, m
    pub level_before_m: f64,
    /// L1: its mean height from 3 to 6 s after, m
    pub level_after_m: f64,
    /// how much further below the lower of its two levels the base dipped
    /// after the change than below its level before it, m
    pub excess_dip_m: f64,
    /// how long the base's moving mean stayed outside its new level's
    /// band, s
    pub recovery_secs: f64,
    /// z_b - L0, the mean of each [`PROFILE_BIN_SECS`] bin of the window
    /// ([`profile_bins`] of them; bin i is centred at
    /// [`profile_bin_secs`]`(i)` from the change), m
    #[serde(default)]
    pub profile_m: Vec<f64>,
}

/// The base heights of the window around a change, as an episode runs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ResponseTrace {
    /// the change's time, s after the terrain's reset
    pub at_secs: f64,
    /// (time after the reset, z_b) of the steps inside the window
    pub samples: Vec<(f64, f64)>,
}

impl ResponseTrace {
    /// A trace of the window around `at_secs`.
    pub fn new(at_secs: f64) -> Self {
        Self {
            at_secs,
            samples: Vec::new(),
        }
    }

    /// Adds a step's base height if it lies in the window.
    pub fn add(&mut self, t_secs: f64, base_height_m: f64) {
        let from = self.at_secs - BEFORE_SECS;
        let to = self.at_secs + SETTLE_SECS + LEVEL_SECS;
        if (from..to).contains(&t_secs) {
            self.samples.push((t_secs, base_height_m));
        }
    }

    /// The response, if the trace covers the whole window (`dt_secs`: the
    /// steps' spacing).
    pub fn response(&self, dt_secs: f64) -> Option<ChangeResponse> {
        let at = self.at_secs;
        let (first, last) = (self.samples.first()?.0, self.samples.last()?.0);
        let end = at + SETTLE_SECS + LEVEL_SECS;
        if first > at - BEFORE_SECS + 2.0 * dt_secs || last < end - 2.0 * dt_secs {
            return None;
        }
        let within = |a: f64, b: f64| self.samples.iter().filter(move |(t, _)| (a..b).contains(t));
        let mean = |a: f64, b: f64| {
            let (sum, n) = within(a, b).fold((0.0, 0usize), |(s, n), (_, z)| (s + z, n + 1));
            (n > 0).then(|| sum / n as f64)
        };
        let min = |a: f64, b: f64| within(a, b).map(|(_, z)| *z).fold(f64::INFINITY, f64::min);
        let level_before_m = mean(at - BEFORE_SECS, at)?;
        let level_after_m = mean(at + SETTLE_SECS, end)?;
        let excess_dip_m = (level_after_m.min(level_before_m) - min(at, at + SETTLE_SECS))
            - (level_before_m - min(at - BEFORE_SECS, at));

        // the moving mean over the window's last SMOOTHING_SECS, at each sample
        let width = ((SMOOTHING_SECS / dt_secs).round() as usize).max(1);
        let mut moving = Vec::with_capacity(self.samples.len());
        let mut sum = 0.0;
        for (i, (t, z)) in self.samples.iter().enumerate() {
            sum += z;
            if i >= width {
                sum -= self.samples[i - width].1;
            }
            if i + 1 >= width {
                moving.push((*t, sum / width as f64));
            }
        }
        let band_m = moving
            .iter()
            .filter(|(t, _)| (at - BEFORE_SECS..at).contains(t))
            .map(|(_, m)| (m - level_before_m).abs())
            .fold(0.0, f64::max)
            + TOLERANCE_M;
        let recovery_secs = moving
            .iter()
            .filter(|(t, m)| {
                (at..at + SETTLE_SECS).contains(t) && (m - level_after_m).abs() > band_m
            })
            .map(|(t, _)| t - at)
            .fold(0.0, f64::max);
        let mut bins = vec![(0.0, 0usize); profile_bins()];
        for (t, z) in &self.samples {
            let i = ((t - (at - BEFORE_SECS)) / PROFILE_BIN_SECS).floor();
            if let Some(bin) = bins.get_mut(i.max(0.0) as usize) {
                bin.0 += z - level_before_m;
                bin.1 += 1;
            }
        }
        let profile_m = bins
            .iter()
            .map(|&(sum, n)| if n > 0 { sum / n as f64 } else { f64::NAN })
            .collect();
        Some(ChangeResponse {
            at_secs: at,
            level_before_m,
            level_after_m,
            excess_dip_m,
            recovery_secs,
            profile_m,
        })
    }
}

/// The responses of an evaluation's episodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResponseSummary {
    /// when the terrain changed, s after each reset
    pub at_secs: f64,
    /// episodes that walked through the whole window
    pub episodes: usize,
    /// episodes that fell or ended before the window's end
    pub without: usize,
    /// L1 - L0, m
    pub level_change_m: Spread,
    /// excess dip, m
    pub excess_dip_m: Spread,
    /// recovery time, s
    pub recovery_secs: Spread,
    /// the episodes' mean profile (z_b - L0 per bin, see
    /// [`ChangeResponse::profile_m`]), m
    #[serde(default)]
    pub mean_profile_m: Vec<f64>,
}

impl ResponseSummary {
    /// The summary of the episodes' responses (`None` for an episode
    /// without one); `None` when the terrain does not change.
    pub fn of(at_secs: Option<f64>, responses: &[Option<ChangeResponse>]) -> Option<Self> {
        let at_secs = at_secs?;
        let got: Vec<&ChangeResponse> = responses.iter().flatten().collect();
        let spread = |f: &dyn Fn(&ChangeResponse) -> f64| {
            Spread::of(&got.iter().map(|r| f(r)).collect::<Vec<_>>())
        };
        Some(Self {
            at_secs,
            episodes: got.len(),
            without: responses.len() - got.len(),
            level_change_m: spread(&|r| r.level_after_m - r.level_before_m),
            excess_dip_m: spread(&|r| r.excess_dip_m),
            recovery_secs: spread(&|r| r.recovery_secs),
            mean_profile_m: (0..profile_bins())
                .map(|i| {
                    let values: Vec<f64> = got
                        .iter()
                        .filter_map(|r| r.profile_m.get(i).copied())
                        .filter(|v| v.is_finite())
                        .collect();
                    if values.is_empty() {
                        f64::NAN
                    } else {
                        values.iter().sum::<f64>() / values.len() as f64
                    }
                })
                .collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1.0 / 240.0;

    /// A walk at 30 cm whose height swings +-1 cm with the 0.75 s phase, a
    /// change at 30 s to 27 cm: a first-order fall with time constant `tau`
    /// and, with `undershoot`, a dip that much below the new level.
    fn trace(tau: f64, undershoot: f64) -> ResponseTrace {
        let mut trace = ResponseTrace::new(30.0);
        for i in 0..(45.0 / DT) as usize {
            let t = i as f64 * DT;
            let swing = 0.01 * (2.0 * std::f64::consts::PI * t / 0.75).sin();
            let level = if t < 30.0 {
                0.30
            } else {
                let s = t - 30.0;
                0.27 + 0.03 * (-s / tau).exp() - undershoot * (s / tau) * (1.0 - s / tau).exp()
            };
            trace.add(t, level + swing);
        }
        trace
    }

    #[test]
    fn a_base_that_settles_at_once_has_no_excess_dip_and_recovers_within_the_smoothing() {
        let r = trace(0.01, 0.0).response(DT).unwrap();
        assert!((r.level_before_m - 0.30).abs() < 1e-3, "{r:?}");
        assert!((r.level_after_m - 0.27).abs() < 1e-3, "{r:?}");
        assert!(r.excess_dip_m.abs() < 1e-3, "{r:?}");
        // the one-phase mean crosses from 30 to 27 cm within 0.75 s
        assert!(r.recovery_secs < SMOOTHING_SECS, "{r:?}");
    }

    #[test]
    fn a_slow_settle_takes_longer_and_an_undershoot_shows_as_the_dip() {
        let fast = trace(0.01, 0.0).response(DT).unwrap();
        let slow = trace(0.5, 0.0).response(DT).unwrap();
        // 3 cm exp(-s / 0.5 s) is inside the 5 mm band after ~0.9 s, and
        // the one-phase mean lags it
        assert!((0.9..2.0).contains(&slow.recovery_secs), "{slow:?}");
        assert!(
            slow.recovery_secs > fast.recovery_secs + 0.5,
            "{slow:?} {fast:?}"
        );
        assert!(slow.excess_dip_m.abs() < 2e-3, "{slow:?}");
        // an undershoot of 4 cm less the decaying 3 cm step where it is
        // deepest: ~3 cm further down than the walk's own swing
        let dip = trace(0.3, 0.04).response(DT).unwrap();
        assert!((0.02..0.04).contains(&dip.excess_dip_m), "{dip:?}");
        assert!(dip.recovery_secs > fast.recovery_secs + 0.5, "{dip:?}");
    }

    #[test]
    fn a_base_rising_to_a_higher_level_is_not_dipping() {
        // the mirror of a slow settle: from 30 cm up to 33 cm
        let mut rising = ResponseTrace::new(30.0);
        for (t, z) in &trace(0.5, 0.0).samples {
            rising.add(*t, 0.60 - z);
        }
        let r = rising.response(DT).unwrap();
        assert!(
            (r.level_after_m - r.level_before_m - 0.03).abs() < 1e-3,
            "{r:?}"
        );
        // no dip below the old level beyond the walk's own (the first
        // troughs after the change are already on their way up)
        assert!(r.excess_dip_m < 2e-3, "{r:?}");
        assert!(r.recovery_secs > 0.9, "{r:?}");
    }

    #[test]
    fn the_profile_is_the_height_from_the_old_level_bin_by_bin_and_the_summary_averages_it() {
        let r = trace(0.01, 0.0).response(DT).unwrap();
        assert_eq!(r.profile_m.len(), profile_bins());
        assert_eq!(profile_bins(), 180);
        for (i, p) in r.profile_m.iter().enumerate() {
            let t = profile_bin_secs(i);
            // the walk's +-1 cm swing around 0 before, around -3 cm after
            let level = if t < 0.0 { 0.0 } else { -0.03 };
            if t.abs() > 0.1 {
                assert!((p - level).abs() < 0.011, "bin {i} at {t} s: {p}");
            }
        }
        // a bin averages its 12 steps: over the phase's swing the bins
        // average to the level
        let before: f64 = r.profile_m[..60].iter().sum::<f64>() / 60.0;
        assert!(before.abs() < 1e-3, "{before}");
        let summary = ResponseSummary::of(
            Some(30.0),
            &[Some(r.clone()), trace(0.5, 0.0).response(DT), None],
        )
        .unwrap();
        let slow = trace(0.5, 0.0).response(DT).unwrap();
        for i in 0..profile_bins() {
            let mean = 0.5 * (r.profile_m[i] + slow.profile_m[i]);
            assert!((summary.mean_profile_m[i] - mean).abs() < 1e-12);
        }
    }

    #[test]
    fn a_trace_that_ends_before_the_window_does_has_no_response() {
        let mut short = trace(0.1, 0.0);
        short.samples.retain(|(t, _)| *t < 33.0);
        assert_eq!(short.response(DT), None);
        let summary =
            ResponseSummary::of(Some(30.0), &[trace(0.1, 0.0).response(DT), None]).unwrap();
        assert_eq!((summary.episodes, summary.without), (1, 1));
        assert_eq!(ResponseSummary::of(None, &[]), None);
    }
}

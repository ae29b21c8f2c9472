//! `[curriculum.advance]`: a stage that ends when the policy is ready for
//! the next one (legged_gym's terrain levels, per run rather than per
//! robot) instead of after a fixed count.
//!
//! ```toml
//! [[curriculum]]
//! terrain = "rigid"
//! iterations = 260     # at most
//! [curriculum.advance]
//! survival = 0.95      # the share of the window's ended episodes that did not fall
//! distance_m = 1.0     # optional: and their mean distance walked, m
//! window = 10          # iterations, all of them in this stage
//! ```
//!
//! After each iteration of the stage that completes a window, the share of
//! the episodes that ended in the window's iterations by the time limit
//! rather than by a fall is compared with `survival`, and with `distance_m`
//! their mean distance (each iteration's `mean_distance_m` weighted by its
//! ended episodes; legged_gym promotes a robot by the distance it walked);
//! the stage ends after the first iteration where both are reached, or
//! after `iterations`. A window in which no episode ended had no fall (its
//! share is 1) and shows no distance (a `distance_m` is not reached).
//!
//! The decision reads only what `metrics.jsonl` records (each iteration's
//! `episodes`, `terminated` and `mean_distance_m`), so a resumed or forked
//! run decides from its history exactly as the uninterrupted run did.

use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::Deserialize;

use super::Experiment;

/// The window of [`Advance`] when the file does not set it, iterations.
pub const DEFAULT_WINDOW: u64 = 10;

/// When a stage moves on before its `iterations`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Advance {
    /// the share of the window's ended episodes that ended without a fall
    /// (by the time limit) at which the stage ends, in (0, 1]
    pub survival: f64,
    /// the mean distance the window's ended episodes walked at which the
    /// stage ends (with `survival`), m; `None`: survival alone
    pub distance_m: Option<f64>,
    /// iterations in the window, at least 1 and at most the stage's
    /// (default [`DEFAULT_WINDOW`], or the stage's iterations if fewer)
    pub window: u64,
}

/// `[curriculum.advance]` as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct AdvanceSection {
    survival: f64,
    #[serde(default)]
    distance_m: Option<f64>,
    #[serde(default)]
    window: Option<u64>,
}

impl AdvanceSection {
    /// The rule of a stage of `iterations`, or the reason it cannot hold.
    pub(super) fn resolve(self, iterations: u64) -> Result<Advance, String> {
        if !(self.survival > 0.0 && self.survival <= 1.0) {
            return Err(format!(
                "survival must be in (0, 1] (a share of episodes), got {}",
                self.survival
            ));
        }
        if let Some(d) = self.distance_m
            && !(d.is_finite() && d > 0.0)
        {
            return Err(format!(
                "distance_m must be a positive distance, m, got {d}"
            ));
        }
        let window = self.window.unwrap_or(DEFAULT_WINDOW.min(iterations));
        if window == 0 || window > iterations {
            return Err(format!(
                "window must be 1 to the stage's {iterations} iterations, got {window}"
            ));
        }
        Ok(Advance {
            survival: self.survival,
            distance_m: self.distance_m,
            window,
        })
    }
}

impl Advance {
    /// Whether `window` (the window's iterations, oldest first) reaches
    /// the rule's survival and distance.
    pub fn is_reached(&self, window: &[EpisodeCounts]) -> bool {
        let ended: u64 = window.iter().map(|c| c.ended).sum();
        let fell: u64 = window.iter().map(|c| c.fell).sum();
        let survives = ended == 0 || (ended - fell) as f64 >= self.survival * ended as f64;
        let walks = match self.distance_m {
            None => true,
            Some(d) => {
                let walked: f64 = window
                    .iter()
                    .map(|c| c.mean_distance_m * c.ended as f64)
                    .sum();
                ended > 0 && walked >= d * ended as f64
            }
        };
        survives && walks
    }

    /// The rule in words, for messages.
    pub fn describe(&self) -> String {
        match self.distance_m {
            None => format!("survival {} over {} iterations", self.survival, self.window),
            Some(d) => format!(
                "survival {} and {d} m walked over {} iterations",
                self.survival, self.window
            ),
        }
    }
}

/// One iteration's episodes, as `metrics.jsonl` records them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeCounts {
    /// episodes that ended in the iteration (`episodes`)
    pub ended: u64,
    /// of them, by a fall (`terminated`)
    pub fell: u64,
    /// their mean distance walked, m (`mean_distance_m`; 0 where none ended)
    pub mean_distance_m: f64,
}

impl EpisodeCounts {
    /// The counts of one `metrics.jsonl` line, `None` where it lacks them.
    pub fn of_record(record: &serde_json::Value) -> Option<Self> {
        let ended = record["episodes"].as_u64()?;
        Some(Self {
            ended,
            fell: record["terminated"].as_u64()?,
            mean_distance_m: match record["mean_distance_m"].as_f64() {
                Some(d) => d,
                None if ended == 0 => 0.0,
                None => return None,
            },
        })
    }
}

/// The episode counts of the first `iterations` iterations in the
/// `metrics.jsonl` at `path`, in order; an error names the file and what is
/// missing.
pub fn read_history(path: &Path, iterations: u64) -> Result<Vec<EpisodeCounts>> {
    let text = std::fs::read_to_string(path).with_context(|| {
        format!(
            "cannot read {}: a curriculum with [curriculum.advance] tells where its stages ended from it",
            path.display()
        )
    })?;
    let mut history = vec![None; iterations as usize];
    for (n, line) in text.lines().enumerate() {
        let record: serde_json::Value = serde_json::from_str(line)
            .with_context(|| format!("{} line {}: not JSON", path.display(), n + 1))?;
        let Some(iteration) = record["iteration"].as_u64() else {
            bail!("{} line {}: no iteration", path.display(), n + 1);
        };
        if (1..=iterations).contains(&iteration) {
            history[iteration as usize - 1] =
                Some(EpisodeCounts::of_record(&record).with_context(|| {
                    format!(
                        "{} line {}: no episodes/terminated/mean_distance_m",
                        path.display(),
                        n + 1
                    )
                })?);
        }
    }
    history
        .into_iter()
        .enumerate()
        .map(|(k, c)| {
            c.with_context(|| format!("{}: iteration {} is missing", path.display(), k + 1))
        })
        .collect()
}

impl Experiment {
    /// Whether any stage moves on when ready.
    pub fn has_advance_rules(&self) -> bool {
        self.curriculum.iter().any(|s| s.advance.is_some())
    }

    /// Decides, from the first iterations' `history`, where the stages
    /// with an [`Advance`] rule ended (`Stage::ended_after`). A stage whose
    /// end the history does not reach stays open: its length counts as its
    /// `iterations` until a longer history decides it.
    pub fn decide_stages(&mut self, history: &[EpisodeCounts]) {
        for stage in &mut self.curriculum {
            stage.ended_after = None;
        }
        let mut start = 0u64;
        for stage in &mut self.curriculum {
            if let Some(rule) = stage.advance {
                let done = (history.len() as u64).saturating_sub(start);
                stage.ended_after = (rule.window..=stage.iterations.min(done)).find(|&n| {
                    let end = (start + n) as usize;
                    rule.is_reached(&history[end - rule.window as usize..end])
                });
                if stage.ended_after.is_none() && done < stage.iterations {
                    return;
                }
            }
            start += stage.length();
        }
    }

    /// [`Self::decide_stages`] from the run's `metrics.jsonl` at `path`, for
    /// the first `iterations` iterations; without [`Advance`] rules the
    /// file is not read.
    pub fn decide_stages_from(&mut self, path: &Path, iterations: u64) -> Result<()> {
        if self.has_advance_rules() {
            let history = read_history(path, iterations)?;
            self.decide_stages(&history);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(list: &[(u64, u64)]) -> Vec<EpisodeCounts> {
        list.iter()
            .map(|&(ended, fell)| EpisodeCounts {
                ended,
                fell,
                mean_distance_m: 0.0,
            })
            .collect()
    }

    #[test]
    fn survival_is_the_share_of_ended_episodes_that_did_not_fall() {
        let rule = Advance {
            survival: 0.9,
            distance_m: None,
            window: 2,
        };
        assert!(rule.is_reached(&counts(&[(10, 1), (10, 1)]))); // 18 of 20
        assert!(!rule.is_reached(&counts(&[(10, 1), (10, 2)]))); // 17 of 20
        assert!(rule.is_reached(&counts(&[(0, 0), (0, 0)]))); // nothing fell
        let all = Advance {
            survival: 1.0,
            distance_m: None,
            window: 1,
        };
        assert!(all.is_reached(&counts(&[(16, 0)])));
        assert!(!all.is_reached(&counts(&[(16, 1)])));
    }

    #[test]
    fn distance_is_the_episode_weighted_mean_of_the_window() {
        let rule = Advance {
            survival: 0.5,
            distance_m: Some(1.0),
            window: 2,
        };
        let walked = |list: &[(u64, u64, f64)]| -> Vec<EpisodeCounts> {
            list.iter()
                .map(|&(ended, fell, d)| EpisodeCounts {
                    ended,
                    fell,
                    mean_distance_m: d,
                })
                .collect()
        };
        // (30 x 0.5 + 10 x 2.5) / 40 = 1.0: reached
        assert!(rule.is_reached(&walked(&[(30, 0, 0.5), (10, 0, 2.5)])));
        // (10 x 0.5 + 30 x 1.2) / 40 = 1.025 but 25 of 40 fell
        assert!(!rule.is_reached(&walked(&[(10, 5, 0.5), (30, 20, 1.2)])));
        // no episode ended: nothing walked is shown
        assert!(!rule.is_reached(&walked(&[(0, 0, 0.0), (0, 0, 0.0)])));
        assert!(rule.describe().contains("1 m walked over 2 iterations"));
    }

    #[test]
    fn a_rule_outside_its_ranges_is_refused_with_the_reason() {
        let resolve = |survival, window| {
            AdvanceSection {
                survival,
                distance_m: None,
                window,
            }
            .resolve(10)
        };
        let bad = |survival, window| resolve(survival, window).unwrap_err();
        assert!(bad(0.0, Some(5)).contains("survival must be in (0, 1]"));
        assert!(bad(1.5, Some(5)).contains("survival must be in (0, 1]"));
        assert!(bad(f64::NAN, Some(5)).contains("survival"));
        assert!(bad(0.9, Some(0)).contains("window must be 1 to the stage's 10"));
        assert!(bad(0.9, Some(11)).contains("window must be 1 to the stage's 10"));
        assert_eq!(resolve(0.9, None).unwrap().window, DEFAULT_WINDOW);
        let far = AdvanceSection {
            survival: 0.9,
            distance_m: Some(-1.0),
            window: None,
        };
        assert!(
            far.resolve(10)
                .unwrap_err()
                .contains("distance_m must be a positive distance")
        );
        assert_eq!(
            AdvanceSection {
                survival: 0.9,
                distance_m: None,
                window: None
            }
            .resolve(4)
            .unwrap()
            .window,
            4,
            "the default window fits a shorter stage"
        );
    }

    /// rigid (at most 5, ready at 90 % over 2 iterations), then 5 cm tiles
    /// (at most 4, ready at full survival over 1), then 2 fixed iterations
    const READY: &str = "[[curriculum]]\nterrain = \"rigid\"\niterations = 5\n[curriculum.advance]\nsurvival = 0.9\nwindow = 2\n[[curriculum]]\nterrain = \"elastic:5cm\"\niterations = 4\n[curriculum.advance]\nsurvival = 1.0\nwindow = 1\n[[curriculum]]\nterrain = \"elastic:2cm\"\niterations = 2\n";

    fn ready() -> Experiment {
        Experiment::from_toml_builtin(READY, "ready.toml").unwrap()
    }

    fn lengths(e: &Experiment) -> Vec<u64> {
        e.curriculum.iter().map(|s| s.length()).collect()
    }

    #[test]
    fn stages_end_where_the_history_first_reaches_their_rule() {
        let mut e = ready();
        assert_eq!(e.total_iterations(), 11, "undecided: the maxima");
        // rigid: 16 of 20 (0.8), then 18 of 20 at iterations 2-3: ends after 3
        let history = counts(&[(10, 4), (10, 2), (10, 0), (10, 3), (10, 0)]);
        e.decide_stages(&history[..2]);
        assert_eq!(lengths(&e), [5, 4, 2], "2 iterations decide nothing");
        e.decide_stages(&history[..3]);
        assert_eq!(lengths(&e), [3, 4, 2]);
        assert_eq!(e.total_iterations(), 9);
        assert_eq!(e.terrain_at(3).1.to_string(), "elastic:5cm");
        // tiles: iteration 4 has a fall, iteration 5 none: ends after 2
        e.decide_stages(&history[..4]);
        assert_eq!(lengths(&e), [3, 4, 2]);
        e.decide_stages(&history);
        assert_eq!(lengths(&e), [3, 2, 2]);
        assert_eq!(e.total_iterations(), 7);
        assert_eq!(e.terrain_at(5).1.to_string(), "elastic:2cm");
        // a shorter history reopens what it does not decide
        e.decide_stages(&history[..3]);
        assert_eq!(lengths(&e), [3, 4, 2]);
    }

    #[test]
    fn a_stage_never_ready_runs_its_maximum_and_the_next_is_decided_after_it() {
        let mut e = ready();
        let mut history = counts(&[(10, 5); 5]);
        e.decide_stages(&history);
        assert_eq!(lengths(&e), [5, 4, 2]);
        history.extend(counts(&[(10, 1), (0, 0)]));
        e.decide_stages(&history);
        assert_eq!(
            lengths(&e),
            [5, 2, 2],
            "a window with no ended episode had no fall"
        );
    }

    #[test]
    fn the_rule_is_written_back_and_refused_when_out_of_range() {
        let e = ready();
        let again = Experiment::from_toml_builtin(&e.to_toml(), "again.toml").unwrap();
        assert_eq!(again.curriculum, e.curriculum);
        assert!(
            e.to_toml()
                .contains("[curriculum.advance]\nsurvival = 0.9\nwindow = 2\n")
        );
        let walked = READY.replacen("window = 2\n", "distance_m = 0.75\nwindow = 2\n", 1);
        let e2 = Experiment::from_toml_builtin(&walked, "walked.toml").unwrap();
        assert_eq!(e2.curriculum[0].advance.unwrap().distance_m, Some(0.75));
        let again = Experiment::from_toml_builtin(&e2.to_toml(), "again.toml").unwrap();
        assert_eq!(again.curriculum, e2.curriculum);
        let default_window = READY.replace("window = 2\n", "");
        let e = Experiment::from_toml_builtin(&default_window, "w.toml").unwrap();
        assert_eq!(e.curriculum[0].advance.unwrap().window, 5);
        for (from, to, message) in [
            (
                "survival = 0.9",
                "survival = 1.2",
                "stage 1 [curriculum.advance]: survival must be in (0, 1]",
            ),
            (
                "window = 2",
                "window = 6",
                "stage 1 [curriculum.advance]: window must be 1 to the stage's 5 iterations, got 6",
            ),
            ("window = 2", "windows = 2", "unknown field `windows`"),
        ] {
            let err = format!(
                "{:#}",
                Experiment::from_toml_builtin(&READY.replace(from, to), "bad.toml").unwrap_err()
            );
            assert!(err.contains("bad.toml") && err.contains(message), "{err}");
        }
    }

    #[test]
    fn the_history_is_read_from_metrics_and_a_gap_is_named() {
        let dir = std::env::temp_dir().join(format!("quadwalk-advance-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("metrics.jsonl");
        std::fs::write(
            &path,
            "{\"iteration\":1,\"episodes\":16,\"terminated\":3,\"mean_distance_m\":0.0}\n{\"iteration\":2,\"episodes\":16,\"terminated\":0,\"mean_distance_m\":0.0}\n{\"iteration\":3,\"episodes\":17,\"terminated\":1,\"mean_distance_m\":0.5}\n",
        )
        .unwrap();
        assert_eq!(read_history(&path, 2).unwrap(), counts(&[(16, 3), (16, 0)]));
        let err = format!("{:#}", read_history(&path, 4).unwrap_err());
        assert!(err.contains("iteration 4 is missing"), "{err}");
        let err = format!(
            "{:#}",
            read_history(&dir.join("none.jsonl"), 1).unwrap_err()
        );
        assert!(
            err.contains("cannot read") && err.contains("none.jsonl"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

//! Why an episode ends early: base too low, pitch too large, a link other
//! than a foot on the ground (checked after every physics step), or, under
//! a [`StallRule`], too little new ground over the last phases (checked
//! at each phase's end).

use super::{PitchReference, StallRule, Task};

/// Why an episode ended early.
#[derive(Debug, Clone, PartialEq)]
pub enum Termination {
    /// the base height (as `base_height_reference` measures it) below the
    /// minimum
    BaseTooLow {
        /// the height, m
        height_m: f64,
    },
    /// |pitch| beyond the limit
    PitchTooLarge {
        /// the pitch, degrees (against the `pitch_reference`)
        pitch_deg: f64,
    },
    /// a link other than a foot touched the ground
    NonFootContact {
        /// the links
        links: Vec<String>,
    },
    /// the last [`StallRule::phases`] phases made less new ground than
    /// [`StallRule::new_ground_m`]
    Stalled {
        /// the new ground they made, m
        new_ground_m: f64,
        /// the window, phases
        phases: usize,
    },
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::BaseTooLow { height_m } => write!(f, "base too low ({:.1} cm)", height_m * 100.0),
            Self::PitchTooLarge { pitch_deg } => write!(f, "pitch too large ({pitch_deg:.1} deg)"),
            Self::NonFootContact { links } => write!(f, "non-foot contact ({})", links.join(", ")),
            Self::Stalled {
                new_ground_m,
                phases,
            } => write!(
                f,
                "stalled ({:.1} cm of new ground in {phases} phases)",
                new_ground_m * 100.0
            ),
        }
    }
}

impl Termination {
    /// Every [`Termination::kind`], in the order of the variants (the
    /// physical falls first, then the [`StallRule`]'s).
    pub const KINDS: [&'static str; 4] = [
        "base_too_low",
        "pitch_too_large",
        "non_foot_contact",
        "stalled",
    ];

    /// A short machine-readable name.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::BaseTooLow { .. } => "base_too_low",
            Self::PitchTooLarge { .. } => "pitch_too_large",
            Self::NonFootContact { .. } => "non_foot_contact",
            Self::Stalled { .. } => "stalled",
        }
    }
}

impl Task {
    pub(super) fn check_termination(&self, base_height_m: f64) -> Option<Termination> {
        if base_height_m < self.config.min_base_height_m {
            return Some(Termination::BaseTooLow {
                height_m: base_height_m,
            });
        }
        let (_, pitch, _) = self.world.base_pose().rotation.euler_angles();
        let pitch = match self.config.pitch_reference {
            PitchReference::World => pitch,
            PitchReference::Ground => pitch - self.world.ground_pitch_rad(),
            PitchReference::Feet => pitch - self.world.feet_ground_pitch_rad(),
        };
        if pitch.to_degrees().abs() > self.config.max_pitch_deg {
            return Some(Termination::PitchTooLarge {
                pitch_deg: pitch.to_degrees(),
            });
        }
        let links = self.world.non_foot_contacts();
        if !links.is_empty() {
            return Some(Termination::NonFootContact { links });
        }
        None
    }

    /// At a phase's end, with `new_ground_m` the ground the phase made:
    /// records it and applies the [`StallRule`], if the task has one.
    pub(super) fn check_stall(&mut self, new_ground_m: f64) -> Option<Termination> {
        let StallRule {
            phases,
            new_ground_m: needed_m,
        } = self.config.stall?;
        let made = &mut self.episode.new_ground_by_phase_m;
        let total_m = made.last().copied().unwrap_or(0.0) + new_ground_m;
        made.push(total_m);
        // made[k]: by the end of phase k (made[0] = 0 at the start)
        let now = made.len() - 1;
        if now < phases {
            return None;
        }
        let window_m = total_m - made[now - phases];
        (window_m < needed_m).then_some(Termination::Stalled {
            new_ground_m: window_m,
            phases,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::action::ACTION_SIZE;
    use crate::scripted::{CYCLE_PHASES, ScriptedCrawl};
    use crate::task::TaskConfig;
    use crate::task::tests::task_on;

    #[test]
    fn an_episode_that_stops_making_ground_stalls_and_the_crawl_does_not() {
        let rule = |phases, new_ground_m| TaskConfig {
            stall: Some(StallRule {
                phases,
                new_ground_m,
            }),
            ..TaskConfig::default()
        };
        // Zero actions step short, under 2 cm a phase on rigid ground: with
        // a rule of 10 cm in 4 phases the episode goes on for the first
        // three phases and stalls at the fourth, paid the termination
        // reward.
        let mut task = task_on("rigid", rule(4, 0.10), 3);
        let mut obs = vec![0.0; task.observation_size()];
        task.reset(&mut obs);
        for phase in 1..=3 {
            let out = task.step_phase(&[0.0; ACTION_SIZE], &mut obs);
            assert!(out.termination.is_none(), "phase {phase}: {out:?}");
        }
        let out = task.step_phase(&[0.0; ACTION_SIZE], &mut obs);
        match out.termination {
            Some(Termination::Stalled {
                new_ground_m,
                phases: 4,
            }) => {
                let made = &task.episode.new_ground_by_phase_m;
                assert_eq!(made.len(), 5);
                assert!((0.02..0.10).contains(&new_ground_m), "{made:?}");
                assert!((made[4] - made[0] - new_ground_m).abs() < 1e-12);
            }
            other => panic!("expected a stall, got {other:?}"),
        }
        assert_eq!(out.reward, -10.0);
        assert!(task.done() && !out.truncated);

        // The crawl walks toward the goal in cycles of 16 phases, some of
        // which shift the body without a step: over any cycle it passes a
        // rule of 2 cm in 16 phases, and no episode of two cycles stalls;
        // the ground made is the goal distance it shortened.
        let mut task = task_on("rigid", rule(CYCLE_PHASES, 0.02), 3);
        task.reset(&mut obs);
        let crawl = ScriptedCrawl::default();
        let start_m = task.goal_in_base().norm();
        for phase in 1..=2 * CYCLE_PHASES {
            let out = task.step_phase(&crawl.act(&task), &mut obs);
            assert!(out.termination.is_none(), "phase {phase}: {out:?}");
        }
        let made = &task.episode.new_ground_by_phase_m;
        assert_eq!(made.len(), 2 * CYCLE_PHASES + 1);
        assert!(made.windows(2).all(|w| w[1] >= w[0]), "{made:?}");
        let closer_m = start_m - task.goal_in_base().norm();
        assert!(
            (made.last().unwrap() - closer_m).abs() < 0.01 && closer_m > 0.05,
            "{made:?} vs {closer_m}"
        );
    }

    #[test]
    fn every_kind_is_listed_once_in_the_order_of_the_variants() {
        let all = [
            Termination::BaseTooLow { height_m: 0.1 },
            Termination::PitchTooLarge { pitch_deg: 20.0 },
            Termination::NonFootContact {
                links: vec!["chassis".into()],
            },
            Termination::Stalled {
                new_ground_m: 0.01,
                phases: 10,
            },
        ];
        assert_eq!(all.map(|t| t.kind()), Termination::KINDS);
    }
}

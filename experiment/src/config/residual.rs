//! `[residual]`: a lower-level policy that corrects the phase plan within
//! each phase (the paper's first proposal for reacting to the ground while
//! it moves): a frozen phase-level policy plans every phase as usual, and
//! the policy being trained moves each foot's target every `control_steps`
//! physics steps from what the robot measures (see
//! [`crate::residual`]).
//!
//! ```toml
//! [residual]
//! phase_policy = "policies/tv2"    # the phase-level policy (a run, checkpoint
//!                                  # or export, as --policy takes it, relative
//!                                  # to where quadwalk runs); its observation,
//!                                  # action prior and physics are the task's;
//!                                  # "none": no phase level, the policy moves
//!                                  # all four feet (a single-level policy)
//! control_steps = 6                # physics steps per control step: 40 Hz,
//!                                  # 30 per phase (must divide 180)
//! max_offset_m = 0.03              # each foot's target moves at most this far
//!                                  # along each base axis
//! offset_cost = 0.02               # reward per control step: -offset_cost x
//!                                  # the mean squared action
//! ```

use std::path::PathBuf;

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

/// The `[residual]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ResidualConfig {
    /// the phase-level policy that plans every phase: a run directory,
    /// checkpoint or exported policy, as `--policy` takes it (a relative
    /// path from the directory quadwalk runs in), `scripted`, or `none`
    /// (no phase level: each phase holds still and the policy moves every
    /// foot)
    pub phase_policy: PathBuf,
    /// physics steps per control step (240 Hz / control_steps); must divide
    /// the phase's 180
    pub control_steps: usize,
    /// bound of each foot's target offset along each base axis, m
    pub max_offset_m: f64,
    /// the cost per control step of the offsets: -offset_cost x the mean
    /// of the squared actions (each in [-1, 1])
    pub offset_cost: f64,
}

impl Default for ResidualConfig {
    fn default() -> Self {
        Self {
            phase_policy: PathBuf::new(),
            control_steps: 6,
            max_offset_m: 0.03,
            offset_cost: 0.02,
        }
    }
}

impl ResidualConfig {
    /// Checks the values against a phase of `steps_per_phase` physics
    /// steps (the `[physics]` rate's).
    pub fn validate(&self, steps_per_phase: usize) -> Result<()> {
        if self.phase_policy.as_os_str().is_empty() {
            bail!("phase_policy is missing: the exported phase-level policy that plans each phase");
        }
        if self.control_steps == 0 || !steps_per_phase.is_multiple_of(self.control_steps) {
            bail!(
                "control_steps = {} must divide the phase's {steps_per_phase} physics steps (at 240 Hz, 180: e.g. 4, 6, 9, 12)",
                self.control_steps
            );
        }
        if !(self.max_offset_m.is_finite() && self.max_offset_m > 0.0 && self.max_offset_m <= 0.25)
        {
            bail!(
                "max_offset_m = {} must be in (0, 0.25] m",
                self.max_offset_m
            );
        }
        if !(self.offset_cost.is_finite() && self.offset_cost >= 0.0) {
            bail!("offset_cost = {} must be >= 0", self.offset_cost);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::action::SAMPLES_PER_PHASE;

    #[test]
    fn bad_values_name_the_key() {
        let good = ResidualConfig {
            phase_policy: "p".into(),
            ..ResidualConfig::default()
        };
        assert!(good.validate(SAMPLES_PER_PHASE).is_ok());
        // 12 divides 180 (240 Hz) but not 90 (120 Hz)
        let twelve = ResidualConfig {
            control_steps: 12,
            ..good.clone()
        };
        assert!(twelve.validate(180).is_ok());
        let err = twelve.validate(90).unwrap_err().to_string();
        assert!(
            err.contains("control_steps = 12 must divide the phase's 90 physics steps"),
            "{err}"
        );
        for (config, expected) in [
            (ResidualConfig::default(), "phase_policy is missing"),
            (
                ResidualConfig {
                    control_steps: 7,
                    ..good.clone()
                },
                "control_steps = 7 must divide",
            ),
            (
                ResidualConfig {
                    max_offset_m: 0.5,
                    ..good.clone()
                },
                "max_offset_m = 0.5",
            ),
            (
                ResidualConfig {
                    offset_cost: -1.0,
                    ..good.clone()
                },
                "offset_cost = -1",
            ),
        ] {
            let err = config.validate(SAMPLES_PER_PHASE).unwrap_err().to_string();
            assert!(err.contains(expected), "{err}");
        }
    }
}

//! Why an episode ends early: base too low, pitch too large, a link other
//! than a foot on the ground (checked after every physics step).

use super::PitchReference;
use super::Task;

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
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::BaseTooLow { height_m } => write!(f, "base too low ({:.1} cm)", height_m * 100.0),
            Self::PitchTooLarge { pitch_deg } => write!(f, "pitch too large ({pitch_deg:.1} deg)"),
            Self::NonFootContact { links } => write!(f, "non-foot contact ({})", links.join(", ")),
        }
    }
}

impl Termination {
    /// Every [`Termination::kind`], in the order of the variants.
    pub const KINDS: [&'static str; 3] = ["base_too_low", "pitch_too_large", "non_foot_contact"];

    /// A short machine-readable name.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::BaseTooLow { .. } => "base_too_low",
            Self::PitchTooLarge { .. } => "pitch_too_large",
            Self::NonFootContact { .. } => "non_foot_contact",
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_kind_is_listed_once_in_the_order_of_the_variants() {
        let all = [
            Termination::BaseTooLow { height_m: 0.1 },
            Termination::PitchTooLarge { pitch_deg: 20.0 },
            Termination::NonFootContact {
                links: vec!["chassis".into()],
            },
        ];
        assert_eq!(all.map(|t| t.kind()), Termination::KINDS);
    }
}

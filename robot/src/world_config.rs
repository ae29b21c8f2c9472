//! The world's settings: the PD model and gains, rapier's solver passes,
//! friction and contact prediction, as an experiment file's `[physics]`
//! table spells them (serde), and their validation.
//!
//! ```toml
//! [physics]               # the defaults
//! pd = "implicit_spring"  # or "motor": a rapier motor constraint per joint
//! substeps = 1            # rapier num_solver_iterations
//! pgs_iterations = 4      # rapier num_internal_pgs_iterations
//! ccd = true
//! kp_n_m_per_rad = 600.0
//! kd_n_m_s_per_rad = 8.0
//! friction = 1.0          # of the robot's colliders
//! prediction_distance_m = 0.02  # rapier's: shapes this close get speculative contacts
//! step_rate_hz = 240      # physics steps per second (the paper's 240)
//! ```
//!
//! `step_rate_hz` sets the physics step, 1 / rate s, and with it the
//! control points of a 0.75 s phase (180 at 240 Hz, 90 at 120 Hz): the
//! phase's curves are sampled, solved by IK and stepped that many times.
//! A coarser step is cheaper (120 Hz costs about half of 240 Hz per phase)
//! and simulates the same scene less finely; a policy carries the rate it
//! trained at, and `quadwalk eval --step-rate-hz` runs it at another.

use serde::{Deserialize, Serialize};

/// A physics setting out of its range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct WorldConfigError(pub String);

/// How the joints' PD controllers are simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum PdModel {
    /// A `MotorModel::ForceBased` position motor per joint: a velocity
    /// constraint row in rapier's solver, solved with the contacts in every
    /// substep, its force capped at the joint's effort. With rapier's
    /// default solver passes (4 substeps, 1 PGS iteration each) the motor
    /// rows and the foot friction do not converge: stance feet slip ~1 cm
    /// per phase and the standing robot creeps 9 cm in 10 s on rigid ground
    /// (docs/notebook/2026-11-29-physics-three-times-faster.md, "What the physics does").
    Motor,
    /// The PD as the multibody's own implicit joint spring and damping
    /// (rapier's `MultibodyJoint::set_spring` and `Multibody::damping_mut`):
    /// `tau = kp (q* - q) - kd q'`, integrated backward-Euler inside the
    /// articulated dynamics, so no solver rows. The effort cap is applied
    /// before each step: where the PD torque at the current state would
    /// exceed the effort, the spring's rest angle is moved so that it equals
    /// the cap, `rest = q + (clamp(tau) + kd q') / kp`. The default: stable
    /// at one substep, and what the robot does then matches the motor model
    /// solved to convergence (4 substeps x 4 PGS iterations).
    #[default]
    ImplicitSpring,
}

impl PdModel {
    /// The name used in configs.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Motor => "motor",
            Self::ImplicitSpring => "implicit_spring",
        }
    }

    /// The model of a config name.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "motor" => Some(Self::Motor),
            "implicit_spring" => Some(Self::ImplicitSpring),
            _ => None,
        }
    }
}

/// Settings of the world (an experiment file's `[physics]` table; fields
/// in the order the file lists them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WorldConfig {
    /// how the PD is simulated
    pub pd: PdModel,
    /// rapier substeps per step (`num_solver_iterations`); the multibody's
    /// mass matrix and its LU are rebuilt in each, so a step costs about
    /// this many times the articulated dynamics
    #[serde(rename = "substeps")]
    pub solver_iterations: usize,
    /// rapier constraint-solver passes inside each substep
    /// (`num_internal_pgs_iterations`)
    pub pgs_iterations: usize,
    /// continuous collision detection against fixed colliders (rapier's
    /// `max_ccd_substeps` 1, or 0 when off)
    pub ccd: bool,
    /// PD position gain, N m/rad
    pub kp_n_m_per_rad: f64,
    /// PD velocity gain, N m s/rad
    pub kd_n_m_s_per_rad: f64,
    /// friction coefficient of the robot's colliders
    pub friction: f64,
    /// how far apart two shapes may be and still get a contact point, m
    /// (rapier's `normalized_prediction_distance`, its default 0.02 m): a
    /// point closer than this but not touching is speculative, a solver
    /// row that acts only if the gap would close within the step. Every
    /// contact row of the robot costs an LU solve against its 18 x 18 mass
    /// matrix, and on tiles a sunk foot is within 2 cm of the neighbouring
    /// tiles' side walls (docs/notebook/2026-11-29-physics-three-times-faster.md, "Contact prediction distance").
    pub prediction_distance_m: f64,
    /// physics steps per second, Hz: the step is 1 / rate s and a 0.75 s
    /// phase takes 0.75 x rate steps, so the rate is a multiple of 4
    /// (written to a config only when it is not the paper's 240)
    #[serde(skip_serializing_if = "is_paper_step_rate")]
    pub step_rate_hz: u32,
}

/// The paper's physics rate, Hz (a 1/240 s step, 180 per phase).
pub const PAPER_STEP_RATE_HZ: u32 = 240;

/// The rates `step_rate_hz` may take, Hz: a quarter to four times the
/// paper's (45 to 720 steps a phase).
pub const STEP_RATE_RANGE_HZ: std::ops::RangeInclusive<u32> = 60..=960;

/// Whether `rate_hz` is the paper's rate (serde's test for leaving the
/// key out of a file).
pub fn is_paper_step_rate(rate_hz: &u32) -> bool {
    *rate_hz == PAPER_STEP_RATE_HZ
}

/// The physics step at `step_rate_hz`, s: 1 / rate.
pub fn dt_secs_at(step_rate_hz: u32) -> f64 {
    1.0 / f64::from(step_rate_hz)
}

/// Physics steps in a 0.75 s phase at `step_rate_hz`: 0.75 x rate.
pub fn steps_per_phase_at(step_rate_hz: u32) -> usize {
    step_rate_hz as usize * 3 / 4
}

impl Default for WorldConfig {
    fn default() -> Self {
        Self {
            kp_n_m_per_rad: 600.0,
            kd_n_m_s_per_rad: 8.0,
            pd: PdModel::ImplicitSpring,
            solver_iterations: 1,
            pgs_iterations: 4,
            ccd: true,
            friction: 1.0,
            prediction_distance_m: 0.02,
            step_rate_hz: PAPER_STEP_RATE_HZ,
        }
    }
}

impl TryFrom<String> for PdModel {
    type Error = WorldConfigError;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::from_name(&name).ok_or_else(|| {
            WorldConfigError(format!(
                "pd must be \"implicit_spring\" or \"motor\", got {name:?}"
            ))
        })
    }
}

impl From<PdModel> for String {
    fn from(value: PdModel) -> Self {
        value.name().to_string()
    }
}

impl WorldConfig {
    /// Checks every value's range; the error names the key (as the
    /// `[physics]` table spells it).
    pub fn validate(&self) -> Result<(), WorldConfigError> {
        let fail = |message: String| Err(WorldConfigError(message));
        for (name, v) in [
            ("substeps", self.solver_iterations),
            ("pgs_iterations", self.pgs_iterations),
        ] {
            if !(1..=64).contains(&v) {
                return fail(format!("{name} must be in 1..=64, got {v}"));
            }
        }
        for (name, v) in [
            ("kp_n_m_per_rad", self.kp_n_m_per_rad),
            ("kd_n_m_s_per_rad", self.kd_n_m_s_per_rad),
            ("friction", self.friction),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return fail(format!("{name} must be a finite number >= 0, got {v}"));
            }
        }
        if self.kp_n_m_per_rad == 0.0 {
            return fail("kp_n_m_per_rad must be positive, got 0".to_string());
        }
        let d = self.prediction_distance_m;
        if !(d.is_finite() && d > 0.0 && d <= 0.1) {
            return fail(format!(
                "prediction_distance_m must be in (0, 0.1] m, got {d}"
            ));
        }
        let rate = self.step_rate_hz;
        if !(STEP_RATE_RANGE_HZ.contains(&rate) && rate.is_multiple_of(4)) {
            return fail(format!(
                "step_rate_hz must be a multiple of 4 in {}..={} Hz (a 0.75 s phase takes 0.75 x rate steps), got {rate}",
                STEP_RATE_RANGE_HZ.start(),
                STEP_RATE_RANGE_HZ.end()
            ));
        }
        Ok(())
    }

    /// The physics step, s: 1 / `step_rate_hz`.
    pub fn dt_secs(&self) -> f64 {
        dt_secs_at(self.step_rate_hz)
    }

    /// Physics steps (IK solves, control points) in a 0.75 s phase:
    /// 0.75 x `step_rate_hz`.
    pub fn steps_per_phase(&self) -> usize {
        steps_per_phase_at(self.step_rate_hz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_toml(text: &str) -> Result<WorldConfig, String> {
        let physics: WorldConfig = toml::from_str(text).map_err(|e| e.message().to_string())?;
        physics.validate().map_err(|e| e.to_string())?;
        Ok(physics)
    }

    #[test]
    fn the_table_names_substeps_and_round_trips() {
        assert_eq!(from_toml("").unwrap(), WorldConfig::default());
        let physics = WorldConfig {
            pd: PdModel::Motor,
            solver_iterations: 4,
            prediction_distance_m: 0.005,
            ..WorldConfig::default()
        };
        let text = toml::to_string(&physics).unwrap();
        assert!(
            text.starts_with("pd = \"motor\"\nsubsteps = 4\npgs_iterations = 4\n"),
            "{text}"
        );
        assert_eq!(from_toml(&text).unwrap(), physics);
        assert!(
            !text.contains("step_rate_hz"),
            "the paper's rate is not written: {text}"
        );
    }

    #[test]
    fn the_step_rate_sets_the_step_and_the_steps_of_a_phase() {
        let paper = WorldConfig::default();
        assert_eq!(paper.steps_per_phase(), crate::action::SAMPLES_PER_PHASE);
        assert_eq!(paper.dt_secs(), crate::DT_SECS);
        let coarse = from_toml("step_rate_hz = 120").unwrap();
        assert_eq!(coarse.steps_per_phase(), 90);
        assert!((coarse.dt_secs() * coarse.steps_per_phase() as f64 - 0.75).abs() < 1e-12);
        let text = toml::to_string(&coarse).unwrap();
        assert!(text.ends_with("step_rate_hz = 120\n"), "{text}");
        assert_eq!(from_toml(&text).unwrap(), coarse);
    }

    #[test]
    fn bad_values_name_the_key() {
        for (text, expected) in [
            ("substep = 2", "unknown field `substep`"),
            ("substeps = 0", "substeps must be in 1..=64, got 0"),
            ("pgs_iterations = 65", "pgs_iterations must be in 1..=64"),
            ("kp_n_m_per_rad = 0.0", "kp_n_m_per_rad must be positive"),
            (
                "kd_n_m_s_per_rad = -1.0",
                "kd_n_m_s_per_rad must be a finite number >= 0",
            ),
            ("friction = -0.1", "friction must be a finite number >= 0"),
            (
                "prediction_distance_m = 0.5",
                "prediction_distance_m must be in (0, 0.1] m",
            ),
            (
                "step_rate_hz = 130",
                "step_rate_hz must be a multiple of 4 in 60..=960 Hz",
            ),
            (
                "step_rate_hz = 56",
                "step_rate_hz must be a multiple of 4 in 60..=960 Hz",
            ),
            ("step_rate_hz = 964", "got 964"),
            (
                "pd = \"spring\"",
                "pd must be \"implicit_spring\" or \"motor\", got \"spring\"",
            ),
        ] {
            let err = from_toml(text).unwrap_err();
            assert!(err.contains(expected), "{text:?} gave {err:?}");
        }
    }
}

//! A residual controller within the phase (`[residual]`, the paper's first
//! proposal for reacting while the ground moves): a frozen phase-level
//! policy plans every phase as quadwalk's task does, and a lower-level
//! policy moves each foot's target every `control_steps` physics steps
//! (40 Hz by default) from what the robot measures. With `phase_policy =
//! "none"` there is no phase level (the paper's second proposal, a
//! single-level policy): each phase's plan holds the base and every foot
//! where they are at its start, and the policy moves all four feet itself.
//! [`ResidualDriver`] runs either for one robot; `TaskEnv` trains through
//! it and [`crate::policy`] evaluates with it, so training and evaluation
//! step alike.
//!
//! The lower-level observation ([`OBSERVATION_SIZE`] values, all in the
//! base frame unless said): the phase's progress (1), the swing leg one-hot
//! (4), the base's roll and pitch (2, rad), its angular velocity (3, rad/s)
//! and linear velocity (3, m/s), the hip heights h_b (4, m), the goal the
//! task observes in the base frame (2, m: x ahead, y left), each foot's
//! planned position at the next step in the base's target frame (12, m),
//! its measured position (12, m) and velocity (12, m/s), whether it
//! touches the ground (4), and the previous action (12). What the feet
//! feel shows as the gap between planned and measured feet and in their
//! velocities: a foot that sinks further than planned lags its plan.
//!
//! The action (12 values in [-1, 1]) times `max_offset_m` moves the feet's
//! targets (FR, FL, RR, RL; x, y, z each) for the control step's physics
//! steps, before IK. The reward of a control step is -offset_cost x the
//! mean squared action, plus, at the control step that ends a phase, the
//! phase's own reward (the task's, termination included): the lower level
//! is paid for what the phase level is paid for.

use std::path::Path;

use anyhow::{Context, Result, bail};
use nalgebra::Vector3;
use robot::WorldConfig;
use robot::task::{ActionPrior, PhaseOutcome, PhaseRun, Task, TaskConfig};

use crate::config::{Experiment, ResidualConfig, default_task};
use crate::policy::Policy;
use robot::snapshot::PhaseObserver;

/// Values of the lower-level observation.
pub const OBSERVATION_SIZE: usize = 71;
/// `phase_policy = "none"`: no phase level (a single-level policy).
pub const NO_PHASE_POLICY: &str = "none";
/// Values of the lower-level action: an offset per foot and axis.
pub const ACTION_SIZE: usize = 12;

/// Gives `experiment` its phase policy's observation, action prior, swing
/// height reference and physics (the phase policy reads the task's
/// observation and was trained in those physics), as an evaluation fits a
/// scene to a policy, and resolves the curriculum's stages over them again;
/// the run's `config.toml` then spells them out, and reading it back gives
/// the same stages. A setting the file gives that the phase policy would
/// replace is refused by name rather than ignored (a value equal to the
/// phase policy's, as a run's own `config.toml` has, is fine). Without a
/// phase level (`"none"`) nothing reads the task's observation but its goal
/// point, so a height scan or an action prior there is refused too.
pub fn fit_to_phase_policy(
    registry: &terrain_plugins::Registry,
    experiment: &mut Experiment,
) -> Result<()> {
    let Some(config) = &experiment.residual else {
        return Ok(());
    };
    let Some(phase_policy) = load_phase_policy(registry, config)? else {
        if experiment.task.observation.height_scan {
            bail!(
                "[task.observation] height_scan = true: with [residual] phase_policy = \"none\" no phase-level policy observes the task, and the lower level sees its own {OBSERVATION_SIZE} values"
            );
        }
        if experiment.task.action_prior != ActionPrior::None {
            bail!(
                "[task] action_prior = {:?}: with [residual] phase_policy = \"none\" there are no phase actions to add the prior to",
                experiment.task.action_prior.name()
            );
        }
        return Ok(());
    };
    let file_task = experiment.task.clone();
    let file_physics = experiment.physics.clone();
    phase_policy.fit_scene(&mut experiment.task, &mut experiment.physics, None)?;
    let default_task = default_task();
    let replaced = [
        (
            "[task.observation]",
            settings_replaced(
                &file_task.observation,
                &experiment.task.observation,
                &default_task.observation,
            ),
        ),
        (
            "[task]",
            settings_replaced(
                &ReplacedTaskKeys::of(&file_task),
                &ReplacedTaskKeys::of(&experiment.task),
                &ReplacedTaskKeys::of(&default_task),
            ),
        ),
        (
            "[physics]",
            settings_replaced(&file_physics, &experiment.physics, &WorldConfig::default()),
        ),
    ];
    for (section, keys) in replaced {
        if !keys.is_empty() {
            bail!(
                "{section} {}: [residual] phase_policy {} was trained otherwise, and a residual's task and physics are its phase policy's; remove the setting or give the phase policy's value",
                keys.join(", "),
                config.phase_policy.display()
            );
        }
    }
    experiment.resolve_stages_again()
}

/// The task keys besides the observation that a residual's phase policy
/// sets.
#[derive(serde::Serialize)]
struct ReplacedTaskKeys {
    action_prior: &'static str,
    swing_height_reference: &'static str,
}

impl ReplacedTaskKeys {
    fn of(task: &TaskConfig) -> Self {
        Self {
            action_prior: task.action_prior.name(),
            swing_height_reference: task.swing_height_reference.name(),
        }
    }
}

/// The keys whose value in `file` is neither the phase policy's (`fitted`)
/// nor the default (where the file is silent), as `key = file's (the phase
/// policy's fitted)`.
fn settings_replaced<T: serde::Serialize>(file: &T, fitted: &T, default: &T) -> Vec<String> {
    // a struct of settings always serialises to a table; an empty one here
    // would let every replaced setting through unnamed
    let table =
        |settings: &T| toml::Table::try_from(settings).expect("settings serialise to a table");
    let (file, fitted, default) = (table(file), table(fitted), table(default));
    file.iter()
        .filter(|(key, value)| fitted.get(*key) != Some(value) && default.get(*key) != Some(value))
        .map(|(key, value)| {
            let phase = fitted.get(key).map_or("not set".into(), |v| v.to_string());
            format!("{key} = {value} (the phase policy's: {phase})")
        })
        .collect()
}

/// The phase policy `config` names (`None` for `"none"`: no phase level).
pub fn load_phase_policy(
    registry: &terrain_plugins::Registry,
    config: &ResidualConfig,
) -> Result<Option<Policy>> {
    let name = config.phase_policy.to_string_lossy();
    if name == NO_PHASE_POLICY {
        return Ok(None);
    }
    Policy::from_arg(registry, &name, None)
        .map(Some)
        .context("[residual] phase_policy")
}

/// `config`'s phase policy as seen from the residual policy at
/// `policy_path`: a relative `phase_policy` that does not exist from the
/// current directory is looked up from the policy's directory and each
/// directory above it, so a shipped residual policy, which names its phase
/// policy from the repository's root (`policies/tv2`), runs from anywhere
/// in the checkout. Left as it is when no such path exists (loading it
/// then names it).
pub fn phase_policy_seen_from(config: &mut ResidualConfig, policy_path: &Path) {
    let named = config.phase_policy.clone();
    if named.as_os_str() == NO_PHASE_POLICY || named.is_absolute() || named.exists() {
        return;
    }
    if let Some(found) = policy_path
        .ancestors()
        .map(|dir| dir.join(&named))
        .find(|candidate| candidate.exists())
    {
        config.phase_policy = found;
    }
}

/// What one control step did.
#[derive(Debug, Clone)]
pub struct ControlOutcome {
    /// the control step's reward (see the module docs)
    pub reward: f64,
    /// the offsets' cost in it (a negative number or 0)
    pub offset_reward: f64,
    /// the phase's outcome, if the phase ended in this control step
    pub phase: Option<PhaseOutcome>,
}

/// The residual controller of one robot: the phase policy, the phase under
/// way and the previous action.
pub struct ResidualDriver {
    config: ResidualConfig,
    /// `None`: no phase level, each phase's plan holds still
    phase_policy: Option<Policy>,
    run: Option<PhaseRun>,
    last_action: [f32; ACTION_SIZE],
}

impl ResidualDriver {
    /// A driver with `phase_policy` planning the phases (`None`: plans that
    /// hold still, the lower level moving every foot).
    pub fn new(config: ResidualConfig, phase_policy: Option<Policy>) -> Self {
        Self {
            config,
            phase_policy,
            run: None,
            last_action: [0.0; ACTION_SIZE],
        }
    }

    /// Its settings.
    pub fn config(&self) -> &ResidualConfig {
        &self.config
    }

    /// Forgets the episode (after the task's reset).
    pub fn reset(&mut self) {
        self.run = None;
        self.last_action = [0.0; ACTION_SIZE];
    }

    /// Plans the next phase with the phase policy from the task's
    /// phase-level observation `phase_obs`.
    pub fn begin_phase(
        &mut self,
        task: &mut Task,
        phase_obs: &[f32],
        observer: &mut dyn PhaseObserver,
    ) -> Result<()> {
        self.run = Some(match &mut self.phase_policy {
            Some(policy) => {
                let action = policy.action(task, phase_obs)?;
                task.begin_phase(&action, observer)
            }
            None => task.begin_phase_holding(observer),
        });
        Ok(())
    }

    /// One control step with `action` (12 values, clipped to [-1, 1]): the
    /// phase goes on `control_steps` physics steps (fewer if it ends or
    /// the robot falls); a phase that ends writes the next phase-level
    /// observation into `phase_obs`.
    pub fn control_step(
        &mut self,
        task: &mut Task,
        action: &[f32],
        phase_obs: &mut [f32],
        observer: &mut dyn PhaseObserver,
    ) -> ControlOutcome {
        let run = self
            .run
            .as_mut()
            .expect("a control step runs inside a phase: begin_phase first");
        let mut clipped = [0.0f32; ACTION_SIZE];
        for (c, a) in clipped.iter_mut().zip(action) {
            *c = a.clamp(-1.0, 1.0);
        }
        let offsets_m: [Vector3<f64>; 4] = std::array::from_fn(|leg| {
            Vector3::from_fn(|axis, _| {
                f64::from(clipped[3 * leg + axis]) * self.config.max_offset_m
            })
        });
        for _ in 0..self.config.control_steps {
            if !task.step_in_phase(run, Some(&offsets_m), observer) {
                break;
            }
        }
        self.last_action = clipped;
        let mean_square =
            clipped.iter().map(|a| f64::from(a * a)).sum::<f64>() / ACTION_SIZE as f64;
        let offset_reward = -self.config.offset_cost * mean_square;
        let phase = if run.finished() {
            let run = self.run.take().expect("the phase under way");
            Some(task.end_phase(run, phase_obs, observer))
        } else {
            None
        };
        ControlOutcome {
            reward: offset_reward + phase.as_ref().map_or(0.0, |p| p.reward),
            offset_reward,
            phase,
        }
    }

    /// Writes the lower-level observation ([`OBSERVATION_SIZE`] values,
    /// see the module docs) into `out`. Between phases (after the last
    /// one) the plan is the measured feet and the progress 1.
    pub fn observe(&self, task: &Task, out: &mut [f32]) {
        assert_eq!(
            out.len(),
            OBSERVATION_SIZE,
            "the residual observation's size"
        );
        let world = task.world();
        let pose = world.base_pose();
        let to_base = pose.rotation.inverse();
        let (linear, angular) = world.base_velocity();
        let feet_base = robot::controller::feet_in_base_m(&pose, world.feet_in_world_m());
        let (progress, swing, planned) = match &self.run {
            Some(run) => (
                run.steps as f64 / run.steps_per_phase as f64,
                Some(run.plan.swing_leg.index()),
                task.planned_feet_m(run),
            ),
            None => (1.0, None, feet_base),
        };
        let (roll, pitch, _) = pose.rotation.euler_angles();
        let mut values: Vec<f64> = Vec::with_capacity(OBSERVATION_SIZE);
        values.push(progress);
        values.extend((0..4).map(|leg| f64::from(u8::from(swing == Some(leg)))));
        values.extend([roll, pitch]);
        values.extend((to_base * angular).iter());
        values.extend((to_base * linear).iter());
        values.extend(task.hip_heights_m());
        let goal_xy_m = task.observed_goal_xy_m().unwrap_or(task.goal_xy_m());
        values.extend(robot::controller::point_in_base(&pose, goal_xy_m).iter());
        for foot in planned {
            values.extend(foot.iter());
        }
        for foot in feet_base {
            values.extend(foot.iter());
        }
        for velocity in world.foot_sole_velocities_m_per_s() {
            values.extend((to_base * velocity).iter());
        }
        values.extend(
            world
                .feet_touching_ground()
                .iter()
                .map(|&t| f64::from(u8::from(t))),
        );
        values.extend(self.last_action.iter().map(|&a| f64::from(a)));
        debug_assert_eq!(values.len(), OBSERVATION_SIZE);
        for (o, v) in out.iter_mut().zip(values) {
            *o = v as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use robot::scripted::ScriptedCrawl;
    use robot::snapshot::NoObserver;
    use robot::task::TaskConfig;
    use robot::{RobotModel, WorldConfig};
    use terrain_plugins::Registry;

    use super::*;
    use crate::scene::make_world;

    fn task(spec: &str) -> Task {
        let registry = Registry::builtin();
        let world = make_world(
            &registry,
            &spec.parse().unwrap(),
            Arc::new(RobotModel::laikago()),
            7,
            [0.0, 0.0],
            &WorldConfig::default(),
        )
        .unwrap();
        Task::new(world, TaskConfig::default(), 5)
    }

    fn driver() -> ResidualDriver {
        let config = ResidualConfig {
            phase_policy: "scripted".into(),
            ..ResidualConfig::default()
        };
        ResidualDriver::new(config, Some(Policy::Scripted(ScriptedCrawl::default())))
    }

    /// A residual's task and physics are its phase policy's, its stages'
    /// included (as reading the run's `config.toml` back gives them); a
    /// setting the file gives that the phase policy would replace is
    /// refused by name, and without a phase level so are settings only a
    /// phase level reads.
    #[test]
    fn a_residual_takes_its_phase_policys_task_and_physics_and_refuses_others() {
        let registry = Registry::builtin();
        let tv2 = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies/tv2");
        let config = |task: &str, physics: &str, phase: &str| {
            format!(
                "[terrain]\nspec = \"elastic:5cm\"\n\n[task]\nmax_paid_progress_m = 0.03\n{task}\n[physics]\n{physics}\n\n[residual]\nphase_policy = {phase:?}\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 1\n\n[[curriculum]]\nterrain = \"elastic:5cm\"\niterations = 1\n\n[curriculum.task]\nmax_paid_progress_m = 0.02\n"
            )
        };
        let fitted = |text: &str| {
            let mut experiment = Experiment::from_toml(text, "c.toml", &registry).unwrap();
            fit_to_phase_policy(&registry, &mut experiment).map(|()| experiment)
        };
        let phase_level = Policy::from_arg(&registry, &tv2.to_string_lossy(), None).unwrap();
        let Policy::Trained { task, .. } = &phase_level else {
            panic!("policies/tv2 is a trained policy")
        };
        let experiment = fitted(&config("", "", &tv2.to_string_lossy())).unwrap();
        assert_ne!(
            task.observation,
            default_task().observation,
            "the test needs a difference"
        );
        for iteration in [0, 1] {
            assert_eq!(experiment.task_at(iteration).observation, task.observation);
        }
        assert_eq!(experiment.task_at(1).max_paid_progress_m, Some(0.02));
        // the run's config.toml gives the same experiment back
        let again = Experiment::from_toml(&experiment.to_toml(), "config.toml", &registry).unwrap();
        assert_eq!(again.task_at(1), experiment.task_at(1));
        assert_eq!(again.physics_at(1), experiment.physics_at(1));
        // settings the phase policy replaces, named
        for (task_keys, physics, named) in [
            (
                "[task.observation]\ngoal_line_ahead_m = 2.0\n",
                "",
                "[task.observation] goal_line_ahead_m = 2.0 (the phase policy's: 1.0)",
            ),
            (
                "swing_height_reference = \"touchdown\"\n",
                "",
                "[task] swing_height_reference = \"touchdown\"",
            ),
            (
                "[task.observation]\nheight_scan = true\n",
                "",
                "[task.observation] height_scan = true",
            ),
            ("", "step_rate_hz = 120", "[physics] step_rate_hz = 120"),
        ] {
            let err = fitted(&config(task_keys, physics, &tv2.to_string_lossy()))
                .err()
                .unwrap_or_else(|| panic!("{named}: accepted"))
                .to_string();
            assert!(err.contains(named) && err.contains("policies/tv2"), "{err}");
        }
        // the phase policy's own values are fine
        assert!(
            fitted(&config(
                "[task.observation]\ngoal_line_ahead_m = 1.0\n",
                "",
                &tv2.to_string_lossy()
            ))
            .is_ok()
        );
        // without a phase level
        assert!(
            fitted(&config(
                "[task.observation]\ngoal_line_ahead_m = 2.0\n",
                "",
                "none"
            ))
            .is_ok()
        );
        for (task_keys, named) in [
            (
                "[task.observation]\nheight_scan = true\n",
                "height_scan = true",
            ),
            (
                "action_prior = \"scripted_crawl\"\n",
                "action_prior = \"scripted_crawl\"",
            ),
        ] {
            let err = fitted(&config(task_keys, "", "none"))
                .err()
                .unwrap()
                .to_string();
            assert!(err.contains(named) && err.contains("\"none\""), "{err}");
        }
    }

    #[test]
    fn a_relative_phase_policy_is_found_from_the_residual_policys_directory_up() {
        let root = std::env::temp_dir().join(format!(
            "quadwalk-phase-policy-seen-from-{}",
            std::process::id()
        ));
        let shipped = root.join("policies");
        std::fs::create_dir_all(shipped.join("tv2")).unwrap();
        std::fs::create_dir_all(shipped.join("residual")).unwrap();
        let named = |name: &str| ResidualConfig {
            phase_policy: name.into(),
            ..ResidualConfig::default()
        };
        let mut config = named("policies/tv2");
        phase_policy_seen_from(&mut config, &shipped.join("residual"));
        assert_eq!(config.phase_policy, shipped.join("tv2"));
        // `none`, and a name found nowhere, stay as they are
        for name in [NO_PHASE_POLICY, "policies/tv9"] {
            let mut config = named(name);
            phase_policy_seen_from(&mut config, &shipped.join("residual"));
            assert_eq!(config.phase_policy, std::path::PathBuf::from(name));
        }
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn zero_offsets_run_the_phase_policys_phases_bit_for_bit() {
        // The crawl on 5 cm tiles: six phases whole, and six driven at 40 Hz
        // with every offset 0: the same rewards to the bit, observations
        // and base poses; a control step's reward is the phase's at its
        // last one and 0 before.
        let (mut plain, mut driven) = (task("elastic:5cm"), task("elastic:5cm"));
        let n = plain.observation_size();
        let (mut obs_a, mut obs_b) = (vec![0.0; n], vec![0.0; n]);
        plain.reset(&mut obs_a);
        driven.reset(&mut obs_b);
        let mut crawl = Policy::Scripted(ScriptedCrawl::default());
        let mut driver = driver();
        let mut own = [0.0f32; OBSERVATION_SIZE];
        for _ in 0..6 {
            let action = crawl.action(&plain, &obs_a).unwrap();
            let whole = plain.step_phase(&action, &mut obs_a);
            driver
                .begin_phase(&mut driven, &obs_b, &mut NoObserver)
                .unwrap();
            let mut steps = 0;
            let outcome = loop {
                driver.observe(&driven, &mut own);
                assert!(own.iter().all(|v| v.is_finite()), "{own:?}");
                let out = driver.control_step(
                    &mut driven,
                    &[0.0; ACTION_SIZE],
                    &mut obs_b,
                    &mut NoObserver,
                );
                steps += 1;
                assert_eq!(out.offset_reward, 0.0);
                match out.phase {
                    Some(phase) => {
                        assert_eq!(out.reward.to_bits(), phase.reward.to_bits());
                        break phase;
                    }
                    None => assert_eq!(out.reward, 0.0),
                }
            };
            assert_eq!(steps, 30, "40 Hz: 30 control steps per phase");
            assert_eq!(outcome.reward.to_bits(), whole.reward.to_bits());
            assert_eq!(obs_a, obs_b);
            assert_eq!(plain.world().base_pose(), driven.world().base_pose());
        }
    }

    #[test]
    fn without_a_phase_level_a_phase_holds_still_until_the_policy_moves_the_feet() {
        // `phase_policy = "none"`: zero offsets for a phase leave the robot
        // standing in its squat (base within 2 cm, feet within 1 cm, the
        // same swing order in the history); 30 control steps a phase.
        let mut task = task("rigid");
        let mut phase_obs = vec![0.0; task.observation_size()];
        task.reset(&mut phase_obs);
        let config = ResidualConfig {
            phase_policy: NO_PHASE_POLICY.into(),
            max_offset_m: 0.15,
            ..ResidualConfig::default()
        };
        let mut driver = ResidualDriver::new(config, None);
        let base_start = task.world().base_pose().translation.vector;
        let feet_start = task.world().feet_in_world_m();
        let swing = task.swing_leg();
        driver
            .begin_phase(&mut task, &phase_obs, &mut NoObserver)
            .unwrap();
        let mut steps = 0;
        let outcome = loop {
            steps += 1;
            let out = driver.control_step(
                &mut task,
                &[0.0; ACTION_SIZE],
                &mut phase_obs,
                &mut NoObserver,
            );
            if let Some(phase) = out.phase {
                break phase;
            }
        };
        assert_eq!(steps, 30);
        assert!(outcome.termination.is_none(), "{outcome:?}");
        let moved_m = (task.world().base_pose().translation.vector - base_start).norm();
        assert!(moved_m < 0.02, "the base moved {moved_m} m");
        for (now, start) in task.world().feet_in_world_m().iter().zip(feet_start) {
            assert!((now - start).norm() < 0.01, "{now} from {start}");
        }
        assert_ne!(
            task.swing_leg(),
            swing,
            "the next phase swings the next leg"
        );
    }

    #[test]
    fn the_observation_reads_the_plan_and_the_feet_and_the_action_moves_them() {
        let mut task = task("elastic:2cm");
        let mut phase_obs = vec![0.0; task.observation_size()];
        task.reset(&mut phase_obs);
        let mut driver = driver();
        driver
            .begin_phase(&mut task, &phase_obs, &mut NoObserver)
            .unwrap();
        let mut own = [0.0f32; OBSERVATION_SIZE];
        driver.observe(&task, &mut own);
        // progress 0, one swing leg, the plan's feet near the measured
        // ones at the phase start (within 2 cm), no previous action
        assert_eq!(own[0], 0.0);
        assert_eq!(own[1..5].iter().sum::<f32>(), 1.0);
        // the goal ahead (the default task's first goal is 2 m away)
        assert!(own[17] > 1.0 && own[18].abs() < 0.3, "{own:?}");
        for k in 0..12 {
            assert!((own[19 + k] - own[31 + k]).abs() < 0.02, "{k}: {own:?}");
        }
        assert!(own[59..].iter().all(|&a| a == 0.0));
        // every foot's target 3 cm lower (action -1 on z, bound 3 cm) for
        // one control step: the cost is offset_cost x 1/3 and the action is
        // the next observation's last block
        let mut action = [0.0f32; ACTION_SIZE];
        for leg in 0..4 {
            action[3 * leg + 2] = -1.0;
        }
        let out = driver.control_step(&mut task, &action, &mut phase_obs, &mut NoObserver);
        assert!((out.offset_reward + 0.02 / 3.0).abs() < 1e-9, "{out:?}");
        driver.observe(&task, &mut own);
        assert!((own[0] - 6.0 / 180.0).abs() < 1e-6);
        assert_eq!(&own[59..], &action[..]);
    }
}

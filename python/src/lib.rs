//! quadwalk from Python: the native module `quadwalk._quadwalk`.
//!
//! The Python package (`pysrc/quadwalk`) wraps these classes in Gymnasium's
//! interfaces; this module holds what runs in Rust:
//!
//! - [`env::Env`]: one task (`Task` on one `World`), stepped a phase at a
//!   time with the GIL released;
//! - [`env::VecEnv`]: N tasks stepped in parallel on a thread pool, with
//!   Gymnasium's next-step autoreset;
//! - [`policy::Policy`]: a quadwalk checkpoint's mean action on numpy
//!   observations;
//! - [`controller::Controller`] and [`controller::Sim`]: the phase-level
//!   controller a robot runs around a policy, and quadwalk's world as a
//!   bare robot it drives step by step;
//! - [`scene::terrains`]: the terrain registry (name, summary, parameters).
//!
//! Scenes are built exactly as `quadwalk rollout` builds them
//! (`experiment::scene::make_world`, `Task::new(world, task, seed)`), so an
//! episode here with seed S is the command's episode with `--seed S`.
//! Errors in what the caller passed (a terrain spec, an experiment file, an
//! action of the wrong size) raise `ValueError` with the message naming the
//! input; a failure past that raises `RuntimeError`.

use pyo3::prelude::*;

mod controller;
mod env;
mod policy;
mod scene;

/// The native module.
#[pymodule]
fn _quadwalk(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<env::Env>()?;
    m.add_class::<env::VecEnv>()?;
    m.add_class::<policy::Policy>()?;
    m.add_class::<controller::Controller>()?;
    m.add_class::<controller::Sim>()?;
    m.add_function(wrap_pyfunction!(scene::terrains, m)?)?;
    m.add("ACTION_SIZE", robot::action::ACTION_SIZE)?;
    m.add("LAIKAGO_URDF", robot::LAIKAGO_URDF)?;
    m.add("PHASE_SECS", robot::action::PHASE_SECS)?;
    m.add("REWARD_TERMS", robot::task::RewardTerms::NAMES.to_vec())?;
    Ok(())
}

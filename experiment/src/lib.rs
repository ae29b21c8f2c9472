//! quadwalk's application layer, shared by every front end (the `quadwalk`
//! command line, the Python package): experiment files and the built-in
//! recipes, scenes (robot and world), the policies that act in them, the
//! training environment, and the train and eval loops, as functions that return
//! results and errors and never exit the process.
//!
//! | module | what |
//! | --- | --- |
//! | [`config`] | experiment files: `[terrain]`, `[task]`, `[physics]`, `[algo]`, `[ppo]`, `[sac]`, `[train]`, `[[curriculum]]` |
//! | [`recipes`] | the recipes `train --terrain SPEC` runs |
//! | [`scene`] | the robot model and a world on a terrain spec |
//! | [`policy`] | what acts: the scripted crawl or a trained policy |
//! | [`task_env`] | N tasks as one `learn::VecEnv`, stepped in parallel |
//! | [`train`] | a run: plan (new, resumed, forked), the loop, the run directory |
//! | [`eval`] | a policy on many unseen episodes: the measures, Table I, `eval.json` |
//!
//! Errors are `anyhow` errors whose context names the file, flag or key
//! at fault: this layer speaks to users through its front ends.

pub mod config;
pub mod eval;
pub mod policy;
pub mod recipes;
pub mod residual;
pub mod scene;
pub mod task_env;
pub mod train;

pub use config::Experiment;
pub use policy::Policy;

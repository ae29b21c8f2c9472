//! `quadwalk train`: checkpoints, resume, Ctrl-C, a kill during a save,
//! damaged checkpoints, and trained policies in `rollout` and `play`.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{failure, json_of, quadwalk};

/// A small, fast experiment: 2 worlds x 4 phases per iteration.
pub(crate) const TINY: &str = "[terrain]\nspec = \"rigid\"\n\n[task]\nmax_phases = 4\n\n[ppo]\nhidden_sizes = [16]\nsteps_per_env = 4\nminibatch_size = 4\nepochs = 2\n\n[train]\nenvs = 2\niterations = 3\ncheckpoint_every = 1\n";

/// A fresh directory under the test target's scratch space.
pub(crate) fn scratch_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("train")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub(crate) fn tiny_config(dir: &Path) -> PathBuf {
    let path = dir.join("tiny.toml");
    std::fs::write(&path, TINY).unwrap();
    path
}

/// [`TINY`] with `from` replaced by `to`, written to `dir/variant.toml`.
fn tiny_variant(dir: &Path, from: &str, to: &str) -> PathBuf {
    assert!(TINY.contains(from), "{from:?} is not in the tiny config");
    let path = dir.join("variant.toml");
    std::fs::write(&path, TINY.replace(from, to)).unwrap();
    path
}

pub(crate) fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Trains `config` 3 iterations into `dir/a`, and 2 into `dir/b` resumed
/// to 3, on two threads: the two runs' weights and metrics must be the
/// same. Returns `dir/a`.
fn three_iterations_resumed_bit_for_bit(config: &Path, dir: &Path) -> PathBuf {
    let (a, b) = (dir.join("a"), dir.join("b"));
    train_on_two_threads(config, &a, "3");
    train_on_two_threads(config, &b, "2");
    resume_on_two_threads(&b, "3");
    assert_eq!(weights(&a), weights(&b), "the resumed run differs");
    assert_eq!(metrics_without_timing(&a), metrics_without_timing(&b));
    a
}

/// Runs `quadwalk train --config CONFIG --run-dir RUN`, which must fail
/// with exit code 1; returns its stderr.
fn training_fails(config: &Path, run: &Path) -> String {
    failure(
        &[
            "train",
            "--config",
            s(config),
            "--run-dir",
            s(run),
            "--rerun",
            "off",
        ],
        1,
    )
}

/// Runs `quadwalk ARGS`, which must succeed; returns its stderr.
pub(crate) fn ok(args: &[&str]) -> String {
    let out = quadwalk(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "quadwalk {args:?}: {stderr}");
    stderr
}

/// `train --config CONFIG --run-dir RUN --iterations N --rerun off`.
fn train_args<'a>(config: &'a Path, run: &'a Path, iterations: &'a str) -> [&'a str; 9] {
    [
        "train",
        "--config",
        s(config),
        "--run-dir",
        s(run),
        "--iterations",
        iterations,
        "--rerun",
        "off",
    ]
}

/// [`train_args`], which must succeed.
pub(crate) fn train_tiny(config: &Path, run: &Path, iterations: &str) {
    ok(&train_args(config, run, iterations));
}

/// The metrics lines without the fields that measure time.
fn metrics_without_timing(run: &Path) -> Vec<Value> {
    std::fs::read_to_string(run.join("metrics.jsonl"))
        .unwrap()
        .lines()
        .map(|line| {
            let mut v: Value = serde_json::from_str(line).unwrap();
            let o = v.as_object_mut().unwrap();
            o.remove("secs");
            o.remove("phases_per_s");
            v
        })
        .collect()
}

/// `train --config CONFIG --run-dir RUN --iterations N --threads 2`, which
/// must succeed; returns its stderr.
fn train_on_two_threads(config: &Path, run: &Path, iterations: &str) -> String {
    train_on_two_threads_with(config, run, iterations, &[])
}

/// [`train_on_two_threads`] with `extra` flags after the others.
fn train_on_two_threads_with(
    config: &Path,
    run: &Path,
    iterations: &str,
    extra: &[&str],
) -> String {
    let mut args = vec![
        "train",
        "--config",
        s(config),
        "--run-dir",
        s(run),
        "--iterations",
        iterations,
        "--threads",
        "2",
        "--rerun",
        "off",
    ];
    args.extend_from_slice(extra);
    ok(&args)
}

/// `train --resume RUN --iterations N --threads 2`, which must succeed.
fn resume_on_two_threads(run: &Path, iterations: &str) -> String {
    ok(&[
        "train",
        "--resume",
        s(run),
        "--iterations",
        iterations,
        "--threads",
        "2",
        "--rerun",
        "off",
    ])
}

/// `train --resume CHECKPOINT --threads 2`, which must succeed.
fn resume_from(checkpoint: &Path) -> String {
    ok(&[
        "train",
        "--resume",
        s(checkpoint),
        "--threads",
        "2",
        "--rerun",
        "off",
    ])
}

/// The shape of the actor's first layer in `run`'s latest weights
/// (safetensors header: inputs, hidden units).
fn first_layer_shape(run: &Path) -> Value {
    let weights = weights(run);
    let header_len = u64::from_le_bytes(weights[..8].try_into().unwrap()) as usize;
    let header: Value = serde_json::from_slice(&weights[8..8 + header_len]).unwrap();
    header["actor.0.weight"]["shape"].clone()
}

/// `rollout --policy POLICY --terrain rigid --phases 2`, which must run
/// both phases.
fn rolls_out_two_phases_on_rigid_ground(policy: &Path) {
    let r = json_of(&[
        "rollout",
        "--policy",
        s(policy),
        "--terrain",
        "rigid",
        "--phases",
        "2",
        "--json",
    ]);
    assert_eq!(r["phases"], 2);
}

fn weights(run: &Path) -> Vec<u8> {
    std::fs::read(run.join("latest/weights.safetensors")).unwrap()
}

#[test]
fn same_seed_same_training_and_resume_continues_bit_for_bit() {
    let dir = scratch_dir("resume");
    let config = tiny_config(&dir);
    let (a, b, c) = (dir.join("a"), dir.join("b"), dir.join("c"));
    let train = |run: &Path, iterations: &str| train_on_two_threads(&config, run, iterations);
    let progress = train(&a, "3");
    assert!(
        progress.contains("iter 3/3") && progress.contains("phases/s"),
        "{progress}"
    );
    train(&c, "3");
    assert_eq!(
        weights(&a),
        weights(&c),
        "same seed and threads, different weights"
    );
    assert_eq!(metrics_without_timing(&a), metrics_without_timing(&c));

    train(&b, "2");
    resume_on_two_threads(&b, "3");
    assert_eq!(
        weights(&a),
        weights(&b),
        "a resumed run differs from the uninterrupted one"
    );
    assert_eq!(metrics_without_timing(&a), metrics_without_timing(&b));
    assert_eq!(metrics_without_timing(&b).len(), 3);

    // the run directory's layout
    let latest = std::fs::read_link(a.join("latest")).unwrap();
    assert_eq!(latest, Path::new("checkpoints/iter-000003"));
    for file in ["weights.safetensors", "state.toml", "config.toml"] {
        assert!(a.join("latest").join(file).is_file(), "{file}");
    }
    let m = &metrics_without_timing(&a)[0];
    for key in [
        "mean_return",
        "mean_distance_m",
        "mean_episode_length",
        "reward_terms",
        "policy_loss",
        "value_loss",
        "entropy",
        "approx_kl",
        "clip_fraction",
        "explained_variance",
    ] {
        assert!(m.get(key).is_some(), "{key} missing in {m}");
    }
    assert_eq!(m["reward_terms"].as_object().unwrap().len(), 5);

    // a finished run says so; a fresh run into a used directory is refused
    let err = failure(&["train", "--resume", s(&a), "--rerun", "off"], 1);
    assert!(err.contains("3 of 3 iterations"), "{err}");
    let err = failure(
        &[
            "train",
            "--config",
            s(&config),
            "--run-dir",
            s(&a),
            "--rerun",
            "off",
        ],
        1,
    );
    assert!(
        err.contains("already holds a run") && err.contains("--resume"),
        "{err}"
    );
}

/// [`TINY`] as two rigid stages of 2 iterations, the second with
/// `stage_2` (its keys and tables) added, trained on 2 threads as run `a`
/// and as run `b`, which is stopped after stage 1 and resumed.
struct TwoStages {
    config: PathBuf,
    a: PathBuf,
    b: PathBuf,
}

impl TwoStages {
    fn new(name: &str, stage_2: &str) -> Self {
        let dir = scratch_dir(name);
        let text = TINY.replace(
            "[train]",
            &format!(
                "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 2\n{stage_2}\n[train]"
            ),
        );
        let config = dir.join("staged.toml");
        std::fs::write(&config, text).unwrap();
        Self {
            config,
            a: dir.join("a"),
            b: dir.join("b"),
        }
    }

    /// `train --config CONFIG --run-dir RUN --threads 2 --rerun off` and
    /// `extra`.
    fn args<'a>(&'a self, run: &'a Path, extra: &[&'a str]) -> Vec<&'a str> {
        let mut args = vec![
            "train",
            "--config",
            s(&self.config),
            "--run-dir",
            s(run),
            "--threads",
            "2",
            "--rerun",
            "off",
        ];
        args.extend_from_slice(extra);
        args
    }

    /// Trains `run` through both stages; the log.
    fn train(&self, run: &Path) -> String {
        ok(&self.args(run, &[]))
    }

    /// Run `b`: trained, cut back to its checkpoint of iteration 2 (the end
    /// of stage 1), which `check` reads, then resumed from it; asserts that
    /// it ends as run `a` (trained before) did.
    fn resume_after_stage_1(&self, check: impl FnOnce(&Path)) {
        let b = &self.b;
        self.train(b);
        std::fs::remove_dir_all(b.join("checkpoints/iter-000003")).unwrap();
        std::fs::remove_dir_all(b.join("checkpoints/iter-000004")).unwrap();
        let checkpoint = b.join("checkpoints/iter-000002");
        check(&checkpoint);
        resume_from(&checkpoint);
        assert_eq!(weights(&self.a), weights(b), "the resumed stage 2 differs");
        assert_eq!(metrics_without_timing(&self.a), metrics_without_timing(b));
    }
}

/// A curriculum stage's learning rate: the stage runs at it, the stage
/// without one at `[ppo]`'s, and a resume at the stage boundary (whose
/// checkpoint holds the first stage's rate) continues bit for bit.
#[test]
fn a_curriculum_stage_sets_its_learning_rate_and_resumes_exactly() {
    let runs = TwoStages::new("stage-rate", "learning_rate = 5e-5\n");
    let log = runs.train(&runs.a);
    assert!(
        log.contains("curriculum stage 2: rigid, learning rate 5e-5"),
        "{log}"
    );
    let rates: Vec<f64> = metrics_without_timing(&runs.a)
        .iter()
        .map(|m| m["learning_rate"].as_f64().unwrap())
        .collect();
    assert_eq!(rates, [2e-4, 2e-4, 5e-5, 5e-5]);

    runs.resume_after_stage_1(|checkpoint| {
        let state = std::fs::read_to_string(checkpoint.join("state.toml")).unwrap();
        assert!(state.contains("learning_rate = 0.0002"), "{state}");
    });
}

/// A curriculum stage's task keys: the stage's worlds run them, the
/// checkpoint's config keeps them, and a resume at the stage boundary
/// continues bit for bit.
#[test]
fn a_curriculum_stage_sets_task_keys_and_resumes_exactly() {
    // stage 2 cuts episodes to 1 phase and charges a fall 50
    let runs = TwoStages::new(
        "stage-task",
        "\n[curriculum.task]\nmax_phases = 1\ntermination_reward = -50.0\n",
    );
    let log = runs.train(&runs.a);
    assert!(
        log.contains("curriculum stage 2: rigid, task: max_phases = 1, termination_reward = -50.0"),
        "{log}"
    );
    let lengths: Vec<f64> = metrics_without_timing(&runs.a)
        .iter()
        .map(|m| m["mean_episode_length"].as_f64().unwrap())
        .collect();
    assert!(
        lengths[..2].iter().all(|&l| l > 1.0),
        "stage 1 runs [task]'s 4-phase episodes: {lengths:?}"
    );
    assert_eq!(lengths[2..], [1.0, 1.0], "stage 2's episodes last 1 phase");

    runs.resume_after_stage_1(|checkpoint| {
        let saved = std::fs::read_to_string(checkpoint.join("config.toml")).unwrap();
        assert!(
            saved.contains("[curriculum.task]\nmax_phases = 1\ntermination_reward = -50.0\n"),
            "{saved}"
        );
    });
}

/// A stage that turns on the observation key `key` (`[curriculum.task.observation]`):
/// the log names it, `check_states` reads the checkpoints of iterations 2
/// (before) and 4 (after the widening), a resume at the boundary keeps the
/// key in its config and ends as the uninterrupted run, a fork from a run
/// that never had it ends the same, and the policy acts.
fn a_stage_turns_on(name: &str, key: &str, check_states: impl FnOnce(&str, &str)) {
    let table = format!("[curriculum.task.observation]\n{key} = true\n");
    let runs = TwoStages::new(name, &format!("\n{table}"));
    let log = runs.train(&runs.a);
    assert!(
        log.contains(&format!(
            "curriculum stage 2: rigid, task: observation = {{ {key} = true }}"
        )),
        "{log}"
    );
    let state = |iteration: &str| {
        std::fs::read_to_string(
            runs.a
                .join("checkpoints")
                .join(iteration)
                .join("state.toml"),
        )
        .unwrap()
    };
    check_states(&state("iter-000002"), &state("iter-000004"));
    runs.resume_after_stage_1(|checkpoint| {
        let saved = std::fs::read_to_string(checkpoint.join("config.toml")).unwrap();
        assert!(saved.contains(&table), "{saved}");
    });
    // a fork from the end of stage 1 of a run that never had it
    let plain = TwoStages::new(&format!("{name}-source"), "");
    plain.train(&plain.a);
    let forked = runs.b.with_file_name("forked");
    ok(&runs.args(
        &forked,
        &["--fork", s(&plain.a.join("checkpoints/iter-000002"))],
    ));
    assert_eq!(weights(&runs.a), weights(&forked), "the fork differs");
    rolls_out_two_phases_on_rigid_ground(&runs.a);
}

/// A stage that turns the critic's privileged values on: the critic is
/// widened when the stage starts (the checkpoint says so from then on), a
/// resume at the boundary and a fork from a run without them end as the
/// uninterrupted run, and the policy acts on the plain observation.
#[test]
fn a_stage_gives_the_critic_privileged_values_and_resumes_and_forks_exactly() {
    a_stage_turns_on(
        "stage-privileged",
        "privileged_critic",
        |before, widened| {
            assert!(!before.contains("privileged_size"));
            assert!(
                widened.contains("privileged_size = 12")
                    && widened.contains("normalizer_appended_from = 102")
                    && widened.contains("normalizer_appended_count = 16.0"),
                "{widened}"
            );
        },
    );
}

/// A stage that turns the height scan on: both networks take its 18
/// values from the stage on (the checkpoint says so), a resume at the
/// boundary and a fork from a run without it end as the uninterrupted run,
/// and the policy acts on the scanned observation.
#[test]
fn a_stage_appends_the_height_scan_and_resumes_and_forks_exactly() {
    a_stage_turns_on("stage-height-scan", "height_scan", |before, widened| {
        assert!(before.contains("obs_size = 102"));
        assert!(
            widened.contains("obs_size = 120")
                && widened.contains("normalizer_appended_from = 102"),
            "{widened}"
        );
    });
}

/// `--fork`: a run that goes on from another run's checkpoint, under a
/// config that trains the checkpoint's iterations as that run did, ends as
/// the config's run from scratch does (weights and metrics), and can be
/// resumed; a checkpoint the config does not reproduce is refused with the
/// first difference, and no run directory is left behind.
#[test]
fn a_fork_ends_as_the_run_from_scratch_and_refuses_a_checkpoint_it_does_not_reproduce() {
    // run `a` of `source`: stage 2 at a lower learning rate
    let source = TwoStages::new("fork-source", "learning_rate = 5e-5\n");
    source.train(&source.a);
    // the config forked to: stage 2 with 1-phase episodes instead
    let target = TwoStages::new("fork-target", "\n[curriculum.task]\nmax_phases = 1\n");
    target.train(&target.a);
    // from the end of stage 1, which both configs train alike
    let stage_1_end = source.a.join("checkpoints/iter-000002");
    let forked = &target.b;
    let log = ok(&target.args(forked, &["--fork", s(&stage_1_end)]));
    assert!(
        log.contains("forked from") && log.contains("at iteration 2"),
        "{log}"
    );
    assert_eq!(
        weights(&target.a),
        weights(forked),
        "the fork differs from the run from scratch"
    );
    assert_eq!(
        metrics_without_timing(&target.a),
        metrics_without_timing(forked)
    );
    let fork_toml = std::fs::read_to_string(forked.join("fork.toml")).unwrap();
    assert!(
        fork_toml.contains("iteration = 2") && fork_toml.contains("iter-000002"),
        "{fork_toml}"
    );
    // the fork's own first checkpoint is its starting point, and resumes
    assert!(
        forked
            .join("checkpoints/iter-000002/weights.safetensors")
            .exists()
    );
    for later in ["iter-000003", "iter-000004"] {
        std::fs::remove_dir_all(forked.join("checkpoints").join(later)).unwrap();
    }
    resume_from(&forked.join("checkpoints/iter-000002"));
    assert_eq!(
        weights(&target.a),
        weights(forked),
        "the resumed fork differs"
    );

    // from inside the source's stage 2, whose episodes and learning rate
    // the target's stage 2 does not have (the task is compared first)
    let refused = target.a.with_file_name("refused");
    let inside_stage_2 = source.a.join("checkpoints/iter-000003");
    let err = failure(&target.args(&refused, &["--fork", s(&inside_stage_2)]), 1);
    assert!(
        err.contains("--fork")
            && err.contains("iteration 3's task: max_phases: 1 against max_phases: 4"),
        "{err}"
    );
    // another seed
    let err = failure(
        &target.args(&refused, &["--fork", s(&stage_1_end), "--seed", "7"]),
        1,
    );
    assert!(err.contains("train.seed: 7 against 0"), "{err}");
    assert!(
        !refused.exists(),
        "a refused fork left {}",
        refused.display()
    );
    // --fork and --resume exclude each other
    let err = failure(
        &["train", "--resume", s(forked), "--fork", s(&stage_1_end)],
        2,
    );
    assert!(err.contains("--fork") && err.contains("--resume"), "{err}");
}

/// `[curriculum.advance]`: a stage ends after the first iteration whose
/// window of episodes reaches its survival (here 1-phase episodes that
/// do not fall, over 2 iterations), before its maximum; the next stage
/// starts there; a run resumed inside the undecided stage, or at the
/// boundary, decides it from its metrics as the uninterrupted run did; a
/// fork from the boundary goes on alike; its exported policy acts.
#[test]
fn a_stage_that_moves_on_when_ready_ends_early_and_resumes_and_forks_exactly() {
    let stage_1 = "[[curriculum]]\nterrain = \"rigid\"\niterations = 6\n[curriculum.task]\nmax_phases = 1\n[curriculum.advance]\nsurvival = 1.0\nwindow = 2\n";
    let runs = TwoStages::new("advance", "");
    let text = std::fs::read_to_string(&runs.config)
        .unwrap()
        .replacen(
            "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\n",
            stage_1,
            1,
        )
        .replace("[train]\n", "[train]\nkeep_checkpoints = 20\n");
    std::fs::write(&runs.config, &text).unwrap();
    let log = runs.train(&runs.a);
    let metrics = metrics_without_timing(&runs.a);
    // where the rule says stage 1 ends, from the recorded counts
    let survived = |m: &Value| m["terminated"] == 0 && m["episodes"].as_u64().unwrap() > 0;
    let ready = (2..=6)
        .find(|&n| metrics[n - 2..n].iter().all(survived))
        .expect("1-phase episodes survive within 6 iterations");
    assert!(ready < 6, "the stage ends before its maximum: {metrics:?}");
    assert!(
        log.contains(&format!(
            "curriculum stage 1 ready after {ready} iterations"
        )),
        "{log}"
    );
    assert_eq!(metrics.len(), ready + 2, "stage 2's 2 iterations follow");
    let lengths: Vec<f64> = metrics
        .iter()
        .map(|m| m["mean_episode_length"].as_f64().unwrap())
        .collect();
    assert!(lengths[..ready].iter().all(|&l| l == 1.0), "{lengths:?}");
    assert!(lengths[ready..].iter().all(|&l| l > 1.0), "{lengths:?}");

    // resumed inside stage 1 (undecided) and at its end
    for from in [1, ready] {
        let b = &runs.b;
        let _ = std::fs::remove_dir_all(b);
        runs.train(b);
        let checkpoint = b.join(format!("checkpoints/iter-{from:06}"));
        for later in from + 1..=ready + 2 {
            let _ = std::fs::remove_dir_all(b.join(format!("checkpoints/iter-{later:06}")));
        }
        resume_from(&checkpoint);
        assert_eq!(weights(&runs.a), weights(b), "resumed from {from}");
        assert_eq!(metrics_without_timing(b), metrics, "resumed from {from}");
    }

    // a fork from the boundary, and the policy it ends with
    let forked = runs.a.with_file_name("forked");
    let boundary = runs.a.join(format!("checkpoints/iter-{ready:06}"));
    ok(&runs.args(&forked, &["--fork", s(&boundary)]));
    assert_eq!(weights(&runs.a), weights(&forked));
    let policy = runs.a.with_file_name("policy");
    ok(&["export", "--checkpoint", s(&runs.a), "--out", s(&policy)]);
    // the policy acts, exported, as the run and as one of its checkpoints
    for acting in [&policy, &runs.a, &boundary] {
        let rollout = json_of(&[
            "rollout",
            "--policy",
            s(acting),
            "--terrain",
            "rigid",
            "--phases",
            "2",
            "--json",
        ]);
        assert_eq!(rollout["phases"], 2, "{}", acting.display());
    }
}

/// `[curriculum.levels]`: every metrics line records each world's level,
/// which moves by at most one per iteration and carries into the next
/// stage with levels; a run resumed inside the first stage or at its end,
/// and a fork from its end, go on from the recorded levels as the
/// uninterrupted run did.
#[test]
fn terrain_levels_are_recorded_and_a_resumed_or_forked_run_goes_on_from_them() {
    let dir = scratch_dir("levels");
    let stage = "[[curriculum]]\niterations = 3\n[curriculum.levels]\nterrains = [\"rigid\", \"elastic:1cm\", \"elastic:2cm\"]\npromote_distance_m = 0.001\n";
    let text = TINY
        .replace("max_phases = 4\n", "max_phases = 2\nmax_pitch_deg = 80.0\n")
        .replace(
            "[train]\n",
            &format!("{stage}\n{stage}\n[train]\nkeep_checkpoints = 10\n"),
        );
    let config = dir.join("levels.toml");
    std::fs::write(&config, text).unwrap();
    let train = |run: &Path, extra: &[&str]| {
        let mut args = vec!["train", "--config", s(&config), "--run-dir", s(run)];
        args.extend_from_slice(&["--threads", "2", "--rerun", "off"]);
        args.extend_from_slice(extra);
        ok(&args)
    };
    let a = dir.join("a");
    let log = train(&a, &[]);
    assert!(log.contains("| level "), "{log}");
    let metrics = metrics_without_timing(&a);
    assert_eq!(metrics.len(), 6);
    let mut before = vec![0u64, 0];
    for m in &metrics {
        let levels: Vec<u64> = serde_json::from_value(m["levels"].clone()).unwrap();
        assert_eq!(levels.len(), 2, "{m}");
        for (now, was) in levels.iter().zip(&before) {
            assert!(
                *now <= 2 && now.abs_diff(*was) <= 1,
                "{before:?} then {levels:?}"
            );
        }
        let mean = levels.iter().sum::<u64>() as f64 / 2.0;
        assert_eq!(m["mean_level"].as_f64(), Some(mean), "{m}");
        before = levels;
    }
    assert!(
        metrics[2]["levels"]
            .as_array()
            .unwrap()
            .iter()
            .any(|l| l != 0),
        "a world has moved up by the end of stage 1: {metrics:?}"
    );
    for from in [1, 3] {
        let b = dir.join(format!("b{from}"));
        train(&b, &[]);
        for later in from + 1..=6 {
            std::fs::remove_dir_all(b.join(format!("checkpoints/iter-{later:06}"))).unwrap();
        }
        resume_from(&b.join(format!("checkpoints/iter-{from:06}")));
        assert_eq!(weights(&a), weights(&b), "resumed from {from}");
        assert_eq!(metrics_without_timing(&b), metrics, "resumed from {from}");
    }
    let forked = dir.join("forked");
    train(&forked, &["--fork", s(&a.join("checkpoints/iter-000003"))]);
    assert_eq!(weights(&a), weights(&forked));
    assert_eq!(metrics_without_timing(&forked), metrics);
}

/// `export --with-checkpoint`: the exported policy carries its checkpoint,
/// byte for byte, and a fork from it ends as the fork from the run's own
/// checkpoint, with the run's metrics up to it.
#[test]
fn a_policy_exported_with_its_checkpoint_forks_like_the_run() {
    let source = TwoStages::new("export-fork-source", "learning_rate = 5e-5\n");
    source.train(&source.a);
    let target = TwoStages::new(
        "export-fork-target",
        "\n[curriculum.task]\nmax_phases = 1\n",
    );
    target.train(&target.a);
    let stage_1_end = source.a.join("checkpoints/iter-000002");
    let policy = source.a.with_file_name("exported");
    ok(&[
        "export",
        "--checkpoint",
        s(&stage_1_end),
        "--out",
        s(&policy),
        "--with-checkpoint",
    ]);
    for name in ["weights.safetensors", "state.toml", "config.toml"] {
        assert_eq!(
            std::fs::read(policy.join("checkpoint").join(name)).unwrap(),
            std::fs::read(stage_1_end.join(name)).unwrap(),
            "{name}"
        );
    }
    // the policy's metrics stop at the exported iteration
    let exported_metrics = std::fs::read_to_string(policy.join("metrics.jsonl")).unwrap();
    assert_eq!(exported_metrics.lines().count(), 2);
    let forked = &target.b;
    ok(&target.args(forked, &["--fork", s(&policy.join("checkpoint"))]));
    assert_eq!(weights(&target.a), weights(forked));
    assert_eq!(
        metrics_without_timing(&target.a),
        metrics_without_timing(forked),
        "the fork's metrics begin with the policy's"
    );
    // the policy itself still acts
    rolls_out_two_phases_on_rigid_ground(&policy);
}

/// `[task.observation] privileged_critic`: the critic sees 12 more values,
/// the run resumes bit for bit, the checkpoint says so, and its policy acts
/// on the task's own observation; SAC refuses it.
#[test]
fn a_privileged_critic_trains_resumes_and_its_policy_acts_on_the_plain_observation() {
    let dir = scratch_dir("privileged");
    let config = tiny_variant(
        &dir,
        "[task]\nmax_phases = 4\n",
        "[task]\nmax_phases = 4\n\n[task.observation]\nprivileged_critic = true\n",
    );
    let a = three_iterations_resumed_bit_for_bit(&config, &dir);
    let state = std::fs::read_to_string(a.join("latest/state.toml")).unwrap();
    assert!(
        state.contains("obs_size = 102") && state.contains("privileged_size = 12"),
        "{state}"
    );
    rolls_out_two_phases_on_rigid_ground(&a);
    let sac = dir.join("sac.toml");
    let text = std::fs::read_to_string(&config).unwrap();
    std::fs::write(&sac, format!("{text}{TINY_SAC}")).unwrap();
    let err = training_fails(&sac, &dir.join("c"));
    assert!(
        err.contains("privileged_critic") && err.contains("PPO"),
        "{err}"
    );
}

/// `[ppo] mirror_augmentation`: every sample is also learned as its
/// left-right mirror image; the run resumes bit for bit and learns other
/// weights than without it. With the crawl prior, whose residual action
/// has no mirror, training stops with an error naming both settings.
#[test]
fn mirror_augmentation_trains_resumes_and_is_refused_with_the_crawl_prior() {
    let dir = scratch_dir("mirror");
    let config = tiny_variant(
        &dir,
        "epochs = 2\n",
        "epochs = 2\nmirror_augmentation = true\n",
    );
    let a = three_iterations_resumed_bit_for_bit(&config, &dir);
    let plain = dir.join("plain");
    train_on_two_threads(&tiny_config(&dir), &plain, "3");
    assert_ne!(weights(&a), weights(&plain));
    let saved = std::fs::read_to_string(a.join("config.toml")).unwrap();
    assert!(saved.contains("mirror_augmentation = true"), "{saved}");
    rolls_out_two_phases_on_rigid_ground(&a);

    let crawl = dir.join("crawl.toml");
    let text = std::fs::read_to_string(&config).unwrap();
    std::fs::write(
        &crawl,
        text.replace(
            "max_phases = 4\n",
            "max_phases = 4\naction_prior = \"scripted_crawl\"\n",
        ),
    )
    .unwrap();
    let err = training_fails(&crawl, &dir.join("c"));
    assert!(
        err.contains("ppo.mirror_augmentation") && err.contains("action_prior"),
        "{err}"
    );
}

/// [`TINY`] learned by SAC: learning starts after 8 transitions.
const TINY_SAC: &str = "\n[algo]\nname = \"sac\"\n\n[sac]\nhidden_sizes = [16]\nbatch_size = 8\nlearning_starts = 8\nsteps_per_env = 4\nbuffer_size = 1000\n";

#[test]
fn sac_trains_resumes_bit_for_bit_and_its_policy_runs() {
    let dir = scratch_dir("sac");
    let config = dir.join("sac.toml");
    std::fs::write(&config, format!("{TINY}{TINY_SAC}")).unwrap();
    let (a, b) = (dir.join("a"), dir.join("b"));
    let train = |run: &Path, iterations: &str| train_on_two_threads(&config, run, iterations);
    let progress = train(&a, "3");
    assert!(
        progress.contains("training (sac)") && progress.contains("alpha"),
        "{progress}"
    );
    train(&b, "2");
    resume_on_two_threads(&b, "3");
    assert_eq!(
        weights(&a),
        weights(&b),
        "a resumed SAC run differs from the uninterrupted one"
    );
    assert_eq!(
        std::fs::read(a.join("latest/replay.safetensors")).unwrap(),
        std::fs::read(b.join("latest/replay.safetensors")).unwrap()
    );
    assert_eq!(metrics_without_timing(&a), metrics_without_timing(&b));
    let m = &metrics_without_timing(&a)[2];
    for key in [
        "critic_loss",
        "actor_loss",
        "alpha",
        "updates",
        "reward_terms",
    ] {
        assert!(m.get(key).is_some(), "{key} missing in {m}");
    }
    assert!(m["updates"].as_u64().unwrap() > 0, "{m}");
    let config_text = std::fs::read_to_string(a.join("config.toml")).unwrap();
    assert!(
        config_text.contains("[algo]\nname = \"sac\""),
        "{config_text}"
    );

    // the trained SAC policy rolls out, evaluates and samples like a PPO one
    let r = json_of(&[
        "rollout",
        "--policy",
        s(&a),
        "--terrain",
        "rigid",
        "--phases",
        "2",
        "--seed",
        "3",
        "--json",
    ]);
    assert!(r["phases"].as_u64().unwrap() >= 1, "{r}");
    let e = json_of(&[
        "eval",
        "--policy",
        s(&a),
        "--terrain",
        "rigid",
        "--phases",
        "2",
        "--seed",
        "3",
        "--episodes",
        "1",
        "--json",
        "--out",
        s(&dir.join("eval")),
    ]);
    assert_eq!(e["episodes"][0]["distance_m"], r["distance_m"]);
    let sampled = |seed: &str| {
        json_of(&[
            "rollout",
            "--policy",
            s(&a),
            "--terrain",
            "rigid",
            "--phases",
            "2",
            "--stochastic",
            "--seed",
            seed,
            "--json",
        ])["distance_m"]
            .clone()
    };
    assert_eq!(sampled("4"), sampled("4"));

    // a bad learner name is refused, naming it
    let err = failure(&["train", "--algo", "dqn", "--terrain", "rigid"], 2);
    assert!(err.contains("dqn"), "{err}");
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[terrain]\nspec = \"rigid\"\n[algo]\nname = \"td3\"\n",
    )
    .unwrap();
    let err = failure(&["train", "--config", s(&bad), "--rerun", "off"], 1);
    assert!(err.contains("td3") && err.contains("[algo]"), "{err}");
}

/// `--algo crossq` trains SAC with CrossQ's critics (its checkpoint says
/// so and resumes bit for bit), and `export` writes a small policy that
/// rolls out as its checkpoint does and cannot be resumed.
#[test]
fn crossq_trains_and_exported_policies_act_as_their_checkpoints() {
    let dir = scratch_dir("crossq");
    let config = dir.join("sac.toml");
    std::fs::write(&config, format!("{TINY}{TINY_SAC}")).unwrap();
    let (a, b) = (dir.join("a"), dir.join("b"));
    let train = |run: &Path, iterations: &str| {
        train_on_two_threads_with(&config, run, iterations, &["--algo", "crossq"])
    };
    let progress = train(&a, "3");
    assert!(progress.contains("training (crossq)"), "{progress}");
    train(&b, "2");
    resume_on_two_threads(&b, "3");
    assert_eq!(weights(&a), weights(&b), "a resumed CrossQ run differs");
    let config_text = std::fs::read_to_string(a.join("config.toml")).unwrap();
    assert!(
        config_text.contains("name = \"crossq\"") && config_text.contains("variant = \"crossq\""),
        "{config_text}"
    );
    // the file's [sac] values stay (hidden_sizes = [16]), CrossQ's defaults fill the rest
    assert!(config_text.contains("policy_delay = 3"), "{config_text}");

    for (run, name) in [(&a, "crossq"), (&dir.join("ppo"), "ppo")] {
        if name == "ppo" {
            train_tiny(&tiny_config(&dir), run, "2");
        }
        let out = dir.join(format!("{name}-policy"));
        let said = String::from_utf8(
            quadwalk(&["export", "--checkpoint", s(run), "--out", s(&out)]).stdout,
        )
        .unwrap();
        assert!(said.contains("exported"), "{said}");
        for file in [
            "policy.safetensors",
            "policy.toml",
            "config.toml",
            "metrics.jsonl",
        ] {
            assert!(out.join(file).is_file(), "{name}: {file} missing");
        }
        assert!(!out.join("weights.safetensors").exists());
        let roll = |policy: &Path, stochastic: bool| {
            let mut args = vec![
                "rollout",
                "--policy",
                s(policy),
                "--terrain",
                "rigid",
                "--phases",
                "3",
                "--seed",
                "5",
                "--json",
            ];
            if stochastic {
                args.push("--stochastic");
            }
            let mut v = json_of(&args);
            v.as_object_mut().unwrap().remove("policy");
            v
        };
        assert_eq!(roll(run, false), roll(&out, false), "{name}: mean action");
        assert_eq!(roll(run, true), roll(&out, true), "{name}: sampled");
        let p = json_of(&[
            "play",
            "--checkpoint",
            s(&out),
            "--terrain",
            "rigid",
            "--phases",
            "1",
            "--rerun",
            "off",
            "--json",
        ]);
        assert!(p["phases"].as_u64().unwrap() >= 1, "{p}");
        let err = failure(&["train", "--resume", s(&out), "--rerun", "off"], 1);
        assert!(err.contains("exported policy"), "{err}");
        let err = failure(&["export", "--checkpoint", s(run), "--out", s(&out)], 1);
        assert!(err.contains("already exists"), "{err}");
        // the ONNX graph: `export --onnx` and `quadwalk onnx` of the
        // exported policy write the same model (onnxruntime's actions are
        // tested in python/tests/test_onnx.py)
        let with_onnx = dir.join(format!("{name}-onnx"));
        ok(&[
            "export",
            "--checkpoint",
            s(run),
            "--out",
            s(&with_onnx),
            "--onnx",
        ]);
        let graph = dir.join(format!("{name}.onnx"));
        let said =
            String::from_utf8(quadwalk(&["onnx", "--policy", s(&out), "--out", s(&graph)]).stdout)
                .unwrap();
        assert!(said.contains("input `observation`"), "{said}");
        assert_eq!(
            std::fs::read(&graph).unwrap(),
            std::fs::read(with_onnx.join("policy.onnx")).unwrap(),
            "{name}"
        );
        let err = failure(&["onnx", "--policy", s(&out), "--out", s(&graph)], 1);
        assert!(err.contains("already exists"), "{err}");
    }
    let err = failure(
        &[
            "onnx",
            "--policy",
            "scripted",
            "--out",
            s(&dir.join("crawl.onnx")),
        ],
        1,
    );
    assert!(err.contains("scripted crawl is not a network"), "{err}");
    let err = failure(
        &[
            "export",
            "--checkpoint",
            s(&dir.join("nothing")),
            "--out",
            s(&dir.join("x")),
        ],
        1,
    );
    assert!(err.contains("nothing"), "{err}");
}

#[test]
fn trained_checkpoints_play_and_roll_out() {
    let dir = scratch_dir("play");
    let config = tiny_config(&dir);
    let run = dir.join("run");
    train_tiny(&config, &run, "1");
    let roll_out = || {
        json_of(&[
            "rollout",
            "--policy",
            s(&run),
            "--terrain",
            "elastic:5cm",
            "--phases",
            "3",
            "--json",
        ])
    };
    let r = roll_out();
    assert!(r["phases"].as_u64().unwrap() >= 1, "{r}");
    assert_eq!(r["policy"], s(&run));
    // deterministic mean action: the same rollout twice
    let again = roll_out();
    assert_eq!(r["distance_m"], again["distance_m"]);
    // --stochastic samples the Gaussian: repeatable for a seed
    let sampled = |seed: &str| {
        json_of(&[
            "rollout",
            "--policy",
            s(&run),
            "--terrain",
            "rigid",
            "--phases",
            "3",
            "--stochastic",
            "--seed",
            seed,
            "--json",
        ])["distance_m"]
            .clone()
    };
    assert_eq!(sampled("4"), sampled("4"));
    let err = failure(&["rollout", "--stochastic", "--phases", "1"], 1);
    assert!(err.contains("--stochastic needs a trained policy"), "{err}");
    let p = json_of(&[
        "play",
        "--checkpoint",
        s(&run.join("latest")),
        "--terrain",
        "rigid",
        "--phases",
        "2",
        "--rerun",
        "off",
        "--json",
    ]);
    assert!(p["phases"].as_u64().unwrap() >= 1, "{p}");
}

#[test]
fn a_lower_level_residual_policy_trains_within_its_phase_policys_phases_and_runs() {
    // `[residual]` on the scripted crawl: the policy trained moves the
    // feet's targets 30 times a phase; 60 control steps per world and
    // iteration are two phases.
    let dir = scratch_dir("lower-residual");
    let config = tiny_variant(&dir, "steps_per_env = 4\n", "steps_per_env = 60\n");
    let text =
        std::fs::read_to_string(&config).unwrap() + "\n[residual]\nphase_policy = \"scripted\"\n";
    std::fs::write(
        &config,
        text.replace("spec = \"rigid\"", "spec = \"elastic:2cm\""),
    )
    .unwrap();
    let run = dir.join("run");
    train_tiny(&config, &run, "2");
    let resolved = std::fs::read_to_string(run.join("latest/config.toml")).unwrap();
    assert!(
        resolved.contains("[residual]\nphase_policy = \"scripted\"\ncontrol_steps = 6\n"),
        "{resolved}"
    );
    // the networks take the 71 lower-level values and give 12 offsets
    assert_eq!(first_layer_shape(&run), serde_json::json!([71, 16]));
    let metrics = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    let first: Value = serde_json::from_str(metrics.lines().next().unwrap()).unwrap();
    assert_eq!(first["phases"], 120, "{first}");
    assert!(first["reward_terms"].get("offset").is_some(), "{first}");
    // it rolls out and evaluates, phase by phase, and moves the crawl's feet
    let rollout = |policy: &str| {
        json_of(&[
            "rollout",
            "--policy",
            policy,
            "--terrain",
            "elastic:2cm",
            "--phases",
            "3",
            "--json",
        ])
    };
    let moved = rollout(s(&run));
    let crawl = rollout("scripted");
    assert_eq!(moved["phases"], 3, "{moved}");
    assert_ne!(moved["distance_m"], crawl["distance_m"]);
    let e = json_of(&[
        "eval",
        "--policy",
        s(&run),
        "--terrain",
        "elastic:2cm",
        "--episodes",
        "1",
        "--phases",
        "3",
        "--seed",
        "0",
        "--json",
        "--out",
        s(&dir.join("eval")),
    ]);
    assert_eq!(e["episodes"][0]["distance_m"], moved["distance_m"], "{e}");
    // its own config is its scene; another policy with that [residual]
    // table would leave it unused, and is refused
    let own = run.join("latest/config.toml");
    json_of(&[
        "rollout",
        "--policy",
        s(&run),
        "--config",
        s(&own),
        "--phases",
        "1",
        "--json",
    ]);
    let err = failure(
        &[
            "rollout",
            "--policy",
            "scripted",
            "--config",
            s(&own),
            "--phases",
            "1",
        ],
        1,
    );
    assert!(
        err.contains("[residual]") && err.contains("not that residual policy"),
        "{err}"
    );
    // without a phase level (`none`) the policy moves every foot itself
    let single = dir.join("single.toml");
    let text = std::fs::read_to_string(&config).unwrap().replace(
        "phase_policy = \"scripted\"\n",
        "phase_policy = \"none\"\nmax_offset_m = 0.15\n",
    );
    std::fs::write(&single, text).unwrap();
    let single_run = dir.join("single-run");
    train_tiny(&single, &single_run, "1");
    let r = json_of(&[
        "rollout",
        "--policy",
        s(&single_run),
        "--terrain",
        "rigid",
        "--phases",
        "2",
        "--json",
    ]);
    assert!(r["phases"].as_u64().unwrap() >= 1, "{r}");
    // a control rate that does not divide the phase is refused
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        TINY.to_string() + "\n[residual]\nphase_policy = \"scripted\"\ncontrol_steps = 7\n",
    )
    .unwrap();
    let err = failure(&train_args(&bad, &dir.join("bad-run"), "1"), 1);
    assert!(
        err.contains("[residual]") && err.contains("control_steps = 7"),
        "{err}"
    );
}

#[test]
fn a_residual_policy_on_the_crawl_trains_and_rolls_out() {
    let dir = scratch_dir("residual");
    let config = tiny_variant(
        &dir,
        "[task]\n",
        "[task]\naction_prior = \"scripted_crawl\"\n",
    );
    let run = dir.join("run");
    train_tiny(&config, &run, "1");
    let resolved = std::fs::read_to_string(run.join("latest/config.toml")).unwrap();
    assert!(
        resolved.contains("action_prior = \"scripted_crawl\""),
        "{resolved}"
    );
    // the networks take the paper's 102 values and the crawl's 27
    assert_eq!(first_layer_shape(&run), serde_json::json!([129, 16]));
    let r = json_of(&[
        "rollout",
        "--policy",
        s(&run),
        "--terrain",
        "rigid",
        "--phases",
        "4",
        "--json",
    ]);
    assert_eq!(r["phases"], 4, "{r}");
    // the crawl itself cannot run on top of the crawl
    let err = failure(
        &[
            "rollout",
            "--policy",
            "scripted",
            "--config",
            s(&config),
            "--phases",
            "1",
        ],
        1,
    );
    assert!(
        err.contains("--policy scripted runs the crawl itself") && err.contains("action_prior"),
        "{err}"
    );
}

#[test]
fn damaged_and_mismatched_checkpoints_give_clear_errors() {
    let dir = scratch_dir("damaged");
    let config = tiny_config(&dir);
    let run = dir.join("run");
    train_tiny(&config, &run, "1");
    let checkpoint = run.join("checkpoints/iter-000001");

    let copy = |name: &str| {
        let to = dir.join(name);
        std::fs::create_dir_all(&to).unwrap();
        for file in ["weights.safetensors", "state.toml", "config.toml"] {
            std::fs::copy(checkpoint.join(file), to.join(file)).unwrap();
        }
        to
    };
    // truncated weights
    let truncated = copy("truncated");
    let bytes = std::fs::read(truncated.join("weights.safetensors")).unwrap();
    std::fs::write(
        truncated.join("weights.safetensors"),
        &bytes[..bytes.len() / 2],
    )
    .unwrap();
    let err = failure(&["rollout", "--policy", s(&truncated), "--phases", "1"], 1);
    assert!(
        err.contains("weights.safetensors") && err.contains("damaged or truncated"),
        "{err}"
    );
    // one flipped byte
    let corrupt = copy("corrupt");
    let mut bytes = std::fs::read(corrupt.join("weights.safetensors")).unwrap();
    let k = bytes.len() - 100;
    bytes[k] ^= 0x10;
    std::fs::write(corrupt.join("weights.safetensors"), &bytes).unwrap();
    let err = failure(
        &[
            "play",
            "--checkpoint",
            s(&corrupt),
            "--phases",
            "1",
            "--rerun",
            "off",
        ],
        1,
    );
    assert!(err.contains("checksum"), "{err}");
    // garbage state file
    let garbage = copy("garbage");
    std::fs::write(garbage.join("state.toml"), "iteration = [").unwrap();
    let err = failure(&["train", "--resume", s(&garbage), "--rerun", "off"], 1);
    assert!(
        err.contains("state.toml") && err.contains("not a valid state file"),
        "{err}"
    );
    // a config whose observation does not fit the networks
    let mismatched = copy("mismatched");
    let text = std::fs::read_to_string(mismatched.join("config.toml")).unwrap();
    std::fs::write(
        mismatched.join("config.toml"),
        text.replace("foot_history = true", "foot_history = false"),
    )
    .unwrap();
    let err = failure(&["rollout", "--policy", s(&mismatched), "--phases", "1"], 1);
    assert!(
        err.contains("102 observations") && err.contains("66"),
        "{err}"
    );
    // not a checkpoint at all
    let err = failure(&["rollout", "--policy", s(&dir), "--phases", "1"], 1);
    assert!(err.contains("not a checkpoint"), "{err}");
    // a sound checkpoint outside a run directory: resuming would not know where to write
    let loose = copy("loose");
    let err = failure(&["train", "--resume", s(&loose), "--rerun", "off"], 1);
    assert!(err.contains("not inside a run directory"), "{err}");
    let err = failure(
        &["train", "--resume", "/nonexistent/run", "--rerun", "off"],
        1,
    );
    assert!(
        err.contains("/nonexistent/run") && err.contains("no such"),
        "{err}"
    );
}

/// `train --terrain TERRAIN --iterations 1` on 2 worlds with no config, and
/// `train --terrain TERRAIN --iterations too_many`: the first run's stderr
/// and `config.toml`, and the refusal's stderr.
fn train_built_in_recipe(terrain: &str, name: &str, too_many: &str) -> (String, String, String) {
    let dir = scratch_dir(name);
    let run = dir.join("run");
    let stderr = ok(&[
        "train",
        "--terrain",
        terrain,
        "--envs",
        "2",
        "--iterations",
        "1",
        "--threads",
        "1",
        "--run-dir",
        s(&run),
        "--rerun",
        "off",
    ]);
    let config = std::fs::read_to_string(run.join("config.toml")).unwrap();
    let refusal = failure(
        &[
            "train",
            "--terrain",
            terrain,
            "--iterations",
            too_many,
            "--run-dir",
            s(&dir.join("long")),
            "--rerun",
            "off",
        ],
        1,
    );
    (stderr, config, refusal)
}

/// `train --terrain elastic:5cm` runs the built-in 5 cm recipe, and
/// `--iterations` keeps its first stages.
#[test]
fn the_5cm_terrain_trains_the_built_in_recipe_cut_by_iterations() {
    let (stderr, config, err) = train_built_in_recipe("elastic:5cm", "recipe", "100000");
    assert!(
        stderr.contains("elastic:5cm: quadwalk's recipe (configs/elastic-5cm-margin.toml)")
            && stderr.contains("training (ppo) on terrain levels rigid, elastic:5mm"),
        "{stderr}"
    );
    assert!(
        config.contains("goal_line_ahead_m = 1.0") && config.contains("mirror_augmentation = true"),
        "{config}"
    );
    assert!(
        config.contains("[[curriculum]]\niterations = 1\n\n[curriculum.levels]\n")
            && !config.contains("terrain = \"elastic:5cm\"\niterations"),
        "one iteration of the first stage: {config}"
    );
    // more iterations than the recipe has: refused, naming its total
    assert!(
        err.contains("--iterations 100000: the curriculum has 420 iterations"),
        "{err}"
    );
}

/// `train --terrain` with T_v2, spelled as the paper's table spells it,
/// runs the built-in T_v2 recipe: the stages of the 5 cm recipe before
/// the current one, then the passages between rigid ground and deep tiles.
#[test]
fn the_tv2_terrain_trains_the_built_in_tv2_recipe() {
    let (stderr, config, err) =
        train_built_in_recipe("varying:2m:2,3,4,5cm,rigid", "recipe-tv2", "501");
    assert!(
        stderr.contains(
            "varying:2m:2cm,3cm,4cm,5cm,rigid: quadwalk's recipe (configs/tv2-levels.toml): levels rigid..elastic:5cm x280 -> elastic:5cm x180 -> varying:2m:4cm,5cm,rigid x40 (500 iterations)"
        ) && stderr.contains("training (ppo) on terrain levels rigid, elastic:5mm"),
        "{stderr}"
    );
    assert!(
        config.contains("spec = \"varying:2m:2cm,3cm,4cm,5cm,rigid\"")
            && config.contains("mirror_augmentation = true"),
        "{config}"
    );
    // one past the recipe's last iteration: refused, naming its total
    assert!(
        err.contains("--iterations 501: the curriculum has 500 iterations"),
        "{err}"
    );
}

/// The README's first command trains exactly as the run that gave
/// `policies/elastic-5cm-margin` did: its first iterations write the shipped
/// `metrics.jsonl` lines, every value but the timings, to the last digit.
/// A change that moves training (physics, task, learner, seeding) fails
/// here.
#[test]
fn the_readme_command_trains_its_first_iterations_as_the_shipped_run_did() {
    let dir = scratch_dir("readme-determinism");
    let run = dir.join("run");
    ok(&[
        "train",
        "--terrain",
        "elastic:5cm",
        "--iterations",
        "2",
        "--threads",
        "2",
        "--run-dir",
        s(&run),
        "--rerun",
        "off",
    ]);
    let without_times = |line: &str| {
        let mut v: Value = serde_json::from_str(line).unwrap();
        let o = v.as_object_mut().unwrap();
        o.remove("secs");
        o.remove("phases_per_s");
        v
    };
    let ours = std::fs::read_to_string(run.join("metrics.jsonl")).unwrap();
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies/elastic-5cm-margin/metrics.jsonl"),
    )
    .unwrap();
    let ours: Vec<_> = ours.lines().map(without_times).collect();
    let shipped: Vec<_> = shipped.lines().take(2).map(without_times).collect();
    assert_eq!(ours.len(), 2);
    for (k, (a, b)) in ours.iter().zip(&shipped).enumerate() {
        // `falls_by_cause` holds shares: times the episodes, they are the
        // episodes that ended in a fall
        let causes = &a["falls_by_cause"];
        let shares: f64 = causes
            .as_object()
            .unwrap()
            .values()
            .map(|s| s.as_f64().unwrap())
            .sum();
        let (episodes, falls) = (
            a["episodes"].as_f64().unwrap(),
            a["terminated"].as_f64().unwrap(),
        );
        assert!(falls > 0.0, "{a}");
        assert!(
            (shares * episodes - falls).abs() < 1e-6,
            "{causes} x {episodes} episodes against {falls} falls"
        );
        assert_eq!(a, b, "iteration {}", k + 1);
    }
}

#[test]
fn bad_training_flags_are_refused() {
    let err = failure(&["train", "--envs", "0", "--rerun", "off"], 2);
    assert!(err.contains("--envs"), "{err}");
    let err = failure(
        &[
            "train",
            "--terrain",
            "rigid",
            "--envs",
            "2",
            "--rerun-envs",
            "5",
            "--rerun",
            "off",
        ],
        1,
    );
    assert!(err.contains("rerun_envs holds 5"), "{err}");
    let err = failure(&["train", "--resume", "x", "--envs", "2"], 2);
    assert!(err.contains("--envs") && err.contains("--resume"), "{err}");
    let err = failure(&["train", "--terrain", "elastic:5"], 1);
    assert!(err.contains("elastic:5"), "{err}");
}

/// Starts a training run in the background with long iterations.
fn start_long_run(run: &Path, config: &Path, envs: &[(&str, &str)]) -> Child {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_quadwalk"));
    cmd.args(train_args(config, run, "1000"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    for (k, v) in envs {
        cmd.env(k, v);
    }
    cmd.spawn().unwrap()
}

fn wait_for(what: &str, timeout: Duration, mut ready: impl FnMut() -> bool) {
    let start = Instant::now();
    while !ready() {
        assert!(start.elapsed() < timeout, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Sends a signal with the system's `kill` (std can only send SIGKILL).
fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

fn metrics_lines(run: &Path) -> usize {
    std::fs::read_to_string(run.join("metrics.jsonl")).map_or(0, |t| t.lines().count())
}

#[test]
fn ctrl_c_leaves_a_complete_checkpoint() {
    let dir = scratch_dir("ctrl-c");
    // checkpoints only every 1000 iterations: what is on disk after Ctrl-C
    // was written by the Ctrl-C
    let config = tiny_variant(&dir, "checkpoint_every = 1", "checkpoint_every = 1000");
    let run = dir.join("run");
    let child = start_long_run(&run, &config, &[]);
    wait_for("two iterations", Duration::from_secs(120), || {
        metrics_lines(&run) >= 2
    });
    signal(&child, "INT");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("Ctrl-C") && !stderr.contains("panicked"),
        "{stderr}"
    );
    let done = metrics_lines(&run) as u64;
    let state = std::fs::read_to_string(run.join("latest/state.toml")).unwrap();
    assert!(
        state.contains(&format!("iteration = {done}\n")),
        "checkpoint is not at iteration {done}: {state}"
    );
    // it loads and the run goes on from it
    ok(&[
        "train",
        "--resume",
        s(&run),
        "--iterations",
        &(done + 1).to_string(),
        "--rerun",
        "off",
    ]);
    assert_eq!(metrics_lines(&run) as u64, done + 1);
}

#[test]
fn a_kill_during_a_save_leaves_the_previous_checkpoint_intact() {
    let dir = scratch_dir("kill");
    let config = tiny_config(&dir);
    let run = dir.join("run");
    // every save pauses 2 s after its first file: kill inside the second save
    let mut child = start_long_run(&run, &config, &[("QUADWALK_TEST_SAVE_PAUSE_MS", "2000")]);
    let partial_of_second = || {
        std::fs::read_dir(run.join("checkpoints")).is_ok_and(|entries| {
            entries.flatten().any(|e| {
                e.file_name()
                    .to_string_lossy()
                    .starts_with(".iter-000002.partial-")
            })
        })
    };
    wait_for(
        "the second save",
        Duration::from_secs(120),
        partial_of_second,
    );
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    assert!(
        partial_of_second(),
        "the kill should have left the half-written save"
    );
    assert!(!run.join("checkpoints/iter-000002").exists());
    assert_eq!(
        std::fs::read_link(run.join("latest")).unwrap(),
        Path::new("checkpoints/iter-000001")
    );
    let r = json_of(&["rollout", "--policy", s(&run), "--phases", "1", "--json"]);
    assert_eq!(r["phases"], 1);
    // resuming starts from iteration 1 and clears the stray directory
    ok(&[
        "train",
        "--resume",
        s(&run),
        "--iterations",
        "2",
        "--rerun",
        "off",
    ]);
    assert!(!partial_of_second());
    assert_eq!(
        std::fs::read_link(run.join("latest")).unwrap(),
        Path::new("checkpoints/iter-000002")
    );
}

/// Every policy shipped in `policies/` loads on a fresh clone (no run
/// directory, no optimiser state) and walks a few phases of its own
/// terrain without error, as `play --checkpoint policies/NAME` would. A
/// policy whose training episodes all ended in a fall in its last
/// iteration (`policies/single-level`, which learned to end them at once)
/// runs until the task's termination instead.
#[test]
fn the_shipped_policies_load_and_run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies");
    let Ok(entries) = std::fs::read_dir(&root) else {
        println!("no policies/ directory: nothing shipped to check");
        return;
    };
    let mut checked = 0;
    for entry in entries {
        let dir = entry.unwrap().path();
        if !dir.join("policy.toml").is_file() {
            continue;
        }
        for file in ["README.md", "metrics.jsonl", "policy.safetensors"] {
            assert!(
                dir.join(file).is_file(),
                "{}: {file} missing",
                dir.display()
            );
        }
        let config = std::fs::read_to_string(dir.join("config.toml")).unwrap();
        let table: toml::Table = config.parse().unwrap();
        let terrain = table["terrain"]["spec"].as_str().unwrap().to_string();
        let r = json_of(&[
            "rollout",
            "--policy",
            s(&dir),
            "--terrain",
            &terrain,
            "--phases",
            "2",
            "--seed",
            "7",
            "--json",
        ]);
        let metrics = std::fs::read_to_string(dir.join("metrics.jsonl")).unwrap();
        let last: serde_json::Value =
            serde_json::from_str(metrics.lines().last().unwrap()).unwrap();
        if last["terminated"] == last["episodes"] {
            assert!(
                r["terminated"].is_string() && r["phases"].as_u64() >= Some(1),
                "{}: {r}",
                dir.display()
            );
        } else {
            assert_eq!(r["phases"].as_u64(), Some(2), "{}: {r}", dir.display());
        }
        checked += 1;
    }
    println!("{checked} shipped policies checked");
}

#[test]
fn the_terrains_beyond_the_paper_train_roll_out_and_evaluate() {
    let dir = scratch_dir("new-terrains");
    for (k, (spec, region)) in [
        (
            "varying:2m:(soil:3cm),(rigid:friction=0.3),2..5cm",
            "soil:3cm",
        ),
        ("rough:1cm:length=4m", "rough:1cm:length=4m"),
        ("slope:5:length=4m", "slope:5:length=4m"),
    ]
    .into_iter()
    .enumerate()
    {
        let config = tiny_variant(&dir, "spec = \"rigid\"", &format!("spec = \"{spec}\""));
        let run = dir.join(format!("run-{k}"));
        train_on_two_threads(&config, &run, "2");
        let saved = std::fs::read_to_string(run.join("config.toml")).unwrap();
        assert!(saved.contains(region), "{saved}");
        let rollout = json_of(&[
            "rollout",
            "--policy",
            s(&run),
            "--terrain",
            spec,
            "--phases",
            "2",
            "--json",
        ]);
        assert_eq!(rollout["phases"], 2, "{spec}: {rollout}");
        assert_eq!(rollout["regions"][0], region, "{spec}: {rollout}");
        let out = dir.join(format!("eval-{k}"));
        ok(&[
            "eval",
            "--policy",
            s(&run),
            "--terrain",
            spec,
            "--episodes",
            "2",
            "--phases",
            "2",
            "--out",
            s(&out),
        ]);
        assert!(out.join("eval.json").is_file());
    }
}

//! `quadwalk eval`: its episodes are rollouts, its files are there and
//! readable, `--compare` reads them back, bad input is refused.

use std::path::Path;

use serde_json::Value;

use super::train::{s, scratch_dir, tiny_config, train_tiny};
use super::{failure, json_of, scratch_file};

/// `eval ARGS --json --out OUT`, which must succeed.
fn eval_json(args: &[&str], out: &Path) -> Value {
    let mut all = vec!["eval"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--json", "--out", s(out)]);
    json_of(&all)
}

/// Asserts that every episode of `eval` equals `rollout` with its seed:
/// distance, phases and termination. `scene` selects the terrain or config.
fn assert_episodes_are_rollouts(eval: &Value, policy: &str, scene: &[&str], phases: &str) {
    let episodes = eval["episodes"].as_array().unwrap();
    assert!(!episodes.is_empty());
    for e in episodes {
        let seed = e["seed"].as_u64().unwrap().to_string();
        let mut args = vec!["rollout", "--policy", policy];
        args.extend_from_slice(scene);
        args.extend_from_slice(&["--seed", &seed, "--phases", phases, "--json"]);
        let r = json_of(&args);
        assert_eq!(e["distance_m"], r["distance_m"], "seed {seed}");
        assert_eq!(e["phases"], r["phases"], "seed {seed}");
        assert_eq!(e["goals_reached"], r["goals_reached"], "seed {seed}");
        match &e["fall"] {
            Value::Null => assert_eq!(r["terminated"], false, "seed {seed}"),
            fall => assert_eq!(fall["cause"], r["terminated"], "seed {seed}"),
        }
    }
}

#[test]
fn eval_measures_the_response_to_a_terrain_that_changes_under_the_robot() {
    // The crawl on tiles that soften from 2 to 5 cm 4 s after each reset
    // (a third into the 5th phase), and that stiffen the other way: the
    // base settles lower, then higher (by ~1.5 cm: the crawl holds its hip
    // height above the sunk tiles, so it makes up half of the 3 cm).
    for (spec, lower) in [("switch:2cm:5cm:4", true), ("switch:5cm:2cm:4", false)] {
        let out = scratch_dir("eval-switch");
        let args = [
            "--policy",
            "scripted",
            "--terrain",
            spec,
            "--episodes",
            "2",
            "--phases",
            "18",
            "--threads",
            "2",
        ];
        let e = eval_json(&args, &out);
        let r = &e["summary"]["change_response"];
        assert_eq!(r["at_secs"], 4.0, "{r}");
        assert_eq!(r["episodes"], 2, "{r}");
        let change_m = r["level_change_m"]["mean"].as_f64().unwrap();
        let sign = if lower { -1.0 } else { 1.0 };
        assert!((0.008..0.04).contains(&(sign * change_m)), "{spec}: {r}");
        for episode in e["episodes"].as_array().unwrap() {
            let own = &episode["change_response"];
            assert!(own["recovery_secs"].as_f64().unwrap() >= 0.0, "{own}");
            assert!(own["excess_dip_m"].is_f64(), "{own}");
        }
    }
    // a terrain that does not change has no response in its report
    let out = scratch_dir("eval-no-switch");
    let e = eval_json(
        &[
            "--terrain",
            "elastic:2cm",
            "--episodes",
            "1",
            "--phases",
            "2",
        ],
        &out,
    );
    assert!(e["summary"].get("change_response").is_none(), "{e}");
}

#[test]
fn eval_episodes_are_the_rollouts_of_their_seeds_and_its_files_are_written() {
    let out = scratch_dir("eval-crawl");
    let scene = ["--terrain", "varying:1m:2,5cm,rigid"];
    let mut args = vec!["--policy", "scripted"];
    args.extend_from_slice(&scene);
    args.extend_from_slice(&["--episodes", "3", "--phases", "16", "--seed", "40"]);
    args.extend_from_slice(&["--threads", "2"]);
    let e = eval_json(&args, &out);
    assert_eq!(e["summary"]["episodes"], 3);
    let seeds: Vec<u64> = e["episodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["seed"].as_u64().unwrap())
        .collect();
    assert_eq!(seeds, [40, 41, 42], "episodes come back in seed order");
    assert_episodes_are_rollouts(&e, "scripted", &scene, "16");
    // the pooled column leads the terrain types and adds them up
    let types = e["summary"]["terrain_types"].as_array().unwrap();
    assert_eq!(types[0]["terrain"], "all");
    let phases: u64 = types[1..]
        .iter()
        .map(|t| t["phases"].as_u64().unwrap())
        .sum();
    assert_eq!(types[0]["phases"].as_u64().unwrap(), phases);
    assert_eq!(phases, 3 * 16);
    // one thread gives the same episodes
    let out1 = scratch_dir("eval-crawl-1");
    let mut args1 = args.clone();
    args1.truncate(args.len() - 2);
    args1.extend_from_slice(&["--threads", "1"]);
    let e1 = eval_json(&args1, &out1);
    assert_eq!(e["episodes"], e1["episodes"]);

    // the files: eval.json with every phase, Table I, three PNGs of the stated size
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("eval.json")).unwrap()).unwrap();
    assert_eq!(report["format"], "quadwalk-eval/1");
    assert_eq!(
        report["episodes"][0]["phase_log"].as_array().unwrap().len(),
        16
    );
    let table = std::fs::read_to_string(out.join("table1.md")).unwrap();
    for row in ["| sigma(h_b) |", "| mu(h_b) |", "| mu(fr) |", "| mu(rl) |"] {
        assert!(table.contains(row), "{row} missing in {table}");
    }
    for name in [
        "distance.png",
        "base_height_phase.png",
        "landing_height.png",
    ] {
        let file = std::fs::File::open(out.join(name)).unwrap();
        let reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .unwrap_or_else(|e| panic!("{name} does not decode: {e}"));
        let info = reader.info();
        assert_eq!((info.width, info.height), (1024, 640), "{name}");
    }

    // --compare lays both side by side
    let c = super::quadwalk(&["eval", "--compare", s(&out), s(&out1)]);
    let text = String::from_utf8_lossy(&c.stdout);
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    assert!(text.contains("| eval-crawl | scripted |"), "{text}");
    assert!(text.contains("| eval-crawl-1 | scripted |"), "{text}");
    assert!(text.contains("| (cm) | eval-crawl: "), "{text}");
    assert!(text.contains("| eval-crawl-1: "), "{text}");
}

#[test]
fn seed_sets_run_as_one_evaluation_with_each_sets_success() {
    let out = scratch_dir("eval-sets");
    // the crawl on rigid ground, two episodes of 4 phases per set
    let scene = [
        "--policy",
        "scripted",
        "--terrain",
        "rigid",
        "--episodes",
        "2",
        "--phases",
        "4",
    ];
    let two_sets = ["--seed", "40", "--seed", "100"];
    let args = [&scene[..], &two_sets, &["--threads", "2"]].concat();
    let e = eval_json(&args, &out);
    let episodes = e["episodes"].as_array().unwrap();
    let seeds: Vec<u64> = episodes
        .iter()
        .map(|e| e["seed"].as_u64().unwrap())
        .collect();
    assert_eq!(
        seeds,
        [40, 41, 100, 101],
        "set after set, each in seed order"
    );
    assert_episodes_are_rollouts(&e, "scripted", &["--terrain", "rigid"], "4");
    // each set's share adds up to the pooled summary
    let sets = e["seed_sets"].as_array().unwrap();
    assert_eq!(sets.len(), 2);
    for (set, own) in sets.iter().zip(episodes.chunks(2)) {
        assert_eq!(set["first_seed"], own[0]["seed"]);
        assert_eq!(set["episodes"], 2);
        let successes = own.iter().filter(|e| e["fall"].is_null()).count();
        assert_eq!(set["successes"].as_u64().unwrap(), successes as u64);
        let mean = own
            .iter()
            .map(|e| e["distance_m"].as_f64().unwrap())
            .sum::<f64>()
            / 2.0;
        assert!((set["mean_distance_m"].as_f64().unwrap() - mean).abs() < 1e-12);
    }
    let pooled: u64 = sets.iter().map(|s| s["successes"].as_u64().unwrap()).sum();
    assert_eq!(e["summary"]["successes"].as_u64().unwrap(), pooled);
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("eval.json")).unwrap()).unwrap();
    assert_eq!(report["seed_sets"], e["seed_sets"]);
    let table = std::fs::read_to_string(out.join("table1.md")).unwrap();
    assert!(
        table.contains("(4 episodes, seed sets 40.., 100..)"),
        "{table}"
    );

    // the text names the sets and prints a line for each
    let text_out = scratch_dir("eval-sets-text");
    let run =
        super::quadwalk(&[&["eval"][..], &scene, &two_sets, &["--out", s(&text_out)]].concat());
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        text.contains("4 episodes x 4 phases, seed sets 40..41, 100..101"),
        "{text}"
    );
    for set in ["40..41", "100..101"] {
        assert!(text.contains(&format!("  seed set      {set}: ")), "{text}");
    }

    // one set writes no breakdown, as before
    let one = eval_json(
        &[&scene[..], &["--seed", "40"]].concat(),
        &scratch_dir("eval-sets-one"),
    );
    assert!(one.get("seed_sets").is_none(), "{one}");
    assert_eq!(
        one["episodes"].as_array().unwrap()[..],
        e["episodes"].as_array().unwrap()[..2]
    );

    // sets that would run a seed twice are refused before anything runs
    let dir = scratch_dir("eval-sets-overlap");
    let err = failure(
        &[
            "eval",
            "--policy",
            "scripted",
            "--terrain",
            "rigid",
            "--episodes",
            "10",
            "--seed",
            "40",
            "--seed",
            "45",
            "--out",
            s(&dir),
        ],
        1,
    );
    assert!(
        err.contains("--seed 40 and --seed 45 would both run seed 45")
            && err.contains("10 consecutive seeds"),
        "{err}"
    );
    assert!(!dir.join("eval.json").exists());
}

#[test]
fn a_fall_is_counted_by_cause_like_the_rollout_ends() {
    // a minimum base height above the squat's: every episode falls at once
    let config = scratch_file(
        "eval-fall.toml",
        "[terrain]\nspec = \"rigid\"\n\n[task]\nmin_base_height_m = 0.40\n",
    );
    let out = scratch_dir("eval-fall");
    let scene = ["--config", s(&config)];
    let mut args = vec!["--episodes", "2", "--phases", "5"];
    args.extend_from_slice(&scene);
    let e = eval_json(&args, &out);
    assert_episodes_are_rollouts(&e, "scripted", &scene, "5");
    let summary = &e["summary"];
    assert_eq!(summary["successes"], 0);
    assert_eq!(summary["falls_by_cause"]["base_too_low"], 2);
    assert_eq!(e["episodes"][0]["fall"]["phase"], 0);
    assert_eq!(e["episodes"][0]["fall"]["terrain"], "rigid");
    // the first goal is 2 m ahead of the start: still so at a fall in phase 0
    let ahead_m = e["episodes"][0]["fall"]["goal_ahead_m"].as_f64().unwrap();
    assert!((ahead_m - 2.0).abs() < 0.1, "{ahead_m}");
    assert_eq!(
        summary["falls_after_a_goal_by_goal_ahead"],
        serde_json::json!([0, 0, 0, 0]),
        "no goal was reached"
    );
    // the same limit as a --task setting over the terrain's task: the same
    // falls, in eval and rollout, and the report names the setting
    let out = scratch_dir("eval-fall-task");
    let scene = ["--terrain", "rigid", "--task", "min_base_height_m=0.40"];
    let mut args = vec!["--episodes", "2", "--phases", "5"];
    args.extend_from_slice(&scene);
    let t = eval_json(&args, &out);
    assert_episodes_are_rollouts(&t, "scripted", &scene, "5");
    assert_eq!(t["summary"]["falls_by_cause"]["base_too_low"], 2);
    assert_eq!(t["episodes"], e["episodes"]);
    assert_eq!(
        t["task_overrides"],
        serde_json::json!(["min_base_height_m=0.40"])
    );
    assert!(
        e.get("task_overrides").is_none(),
        "none given: none written"
    );
}

/// The crawl on a 3 m field (tiles end at x = 1.5 m) walks off its end: a
/// fall, marked as at the end of the terrain by eval and rollout alike; a
/// fall far from the end (above) is not.
#[test]
fn walking_off_a_short_field_is_marked_as_the_end_of_the_terrain() {
    let out = scratch_dir("eval-field-end");
    let scene = ["--terrain", "varying:2m:rigid:length=3m:back=1.5m"];
    let mut args = vec!["--episodes", "1", "--phases", "300", "--seed", "3"];
    args.extend_from_slice(&scene);
    let e = eval_json(&args, &out);
    assert_episodes_are_rollouts(&e, "scripted", &scene, "300");
    let fall = &e["episodes"][0]["fall"];
    assert_eq!(fall["at_terrain_end"], true, "{fall}");
    assert_eq!(e["summary"]["falls_at_terrain_end"], 1);
    let r = json_of(&[
        "rollout", "--policy", "scripted", scene[0], scene[1], "--phases", "300", "--seed", "3",
        "--json",
    ]);
    assert_eq!(r["at_terrain_end"], true, "{r}");
    assert!(r["distance_m"].as_f64().unwrap() > 0.5, "{r}");

    let near = scratch_dir("eval-fall-not-at-end");
    let config = scratch_file(
        "eval-fall-near.toml",
        "[terrain]\nspec = \"elastic:2cm\"\n\n[task]\nmin_base_height_m = 0.40\n",
    );
    let e = eval_json(
        &["--episodes", "1", "--phases", "5", "--config", s(&config)],
        &near,
    );
    assert_eq!(e["episodes"][0]["fall"]["at_terrain_end"], false);
    assert_eq!(e["summary"]["falls_at_terrain_end"], 0);
}

#[test]
fn a_trained_policy_evaluates_like_it_rolls_out_and_misfits_are_refused() {
    let dir = scratch_dir("eval-trained");
    let config = tiny_config(&dir);
    let run = dir.join("run");
    train_tiny(&config, &run, "1");
    let scene = ["--terrain", "elastic:5cm"];
    let mut args = vec!["--policy", s(&run)];
    args.extend_from_slice(&scene);
    args.extend_from_slice(&["--episodes", "2", "--phases", "3", "--seed", "11"]);
    let e = eval_json(&args, &dir.join("out"));
    assert_episodes_are_rollouts(&e, s(&run), &scene, "3");

    // a config whose observation differs from the checkpoint's
    let misfit = dir.join("misfit.toml");
    std::fs::write(
        &misfit,
        "[terrain]\nspec = \"rigid\"\n\n[task.observation]\nfoot_history = false\n",
    )
    .unwrap();
    let err = failure(&["eval", "--policy", s(&run), "--config", s(&misfit)], 1);
    assert!(
        err.contains("misfit.toml") && err.contains("observes 102 values"),
        "{err}"
    );
}

/// The tiny config with its physics at 120 Hz, written to
/// `dir/tiny-120.toml`.
fn tiny_at_120_hz(dir: &Path) -> std::path::PathBuf {
    let config = dir.join("tiny-120.toml");
    std::fs::write(
        &config,
        super::train::TINY.replace("[ppo]", "[physics]\nstep_rate_hz = 120\n\n[ppo]"),
    )
    .unwrap();
    config
}

/// A policy trained at 120 Hz carries its rate into its checkpoint and
/// evaluates at it; `--step-rate-hz 240` judges it at the paper's rate
/// (eval.json says which); a rate a world cannot step at is refused.
#[test]
fn a_policy_trained_at_120_hz_evaluates_at_its_rate_or_the_one_asked() {
    let dir = scratch_dir("eval-step-rate");
    let config = tiny_at_120_hz(&dir);
    let run = dir.join("run");
    let log = super::train::ok(&[
        "train",
        "--config",
        s(&config),
        "--run-dir",
        s(&run),
        "--iterations",
        "1",
        "--rerun",
        "off",
    ]);
    assert!(
        log.contains("training (ppo) on rigid, physics at 120 Hz with 2 environments"),
        "{log}"
    );
    let saved = std::fs::read_to_string(run.join("config.toml")).unwrap();
    assert!(saved.contains("step_rate_hz = 120"), "{saved}");
    let args = [
        "--policy",
        s(&run),
        "--terrain",
        "rigid",
        "--episodes",
        "1",
        "--phases",
        "2",
    ];
    let own = eval_json(&args, &dir.join("own"));
    assert_eq!(own["step_rate_hz"], 120);
    let mut paper_args = args.to_vec();
    paper_args.extend_from_slice(&["--step-rate-hz", "240"]);
    let paper = eval_json(&paper_args, &dir.join("paper"));
    assert!(paper.get("step_rate_hz").is_none(), "240 Hz is not written");
    assert_eq!(paper["episodes"][0]["phases"], 2);
    for (rate, expected) in [
        (
            "130",
            "--step-rate-hz 130: step_rate_hz must be a multiple of 4 in 60..=960 Hz",
        ),
        (
            "0",
            "--step-rate-hz 0: step_rate_hz must be a multiple of 4",
        ),
    ] {
        let mut bad = args.to_vec();
        bad.extend_from_slice(&["--step-rate-hz", rate]);
        let mut all = vec!["eval"];
        all.extend_from_slice(&bad);
        let err = failure(&all, 1);
        assert!(err.contains(expected), "{err}");
    }
    let err = failure(&["eval", "--terrain", "rigid", "--step-rate-hz", "x"], 2);
    assert!(err.contains("--step-rate-hz"), "{err}");
}

/// A curriculum whose second stage steps the worlds at 120 Hz
/// (`[curriculum.physics]`): the stage's start says so, a checkpoint of
/// stage 1 evaluates at 240 Hz and one of stage 2 at 120 Hz (a policy runs
/// at the physics of its last iteration), and a fork from a run whose
/// first iteration stepped at another rate is refused, naming it.
#[test]
fn a_stage_that_sets_its_physics_trains_and_hands_its_rate_to_the_policy() {
    let dir = scratch_dir("stage-physics");
    let staged = dir.join("staged.toml");
    let stages = "[[curriculum]]\nterrain = \"rigid\"\niterations = 1\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 1\n\n[curriculum.physics]\nstep_rate_hz = 120\n";
    std::fs::write(&staged, format!("{}{stages}", super::train::TINY)).unwrap();
    let run = dir.join("run");
    let config = s(&staged);
    let log = super::train::ok(&[
        "train",
        "--config",
        config,
        "--run-dir",
        s(&run),
        "--rerun",
        "off",
    ]);
    assert!(
        log.contains("training (ppo) on rigid with")
            && log.contains("curriculum stage 2: rigid, physics: step_rate_hz = 120"),
        "{log}"
    );
    let rate_of = |policy: &Path, out: &str| {
        let report = eval_json(
            &[
                "--policy",
                s(policy),
                "--terrain",
                "rigid",
                "--episodes",
                "1",
                "--phases",
                "2",
            ],
            &dir.join(out),
        );
        report["step_rate_hz"].as_u64().unwrap_or(240)
    };
    assert_eq!(
        rate_of(&run.join("checkpoints/iter-000001"), "stage-1"),
        240
    );
    assert_eq!(rate_of(&run, "stage-2"), 120);
    // a run at 120 Hz throughout did not train iteration 1 as this config
    let all_120 = tiny_at_120_hz(&dir);
    let other = dir.join("other");
    train_tiny(&all_120, &other, "1");
    let refused = dir.join("refused");
    let err = failure(
        &[
            "train",
            "--config",
            config,
            "--run-dir",
            s(&refused),
            "--rerun",
            "off",
            "--fork",
            s(&other.join("checkpoints/iter-000001")),
        ],
        1,
    );
    assert!(
        err.contains("iteration 1's [physics] settings")
            && err.contains("step_rate_hz: 240 against step_rate_hz: 120"),
        "{err}"
    );
}

#[test]
fn bad_eval_input_is_refused_with_what_is_wrong() {
    let err = failure(&["eval", "--policy", "no/such/run"], 1);
    assert!(err.contains("no/such/run"), "{err}");
    let err = failure(&["eval", "--episodes", "0"], 2);
    assert!(err.contains("--episodes"), "{err}");
    let err = failure(&["eval", "--phases", "0"], 2);
    assert!(err.contains("--phases"), "{err}");
    let empty = scratch_dir("eval-empty");
    let err = failure(&["eval", "--compare", s(&empty)], 1);
    assert!(
        err.contains("eval.json") && err.contains("no evaluation"),
        "{err}"
    );
    for (setting, expected) in [
        (
            "base_height_reference=belly",
            "base_height_reference must be \"hips\"",
        ),
        (
            "observation.foot_velocity=false",
            "observation sets the networks' input",
        ),
        ("max_phase=3", "unknown field `max_phase`"),
    ] {
        let err = failure(&["eval", "--terrain", "rigid", "--task", setting], 1);
        assert!(
            err.contains(&format!("--task {setting:?}")) && err.contains(expected),
            "{err}"
        );
    }
    let err = failure(&["eval", "--terrain", "elastic:-5cm"], 1);
    assert!(
        err.contains("elastic:-5cm") || err.contains("-5cm"),
        "{err}"
    );
}

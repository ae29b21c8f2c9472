//! The example's own `quadwalk-pontoon` binary runs every command on the
//! pontoon terrain: the plugin reaches the command line through
//! `quadwalk_cli::App` from a crate outside quadwalk's own.

use std::path::Path;
use std::process::{Command, ExitCode, Output};

use serde_json::Value;

fn pontoon(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadwalk-pontoon"))
        .args(args)
        .output()
        .expect("quadwalk-pontoon runs")
}

fn ok(args: &[&str]) -> String {
    let out = pontoon(args);
    assert!(
        out.status.success(),
        "quadwalk-pontoon {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

fn json(args: &[&str]) -> Value {
    serde_json::from_str(ok(args).trim()).unwrap()
}

#[test]
fn terrain_list_and_show_know_the_plugin_beside_the_built_in_ones() {
    let list = ok(&["terrain", "list"]);
    for name in ["rigid", "elastic", "varying", "pontoon"] {
        assert!(
            list.lines().any(|l| l.starts_with(name)),
            "{name} listed:\n{list}"
        );
    }
    assert!(list.contains("usage: pontoon:<depth>"), "{list}");
    let show = json(&["terrain", "show", "pontoon:3cm", "--json"]);
    assert_eq!(show["terrain"], "pontoon:3cm");
    assert_eq!(show["tile_count"], 33);
    assert_eq!(show["regions"][0]["expected_sink_m"], 0.03);
}

#[test]
fn the_robot_stands_on_one_plate_and_sinks_it_the_named_depth_streamed_to_rerun() {
    let dir = tempfile::tempdir().unwrap();
    let rrd = dir.path().join("stand.rrd");
    let sink = format!("save:{}", rrd.display());
    let report = json(&[
        "stand",
        "--terrain",
        "pontoon:3cm",
        "--seconds",
        "3",
        "--json",
        "--rerun",
        &sink,
    ]);
    let sink_m = report["mean_loaded_sink_m"].as_f64().unwrap();
    assert!((sink_m - 0.03).abs() < 0.003, "sink {sink_m} m");
    assert!(report["max_tilt_deg"].as_f64().unwrap() < 2.0, "{report}");
    assert!(report["non_foot_contacts"].as_array().unwrap().is_empty());
    assert!(report["rerun_frames"].as_u64().unwrap() > 0, "{report}");
    assert!(std::fs::metadata(&rrd).unwrap().len() > 0);
}

#[test]
fn train_rollout_and_eval_run_on_the_plugin_and_its_checkpoint_needs_it() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let run_arg = run.to_str().unwrap();
    ok(&[
        "train",
        "--terrain",
        "pontoon:3cm",
        "--iterations",
        "2",
        "--envs",
        "2",
        "--threads",
        "2",
        "--rerun",
        "off",
        "--run-dir",
        run_arg,
    ]);
    let config = std::fs::read_to_string(run.join("config.toml")).unwrap();
    assert!(config.contains("pontoon:3cm"), "{config}");
    assert_eq!(
        std::fs::read_to_string(run.join("metrics.jsonl"))
            .unwrap()
            .lines()
            .count(),
        2
    );
    // The checkpoint acts on its own terrain...
    let rollout = json(&[
        "rollout",
        "--policy",
        run_arg,
        "--phases",
        "3",
        "--json",
        "--terrain",
        "pontoon:3cm",
    ]);
    assert_eq!(rollout["regions"][0], "pontoon:3cm");
    // ...and is evaluated on it.
    let out = dir.path().join("eval");
    ok(&[
        "eval",
        "--policy",
        run_arg,
        "--terrain",
        "pontoon:3cm",
        "--episodes",
        "2",
        "--phases",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(Path::new(&out).join("eval.json").is_file());

    // A binary without the plugin cannot read the run back: the config names
    // a terrain it does not know (the error names it; see tests/cli).
    let code = quadwalk_cli::App::new().run_from(["quadwalk", "train", "--resume", run_arg]);
    assert_eq!(code, ExitCode::FAILURE);
}

//! End-to-end tests of the `quadwalk` binary: what a user types, what they
//! get back, and the physical figures the simulation core must reach.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use serde_json::Value;

mod eval;
#[cfg(feature = "rerun")]
mod rerun_stream;
mod results;
mod train;
mod video;

fn quadwalk(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_quadwalk"))
        .args(args)
        .output()
        .expect("the quadwalk binary runs")
}

fn json_of(args: &[&str]) -> Value {
    let out = quadwalk(args);
    assert!(
        out.status.success(),
        "quadwalk {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "quadwalk {args:?} printed no JSON ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// Writes `text` to a file called `name` in this binary's scratch directory
/// (in the target's temporary space) and returns its path.
fn scratch_file(name: &str, text: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("e2e");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs a command that must fail; returns its stderr.
fn failure(args: &[&str], code: i32) -> String {
    let out = quadwalk(args);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(code), "quadwalk {args:?}: {stderr}");
    assert!(
        !stderr.contains("panicked"),
        "quadwalk {args:?} panicked: {stderr}"
    );
    stderr
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

fn shared(relative: &str) -> Option<PathBuf> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared")
        .join(relative);
    if path.exists() {
        Some(path)
    } else {
        println!(
            "skipped: {} is absent (shared test data lives beside the checkout)",
            path.display()
        );
        None
    }
}

#[test]
fn stands_ten_seconds_on_rigid_ground() {
    let r = json_of(&["stand", "--terrain", "rigid", "--seconds", "10", "--json"]);
    assert!(f(&r, "max_tilt_deg") < 2.0, "{r}");
    assert!(f(&r, "base_height_drift_m") < 0.005, "{r}");
    assert_eq!(f(&r, "window_secs"), 5.0);
    assert_eq!(r["non_foot_contacts"], Value::Array(vec![]), "{r}");
}

#[test]
fn sinks_the_named_depth_on_elastic_terrain() {
    for (spec, depth) in [("elastic:2cm", 0.02), ("elastic:5cm", 0.05)] {
        let r = json_of(&["stand", "--terrain", spec, "--seconds", "10", "--json"]);
        let sink = f(&r, "mean_loaded_sink_m");
        assert!(
            (sink - depth).abs() <= 0.1 * depth,
            "{spec}: sink {sink} in {r}"
        );
        assert!(f(&r, "max_tilt_deg") < 5.0, "{spec}: {r}");
        assert_eq!(r["non_foot_contacts"], Value::Array(vec![]), "{spec}: {r}");
    }
}

#[test]
fn sinks_each_regions_depth_on_varying_terrain() {
    let spec = "varying:2m:2,5cm";
    let shown = json_of(&["terrain", "show", spec, "--json"]);
    let regions = shown["regions"].as_array().unwrap();
    let mut checked = Vec::new();
    for label in ["elastic:2cm", "elastic:5cm"] {
        // The first region of each type past the start, robot on a whole tile pitch near its middle.
        let region = regions
            .iter()
            .find(|r| r["label"] == label && r["index"].as_u64() > Some(0))
            .unwrap_or_else(|| panic!("no {label} region in {shown}"));
        let range = region["x_range_m"].as_array().unwrap();
        let middle = (range[0].as_f64().unwrap() + range[1].as_f64().unwrap()) / 2.0;
        let x = (middle / 0.2).round() * 0.2;
        let r = json_of(&[
            "stand",
            "--terrain",
            spec,
            "--x",
            &format!("{x}"),
            "--seconds",
            "10",
            "--json",
        ]);
        assert_eq!(r["region"], *label, "{r}");
        let depth = f(&r, "expected_sink_m");
        let sink = f(&r, "mean_loaded_sink_m");
        assert!(
            (sink - depth).abs() <= 0.1 * depth,
            "{label} at x = {x}: sink {sink} in {r}"
        );
        assert!(f(&r, "max_tilt_deg") < 5.0, "{r}");
        checked.push(depth);
    }
    assert_eq!(checked, vec![0.02, 0.05]);
}

#[test]
fn terrain_list_and_show_describe_the_plugins() {
    let out = quadwalk(&["terrain", "list"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in [
        "rigid",
        "elastic",
        "varying",
        "usage: elastic:<depth>[:key=value...]",
        "travel",
    ] {
        assert!(text.contains(name), "{name} missing from:\n{text}");
    }
    let shown = json_of(&["terrain", "show", "elastic:5cm", "--json"]);
    // k = m g / (4 d) with the Laikago's 25.567 kg.
    let k = shown["regions"][0]["stiffness_n_per_m"].as_f64().unwrap();
    assert!((k - 25.567 * 9.81 / 0.2).abs() < 0.01, "{shown}");
    assert_eq!(shown["tile_count"], 3000);
    let text = String::from_utf8_lossy(
        &quadwalk(&["terrain", "show", "varying:2m:2,3,4,5cm,rigid"]).stdout,
    )
    .to_string();
    assert!(
        text.contains("elastic:2cm") && text.contains("expected sink"),
        "{text}"
    );
}

#[test]
fn bench_reports_steps_per_second_per_terrain_and_thread_count() {
    let r = json_of(&[
        "bench",
        "--seconds",
        "0.25",
        "--repeat",
        "1",
        "--threads",
        "1,2",
        "--json",
    ]);
    let rows = r["results"].as_array().unwrap();
    assert_eq!(rows.len(), 6, "{r}");
    for row in rows {
        assert!(f(row, "steps_per_s") > 0.0, "{row}");
        assert!([1, 2].contains(&row["threads"].as_u64().unwrap()), "{row}");
    }
    let terrains: Vec<&str> = rows
        .iter()
        .map(|row| row["terrain"].as_str().unwrap())
        .collect();
    assert!(
        terrains.contains(&"rigid") && terrains.contains(&"elastic:5cm"),
        "{terrains:?}"
    );
    assert_eq!(r["physics"]["prediction_distance_m"], 0.02, "{r}");
}

#[test]
fn bench_measures_the_physics_of_an_experiment_file() {
    let config = scratch_file(
        "bench-physics.toml",
        "[terrain]\nspec = \"rigid\"\n[physics]\nprediction_distance_m = 0.005\npgs_iterations = 2\n",
    );
    let r = json_of(&[
        "bench",
        "--config",
        config.to_str().unwrap(),
        "--terrain",
        "rigid",
        "--seconds",
        "0.25",
        "--repeat",
        "1",
        "--threads",
        "1",
        "--phases",
        "2",
        "--json",
    ]);
    assert_eq!(r["physics"]["prediction_distance_m"], 0.005, "{r}");
    assert_eq!(r["physics"]["pgs_iterations"], 2, "{r}");
    let row = &r["results"][0];
    assert!(
        f(row, "steps_per_s") > 0.0 && f(row, "phases_per_s") > 0.0,
        "{row}"
    );
    let bad = scratch_file(
        "bench-bad-physics.toml",
        "[terrain]\nspec = \"rigid\"\n[physics]\nprediction_distance_m = 0.0\n",
    );
    let stderr = failure(&["bench", "--config", bad.to_str().unwrap()], 1);
    assert!(
        stderr.contains("prediction_distance_m") && stderr.starts_with("error: "),
        "{stderr:?}"
    );
}

#[test]
fn bad_input_gives_one_line_errors_and_no_panic() {
    let cases: &[(&[&str], i32, &str)] = &[
        (
            &["stand", "--terrain", "sand:5cm"],
            1,
            "unknown terrain \"sand\"",
        ),
        (&["stand", "--terrain", "elastic:5"], 1, "has no unit"),
        (
            &["stand", "--terrain", "elastic:30cm"],
            1,
            "beyond the tile travel",
        ),
        (&["terrain", "show", "varying:2m:"], 1, "the list is empty"),
        (
            &["stand", "--robot", "/nonexistent/robot.urdf"],
            1,
            "/nonexistent/robot.urdf: cannot read it",
        ),
        (
            &["stand", "--terrain", "elastic:5cm", "--x", "100"],
            1,
            "outside terrain",
        ),
        (&["stand", "--seconds", "-1"], 2, "--seconds"),
        (&["stand", "--seconds", "nan"], 2, "--seconds"),
        (&["stand", "--bogus"], 2, "--bogus"),
        (&["bench", "--threads", "0"], 2, "--threads"),
        (
            &["bench", "--terrain", "elastic:0cm"],
            1,
            "greater than zero",
        ),
    ];
    for (args, code, expected) in cases {
        let stderr = failure(args, *code);
        assert!(
            stderr.contains(expected),
            "quadwalk {args:?}: {stderr:?} does not mention {expected:?}"
        );
        if *code == 1 {
            assert_eq!(
                stderr.trim_end().lines().count(),
                1,
                "quadwalk {args:?}: not one line: {stderr:?}"
            );
            assert!(stderr.starts_with("error: "), "{stderr:?}");
        }
    }
}

#[test]
fn a_terrain_whose_plugin_is_not_registered_is_named_with_how_to_register_it() {
    // An experiment file and a curriculum written for a binary with more plugins.
    let config = scratch_file("pontoon.toml", "[terrain]\nspec = \"pontoon:3cm\"\n");
    let stderr = failure(&["stand", "--config", config.to_str().unwrap()], 1);
    let curriculum = scratch_file(
        "pontoon-stages.toml",
        "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\n[[curriculum]]\nterrain = \"pontoon:3cm\"\niterations = 2\n",
    );
    let stages = failure(&["train", "--config", curriculum.to_str().unwrap()], 1);
    for (stderr, file) in [(stderr, "pontoon.toml"), (stages, "pontoon-stages.toml")] {
        for expected in [
            file,
            "unknown terrain \"pontoon\"",
            "known terrains: rigid, elastic, varying",
            "App::new().add_terrain",
        ] {
            assert!(stderr.contains(expected), "{stderr:?} lacks {expected:?}");
        }
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr:?}");
    }
}

#[test]
fn malformed_urdf_is_refused_with_its_path() {
    let broken = scratch_file("broken.urdf", "<robot name='x'><link name='a'>");
    let stderr = failure(&["stand", "--robot", broken.to_str().unwrap()], 1);
    assert!(stderr.contains("broken.urdf: not valid URDF"), "{stderr}");
    let three_legs = scratch_file("three_legs.urdf", &robot_urdf_without_leg("RL"));
    let stderr = failure(&["stand", "--robot", three_legs.to_str().unwrap()], 1);
    assert!(
        stderr.contains("three_legs.urdf") && stderr.contains("actuated joints"),
        "{stderr}"
    );
}

/// The built-in URDF with one leg's joints and links removed.
fn robot_urdf_without_leg(leg: &str) -> String {
    let mut out = String::new();
    let mut skipping = false;
    for line in robot::LAIKAGO_URDF.lines() {
        let starts = line
            .trim_start()
            .starts_with(&format!("<link name=\"{leg}_"))
            || line
                .trim_start()
                .starts_with(&format!("<link name=\"toe{leg}\""))
            || line
                .trim_start()
                .starts_with(&format!("<joint name=\"{leg}_"))
            || line
                .trim_start()
                .starts_with(&format!("<joint name=\"jtoe{leg}\""));
        if starts {
            skipping = true;
        }
        if !skipping {
            out.push_str(line);
            out.push('\n');
        }
        if skipping && (line.trim() == "</link>" || line.trim() == "</joint>") {
            skipping = false;
        }
    }
    out
}

#[test]
fn third_party_urdf_stands_on_rigid_ground() {
    let Some(path) = shared("robots/laikago/laikago_toes_zup.urdf") else {
        return;
    };
    let r = json_of(&[
        "stand",
        "--terrain",
        "rigid",
        "--robot",
        path.to_str().unwrap(),
        "--seconds",
        "3",
        "--json",
    ]);
    assert!((f(&r, "robot_mass_kg") - 25.567).abs() < 0.26, "{r}");
    assert!(f(&r, "max_tilt_deg") < 5.0, "{r}");
}

#[test]
fn stand_reads_the_terrain_from_a_toml_file() {
    let good = scratch_file(
        "stand.toml",
        "[terrain]\nplugin = \"elastic\"\ndepth = \"2cm\"\nlength = \"3m\"\nback = \"1.5m\"\n",
    );
    let r = json_of(&[
        "stand",
        "--config",
        good.to_str().unwrap(),
        "--seconds",
        "4",
        "--json",
    ]);
    assert_eq!(r["terrain"], "elastic:2cm:length=3m:back=1.5m", "{r}");
    assert!((f(&r, "mean_loaded_sink_m") - 0.02).abs() < 0.002, "{r}");
    let bad = scratch_file(
        "bad.toml",
        "[terrain]\nspec = \"elastic:2cm\"\ncolour = \"red\"\n",
    );
    let stderr = failure(&["stand", "--config", bad.to_str().unwrap()], 1);
    assert!(
        stderr.contains("bad.toml [terrain]") && stderr.contains("colour"),
        "{stderr}"
    );
    let stderr = failure(
        &[
            "stand",
            "--config",
            good.to_str().unwrap(),
            "--terrain",
            "rigid",
        ],
        2,
    );
    assert!(stderr.contains("cannot be used with"), "{stderr}");
}

#[test]
fn a_closed_pipe_ends_output_quietly() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_quadwalk"))
        .args(["terrain", "show", "varying:2m:2,3,4,5cm,rigid:length=100m"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.status.success(), "{stderr}");
}

/// Runs the scripted crawl and checks the figure: at least 4 m
/// forward, no termination, every reward term reported.
fn crawl_walks_four_metres(terrain: &str, phases: u64) -> Value {
    let r = json_of(&[
        "rollout",
        "--policy",
        "scripted",
        "--terrain",
        terrain,
        "--phases",
        &phases.to_string(),
        "--json",
    ]);
    assert!(f(&r, "distance_m") >= 4.0, "{r}");
    assert_eq!(r["terminated"], false, "{r}");
    assert_eq!(r["phases"], phases);
    let terms = r["reward_terms"].as_object().unwrap();
    for name in ["distance", "orientation", "height", "torque", "roll"] {
        assert!(terms[name].as_f64().is_some(), "{name} missing in {r}");
    }
    let total: f64 = terms.values().map(|v| v.as_f64().unwrap()).sum();
    assert!((total - f(&r, "reward_total")).abs() < 1e-9, "{r}");
    assert!(
        r["goals_reached"].as_u64().unwrap() >= 2,
        "two goals 2 m apart passed: {r}"
    );
    r
}

#[test]
fn the_scripted_crawl_walks_four_metres_on_rigid_ground() {
    // 6.5 m in 640 phases (docs/guide/task.md; stance feet slip ~4.6 mm per phase);
    // 4 m take ~400.
    crawl_walks_four_metres("rigid", 480);
}

#[test]
fn the_scripted_crawl_walks_four_metres_on_2cm_tiles() {
    // 4.4 m in 640 phases with seed 0 (4.5 and 4.4 m with seeds 1 and 2, docs/guide/task.md).
    let r = crawl_walks_four_metres("elastic:2cm", 640);
    assert_eq!(r["regions"], serde_json::json!(["elastic:2cm"]));
    assert!(f(&r, "lateral_drift_m").abs() < 0.5, "{r}");
}

#[test]
fn rollout_reports_termination_and_refuses_unknown_policies() {
    // A termination is reported, not an error: with a pitch limit of 0.5
    // degrees the crawl's first steps end the episode.
    let config = scratch_file(
        "strict.toml",
        "[terrain]\nspec = \"elastic:5cm\"\n[task]\nmax_pitch_deg = 0.5\n",
    );
    let r = json_of(&[
        "rollout",
        "--config",
        config.to_str().unwrap(),
        "--phases",
        "20",
        "--json",
    ]);
    assert_eq!(r["terminated"], "pitch_too_large", "{r}");
    assert!(r["phases"].as_u64().unwrap() < 20);
    let stderr = failure(&["rollout", "--policy", "runs/none"], 1);
    assert!(
        stderr.contains("policy \"runs/none\" is neither `scripted` nor an existing checkpoint"),
        "{stderr}"
    );
    let stderr = failure(&["rollout", "--phases", "0"], 2);
    assert!(stderr.contains("--phases"), "{stderr}");
}

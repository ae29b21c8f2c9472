//! Rerun streaming, checked with Rerun's own tooling: the `rerun` command
//! and the Python reader of `rerun-sdk==0.36.3`, which the test set-up
//! installs into `target/rerun-venv` (once; pip needs PyPI the first time).

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use serde_json::Value;

use super::{json_of, quadwalk};

const RERUN_SDK: &str = "rerun-sdk==0.36.3";

/// The virtual environment with rerun-sdk, made on first use.
fn rerun_venv() -> &'static Path {
    static VENV: OnceLock<PathBuf> = OnceLock::new();
    static LOCK: Mutex<()> = Mutex::new(());
    VENV.get_or_init(|| {
        let _guard = LOCK.lock().unwrap();
        let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/rerun-venv");
        let python = venv.join("bin/python");
        let ready = venv.join(".rerun-sdk-0.36.3");
        if !ready.exists() {
            let status = Command::new("python3")
                .args(["-m", "venv"])
                .arg(&venv)
                .status()
                .expect("python3 runs (the Rerun tests need Python 3 with venv)");
            assert!(
                status.success(),
                "python3 -m venv {} failed",
                venv.display()
            );
            let status = Command::new(&python)
                .args(["-m", "pip", "install", "--quiet", RERUN_SDK])
                .status()
                .expect("pip runs");
            assert!(status.success(), "pip install {RERUN_SDK} failed");
            std::fs::write(&ready, RERUN_SDK).unwrap();
        }
        venv
    })
}

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rerun");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let _ = std::fs::remove_file(&path);
    path
}

/// Runs `quadwalk ARGS`, which must succeed.
fn quadwalk_ok(args: &[&str]) -> std::process::Output {
    let out = super::quadwalk(args);
    assert!(
        out.status.success(),
        "quadwalk {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The strings of a JSON array.
fn strings(list: &Value) -> Vec<&str> {
    list.as_array()
        .unwrap()
        .iter()
        .map(|e| e.as_str().unwrap())
        .collect()
}

/// What the Python reader finds in an `.rrd`: see `read_rrd.py`.
fn read_rrd(path: &Path) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/cli/read_rrd.py");
    let out = Command::new(rerun_venv().join("bin/python"))
        .arg(&script)
        .arg(path)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "read_rrd.py {} failed: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("read_rrd.py prints JSON")
}

/// The simulation's own values for the rollout the test records: base
/// position and tile sinks at every logged frame.
fn simulated_frames(spec: &str, seed: u64, phases: usize, rate: viz::LogRate) -> Vec<Frame> {
    use robot::snapshot::PhaseObserver;
    use robot::task::{Task, TaskConfig};

    struct Recorder {
        rate: viz::LogRate,
        frames: Vec<Frame>,
        last: Option<(usize, usize)>,
    }
    impl Recorder {
        fn record(&mut self, task: &Task) {
            let snap = task.snapshot(viz::VizSettings::default().tiles_half_side_m);
            self.frames.push(Frame {
                sim_time_s: snap.sim_time_s,
                base_m: snap.body_poses[0].translation.vector.into(),
                sinks_m: snap.tiles.iter().map(|t| t.sink_m).collect(),
            });
        }
    }
    impl PhaseObserver for Recorder {
        fn stepped(&mut self, task: &Task, step: usize) {
            if self.rate.logs_step(step, task.world().steps_per_phase()) {
                self.record(task);
                self.last = Some((task.phase(), step));
            }
        }
        fn phase_ended(&mut self, task: &Task, outcome: &robot::task::PhaseOutcome) {
            if self.last != Some((task.phase() - 1, outcome.steps)) {
                self.record(task);
            }
        }
    }

    let registry = terrain_plugins::Registry::builtin();
    let model = std::sync::Arc::new(robot::RobotModel::laikago());
    let ctx = terrain_plugins::BuildContext {
        supported_mass_kg: model.total_mass_kg(),
        seed,
        ..Default::default()
    };
    let terrain = registry.create(spec, &ctx).unwrap();
    let world =
        robot::World::new(model, terrain, robot::WorldConfig::default(), [0.0, 0.0]).unwrap();
    let config = TaskConfig {
        max_phases: phases,
        ..TaskConfig::default()
    };
    let mut task = Task::new(world, config, seed);
    let mut obs = vec![0.0f32; task.observation_size()];
    task.reset(&mut obs);
    let mut recorder = Recorder {
        rate,
        frames: Vec::new(),
        last: None,
    };
    recorder.record(&task);
    let crawl = robot::scripted::ScriptedCrawl::default();
    while !task.done() {
        let action = crawl.act(&task);
        task.step_phase_observed(&action, &mut obs, &mut recorder);
    }
    recorder.frames
}

#[derive(Debug)]
struct Frame {
    sim_time_s: f64,
    base_m: [f64; 3],
    sinks_m: Vec<f64>,
}

#[test]
fn a_saved_rollout_holds_the_simulations_values() {
    let rrd = scratch("rollout.rrd");
    let (spec, seed, phases) = ("elastic:5cm", 3, 3usize);
    let summary = json_of(&[
        "rollout",
        "--terrain",
        spec,
        "--seed",
        &seed.to_string(),
        "--phases",
        &phases.to_string(),
        "--rerun",
        &format!("save:{}", rrd.display()),
        "--rerun-rate",
        "45",
        "--json",
    ]);
    let rate: viz::LogRate = "45".parse().unwrap();
    let expected = simulated_frames(spec, seed, phases, rate);
    let ran = summary["phases"].as_u64().unwrap() as usize;
    assert_eq!(ran, phases, "the short rollout runs all its phases");
    // One frame after the reset, then 180 / 45 = 4 per phase.
    assert_eq!(expected.len(), 1 + phases * 4);
    assert_eq!(
        summary["rerun_frames"].as_u64(),
        Some(expected.len() as u64)
    );

    let content = read_rrd(&rrd);
    let entities: Vec<&str> = strings(&content["entities"]);
    for path in [
        "/world/robot/chassis",
        "/world/robot/chassis/shape_0",
        "/world/base/trajectory",
        "/world/goal",
        "/world/targets/base",
        "/world/targets/orientation",
        "/world/targets/swing_foot",
        "/world/targets/landing",
        "/world/terrain/tiles",
        "/world/terrain/regions",
        "/world/contacts",
        "/reward/distance",
        "/reward/total",
        "/base/height_m",
        "/base/pitch_deg",
        "/torque/FR_hip_motor_2_chassis_joint",
    ] {
        assert!(entities.contains(&path), "{path} missing from {entities:?}");
    }
    // the paper's observation shows the current goal, already logged
    assert!(!entities.contains(&"/world/observed_goal"), "{entities:?}");
    for timeline in ["sim_time", "phase"] {
        assert!(
            content["timelines"]
                .as_array()
                .unwrap()
                .iter()
                .any(|t| t == timeline),
            "timeline {timeline} missing"
        );
    }
    let base = content["base_positions"].as_array().unwrap();
    let tiles = content["tile_sinks"].as_array().unwrap();
    assert_eq!(base.len(), expected.len(), "logged frames");
    assert_eq!(tiles.len(), expected.len(), "logged tile frames");
    assert_eq!(
        content["phase_starts"].as_u64(),
        Some(phases as u64),
        "one set of curves per phase"
    );
    for (i, frame) in expected.iter().enumerate() {
        let t = base[i]["sim_time_s"].as_f64().unwrap();
        assert!(
            (t - frame.sim_time_s).abs() < 1e-6,
            "frame {i}: time {t} vs {}",
            frame.sim_time_s
        );
        let p: Vec<f64> = base[i]["xyz"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        for k in 0..3 {
            // Logged as f32.
            assert!(
                (p[k] - frame.base_m[k]).abs() < 1e-5,
                "frame {i}: base {p:?} vs {:?}",
                frame.base_m
            );
        }
        let sinks: Vec<f64> = tiles[i]["sinks_m"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(sinks.len(), frame.sinks_m.len(), "frame {i}: tile count");
        assert!(!sinks.is_empty(), "tiles near the robot are logged");
        for (a, b) in sinks.iter().zip(&frame.sinks_m) {
            assert!((a - b).abs() < 1e-5, "frame {i}: sink {a} vs {b}");
        }
    }
    // The robot stands on the tiles: some of them are pushed down.
    let deepest = expected
        .last()
        .unwrap()
        .sinks_m
        .iter()
        .cloned()
        .fold(0.0, f64::max);
    assert!(deepest > 0.02, "deepest logged sink {deepest} m");

    // Rerun's own verifier accepts the file.
    let verify = Command::new(rerun_venv().join("bin/rerun"))
        .args(["rrd", "verify"])
        .arg(&rrd)
        .output()
        .unwrap();
    assert!(
        verify.status.success(),
        "rerun rrd verify: {}",
        String::from_utf8_lossy(&verify.stderr)
    );
}

/// A `rerun` server started on a free port on 127.0.0.1 that saves what it
/// receives.
struct Receiver {
    child: Child,
    port: u16,
}

impl Receiver {
    fn start(save: &Path) -> Self {
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let child = Command::new(rerun_binary())
            .args(["--bind", "127.0.0.1", "--port", &port.to_string(), "--save"])
            .arg(save)
            .env("RERUN_ANALYTICS", "0")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("rerun starts");
        let deadline = Instant::now() + Duration::from_secs(60);
        while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(Instant::now() < deadline, "rerun did not listen on {port}");
            std::thread::sleep(Duration::from_millis(100));
        }
        Self { child, port }
    }
}

impl Receiver {
    /// Ends the server.
    fn stop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The `rerun` executable itself: `bin/rerun` from pip is a Python launcher
/// that starts it as a child, which killing the launcher would leave behind.
fn rerun_binary() -> PathBuf {
    let lib = rerun_venv().join("lib");
    std::fs::read_dir(&lib)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.path().join("site-packages/rerun_sdk/rerun_cli/rerun"))
        .find(|p| p.exists())
        .unwrap_or_else(|| panic!("no rerun_cli/rerun under {}", lib.display()))
}

impl Drop for Receiver {
    fn drop(&mut self) {
        self.stop();
    }
}

#[test]
fn a_live_stream_reaches_a_receiver_and_a_missing_one_is_a_warning() {
    let saved = scratch("received.rrd");
    let mut receiver = Receiver::start(&saved);
    let url = format!("connect:rerun+http://127.0.0.1:{}/proxy", receiver.port);
    let out = quadwalk(&[
        "rollout",
        "--terrain",
        "rigid",
        "--phases",
        "2",
        "--rerun",
        &url,
        "--json",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["rerun_frames"].as_u64(), Some(3), "{stderr}");
    // The server writes as it receives; wait for the frames to land.
    let deadline = Instant::now() + Duration::from_secs(60);
    let content = loop {
        std::thread::sleep(Duration::from_millis(500));
        if saved.exists() {
            // Stop the server so that the file is complete.
            receiver.stop();
            break read_rrd(&saved);
        }
        assert!(Instant::now() < deadline, "the receiver saved nothing");
    };
    assert_eq!(
        content["base_positions"].as_array().unwrap().len(),
        3,
        "frames received: {content}"
    );

    // Nobody listens on the port any more: a warning, and the run goes on.
    let out = quadwalk(&[
        "rollout",
        "--terrain",
        "rigid",
        "--phases",
        "1",
        "--rerun",
        &url,
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("warning: no Rerun viewer at"), "{stderr}");
}

/// Training streams env 0's rollouts with `iteration` on their timeline,
/// and the training curves as scalars.
#[test]
fn training_streams_rollouts_and_curves() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("rerun-train");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("tiny.toml");
    std::fs::write(
        &config,
        "[terrain]\nspec = \"elastic:5cm\"\n[task]\nmax_phases = 3\n[task.observation]\ngoal_line_ahead_m = 1.0\n[ppo]\nhidden_sizes = [8]\nsteps_per_env = 3\nminibatch_size = 6\nepochs = 1\n[train]\nenvs = 2\nrerun_envs = [0, 1]\n",
    )
    .unwrap();
    let rrd = dir.join("train.rrd");
    let out = Command::new(env!("CARGO_BIN_EXE_quadwalk"))
        .args([
            "train",
            "--config",
            config.to_str().unwrap(),
            "--run-dir",
            dir.join("run").to_str().unwrap(),
        ])
        .args([
            "--iterations",
            "2",
            "--rerun",
            &format!("save:{}", rrd.display()),
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let content = read_rrd(&rrd);
    let entities: Vec<&str> = strings(&content["entities"]);
    let timelines: Vec<&str> = strings(&content["timelines"]);
    for entity in [
        "/train/mean_return",
        "/train/policy_loss",
        "/train/phases_per_s",
        "/world/robot/chassis",
        "/world/terrain/tiles",
        // the policy observes the goals' line ahead: the point is shown
        "/world/observed_goal",
    ] {
        assert!(entities.contains(&entity), "{entity} missing: {entities:?}");
    }
    assert!(timelines.contains(&"iteration"), "{timelines:?}");
    // two iterations x (reset + 3 phases) of env 0
    assert_eq!(content["phase_starts"], 6, "{content}");
    // env 1 goes to its own file
    let second = read_rrd(&dir.join("train-env1.rrd"));
    assert_eq!(second["phase_starts"], 6, "{second}");
}

/// `stand` takes the same `--rerun` flags: a 3 s stand logged every 90
/// steps gives 1 + 8 frames of the robot and the tiles.
#[test]
fn stand_streams_too() {
    let rrd = scratch("stand.rrd");
    let sink = format!("save:{}", rrd.display());
    let out = quadwalk_ok(&[
        "stand",
        "--terrain",
        "elastic:5cm",
        "--seconds",
        "3",
        "--json",
        "--rerun",
        &sink,
        "--rerun-rate",
        "90",
    ]);
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["rerun_frames"], 9, "{report}");
    let content = read_rrd(&rrd);
    assert_eq!(content["base_positions"].as_array().unwrap().len(), 9);
    assert_eq!(content["tile_sinks"].as_array().unwrap().len(), 9);
    // the last frame: the robot has sunk into the 5 cm tiles
    let last = content["tile_sinks"].as_array().unwrap().last().unwrap()["sinks_m"]
        .as_array()
        .unwrap()
        .clone();
    let deepest = last.iter().map(|v| v.as_f64().unwrap()).fold(0.0, f64::max);
    assert!(deepest > 0.03, "no tile sank: {last:?}");
    // standing has no goal, so none is drawn
    let entities = strings(&content["entities"]);
    assert!(entities.contains(&"/world/base/trajectory"), "{entities:?}");
    assert!(!entities.contains(&"/world/goal"), "{entities:?}");
}

/// Relief is drawn as its ground mesh; flat ground and tiles have none.
#[test]
fn relief_streams_its_ground() {
    for (spec, has_ground) in [
        ("rough:1cm", true),
        ("slope:5", true),
        ("elastic:5cm", false),
    ] {
        let rrd = scratch(&format!("ground-{}.rrd", spec.replace(':', "_")));
        let sink = format!("save:{}", rrd.display());
        quadwalk_ok(&[
            "stand",
            "--terrain",
            spec,
            "--seconds",
            "0.5",
            "--rerun",
            &sink,
        ]);
        let content = read_rrd(&rrd);
        let entities = strings(&content["entities"]);
        assert_eq!(
            entities.contains(&"/world/terrain/ground"),
            has_ground,
            "{spec}: {entities:?}"
        );
        assert!(entities.contains(&"/world/robot/chassis"), "{entities:?}");
    }
}

/// `bench --rerun` streams the world on thread 0 of the phase-rate
/// measurement: 2 phases give 2 sets of curves.
#[test]
fn bench_streams_its_phase_world() {
    let rrd = scratch("bench.rrd");
    let sink = format!("save:{}", rrd.display());
    let out = quadwalk_ok(&[
        "bench",
        "--terrain",
        "rigid",
        "--threads",
        "1",
        "--seconds",
        "0.1",
        "--repeat",
        "1",
        "--phases",
        "2",
        "--json",
        "--rerun",
        &sink,
    ]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("include Rerun logging"));
    let content = read_rrd(&rrd);
    assert_eq!(content["phase_starts"], 2, "{content}");
}

/// `eval --rerun` logs its curves: distance per episode, Fig. 4 per terrain
/// type and the landing heights, on their own timelines.
#[test]
fn eval_streams_its_curves() {
    let rrd = scratch("eval.rrd");
    let sink = format!("save:{}", rrd.display());
    let out_dir = scratch("eval-out");
    quadwalk_ok(&[
        "eval",
        "--terrain",
        "elastic:2cm",
        "--episodes",
        "2",
        "--phases",
        "4",
        "--json",
        "--out",
        out_dir.to_str().unwrap(),
        "--rerun",
        &sink,
    ]);
    let content = read_rrd(&rrd);
    let entities = strings(&content["entities"]);
    for entity in [
        "/eval/distance_m",
        "/eval/base_height_cm/elastic_2cm/mean",
        "/eval/base_height_cm/elastic_2cm/mean_plus_std",
        "/eval/landing_height_cm/elastic_2cm",
    ] {
        assert!(entities.contains(&entity), "{entity} missing: {entities:?}");
    }
    let timelines = strings(&content["timelines"]);
    for timeline in ["episode", "phase_angle_deg", "foot"] {
        assert!(timelines.contains(&timeline), "{timeline}: {timelines:?}");
    }
}

/// What a person sees: a recording opened in Rerun's web viewer, drawn by
/// headless Chromium's software rasteriser (`scripts/viewer_screenshot.py`;
/// CI installs Chromium, see `.ci/run`), has the robot in its 3D view from
/// the start, large: the eye follows the base.
#[test]
fn the_web_viewer_shows_the_robot_in_its_3d_view() {
    let rrd = scratch("viewer.rrd");
    let png = scratch("viewer.png");
    let policy = Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies/elastic-5cm");
    quadwalk_ok(&[
        "rollout",
        "--policy",
        policy.to_str().unwrap(),
        "--terrain",
        "elastic:5cm",
        "--phases",
        "8",
        "--rerun",
        &format!("save:{}", rrd.display()),
    ]);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/viewer_screenshot.py");
    let out = Command::new(rerun_venv().join("bin/python"))
        .arg(&script)
        .arg(&rrd)
        .arg(&png)
        .args(["--timeout", "400"])
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "viewer_screenshot.py: {}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let report: Value =
        serde_json::from_slice(&std::fs::read(png.with_extension("json")).unwrap()).unwrap();
    assert_eq!(report["robot_in_view"], Value::Bool(true), "{report}");
    // The eye 2 m from the base: the robot covers a few percent of the
    // window (about 1 % at 1600x900), not the handful of pixels it covers
    // when the view frames the whole terrain.
    let percent = report["robot_percent"].as_f64().unwrap();
    assert!(percent >= 0.5, "{report}");
    let png_bytes = std::fs::read(&png).unwrap();
    assert_eq!(&png_bytes[..8], b"\x89PNG\r\n\x1a\n", "a PNG");
}

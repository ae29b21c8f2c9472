//! What the physics does, for comparing simulation settings:
//! `cargo run --release -p robot --example physics_fidelity -- [options]`.
//!
//! For one [`WorldConfig`] it measures, on `rigid`, `elastic:2cm` and
//! `elastic:5cm`:
//! - standing 10 s in the squat: the mean sink of the loaded tiles against
//!   the named depth, the largest tilt, the base height's drift over the
//!   last 5 s and the base's horizontal drift;
//! - the scripted crawl (640 phases, seeds 0-2 unless told): distance,
//!   phases survived and the termination, the torque term R_t's mean, the
//!   mean joint torque norm tau_ave, and the PD tracking error (RMS over
//!   joints of q* - q, averaged over every step, and its largest value),
//!   and how far the stance feet slide over a phase (the crawl holds them
//!   still in the world).
//!
//! Options: `--pd motor|implicit_spring`, `--substeps N`
//! (`num_solver_iterations`), `--pgs N` (`num_internal_pgs_iterations`),
//! `--ccd on|off`, `--kd X`, `--prediction-m X` (rapier's contact
//! prediction distance), `--phases N`, `--seeds 0,1,2`, `--threads N`.
//! Prints a Markdown table per part and one JSON line per run.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use robot::scripted::ScriptedCrawl;
use robot::task::{PhaseOutcome, Task, TaskConfig};
use robot::{PdModel, RobotModel, World, WorldConfig};
use terrain_plugins::{BuildContext, Registry};

const TERRAINS: [&str; 3] = ["rigid", "elastic:2cm", "elastic:5cm"];

struct Options {
    config: WorldConfig,
    phases: usize,
    seeds: Vec<u64>,
    threads: usize,
}

fn parse_options() -> Result<Options, String> {
    let mut o = Options {
        config: WorldConfig::default(),
        phases: 640,
        seeds: vec![0, 1, 2],
        threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let value = args.next().ok_or_else(|| format!("{flag} needs a value"))?;
        let bad = || format!("{flag} {value}: not a valid value");
        match flag.as_str() {
            "--pd" => o.config.pd = PdModel::from_name(&value).ok_or_else(bad)?,
            "--substeps" => o.config.solver_iterations = value.parse().map_err(|_| bad())?,
            "--pgs" => o.config.pgs_iterations = value.parse().map_err(|_| bad())?,
            "--kd" => o.config.kd_n_m_s_per_rad = value.parse().map_err(|_| bad())?,
            "--ccd" => o.config.ccd = value == "on",
            "--prediction-m" => {
                o.config.prediction_distance_m = value.parse().map_err(|_| bad())?;
                let m = o.config.prediction_distance_m;
                if !(m.is_finite() && m > 0.0) {
                    return Err(bad());
                }
            }
            "--phases" => o.phases = value.parse().map_err(|_| bad())?,
            "--threads" => o.threads = value.parse().map_err(|_| bad())?,
            "--seeds" => {
                o.seeds = value
                    .split(',')
                    .map(|s| s.parse().map_err(|_| bad()))
                    .collect::<Result<_, _>>()?
            }
            _ => return Err(format!("unknown option {flag}")),
        }
    }
    if o.config.solver_iterations == 0 || o.config.pgs_iterations == 0 || o.threads == 0 {
        return Err("--substeps, --pgs and --threads must be at least 1".into());
    }
    Ok(o)
}

fn world(spec: &str, config: &WorldConfig, seed: u64) -> World {
    let model = Arc::new(RobotModel::laikago());
    let ctx = BuildContext {
        supported_mass_kg: model.total_mass_kg(),
        seed,
        ..BuildContext::default()
    };
    let terrain = Registry::builtin()
        .create(spec, &ctx)
        .expect("a valid spec");
    World::new(model, terrain, config.clone(), [0.0, 0.0]).expect("the Laikago fits")
}

enum Job {
    Stand(&'static str),
    Crawl(&'static str, u64),
}

fn stand(spec: &str, config: &WorldConfig) -> String {
    let mut w = world(spec, config, 0);
    let start = w.base_pose().translation.vector;
    let r = robot::stand::stand(&mut w, 10.0);
    let end = w.base_pose().translation.vector;
    let drift_mm = ((end.x - start.x).powi(2) + (end.y - start.y).powi(2)).sqrt() * 1000.0;
    let line = format!(
        "| {spec} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} | {:.3} |",
        r.mean_loaded_sink_m * 100.0,
        r.expected_sink_m * 100.0,
        r.max_tilt_deg,
        r.base_height_drift_m * 1000.0,
        drift_mm,
        r.base_height_m
    );
    println!(
        "{{\"part\":\"stand\",\"terrain\":\"{spec}\",\"sink_cm\":{:.4},\"expected_cm\":{:.4},\"max_tilt_deg\":{:.4},\"height_drift_mm\":{:.4},\"horizontal_drift_mm\":{drift_mm:.4},\"base_height_m\":{:.5}}}",
        r.mean_loaded_sink_m * 100.0,
        r.expected_sink_m * 100.0,
        r.max_tilt_deg,
        r.base_height_drift_m * 1000.0,
        r.base_height_m
    );
    line
}

/// Tracking error and torque, step by step.
#[derive(Default)]
struct Tracking {
    rms_sum_rad: f64,
    rms_max_rad: f64,
    torque_norm_sum_n_m: f64,
    steps: usize,
    /// feet at the phase start (world frame) and the swing leg
    phase_start: Option<([nalgebra::Vector3<f64>; 4], usize)>,
    /// horizontal travel of the stance feet over their phase, summed, m
    stance_slip_sum_m: f64,
    stance_slip_count: usize,
}

impl robot::snapshot::PhaseObserver for Tracking {
    fn phase_started(&mut self, task: &Task, start: &robot::snapshot::PhaseStart) {
        self.phase_start = Some((task.world().feet_in_world_m(), start.swing_leg.index()));
    }

    fn phase_ended(&mut self, task: &Task, outcome: &PhaseOutcome) {
        // The crawl holds stance feet still in the world: any horizontal
        // travel of theirs over a whole phase is slip (tiles move only
        // vertically).
        let Some((feet, swing)) = self.phase_start.take() else {
            return;
        };
        if outcome.termination.is_some() {
            return;
        }
        let now = task.world().feet_in_world_m();
        for leg in (0..4).filter(|&l| l != swing) {
            let d = now[leg] - feet[leg];
            self.stance_slip_sum_m += d.x.hypot(d.y);
            self.stance_slip_count += 1;
        }
    }

    fn stepped(&mut self, task: &Task, _step: usize) {
        let w = task.world();
        let q = w.joint_positions_rad();
        let n = q.len() as f64;
        let rms = (w
            .joint_targets_rad()
            .iter()
            .zip(&q)
            .map(|(t, q)| (t - q).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        self.rms_sum_rad += rms;
        self.rms_max_rad = self.rms_max_rad.max(rms);
        self.torque_norm_sum_n_m += w
            .applied_torques_n_m()
            .iter()
            .map(|t| t * t)
            .sum::<f64>()
            .sqrt();
        self.steps += 1;
    }
}

fn crawl(spec: &str, seed: u64, config: &WorldConfig, phases: usize) -> String {
    let w = world(spec, config, seed);
    let task_config = TaskConfig {
        max_phases: phases,
        ..TaskConfig::default()
    };
    let mut task = Task::new(w, task_config, seed);
    let mut obs = vec![0.0f32; task.observation_size()];
    task.reset(&mut obs);
    let start = task.start_xy_m();
    let crawl = ScriptedCrawl::default();
    let mut tracking = Tracking::default();
    let (mut torque_term_sum, mut done) = (0.0, 0usize);
    let mut last: Option<PhaseOutcome> = None;
    let clock = Instant::now();
    while !task.done() {
        let action = crawl.act(&task);
        let outcome = task.step_phase_observed(&action, &mut obs, &mut tracking);
        torque_term_sum += outcome.terms.torque;
        done += 1;
        last = Some(outcome);
    }
    let secs = clock.elapsed().as_secs_f64();
    let distance_m = task.world().base_pose().translation.x - start[0];
    let termination = last
        .and_then(|o| o.termination)
        .map_or("-".to_string(), |t| format!("{t} at phase {done}"));
    let steps = tracking.steps.max(1) as f64;
    let slip_mm = 1000.0 * tracking.stance_slip_sum_m / tracking.stance_slip_count.max(1) as f64;
    println!(
        "{{\"part\":\"crawl\",\"terrain\":\"{spec}\",\"seed\":{seed},\"distance_m\":{distance_m:.4},\"phases\":{done},\"termination\":\"{termination}\",\"torque_term_mean\":{:.5},\"tau_ave_n_m\":{:.4},\"tracking_rms_mean_rad\":{:.5},\"tracking_rms_max_rad\":{:.5},\"stance_slip_mm\":{:.3},\"ms_per_phase\":{:.2}}}",
        torque_term_sum / done.max(1) as f64,
        tracking.torque_norm_sum_n_m / steps,
        tracking.rms_sum_rad / steps,
        tracking.rms_max_rad,
        slip_mm,
        secs * 1000.0 / done.max(1) as f64
    );
    format!(
        "| {spec} | {seed} | {distance_m:.2} | {done} | {termination} | {:.3} | {:.1} | {:.4} | {:.3} | {slip_mm:.2} |",
        torque_term_sum / done.max(1) as f64,
        tracking.torque_norm_sum_n_m / steps,
        tracking.rms_sum_rad / steps,
        tracking.rms_max_rad
    )
}

fn main() -> std::process::ExitCode {
    let options = match parse_options() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("physics_fidelity: {e}");
            return std::process::ExitCode::from(2);
        }
    };
    let c = &options.config;
    println!(
        "settings: pd {}, kp {}, kd {}, substeps {}, pgs {}, ccd {}, prediction {} m",
        c.pd.name(),
        c.kp_n_m_per_rad,
        c.kd_n_m_s_per_rad,
        c.solver_iterations,
        c.pgs_iterations,
        c.ccd,
        c.prediction_distance_m
    );
    // Speed first, alone on the machine: the robot standing on the paper's
    // scene (15 x 5 tiles), one thread, median of 3 runs of 2,400 steps.
    let mut rates: Vec<f64> = (0..3)
        .map(|_| {
            let mut w = world("elastic:5cm:length=3m:back=1.5m:width=1m", c, 0);
            for _ in 0..240 {
                w.step();
            }
            let clock = Instant::now();
            for _ in 0..2400 {
                w.step();
            }
            2400.0 / clock.elapsed().as_secs_f64()
        })
        .collect();
    rates.sort_by(f64::total_cmp);
    println!(
        "standing on 15 x 5 tiles, one thread: {:.0} steps/s (runs {rates:.0?})",
        rates[1]
    );
    let mut jobs: Vec<(usize, Job)> = Vec::new();
    for spec in TERRAINS {
        jobs.push((jobs.len(), Job::Stand(spec)));
    }
    for spec in TERRAINS {
        for &seed in &options.seeds {
            jobs.push((jobs.len(), Job::Crawl(spec, seed)));
        }
    }
    let total = jobs.len();
    let queue = Mutex::new(jobs);
    let results = Mutex::new(vec![String::new(); total]);
    std::thread::scope(|scope| {
        for _ in 0..options.threads {
            scope.spawn(|| {
                loop {
                    let Some((k, job)) = queue.lock().unwrap().pop() else {
                        break;
                    };
                    let line = match job {
                        Job::Stand(spec) => stand(spec, &options.config),
                        Job::Crawl(spec, seed) => {
                            crawl(spec, seed, &options.config, options.phases)
                        }
                    };
                    results.lock().unwrap()[k] = line;
                }
            });
        }
    });
    let results = results.into_inner().unwrap();
    println!();
    println!(
        "| terrain | sink, cm | named, cm | max tilt, deg | height drift, mm | horizontal drift, mm | base height, m |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for line in &results[..TERRAINS.len()] {
        println!("{line}");
    }
    println!();
    println!(
        "| terrain | seed | distance, m | phases | termination | R_t mean | tau_ave, N m | tracking RMS mean, rad | tracking RMS max, rad | stance-foot slip per phase, mm |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for line in &results[TERRAINS.len()..] {
        println!("{line}");
    }
    std::process::ExitCode::SUCCESS
}

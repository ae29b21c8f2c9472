//! The cost of one SAC or CrossQ gradient step with candle on this machine,
//! at the robot's sizes (102 observations, 27 actions), for choosing the
//! update-to-data ratio.
//!
//! ```sh
//! cargo run --release -p learn --example update_cost            # every setting below
//! cargo run --release -p learn --example update_cost -- 200     # steps per setting
//! ```
//!
//! Prints one line per setting: the median milliseconds per gradient step
//! (critics, and the actor and temperature on every `policy_delay`-th
//! step) over the timed steps, after 20 untimed ones. Single-threaded
//! unless candle's own threads are allowed (`RAYON_NUM_THREADS`).

use std::time::Instant;

use learn::sac::replay::ReplayBuffer;
use learn::sac::{SacAgent, SacConfig};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const OBS: usize = 102;
const ACTIONS: usize = 27;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let steps: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let settings: Vec<(&str, SacConfig)> = vec![
        (
            "SAC 256-256, batch 256 (SB3 defaults)",
            SacConfig::default(),
        ),
        (
            "SAC 256-128, batch 128",
            SacConfig {
                hidden_sizes: vec![256, 128],
                batch_size: 128,
                ..SacConfig::default()
            },
        ),
        (
            "CrossQ, critics 256-256, batch 256 (quadwalk's CrossQ defaults)",
            SacConfig::crossq(),
        ),
        (
            "CrossQ, critics 512-512, batch 256",
            SacConfig {
                critic_hidden_sizes: Some(vec![512, 512]),
                ..SacConfig::crossq()
            },
        ),
        (
            "CrossQ, critics 1024-1024, batch 256",
            SacConfig {
                critic_hidden_sizes: Some(vec![1024, 1024]),
                ..SacConfig::crossq()
            },
        ),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut buffer = ReplayBuffer::new(OBS, ACTIONS, 10_000);
    for _ in 0..10_000 {
        let obs: Vec<f32> = (0..OBS).map(|_| rng.random_range(-1.0..1.0)).collect();
        let next: Vec<f32> = (0..OBS).map(|_| rng.random_range(-1.0..1.0)).collect();
        let action: Vec<f32> = (0..ACTIONS).map(|_| rng.random_range(-1.0..1.0)).collect();
        buffer.push(&obs, &action, rng.random_range(-1.0..1.0), &next, false);
    }
    for (name, config) in settings {
        let batch_size = config.batch_size;
        let mut agent = SacAgent::new(config, OBS, ACTIONS, 0).expect("valid settings");
        let mut times = Vec::with_capacity(steps);
        for k in 0..steps + 20 {
            let batch = buffer.sample(batch_size, &mut rng);
            let t = Instant::now();
            agent.update(&batch).expect("update");
            if k >= 20 {
                times.push(t.elapsed().as_secs_f64() * 1e3);
            }
        }
        println!(
            "{name}: {:.1} ms per gradient step (median of {steps})",
            median(times)
        );
    }
}

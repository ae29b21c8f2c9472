//! `cargo bench -p robot`: physics steps per second of the Laikago standing,
//! one world on one thread, median of 5 timed runs of 10 simulated seconds
//! (no external harness; `quadwalk bench` measures several threads and phase
//! rates and is the figure BENCHMARKS.md records).

use std::sync::Arc;
use std::time::Instant;

use robot::{RobotModel, World, WorldConfig};
use terrain_plugins::{BuildContext, Registry};

fn main() {
    let model = Arc::new(RobotModel::laikago());
    let ctx = BuildContext {
        supported_mass_kg: model.total_mass_kg(),
        ..BuildContext::default()
    };
    for spec in [
        "rigid",
        "elastic:5cm:length=3m:back=1.5m:width=1m",
        "elastic:5cm",
    ] {
        let mut rates = Vec::new();
        for _ in 0..5 {
            let terrain = Registry::builtin().create(spec, &ctx).expect("valid spec");
            let mut world = World::new(model.clone(), terrain, WorldConfig::default(), [0.0, 0.0])
                .expect("robot fits");
            for _ in 0..240 {
                world.step();
            }
            let steps = 2400;
            let start = Instant::now();
            for _ in 0..steps {
                world.step();
            }
            rates.push(steps as f64 / start.elapsed().as_secs_f64());
        }
        rates.sort_by(f64::total_cmp);
        let median = rates[rates.len() / 2];
        println!(
            "{spec:<45} {median:>8.0} steps/s  ({:.1} us/step), median of 5",
            1e6 / median
        );
    }
}

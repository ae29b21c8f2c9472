//! What an iteration reports: the line of `metrics.jsonl` and the curves
//! streamed to Rerun. The algorithm's own figures go in under their names,
//! whichever algorithm trains.

use learn::{Figure, IterationStats};
use serde_json::json;

/// The curves streamed to Rerun per iteration: the episodes' return,
/// distance and length, every measured figure of the algorithm (counts are
/// left out), and the training rate.
pub fn curves(stats: &IterationStats) -> Vec<(String, f64)> {
    let episodes = &stats.episodes;
    let mut curves = vec![
        ("mean_return", episodes.mean_return),
        ("mean_distance_m", stats.episode_metric("distance_m")),
        ("mean_episode_length", episodes.mean_length),
    ];
    curves.extend(
        stats
            .figures
            .iter()
            .filter_map(|(name, figure)| match figure {
                Figure::Value(v) => Some((*name, Some(*v))),
                Figure::Count(_) | Figure::Missing => None,
            }),
    );
    curves.push(("phases_per_s", Some(stats.steps_per_sec)));
    curves
        .into_iter()
        .filter_map(|(n, v)| v.map(|v| (n.to_string(), v)))
        .collect()
}

/// The share of the iteration's ended episodes that each termination the
/// environment reports ended (`robot::task::Termination::KINDS`, `stalled`
/// only under a stall rule), null where no episode ended.
fn falls_by_cause(stats: &IterationStats) -> serde_json::Value {
    robot::task::Termination::KINDS
        .iter()
        .filter_map(|kind| {
            let name = format!("fell_{kind}");
            let (_, share) = stats.episodes.metrics.iter().find(|(n, _)| *n == name)?;
            Some((kind.to_string(), json!(share)))
        })
        .collect::<serde_json::Map<_, _>>()
        .into()
}

/// The JSON line of one iteration.
pub fn record(
    stats: &IterationStats,
    terrain: &terrain_plugins::TerrainSpec,
    logging_secs: f64,
) -> serde_json::Value {
    let episodes = &stats.episodes;
    let terms: serde_json::Map<String, serde_json::Value> = episodes
        .reward_terms
        .iter()
        .map(|(n, v)| (n.clone(), json!(v)))
        .collect();
    let mut record = json!({
        "iteration": stats.iteration,
        "terrain": terrain.to_string(),
        "phases": stats.steps,
        "episodes": episodes.episodes,
        "terminated": episodes.terminated,
        "mean_return": episodes.mean_return,
        "mean_episode_length": episodes.mean_length,
        "mean_distance_m": stats.episode_metric("distance_m"),
        "mean_goals_reached": stats.episode_metric("goals_reached"),
        "falls_by_cause": falls_by_cause(stats),
        "mean_phase_reward": episodes.mean_step_reward,
        "reward_terms": terms,
        "phases_per_s": stats.steps_per_sec,
    });
    let mut secs = serde_json::Map::new();
    secs.insert("env".into(), json!(stats.env_secs - logging_secs));
    secs.insert("logging".into(), json!(logging_secs));
    for (name, value) in &stats.secs {
        secs.insert(name.to_string(), json!(value));
    }
    if let Some(record) = record.as_object_mut() {
        for (name, figure) in &stats.figures {
            let value = match figure {
                Figure::Count(n) => json!(n),
                Figure::Value(v) => json!(v),
                Figure::Missing => serde_json::Value::Null,
            };
            record.insert(name.to_string(), value);
        }
        record.insert("secs".into(), serde_json::Value::Object(secs));
    }
    record
}

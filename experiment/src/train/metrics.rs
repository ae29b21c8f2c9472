//! What an iteration reports: the line of `metrics.jsonl` and the curves
//! streamed to Rerun.

use learn::LearnerStats;
use serde_json::json;

/// The curves streamed to Rerun per iteration.
pub fn curves(stats: &LearnerStats) -> Vec<(String, f64)> {
    let (mean_return, mean_length) = stats.episode_means();
    let mut curves = vec![
        ("mean_return", mean_return),
        ("mean_distance_m", stats.episode_metric("distance_m")),
        ("mean_episode_length", mean_length),
    ];
    match stats {
        LearnerStats::Ppo(s) => curves.extend([
            ("policy_loss", Some(s.policy_loss)),
            ("value_loss", Some(s.value_loss)),
            ("entropy", Some(s.entropy)),
            ("approx_kl", Some(s.approx_kl)),
            ("clip_fraction", Some(s.clip_fraction)),
            ("explained_variance", Some(s.explained_variance)),
            ("learning_rate", Some(s.learning_rate)),
        ]),
        LearnerStats::Sac(s) => curves.extend([
            ("critic_loss", s.critic_loss),
            ("actor_loss", s.actor_loss),
            ("alpha", Some(s.alpha)),
            ("entropy", s.entropy),
        ]),
    }
    curves.push(("phases_per_s", Some(stats.steps_per_sec())));
    curves
        .into_iter()
        .filter_map(|(n, v)| v.map(|v| (n.to_string(), v)))
        .collect()
}

/// The JSON line of one iteration.
pub fn record(
    stats: &LearnerStats,
    terrain: &terrain_plugins::TerrainSpec,
    logging_secs: f64,
) -> serde_json::Value {
    let (mean_step_reward, reward_terms) = stats.step_rewards();
    let terms: serde_json::Map<String, serde_json::Value> = reward_terms
        .iter()
        .map(|(n, v)| (n.clone(), json!(v)))
        .collect();
    let (episodes, terminated) = stats.episodes();
    let (mean_return, mean_length) = stats.episode_means();
    let mut record = json!({
        "iteration": stats.iteration(),
        "terrain": terrain.to_string(),
        "phases": stats.steps(),
        "episodes": episodes,
        "terminated": terminated,
        "mean_return": mean_return,
        "mean_episode_length": mean_length,
        "mean_distance_m": stats.episode_metric("distance_m"),
        "mean_goals_reached": stats.episode_metric("goals_reached"),
        "mean_phase_reward": mean_step_reward,
        "reward_terms": terms,
        "phases_per_s": stats.steps_per_sec(),
    });
    let fields = match stats {
        LearnerStats::Ppo(s) => json!({
            "policy_loss": s.policy_loss,
            "value_loss": s.value_loss,
            "entropy": s.entropy,
            "approx_kl": s.approx_kl,
            "clip_fraction": s.clip_fraction,
            "explained_variance": s.explained_variance,
            "grad_norm_actor": s.grad_norm.0,
            "grad_norm_critic": s.grad_norm.1,
            "action_std": s.action_std,
            "epochs": s.epochs,
            "learning_rate": s.learning_rate,
            "secs": {
                "env": s.env_secs - logging_secs,
                "logging": logging_secs,
                "inference": s.inference_secs,
                "update": s.update_secs,
            },
        }),
        LearnerStats::Sac(s) => json!({
            "total_phases": s.total_steps,
            "updates": s.updates,
            "critic_loss": s.critic_loss,
            "actor_loss": s.actor_loss,
            "alpha": s.alpha,
            "entropy": s.entropy,
            "secs": {
                "env": s.env_secs - logging_secs,
                "logging": logging_secs,
                "update": s.update_secs,
            },
        }),
    };
    if let (Some(record), Some(fields)) = (record.as_object_mut(), fields.as_object()) {
        record.extend(fields.clone());
    }
    record
}

//! Numbers in the results pages.

/// `value` to `decimals` places, without the minus sign of a value that
/// rounds to zero ("0.000", not "-0.000": a policy that stands still is
/// not going backwards).
pub fn fixed(value: f64, decimals: usize) -> String {
    let text = format!("{value:.decimals$}");
    match text.strip_prefix('-') {
        Some(magnitude) if magnitude.chars().all(|c| c == '0' || c == '.') => magnitude.to_string(),
        _ => text,
    }
}

/// A spread as a table cell: "mean (min-max)", each to `decimals` places
/// as [`fixed`] writes them.
pub fn mean_and_range(spread: &experiment::eval::summary::Spread, decimals: usize) -> String {
    format!(
        "{} ({}-{})",
        fixed(spread.mean, decimals),
        fixed(spread.min, decimals),
        fixed(spread.max, decimals)
    )
}

/// An evaluation's success as a table cell: "successes/episodes", and
/// each seed set's successes after it when there were several sets
/// ("27/30 (9, 8, 10)"), since a bar like 9 of 10 holds per set.
pub fn success(report: &experiment::eval::EvalReport) -> String {
    let s = &report.summary;
    let pooled = format!("{}/{}", s.successes, s.episodes);
    if report.seed_sets.len() < 2 {
        return pooled;
    }
    let per_set: Vec<String> = report
        .seed_sets
        .iter()
        .map(|set| set.successes.to_string())
        .collect();
    format!("{pooled} ({})", per_set.join(", "))
}

#[cfg(test)]
mod tests {
    use super::{fixed, mean_and_range, success};

    #[test]
    fn a_value_that_rounds_to_zero_has_no_sign() {
        assert_eq!(fixed(-0.0002, 3), "0.000");
        assert_eq!(fixed(-0.0, 2), "0.00");
        assert_eq!(fixed(-0.0006, 3), "-0.001");
        assert_eq!(fixed(0.0494, 3), "0.049");
        assert_eq!(fixed(-1.5, 1), "-1.5");
        assert_eq!(fixed(-0.4, 0), "0");
    }

    #[test]
    fn a_spread_reads_mean_then_range() {
        let mut spread = experiment::eval::summary::Spread::of(&[0.42, 19.9, 20.03]);
        assert_eq!(mean_and_range(&spread, 2), "13.45 (0.42-20.03)");
        spread.min = -0.001;
        assert_eq!(mean_and_range(&spread, 2), "13.45 (0.00-20.03)");
    }

    #[test]
    fn a_success_shows_each_seed_sets_share_when_there_are_several() {
        use experiment::eval::seed_sets::SeedSetSummary;
        let set = |first_seed, successes| SeedSetSummary {
            first_seed,
            episodes: 2,
            successes,
            mean_distance_m: 1.0,
        };
        let mut summary = experiment::eval::summary::Summary::of(&[], 0.75);
        (summary.successes, summary.episodes) = (3, 4);
        let mut report = experiment::eval::EvalReport {
            format: "quadwalk-eval/1".into(),
            policy: "p".into(),
            terrain: "rigid".into(),
            first_seed: 7,
            max_phases: 400,
            stochastic: false,
            task_overrides: Vec::new(),
            step_rate_hz: 240,
            summary,
            seed_sets: vec![set(7, 2), set(41, 1)],
            episodes: Vec::new(),
        };
        assert_eq!(success(&report), "3/4 (2, 1)");
        report.seed_sets.truncate(1);
        assert_eq!(success(&report), "3/4");
    }
}

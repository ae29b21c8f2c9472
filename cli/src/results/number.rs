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

#[cfg(test)]
mod tests {
    use super::{fixed, mean_and_range};

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
}

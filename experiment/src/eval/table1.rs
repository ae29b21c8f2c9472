//! The paper's Table I: mean and standard deviation of the base height h_b
//! and the mean target landing height of each foot relative to the squat,
//! in cm, one column per terrain type (definitions in `record.rs`).

use super::summary::{MeanStd, TerrainSummary};

/// Rows of Table I in the paper's order, then the spreads of the landing
/// heights and the phases behind each column.
const FEET: [(&str, &str); 4] = [("fr", "FR"), ("fl", "FL"), ("rr", "RR"), ("rl", "RL")];

fn cm(value: Option<f64>) -> String {
    value.map_or("-".to_string(), |v| format!("{:.1}", v * 100.0))
}

/// Table I as Markdown: `columns` are (heading, figures) pairs.
pub fn markdown(columns: &[(String, &TerrainSummary)]) -> String {
    let mut rows: Vec<(String, Vec<String>)> = vec![
        (
            "sigma(h_b)".into(),
            columns
                .iter()
                .map(|(_, t)| cm(t.base_height_m.std))
                .collect(),
        ),
        (
            "mu(h_b)".into(),
            columns
                .iter()
                .map(|(_, t)| cm(t.base_height_m.mean))
                .collect(),
        ),
    ];
    let foot = |t: &TerrainSummary, key: &str| -> MeanStd {
        t.landing_height_m.get(key).copied().unwrap_or(MeanStd {
            mean: None,
            std: None,
            count: 0,
        })
    };
    for (short, key) in FEET {
        rows.push((
            format!("mu({short})"),
            columns.iter().map(|(_, t)| cm(foot(t, key).mean)).collect(),
        ));
    }
    for (short, key) in FEET {
        rows.push((
            format!("sigma({short})"),
            columns.iter().map(|(_, t)| cm(foot(t, key).std)).collect(),
        ));
    }
    rows.push((
        "phases".into(),
        columns.iter().map(|(_, t)| t.phases.to_string()).collect(),
    ));
    let mut out = String::from("| (cm) |");
    for (heading, _) in columns {
        out.push_str(&format!(" {heading} |"));
    }
    out.push_str("\n| --- |");
    for _ in columns {
        out.push_str(" ---: |");
    }
    out.push('\n');
    for (name, cells) in rows {
        out.push_str(&format!("| {name} |"));
        for cell in cells {
            out.push_str(&format!(" {cell} |"));
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::super::record::TerrainSamples;
    use super::super::summary::angle_bin_centre_deg;
    use super::*;
    use robot::model::LegName;
    use robot::task::SWING_ORDER;

    /// One four-phase cycle whose answers are known by hand: in the phase of
    /// swing slot s (FL, RR, FR, RL) h_b is 30 + s cm at every step, and the
    /// swing foot is sent to land (10 - 5 s) cm above its squat height.
    fn crafted_cycle() -> TerrainSamples {
        let mut s = TerrainSamples::default();
        for (slot, &leg) in SWING_ORDER.iter().enumerate() {
            s.phases += 1;
            s.landing_height_m[leg.index()].add(0.10 - 0.05 * slot as f64);
            for i in 1..=180 {
                s.add_step(leg, i, 180, 0.30 + 0.01 * slot as f64);
            }
        }
        s
    }

    #[test]
    fn table_one_and_figure_four_of_a_crafted_cycle() {
        let t = TerrainSummary::from_samples("elastic:5cm", &crafted_cycle(), 0.75);
        // mu(h_b) = mean(30, 31, 32, 33) = 31.5 cm; sigma = sqrt(mean of
        // (1.5^2, 0.5^2, 0.5^2, 1.5^2)) = sqrt(1.25) cm
        assert!((t.base_height_m.mean.unwrap() - 0.315).abs() < 1e-9);
        assert!((t.base_height_m.std.unwrap() - 0.0125f64.sqrt() / 10.0).abs() < 1e-9);
        assert_eq!(t.base_height_m.count, 720);
        // landing: FL slot 0 -> 10 cm, RR 1 -> 5 cm, FR 2 -> 0, RL 3 -> -5 cm
        let landing = |leg: LegName| t.landing_height_m[leg.short()].mean.unwrap();
        assert!((landing(LegName::FrontLeft) - 0.10).abs() < 1e-12);
        assert!((landing(LegName::RearRight) - 0.05).abs() < 1e-12);
        assert!(landing(LegName::FrontRight).abs() < 1e-12);
        assert!((landing(LegName::RearLeft) + 0.05).abs() < 1e-12);
        // Fig. 4: each quarter of the cycle holds its phase's height, two
        // steps per 1-degree bin, no spread
        assert_eq!(t.base_height_by_angle_m.len(), 360);
        for (bin, b) in t.base_height_by_angle_m.iter().enumerate() {
            let quarter = (angle_bin_centre_deg(bin) / 90.0) as usize;
            assert_eq!(b.count, 2, "bin {bin}");
            assert!((b.mean.unwrap() - (0.30 + 0.01 * quarter as f64)).abs() < 1e-12);
            assert!(b.std.unwrap() < 1e-6);
        }
        let md = markdown(&[("T_c^5".into(), &t)]);
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(lines[0], "| (cm) | T_c^5 |");
        assert_eq!(lines[2], "| sigma(h_b) | 1.1 |");
        assert_eq!(lines[3], "| mu(h_b) | 31.5 |");
        assert_eq!(lines[4], "| mu(fr) | 0.0 |");
        assert_eq!(lines[5], "| mu(fl) | 10.0 |");
        assert_eq!(lines[6], "| mu(rr) | 5.0 |");
        assert_eq!(lines[7], "| mu(rl) | -5.0 |");
        assert_eq!(lines.last().unwrap(), &"| phases | 4 |");
    }

    #[test]
    fn a_column_without_samples_prints_dashes() {
        let t = TerrainSummary::from_samples("rigid", &TerrainSamples::default(), 0.75);
        let md = markdown(&[("rigid".into(), &t)]);
        assert!(md.contains("| mu(h_b) | - |"), "{md}");
    }
}

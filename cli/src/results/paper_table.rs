//! The paper's Table I (and Fig. 4) from the four scenario policies, each
//! cell beside the paper's value, and the paper's four findings about it
//! checked against our numbers.
//!
//! The paper's columns: T_v2^ave is the T_v2 policy on T_v2 with every
//! region pooled, T_v2^2 and T_v2^5 the same episodes' phases on 2 cm and
//! 5 cm regions (the terrain under the base at the phase's start), T_v8^2
//! and T_v8^5 likewise for the T_v8 policy on T_v8, T_c^2 and T_c^5 the
//! constant-stiffness policies on their own terrain. Rows: sigma(h_b) and
//! mu(h_b), the base height over every physics step; mu(fr) .. mu(rl), the
//! swing foot's target landing height relative to its squat height (cm).

use std::fmt::Write as _;

use experiment::eval::summary::{ALL_TERRAIN, MeanStd, TerrainSummary};

/// The paper's terrain specs of its four scenarios.
pub const SCENARIO_TERRAINS: [(&str, &str); 4] = [
    ("tv2", "varying:2m:2,3,4,5cm,rigid"),
    ("tv8", "varying:8m:2,3,4,5cm,rigid"),
    ("tc2", "elastic:2cm"),
    ("tc5", "elastic:5cm"),
];

/// One column of Table I: its heading, the scenario whose evaluation it
/// reads, and the terrain type within it.
pub struct Column {
    /// the paper's heading
    pub heading: &'static str,
    /// the scenario (`tv2`, `tv8`, `tc2`, `tc5`)
    pub scenario: &'static str,
    /// the terrain type label ([`ALL_TERRAIN`] for every phase pooled)
    pub terrain_type: &'static str,
}

/// The paper's seven columns, in its order.
pub const COLUMNS: [Column; 7] = [
    Column {
        heading: "T_v2^ave",
        scenario: "tv2",
        terrain_type: ALL_TERRAIN,
    },
    Column {
        heading: "T_v2^2",
        scenario: "tv2",
        terrain_type: "elastic:2cm",
    },
    Column {
        heading: "T_v2^5",
        scenario: "tv2",
        terrain_type: "elastic:5cm",
    },
    Column {
        heading: "T_v8^2",
        scenario: "tv8",
        terrain_type: "elastic:2cm",
    },
    Column {
        heading: "T_v8^5",
        scenario: "tv8",
        terrain_type: "elastic:5cm",
    },
    Column {
        heading: "T_c^2",
        scenario: "tc2",
        terrain_type: ALL_TERRAIN,
    },
    Column {
        heading: "T_c^5",
        scenario: "tc5",
        terrain_type: ALL_TERRAIN,
    },
];

/// The rows, in the paper's order.
pub const ROWS: [&str; 6] = [
    "sigma(h_b)",
    "mu(h_b)",
    "mu(fr)",
    "mu(fl)",
    "mu(rr)",
    "mu(rl)",
];

/// The paper's Table I, cm: `PAPER[row][column]` in [`ROWS`] and
/// [`COLUMNS`] order (Kim and Lee, Table I).
pub const PAPER: [[f64; 7]; 6] = [
    [3.1, 3.2, 3.2, 3.2, 3.1, 3.3, 2.9],
    [33.1, 33.7, 32.8, 33.0, 32.6, 35.8, 33.5],
    [13.8, 13.0, 12.6, 6.3, 6.8, 6.9, 14.4],
    [5.4, 5.9, 4.5, -0.7, 0.2, 1.1, 6.1],
    [-1.7, -2.3, -2.9, -7.7, -5.6, -6.3, -1.8],
    [-9.7, -10.5, -10.1, -14.8, -11.8, -14.8, -8.9],
];

/// Two columns' landing heights "differ" when some foot's means are at
/// least this far apart, cm. The paper calls T_v2^2 and T_v2^5 alike with
/// at most 1.4 cm between them, and T_c^2 and T_c^5 different with at least
/// 4.5 cm; the line lies between.
pub const DIFFER_CM: f64 = 2.0;

/// The base height is "alike across columns" when its means span at most
/// this much, cm (the paper's own span: 32.6-35.8).
pub const ALIKE_MEAN_SPAN_CM: f64 = 3.2;

/// ... and its standard deviations at most this much, cm (the paper's:
/// 2.9-3.3).
pub const ALIKE_STD_SPAN_CM: f64 = 1.0;

/// Our value of each cell, cm (`None` where the column has no phases).
pub type Ours = [[Option<f64>; 7]; 6];

/// Reads our cells from each column's terrain summary (`None`: the scenario
/// was not evaluated or never walked on that terrain type).
pub fn ours(columns: &[Option<&TerrainSummary>; 7]) -> Ours {
    let mut cells = [[None; 7]; 6];
    for (c, t) in columns.iter().enumerate() {
        let Some(t) = t else { continue };
        let foot = |key: &str| t.landing_height_m.get(key).and_then(|m: &MeanStd| m.mean);
        let values = [
            t.base_height_m.std,
            t.base_height_m.mean,
            foot("FR"),
            foot("FL"),
            foot("RR"),
            foot("RL"),
        ];
        for (r, v) in values.into_iter().enumerate() {
            cells[r][c] = v.map(|m| 100.0 * m);
        }
    }
    cells
}

fn cell(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.1}"))
}

/// Table I as Markdown: `ours / paper` in each cell, then the phases
/// behind each column.
pub fn markdown(ours: &Ours, phases: &[usize; 7]) -> String {
    let mut out = String::from("| cm, ours / paper |");
    for c in &COLUMNS {
        let _ = write!(out, " {} |", c.heading);
    }
    out.push_str("\n| --- |");
    out.push_str(&" ---: |".repeat(COLUMNS.len()));
    out.push('\n');
    for (r, row) in ROWS.iter().enumerate() {
        let _ = write!(out, "| {row} |");
        for c in 0..COLUMNS.len() {
            let _ = write!(out, " {} / {:.1} |", cell(ours[r][c]), PAPER[r][c]);
        }
        out.push('\n');
    }
    out.push_str("| phases (ours) |");
    for p in phases {
        let _ = write!(out, " {p} |");
    }
    out.push('\n');
    out
}

/// The largest per-foot difference between columns `a` and `b` of `t`, cm,
/// with the foot's row; `None` when a foot is missing.
fn foot_gap(t: &[[Option<f64>; 7]; 6], a: usize, b: usize) -> Option<(f64, [f64; 4])> {
    let mut gaps = [0.0; 4];
    for (k, gap) in gaps.iter_mut().enumerate() {
        *gap = (t[2 + k][a]? - t[2 + k][b]?).abs();
    }
    Some((gaps.iter().cloned().fold(0.0, f64::max), gaps))
}

/// Column index by heading.
fn col(heading: &str) -> usize {
    COLUMNS
        .iter()
        .position(|c| c.heading == heading)
        .expect("a paper column")
}

/// One of the paper's findings, checked.
pub struct Finding {
    /// (a) .. (d)
    pub key: &'static str,
    /// what the paper says
    pub claim: &'static str,
    /// whether our numbers say the same (`None`: a column is missing)
    pub holds: Option<bool>,
    /// our numbers, and the paper's
    pub evidence: String,
}

fn gaps_text(gaps: &[f64; 4]) -> String {
    format!(
        "fr {:.1}, fl {:.1}, rr {:.1}, rl {:.1} cm",
        gaps[0], gaps[1], gaps[2], gaps[3]
    )
}

/// The paper's four findings about Table I, checked on `ours` (and, for
/// comparison, on the paper's own values with the same rule).
pub fn findings(ours: &Ours) -> Vec<Finding> {
    let paper: [[Option<f64>; 7]; 6] = PAPER.map(|row| row.map(Some));
    let pair = |a: &str, b: &str| {
        let (ia, ib) = (col(a), col(b));
        (foot_gap(ours, ia, ib), foot_gap(&paper, ia, ib))
    };
    let mut out = Vec::new();

    let (o, p) = pair("T_c^2", "T_c^5");
    out.push(Finding {
        key: "(a)",
        claim: "T_c^2 and T_c^5 land their feet at different heights",
        holds: o.map(|(max, _)| max >= DIFFER_CM),
        evidence: format!(
            "Per-foot gaps between T_c^2 and T_c^5: ours {}; the paper's {}",
            o.map_or("-".into(), |(_, g)| gaps_text(&g)),
            p.map_or("-".into(), |(_, g)| gaps_text(&g))
        ),
    });

    let (o, p) = pair("T_v2^2", "T_v2^5");
    out.push(Finding {
        key: "(b)",
        claim: "T_v2's 2 cm and 5 cm columns are alike (one conservative gait)",
        holds: o.map(|(max, _)| max < DIFFER_CM),
        evidence: format!(
            "Per-foot gaps between T_v2^2 and T_v2^5: ours {}; the paper's {}",
            o.map_or("-".into(), |(_, g)| gaps_text(&g)),
            p.map_or("-".into(), |(_, g)| gaps_text(&g))
        ),
    });

    let (o, p) = pair("T_v8^2", "T_v8^5");
    let rear_most = |g: &[f64; 4]| (g[2] + g[3]) > (g[0] + g[1]);
    out.push(Finding {
        key: "(c)",
        claim: "T_v8's 2 cm and 5 cm columns differ, the rear feet most",
        holds: o.map(|(max, g)| max >= DIFFER_CM && rear_most(&g)),
        evidence: format!(
            "Per-foot gaps between T_v8^2 and T_v8^5: ours {}; the paper's {}",
            o.map_or("-".into(), |(_, g)| gaps_text(&g)),
            p.map_or("-".into(), |(_, g)| gaps_text(&g))
        ),
    });

    let span = |t: &[[Option<f64>; 7]; 6], row: usize| -> Option<(f64, f64)> {
        let values: Vec<f64> = t[row].iter().flatten().copied().collect();
        (values.len() == 7).then(|| {
            values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                })
        })
    };
    let (mean_o, std_o) = (span(ours, 1), span(ours, 0));
    let (mean_p, std_p) = (span(&paper, 1), span(&paper, 0));
    let show = |s: Option<(f64, f64)>| s.map_or("-".into(), |(lo, hi)| format!("{lo:.1}-{hi:.1}"));
    out.push(Finding {
        key: "(d)",
        claim: "mu(h_b) and sigma(h_b) are alike across the columns",
        holds: match (mean_o, std_o) {
            (Some((ml, mh)), Some((sl, sh))) => {
                Some(mh - ml <= ALIKE_MEAN_SPAN_CM && sh - sl <= ALIKE_STD_SPAN_CM)
            }
            _ => None,
        },
        evidence: format!(
            "mu(h_b) spans {} cm (the paper's {}), sigma(h_b) {} cm (the paper's {})",
            show(mean_o),
            show(mean_p),
            show(std_o),
            show(std_p)
        ),
    });
    out
}

/// The findings as a Markdown list.
pub fn findings_markdown(findings: &[Finding]) -> String {
    let mut out = String::new();
    for f in findings {
        let verdict = match f.holds {
            Some(true) => "**holds**",
            Some(false) => "**does not hold**",
            None => "**not checked** (a column has no phases)",
        };
        let _ = writeln!(
            out,
            "- {} The paper: {}. Ours: {verdict}. {}.",
            f.key, f.claim, f.evidence
        );
    }
    out
}

/// Relabels a scenario's pooled terrain summary for Fig. 4's legend.
pub fn fig4_curve(label: &str, summary: &TerrainSummary) -> TerrainSummary {
    let mut curve = summary.clone();
    curve.terrain = label.to_string();
    curve
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_papers_own_table_gives_the_papers_findings() {
        // Checked on the paper's values, the rules reproduce what the
        // paper concludes from them.
        let paper: Ours = PAPER.map(|row| row.map(Some));
        let f = findings(&paper);
        let holds: Vec<Option<bool>> = f.iter().map(|f| f.holds).collect();
        assert_eq!(holds, [Some(true); 4]);
        // its mu(h_b) spans 3.2 cm (32.6-35.8), its sigma(h_b) 0.4 cm
        assert!(f[3].evidence.contains("32.6-35.8"), "{}", f[3].evidence);
    }

    #[test]
    fn the_table_puts_ours_beside_the_papers() {
        let mut ours: Ours = [[None; 7]; 6];
        ours[1][0] = Some(31.25);
        let md = markdown(&ours, &[4, 0, 0, 0, 0, 0, 0]);
        let lines: Vec<&str> = md.lines().collect();
        assert_eq!(
            lines[0],
            "| cm, ours / paper | T_v2^ave | T_v2^2 | T_v2^5 | T_v8^2 | T_v8^5 | T_c^2 | T_c^5 |"
        );
        assert!(
            lines[3].starts_with("| mu(h_b) | 31.2 / 33.1 | - / 33.7 |"),
            "{}",
            lines[3]
        );
        assert_eq!(
            lines.last().unwrap(),
            &"| phases (ours) | 4 | 0 | 0 | 0 | 0 | 0 | 0 |"
        );
        let f = findings(&ours);
        assert!(f.iter().all(|f| f.holds.is_none()));
    }
}

//! Controllers side by side (the paper's future work, issue 42): each
//! controller's success and speed on terrains, and its response to a
//! terrain that changes under it (level change, excess dip, recovery
//! time), as tables and one figure of the mean response.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;

use super::grid::terrain_grid;
use super::number::{fixed, success};
use crate::eval::plots::{self, Curve, Panel};
use experiment::eval::EvalReport;
use experiment::eval::response::profile_bin_secs;

/// One controller's evaluation on one terrain.
pub struct Cell<'a> {
    /// the row's name
    pub name: &'a str,
    /// the terrain spec
    pub terrain: &'a str,
    /// its evaluation (every seed set)
    pub report: &'a EvalReport,
}

/// The success and speed table (controllers down, terrains across).
pub fn terrain_table(rows: &[(&str, &str)], terrains: &[String], cells: &[Cell]) -> String {
    let grid = terrain_grid(
        &["controller", "policy"],
        rows,
        |(name, policy)| vec![name.to_string(), policy.to_string()],
        terrains,
        |(name, _), t| {
            find(cells, name, t).map(|c| {
                format!(
                    "{}, {} m/s",
                    success(c.report),
                    fixed(c.report.summary.mean_speed_m_per_s.mean, 3)
                )
            })
        },
    );
    format!(
        "Episodes that ran every phase without a fall, of those run, and the mean speed (distance along x over the simulated time, per episode):\n\n{grid}"
    )
}

/// The response table: one row per controller and change.
pub fn response_table(rows: &[(&str, &str)], changes: &[String], cells: &[Cell]) -> String {
    let mut out = String::from(
        "The base's height above the ground at rest, z_b, around the change (`quadwalk eval`'s response; docs/guide/evaluation.md): the level change L1 - L0 (means over the 3 s before and 3-6 s after), the excess dip (how much further below the lower level the base goes in the 3 s after the change than it went below its own level in the walk before) and the recovery time (until the one-phase mean of z_b stays within the walk's own band of the new level), mean (max) over the episodes that walked through the window; falls: the episodes that fell at any time in their phases, before the window's end or after it.\n\n| controller | change | episodes through | level change, cm | excess dip, cm | recovery, s | falls |\n| --- | --- | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for (name, _) in rows {
        for t in changes {
            let Some(c) = find(cells, name, t) else {
                continue;
            };
            let s = &c.report.summary;
            let falls = s.episodes - s.successes;
            match &s.change_response {
                Some(r) if r.episodes > 0 => {
                    let _ = writeln!(
                        out,
                        "| {name} | `{t}` | {}/{} | {:+.2} | {:.2} ({:.2}) | {:.2} ({:.2}) | {falls} |",
                        r.episodes,
                        s.episodes,
                        100.0 * r.level_change_m.mean,
                        100.0 * r.excess_dip_m.mean,
                        100.0 * r.excess_dip_m.max,
                        r.recovery_secs.mean,
                        r.recovery_secs.max,
                    );
                }
                _ => {
                    let _ = writeln!(
                        out,
                        "| {name} | `{t}` | 0/{} | - | - | - | {falls} |",
                        s.episodes
                    );
                }
            }
        }
    }
    out
}

/// The figure: per change, each controller's mean z_b - L0 around the
/// change.
pub fn response_png(
    path: &Path,
    rows: &[(&str, &str)],
    changes: &[String],
    cells: &[Cell],
) -> Result<()> {
    // the panels sit side by side: the change's spec alone fits its width
    // (the y axis says what is drawn)
    let titles: Vec<String> = changes.to_vec();
    let lines: Vec<Vec<Curve>> = changes
        .iter()
        .map(|t| {
            rows.iter()
                .enumerate()
                .filter_map(|(k, (name, _))| {
                    let r = find(cells, name, t)?
                        .report
                        .summary
                        .change_response
                        .as_ref()?;
                    let points: Vec<(f64, f64)> = r
                        .mean_profile_m
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| v.is_finite())
                        .map(|(i, v)| (profile_bin_secs(i), 100.0 * v))
                        .collect();
                    (!points.is_empty()).then(|| Curve {
                        label: format!("{name} ({} episodes)", r.episodes),
                        colour_index: k,
                        points,
                    })
                })
                .collect()
        })
        .collect();
    let panels: Vec<Panel> = titles
        .iter()
        .zip(&lines)
        .map(|(title, lines)| Panel {
            title,
            x_desc: "seconds from the change",
            y_desc: "z_b - L0, cm (mean over episodes)",
            lines,
        })
        .collect();
    plots::panels(path, &panels)
}

fn find<'a>(cells: &'a [Cell], name: &str, terrain: &str) -> Option<&'a Cell<'a>> {
    cells
        .iter()
        .find(|c| c.name == name && c.terrain == terrain)
}

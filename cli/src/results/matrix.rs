//! Every policy on every terrain: success, distance, speed, cost of
//! transport, foot slip and falls by cause per cell.

use std::fmt::Write as _;

use super::grid::terrain_grid;
use super::number::{fixed, mean_and_range, success};
use experiment::eval::EvalReport;

/// One cell: a policy's evaluation on a terrain, with the commands that
/// ran it.
pub struct Cell<'a> {
    /// the policy path
    pub policy: &'a str,
    /// the terrain spec
    pub terrain: &'a str,
    /// its evaluation (every seed set)
    pub report: &'a EvalReport,
    /// the `quadwalk eval` commands, one per seed set
    pub commands: Vec<String>,
}

/// The success grid (policies down, terrains across), then one row per
/// cell with every measure and its commands.
pub fn markdown(policies: &[String], terrains: &[String], cells: &[Cell]) -> String {
    let find = |p: &str, t: &str| cells.iter().find(|c| c.policy == p && c.terrain == t);
    let mut out = String::from(
        "Episodes that ran every phase without a fall, of those run (all seed sets together, then each set's when there are several):\n\n",
    );
    out.push_str(&terrain_grid(
        &["policy"],
        policies,
        |p| vec![p.clone()],
        terrains,
        |p, t| find(p, t).map(|c| success(c.report)),
    ));
    out.push_str(
        "\nPer cell: speed is the distance along x over the simulated time, per episode (mean); the cost of transport is the joints' mechanical energy (the sum over steps of |tau q_dot| dt) over m g times the distance, all episodes pooled; foot slip is the horizontal travel of the feet while they touch the ground, per phase (mean over episodes).\n\n| policy | terrain | success | distance, m (mean; min-max) | speed, m/s | cost of transport | foot slip, cm/phase | falls by cause |\n| --- | --- | ---: | --- | ---: | ---: | ---: | --- |\n",
    );
    for p in policies {
        for t in terrains {
            let Some(c) = find(p, t) else { continue };
            let s = &c.report.summary;
            let _ = writeln!(
                out,
                "| {p} | `{t}` | {} | {} | {} | {} | {:.2} | {} |",
                success(c.report),
                mean_and_range(&s.distance_m, 2),
                fixed(s.mean_speed_m_per_s.mean, 3),
                s.cost_of_transport
                    .map_or("-".into(), |v| format!("{v:.2}")),
                100.0 * s.foot_slip_m_per_phase.mean,
                falls_cell(s)
            );
        }
    }
    out.push_str("\nThe commands of each cell (one `quadwalk eval` per seed set):\n\n```sh\n");
    for c in cells {
        for command in &c.commands {
            let _ = writeln!(out, "{command}");
        }
    }
    out.push_str("```\n");
    out
}

/// A cell's falls by cause, and how many of them came at the far end of
/// the terrain (the episode outran the field: not a fault of the gait).
fn falls_cell(s: &experiment::eval::summary::Summary) -> String {
    match s.falls_at_terrain_end {
        0 => s.falls_text(),
        n => format!(
            "{} ({n} at the end of the terrain: walked off it)",
            s.falls_text()
        ),
    }
}

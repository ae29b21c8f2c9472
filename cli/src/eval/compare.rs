//! `quadwalk eval --compare DIR DIR ...`: several evaluations side by side,
//! a Table I across scenarios like the paper's and a summary row each.

use std::path::Path;

use anyhow::{Context, Result};

use super::summary::TerrainSummary;
use super::{EvalReport, table_columns, table1};

/// The Markdown comparison of `reports` (named by their directories).
pub fn markdown(reports: &[(String, EvalReport)]) -> String {
    let mut out = String::from(
        "| evaluation | policy | terrain | episodes | success | distance mean (m) | median | p10 | p90 | falls |\n| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n",
    );
    for (name, r) in reports {
        let s = &r.summary;
        let falls: Vec<String> = s
            .falls_by_cause
            .iter()
            .map(|(c, n)| format!("{c} {n}"))
            .collect();
        out.push_str(&format!(
            "| {name} | {} | {} | {} | {:.0} % | {:.2} | {:.2} | {:.2} | {:.2} | {} |\n",
            r.policy,
            r.terrain,
            s.episodes,
            100.0 * s.success_rate,
            s.distance_m.mean,
            s.distance_m.median,
            s.distance_m.p10,
            s.distance_m.p90,
            if falls.is_empty() {
                "none".to_string()
            } else {
                falls.join(", ")
            }
        ));
    }
    let columns: Vec<(String, &TerrainSummary)> = reports
        .iter()
        .flat_map(|(name, r)| {
            table_columns(&r.summary)
                .into_iter()
                .map(move |t| (format!("{name}: {}", t.terrain), t))
        })
        .collect();
    out.push_str("\nTable I (cm)\n\n");
    out.push_str(&table1::markdown(&columns));
    out
}

/// Reads the evaluations in `dirs` and prints (and with `out`, writes
/// `compare.md`) their comparison.
pub fn compare(dirs: &[std::path::PathBuf], out: Option<&Path>, json: bool) -> Result<()> {
    let reports = dirs
        .iter()
        .map(|dir| {
            let name = dir.file_name().map_or(dir.display().to_string(), |n| {
                n.to_string_lossy().to_string()
            });
            Ok((name, EvalReport::read(dir)?))
        })
        .collect::<Result<Vec<_>>>()?;
    let text = markdown(&reports);
    if let Some(dir) = out {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("--out {}: cannot create the directory", dir.display()))?;
        let path = dir.join("compare.md");
        std::fs::write(&path, &text).with_context(|| format!("cannot write {}", path.display()))?;
    }
    if json {
        let value: Vec<_> = reports
            .iter()
            .map(|(name, r)| {
                serde_json::json!({
                    "evaluation": name,
                    "policy": r.policy,
                    "terrain": r.terrain,
                    "summary": r.summary,
                })
            })
            .collect();
        out!("{}", serde_json::Value::Array(value));
    } else {
        for line in text.lines() {
            out!("{line}");
        }
    }
    Ok(())
}

//! A markdown grid with terrains across: leading columns that name each
//! row, then one cell per terrain (the matrix's success grid, the
//! controllers' success and speed table).

use std::fmt::Write as _;

/// The header (`leading` then each terrain, in backticks), the alignment
/// row (terrain cells right-aligned) and one line per row: its
/// `leading_cells`, then `cell` of each terrain ("-" where it gives none).
pub fn terrain_grid<R>(
    leading: &[&str],
    rows: &[R],
    leading_cells: impl Fn(&R) -> Vec<String>,
    terrains: &[String],
    cell: impl Fn(&R, &str) -> Option<String>,
) -> String {
    let mut out = String::from("|");
    for name in leading {
        let _ = write!(out, " {name} |");
    }
    for t in terrains {
        let _ = write!(out, " `{t}` |");
    }
    out.push_str("\n|");
    out.push_str(&" --- |".repeat(leading.len()));
    out.push_str(&" ---: |".repeat(terrains.len()));
    out.push('\n');
    for row in rows {
        out.push('|');
        for text in leading_cells(row) {
            let _ = write!(out, " {text} |");
        }
        for t in terrains {
            let text = cell(row, t).unwrap_or_else(|| "-".into());
            let _ = write!(out, " {text} |");
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_has_a_header_an_alignment_row_and_a_line_per_row() {
        let terrains = vec!["rigid".to_string(), "soil:4cm".to_string()];
        let grid = terrain_grid(
            &["policy"],
            &["a", "b"],
            |p| vec![p.to_string()],
            &terrains,
            |p, t| (*p == "a" || t == "rigid").then(|| format!("{p} on {t}")),
        );
        assert_eq!(
            grid,
            "| policy | `rigid` | `soil:4cm` |\n| --- | ---: | ---: |\n| a | a on rigid | a on soil:4cm |\n| b | b on rigid | - |\n"
        );
    }
}

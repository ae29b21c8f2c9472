//! `--task KEY=VALUE`: a `[task]` setting given on the command line, on top
//! of the scene's task: what judges an evaluation (its terminations and
//! rewards), e.g. `quadwalk eval --policy P --terrain soil:4cm --task
//! base_height_reference=feet`.
//!
//! VALUE is read as a TOML value (`0.15`, `[0.0, 1.0]`, `"feet"`); a word
//! that is not one is a string, so `base_height_reference=feet` needs no
//! quotes. The keys that set the networks' input (`observation`,
//! `action_prior`) and how the actions are read (`swing_height_reference`)
//! are refused: a trained policy brings its own, and the crawl reads no
//! input.

use robot::task::TaskConfig;

use super::curriculum::FIXED_TASK_KEYS;
use super::defaults::overlay;

/// One `KEY=VALUE`, read.
fn parse(text: &str) -> Result<(String, toml::Value), String> {
    let Some((key, value)) = text.split_once('=') else {
        return Err(format!(
            "--task {text:?}: expected KEY=VALUE, e.g. base_height_reference=feet"
        ));
    };
    let (key, value) = (key.trim(), value.trim());
    if key.is_empty() || value.is_empty() {
        return Err(format!(
            "--task {text:?}: expected KEY=VALUE, e.g. base_height_reference=feet"
        ));
    }
    if let Some(fixed) = FIXED_TASK_KEYS
        .iter()
        .find(|k| key == **k || key.starts_with(&format!("{k}.")))
    {
        return Err(format!(
            "--task {text:?}: {fixed} sets the networks' input, which a trained policy brings with it (and the crawl reads none); it cannot be changed for a run"
        ));
    }
    if key == "swing_height_reference" {
        return Err(format!(
            "--task {text:?}: swing_height_reference says how the policy's actions are read, which a trained policy brings with it; it cannot be changed for a run"
        ));
    }
    let value = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.to_string()));
    Ok((key.to_string(), value))
}

/// `task` with each of `overrides` (`KEY=VALUE`) on top, checked; errors
/// name the override.
pub fn apply_task_overrides(task: &TaskConfig, overrides: &[String]) -> Result<TaskConfig, String> {
    let mut result = task.clone();
    for text in overrides {
        let (key, value) = parse(text)?;
        let table = toml::Table::from_iter([(key, value)]);
        result = overlay(&result, Some(&table)).map_err(|e| format!("--task {text:?}: {e}"))?;
        result
            .validate()
            .map_err(|e| format!("--task {text:?}: {e}"))?;
    }
    Ok(result)
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::task::{BaseHeightReference, PitchReference};

    #[test]
    fn overrides_go_on_top_of_the_task_in_order_and_bare_words_are_strings() {
        let task = TaskConfig::default();
        let got = apply_task_overrides(
            &task,
            &[
                "base_height_reference=feet".into(),
                "pitch_reference = \"ground\"".into(),
                "min_base_height_m=0.15".into(),
                "start_x_range_m=[0.0, 1.0]".into(),
                "min_base_height_m=0.18".into(),
            ],
        )
        .unwrap();
        assert_eq!(
            got,
            TaskConfig {
                base_height_reference: BaseHeightReference::Feet,
                pitch_reference: PitchReference::Ground,
                min_base_height_m: 0.18,
                start_x_range_m: (0.0, 1.0),
                ..task.clone()
            }
        );
        assert_eq!(apply_task_overrides(&task, &[]).unwrap(), task);
    }

    #[test]
    fn a_bad_override_is_named_with_what_is_wrong() {
        let task = TaskConfig::default();
        for (text, expected) in [
            ("base_height_reference", "expected KEY=VALUE"),
            ("=feet", "expected KEY=VALUE"),
            (
                "base_height_reference=belly",
                "base_height_reference must be \"hips\"",
            ),
            ("min_base_height=0.1", "unknown field `min_base_height`"),
            (
                "min_base_height_m=-1",
                "min_base_height_m must be a positive number",
            ),
            (
                "observation.foot_history=false",
                "observation sets the networks' input",
            ),
            (
                "action_prior=scripted_crawl",
                "action_prior sets the networks' input",
            ),
            (
                "swing_height_reference=touchdown",
                "how the policy's actions are read",
            ),
        ] {
            let err = apply_task_overrides(&task, &[text.to_string()]).unwrap_err();
            assert!(err.contains(&format!("--task {text:?}")), "{err}");
            assert!(err.contains(expected), "{text}: {err}");
        }
    }
}

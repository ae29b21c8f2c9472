//! Experiment files in TOML: `[terrain]` and `[task]` (later issues add
//! PPO and run sections). Unknown keys are errors.
//!
//! ```toml
//! [task]
//! max_phases = 40
//! goal_spacing_m = 2.0
//! start_x_range_m = [-0.5, 0.5]
//!
//! [task.observation]      # the paper's ablations
//! foot_history = false    # drop the three previous phase-start foot positions (-36)
//! short_history = true    # foot positions 4 and 8 ms ago (24)
//! foot_velocity = true    # foot velocities (12)
//! ```
//!
//! The terrain is given either as a spec string or as a table whose keys are
//! the plugin's parameters; both go through the same registry validation:
//!
//! ```toml
//! [terrain]
//! spec = "varying:2m:2,3,4,5cm,rigid"
//! ```
//!
//! ```toml
//! [terrain]
//! plugin = "elastic"
//! depth = "5cm"
//! travel = "12cm"
//! damping = 0.4
//! ```
//!
//! Lists may be TOML arrays: `surfaces = ["2cm", "5cm", "rigid"]`.

use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};
use robot::task::{ObservationConfig, TaskConfig};
use serde::Deserialize;
use terrain_plugins::{Registry, TerrainSpec};

/// The sections an experiment file may have.
const KNOWN_SECTIONS: [&str; 2] = ["terrain", "task"];

/// A parsed experiment file.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// the terrain
    pub terrain: TerrainSpec,
    /// the task settings (defaults where the file is silent)
    pub task: TaskConfig,
}

impl Experiment {
    /// Reads an experiment file.
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("config {}: cannot read it", path.display()))?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Parses TOML text; `source` names it in errors.
    pub fn from_toml(text: &str, source: &str) -> Result<Self> {
        let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            anyhow!("config {source}: not valid TOML: {}", e.message())
        })?;
        for key in doc.keys() {
            if !KNOWN_SECTIONS.contains(&key.as_str()) {
                bail!(
                    "config {source}: unknown section or key {key:?} (known: {})",
                    KNOWN_SECTIONS.join(", ")
                );
            }
        }
        let terrain = terrain_from_table(&doc, source)?;
        let task = match doc.get("task") {
            None => TaskConfig::default(),
            Some(value) => {
                let section: TaskSection =
                    value.clone().try_into().map_err(|e: toml::de::Error| {
                        anyhow!("config {source} [task]: {}", e.message())
                    })?;
                section
                    .resolve()
                    .map_err(|e| anyhow!("config {source} [task]: {e}"))?
            }
        };
        Ok(Self { terrain, task })
    }
}

/// `[task]`: every key optional, defaults from [`TaskConfig::default`].
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskSection {
    goal_spacing_m: Option<f64>,
    goal_reached_m: Option<f64>,
    max_phases: Option<usize>,
    start_x_range_m: Option<[f64; 2]>,
    start_y_range_m: Option<[f64; 2]>,
    min_base_height_m: Option<f64>,
    max_pitch_deg: Option<f64>,
    termination_reward: Option<f64>,
    settle_secs: Option<f64>,
    observation: Option<ObservationSection>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ObservationSection {
    foot_history: Option<bool>,
    short_history: Option<bool>,
    foot_velocity: Option<bool>,
}

impl TaskSection {
    fn resolve(self) -> Result<TaskConfig, String> {
        let d = TaskConfig::default();
        let o = ObservationConfig::default();
        let positive = |name: &str, v: Option<f64>, default: f64| match v {
            Some(v) if !(v.is_finite() && v > 0.0) => {
                Err(format!("{name} must be a positive number, got {v}"))
            }
            Some(v) => Ok(v),
            None => Ok(default),
        };
        let range = |name: &str, v: Option<[f64; 2]>, default: (f64, f64)| match v {
            Some([a, b]) if !(a.is_finite() && b.is_finite() && a <= b) => Err(format!(
                "{name} must be [low, high] with low <= high, got [{a}, {b}]"
            )),
            Some([a, b]) => Ok((a, b)),
            None => Ok(default),
        };
        let max_phases = self.max_phases.unwrap_or(d.max_phases);
        if max_phases == 0 {
            return Err("max_phases must be at least 1".to_string());
        }
        let termination_reward = self.termination_reward.unwrap_or(d.termination_reward);
        if !termination_reward.is_finite() {
            return Err("termination_reward must be finite".to_string());
        }
        let observation = self.observation.map_or(o, |s| ObservationConfig {
            foot_history: s.foot_history.unwrap_or(o.foot_history),
            short_history: s.short_history.unwrap_or(o.short_history),
            foot_velocity: s.foot_velocity.unwrap_or(o.foot_velocity),
        });
        Ok(TaskConfig {
            goal_spacing_m: positive("goal_spacing_m", self.goal_spacing_m, d.goal_spacing_m)?,
            goal_reached_m: positive("goal_reached_m", self.goal_reached_m, d.goal_reached_m)?,
            max_phases,
            start_x_range_m: range("start_x_range_m", self.start_x_range_m, d.start_x_range_m)?,
            start_y_range_m: range("start_y_range_m", self.start_y_range_m, d.start_y_range_m)?,
            min_base_height_m: positive(
                "min_base_height_m",
                self.min_base_height_m,
                d.min_base_height_m,
            )?,
            max_pitch_deg: positive("max_pitch_deg", self.max_pitch_deg, d.max_pitch_deg)?,
            termination_reward,
            settle_secs: match self.settle_secs {
                Some(v) if !(v.is_finite() && v >= 0.0) => {
                    return Err(format!("settle_secs must be >= 0, got {v}"));
                }
                Some(v) => v,
                None => d.settle_secs,
            },
            observation,
        })
    }
}

/// Reads the `[terrain]` section of a parsed file; `source` names it in errors.
fn terrain_from_table(doc: &toml::Table, source: &str) -> Result<TerrainSpec> {
    let section = doc
        .get("terrain")
        .ok_or_else(|| anyhow!("config {source}: no [terrain] section"))?;
    let table = section
        .as_table()
        .ok_or_else(|| anyhow!("config {source}: terrain must be a table ([terrain])"))?;
    let registry = Registry::builtin();
    let name = format!("{source} [terrain]");
    match (table.get("spec"), table.get("plugin")) {
        (Some(_), Some(_)) => bail!(
            "config {name}: give either spec = \"...\" or plugin = \"...\" with its parameters, not both"
        ),
        (Some(spec), None) => {
            if table.len() > 1 {
                let extra: Vec<&String> = table.keys().filter(|k| *k != "spec").collect();
                bail!(
                    "config {name}: with spec = \"...\" no other keys are allowed, found {extra:?}"
                );
            }
            let spec = spec.as_str().ok_or_else(|| {
                anyhow!("config {name}: spec must be a string such as \"elastic:5cm\"")
            })?;
            Ok(registry
                .parse(spec)
                .with_context(|| format!("config {name}"))?)
        }
        (None, Some(plugin)) => {
            let plugin = plugin.as_str().ok_or_else(|| {
                anyhow!("config {name}: plugin must be a string such as \"elastic\"")
            })?;
            let mut entries = Vec::new();
            for (key, value) in table.iter().filter(|(k, _)| *k != "plugin") {
                entries.push((
                    key.clone(),
                    value_text(value).with_context(|| format!("config {name}: key {key}"))?,
                ));
            }
            Ok(registry.parse_table(&name, plugin, &entries)?)
        }
        (None, None) => bail!("config {name}: needs spec = \"...\" or plugin = \"...\""),
    }
}

/// A TOML value as the text the spec grammar reads.
fn value_text(value: &toml::Value) -> Result<String> {
    Ok(match value {
        toml::Value::String(s) => s.clone(),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::Float(f) => f.to_string(),
        toml::Value::Array(items) => items
            .iter()
            .map(value_text)
            .collect::<Result<Vec<_>>>()?
            .join(","),
        other => bail!("{} is not a string, number or list", other.type_str()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn terrain_from_toml(text: &str, source: &str) -> Result<TerrainSpec> {
        Experiment::from_toml(text, source).map(|e| e.terrain)
    }

    #[test]
    fn task_section_sets_the_task_and_refuses_unknown_keys() {
        let e = Experiment::from_toml(
            "[terrain]\nspec = \"rigid\"\n[task]\nmax_phases = 12\n[task.observation]\nfoot_history = false\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(e.task.max_phases, 12);
        assert!(!e.task.observation.foot_history);
        assert_eq!(e.task.observation.size(), 102 - 36);
        for (text, expected) in [
            (
                "[terrain]\nspec = \"rigid\"\n[task]\nmax_phase = 3\n",
                "unknown field `max_phase`",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\nmax_phases = 0\n",
                "at least 1",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\ngoal_spacing_m = -2.0\n",
                "positive",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\nstart_x_range_m = [1.0, 0.0]\n",
                "low <= high",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task.observation]\nfoot_speed = true\n",
                "unknown field `foot_speed`",
            ),
        ] {
            let err = format!("{:#}", Experiment::from_toml(text, "t.toml").unwrap_err());
            assert!(
                err.contains(expected) && err.contains("t.toml [task]"),
                "{text:?} gave {err:?}"
            );
        }
    }

    #[test]
    fn spec_and_table_forms_give_the_same_terrain() {
        let a =
            terrain_from_toml("[terrain]\nspec = \"elastic:5cm:travel=12cm\"\n", "a.toml").unwrap();
        let b = terrain_from_toml(
            "[terrain]\nplugin = \"elastic\"\ndepth = \"5cm\"\ntravel = \"12cm\"\n",
            "b.toml",
        )
        .unwrap();
        assert_eq!(a, b);
        let c = terrain_from_toml("[terrain]\nplugin = \"varying\"\nevery = \"2m\"\nsurfaces = [\"2cm\", \"5cm\", \"rigid\"]\ndamping = 0.4\n", "c.toml").unwrap();
        assert_eq!(c.to_string(), "varying:2m:2cm,5cm,rigid:damping=0.4");
    }

    #[test]
    fn bad_files_name_the_file_and_the_problem() {
        let cases = [
            ("[terrain]\nspec = \"elastic:5\"\n", "has no unit"),
            (
                "[terrain]\nplugin = \"elastic\"\ndepth = \"30cm\"\n",
                "beyond the tile travel",
            ),
            (
                "[terrain]\nplugin = \"elastic\"\ndepht = \"3cm\"\n",
                "has no parameter \"depht\"",
            ),
            (
                "[terrain]\nspec = \"rigid\"\nplugin = \"rigid\"\n",
                "not both",
            ),
            (
                "[terrian]\nspec = \"rigid\"\n",
                "unknown section or key \"terrian\"",
            ),
            ("[terrain]\nspec = 5\n", "spec must be a string"),
            ("[terrain\n", "not valid TOML"),
            ("", "no [terrain] section"),
            (
                "[terrain]\nplugin = \"elastic\"\ndepth = true\n",
                "not a string, number or list",
            ),
        ];
        for (text, expected) in cases {
            let err = format!("{:#}", terrain_from_toml(text, "x.toml").unwrap_err());
            assert!(err.contains(expected), "{text:?} gave {err:?}");
            assert!(err.contains("x.toml"), "{err:?}");
        }
    }
}

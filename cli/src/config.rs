//! Experiment files in TOML. Today they hold the terrain; later issues add
//! the task, PPO and run sections. Unknown keys are errors.
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

use anyhow::{anyhow, bail, Context, Result};
use terrain_plugins::{Registry, TerrainSpec};

/// The sections an experiment file may have.
const KNOWN_SECTIONS: [&str; 1] = ["terrain"];

/// Reads the `[terrain]` section of an experiment file.
pub fn terrain_from_file(path: &Path) -> Result<TerrainSpec> {
    let text = std::fs::read_to_string(path).with_context(|| format!("config {}: cannot read it", path.display()))?;
    terrain_from_toml(&text, &path.display().to_string())
}

/// Reads the `[terrain]` section of TOML text; `source` names it in errors.
pub fn terrain_from_toml(text: &str, source: &str) -> Result<TerrainSpec> {
    let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| anyhow!("config {source}: not valid TOML: {}", e.message()))?;
    for key in doc.keys() {
        if !KNOWN_SECTIONS.contains(&key.as_str()) {
            bail!("config {source}: unknown section or key {key:?} (known: {})", KNOWN_SECTIONS.join(", "));
        }
    }
    let section = doc.get("terrain").ok_or_else(|| anyhow!("config {source}: no [terrain] section"))?;
    let table = section.as_table().ok_or_else(|| anyhow!("config {source}: terrain must be a table ([terrain])"))?;
    let registry = Registry::builtin();
    let name = format!("{source} [terrain]");
    match (table.get("spec"), table.get("plugin")) {
        (Some(_), Some(_)) => bail!("config {name}: give either spec = \"...\" or plugin = \"...\" with its parameters, not both"),
        (Some(spec), None) => {
            if table.len() > 1 {
                let extra: Vec<&String> = table.keys().filter(|k| *k != "spec").collect();
                bail!("config {name}: with spec = \"...\" no other keys are allowed, found {extra:?}");
            }
            let spec = spec.as_str().ok_or_else(|| anyhow!("config {name}: spec must be a string such as \"elastic:5cm\""))?;
            Ok(registry.parse(spec).with_context(|| format!("config {name}"))?)
        }
        (None, Some(plugin)) => {
            let plugin = plugin.as_str().ok_or_else(|| anyhow!("config {name}: plugin must be a string such as \"elastic\""))?;
            let mut entries = Vec::new();
            for (key, value) in table.iter().filter(|(k, _)| *k != "plugin") {
                entries.push((key.clone(), value_text(value).with_context(|| format!("config {name}: key {key}"))?));
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
        toml::Value::Array(items) => items.iter().map(value_text).collect::<Result<Vec<_>>>()?.join(","),
        other => bail!("{} is not a string, number or list", other.type_str()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_and_table_forms_give_the_same_terrain() {
        let a = terrain_from_toml("[terrain]\nspec = \"elastic:5cm:travel=12cm\"\n", "a.toml").unwrap();
        let b = terrain_from_toml("[terrain]\nplugin = \"elastic\"\ndepth = \"5cm\"\ntravel = \"12cm\"\n", "b.toml").unwrap();
        assert_eq!(a, b);
        let c = terrain_from_toml("[terrain]\nplugin = \"varying\"\nevery = \"2m\"\nsurfaces = [\"2cm\", \"5cm\", \"rigid\"]\ndamping = 0.4\n", "c.toml").unwrap();
        assert_eq!(c.to_string(), "varying:2m:2cm,5cm,rigid:damping=0.4");
    }

    #[test]
    fn bad_files_name_the_file_and_the_problem() {
        let cases = [
            ("[terrain]\nspec = \"elastic:5\"\n", "has no unit"),
            ("[terrain]\nplugin = \"elastic\"\ndepth = \"30cm\"\n", "beyond the tile travel"),
            ("[terrain]\nplugin = \"elastic\"\ndepht = \"3cm\"\n", "has no parameter \"depht\""),
            ("[terrain]\nspec = \"rigid\"\nplugin = \"rigid\"\n", "not both"),
            ("[terrian]\nspec = \"rigid\"\n", "unknown section or key \"terrian\""),
            ("[terrain]\nspec = 5\n", "spec must be a string"),
            ("[terrain\n", "not valid TOML"),
            ("", "no [terrain] section"),
            ("[terrain]\nplugin = \"elastic\"\ndepth = true\n", "not a string, number or list"),
        ];
        for (text, expected) in cases {
            let err = format!("{:#}", terrain_from_toml(text, "x.toml").unwrap_err());
            assert!(err.contains(expected), "{text:?} gave {err:?}");
            assert!(err.contains("x.toml"), "{err:?}");
        }
    }
}

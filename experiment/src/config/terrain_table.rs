//! `[terrain]`: a spec string, or a table of the plugin's parameters; both
//! go through the registry's validation.

use anyhow::{Context, Result, anyhow, bail};
use terrain_plugins::{Registry, TerrainSpec};

/// Reads the `[terrain]` section of a parsed file; `source` names it in errors.
pub(super) fn terrain_from_table(
    doc: &toml::Table,
    source: &str,
    registry: &Registry,
) -> Result<TerrainSpec> {
    let section = doc
        .get("terrain")
        .ok_or_else(|| anyhow!("config {source}: no [terrain] section"))?;
    let table = section
        .as_table()
        .ok_or_else(|| anyhow!("config {source}: terrain must be a table ([terrain])"))?;
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

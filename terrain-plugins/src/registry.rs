//! The terrain plugin trait and the registry of plugins.
//!
//! The registry is an explicit list: [`Registry::builtin`] names every
//! built-in plugin, and a user's plugin is one more [`Registry::register`]
//! call. Names are unique; a second plugin with a taken name is refused.

use std::collections::BTreeSet;

use crate::spec::{ParamDecl, SpecError, TerrainSpec};
use crate::{BuildContext, Terrain};

/// A terrain model: its name, a one-line summary, its parameters, and how to
/// make a terrain from a parsed spec.
pub trait TerrainPlugin: Send + Sync {
    /// The name used in specs (`elastic` in `elastic:5cm`); lowercase ASCII.
    fn name(&self) -> &'static str;
    /// One line for `quadwalk terrain list`.
    fn summary(&self) -> &'static str;
    /// Declared parameters: required ones (positional) first, in order.
    fn params(&self) -> Vec<ParamDecl>;
    /// Checks relations between parameters that single values cannot
    /// (e.g. depth within the tile travel). Returns the reason on failure.
    fn validate(&self, _spec: &TerrainSpec) -> Result<(), String> {
        Ok(())
    }
    /// Makes the terrain (not yet built into a physics world).
    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain>;
}

/// Why a plugin could not be registered.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RegistryError {
    /// Another plugin already has this name.
    #[error("a terrain plugin named {0:?} is already registered")]
    Duplicate(String),
    /// The name is not lowercase ASCII letters, digits, `-` or `_`.
    #[error(
        "terrain plugin name {0:?} must be non-empty lowercase ASCII letters, digits, '-' or '_'"
    )]
    BadName(String),
}

/// The list of known terrain plugins.
pub struct Registry {
    plugins: Vec<Box<dyn TerrainPlugin>>,
}

impl Registry {
    /// A registry with no plugins.
    pub fn empty() -> Self {
        Self {
            plugins: Vec::new(),
        }
    }

    /// A registry with the built-in plugins: `rigid`, `elastic`, `varying`,
    /// `soil`, `switch`, `slope`, `steps`, `rough`.
    pub fn builtin() -> Self {
        let mut registry = Self::empty();
        for plugin in [
            Box::new(crate::rigid::RigidPlugin) as Box<dyn TerrainPlugin>,
            Box::new(crate::elastic::ElasticPlugin),
            Box::new(crate::varying::VaryingPlugin),
            Box::new(crate::soil::SoilPlugin),
            Box::new(crate::switch::SwitchPlugin),
            Box::new(crate::relief::SlopePlugin),
            Box::new(crate::relief::StepsPlugin),
            Box::new(crate::relief::RoughPlugin),
        ] {
            registry
                .register(plugin)
                .expect("built-in plugin names are unique and valid");
        }
        registry
    }

    /// Adds a plugin; refuses a name already taken.
    pub fn register(&mut self, plugin: Box<dyn TerrainPlugin>) -> Result<(), RegistryError> {
        let name = plugin.name();
        let valid = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_');
        if !valid {
            return Err(RegistryError::BadName(name.to_string()));
        }
        if self.get(name).is_some() {
            return Err(RegistryError::Duplicate(name.to_string()));
        }
        self.plugins.push(plugin);
        Ok(())
    }

    /// The plugin with this name.
    pub fn get(&self, name: &str) -> Option<&dyn TerrainPlugin> {
        self.plugins
            .iter()
            .find(|p| p.name() == name)
            .map(|p| p.as_ref())
    }

    /// All plugins, in registration order.
    pub fn plugins(&self) -> impl Iterator<Item = &dyn TerrainPlugin> {
        self.plugins.iter().map(|p| p.as_ref())
    }

    fn known(&self) -> String {
        self.plugins
            .iter()
            .map(|p| p.name())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// `elastic:<depth>[:key=value...]`, for help and errors.
    pub fn usage(plugin: &dyn TerrainPlugin) -> String {
        let mut usage = plugin.name().to_string();
        for decl in plugin.params() {
            if decl.default.is_none() {
                usage.push_str(&format!(":<{}>", decl.name));
            }
        }
        usage.push_str("[:key=value...]");
        usage
    }

    /// Parses `name:arg:arg:key=value` into a spec with every value resolved.
    pub fn parse(&self, input: &str) -> Result<TerrainSpec, SpecError> {
        let trimmed = input.trim();
        if trimmed.is_empty() {
            return Err(SpecError::Empty {
                input: input.to_string(),
                known: self.known(),
            });
        }
        // `:` inside parentheses belongs to a nested spec (a varying region).
        let mut parts = crate::spec::split_top_level(trimmed, ':').into_iter();
        let name = parts.next().unwrap_or_default().trim();
        let mut positional = Vec::new();
        let mut named = Vec::new();
        for part in parts {
            // `key=value`, unless the `=` belongs to a parenthesised region
            match part
                .split_once('=')
                .filter(|(key, _)| !key.contains(['(', ',']))
            {
                Some((key, value)) => named.push((key.trim().to_string(), value.to_string())),
                None => positional.push(part.to_string()),
            }
        }
        self.resolve(input, name, &positional, &named)
    }

    /// Builds a spec from a table (`plugin = "elastic"`, `depth = "5cm"`, ...):
    /// every entry is `key=value`, the required parameters included, and goes
    /// through the same checks as [`Self::parse`]. `input` is how the caller
    /// names the table in errors (e.g. the TOML file and section).
    pub fn parse_table(
        &self,
        input: &str,
        plugin: &str,
        entries: &[(String, String)],
    ) -> Result<TerrainSpec, SpecError> {
        self.resolve(input, plugin.trim(), &[], entries)
    }

    fn resolve(
        &self,
        input: &str,
        name: &str,
        positional: &[String],
        named: &[(String, String)],
    ) -> Result<TerrainSpec, SpecError> {
        let plugin = self.get(name).ok_or_else(|| {
            if name.is_empty() {
                SpecError::Empty {
                    input: input.to_string(),
                    known: self.known(),
                }
            } else {
                SpecError::UnknownPlugin {
                    input: input.to_string(),
                    name: name.to_string(),
                    known: self.known(),
                }
            }
        })?;
        let decls = plugin.params();
        let required: Vec<&ParamDecl> = decls.iter().filter(|d| d.default.is_none()).collect();
        let known_names = || decls.iter().map(|d| d.name).collect::<Vec<_>>().join(", ");

        let mut given: Vec<Option<String>> = vec![None; decls.len()];
        let mut seen = BTreeSet::new();
        for (key, value) in named {
            let Some(index) = decls.iter().position(|d| d.name == key) else {
                return Err(SpecError::BadKey {
                    input: input.to_string(),
                    plugin: name.to_string(),
                    problem: "has no parameter",
                    name: key.clone(),
                    known: known_names(),
                });
            };
            if !seen.insert(key.as_str()) {
                return Err(SpecError::BadKey {
                    input: input.to_string(),
                    plugin: name.to_string(),
                    problem: "was given parameter twice:",
                    name: key.clone(),
                    known: known_names(),
                });
            }
            given[index] = Some(value.clone());
        }
        // Positional arguments fill the required parameters not given by name.
        let open: Vec<usize> = decls
            .iter()
            .enumerate()
            .filter(|(i, d)| d.default.is_none() && given[*i].is_none())
            .map(|(i, _)| i)
            .collect();
        if positional.len() != open.len() {
            return Err(SpecError::Arity {
                input: input.to_string(),
                plugin: name.to_string(),
                expected: required.len(),
                got: positional.len() + (required.len() - open.len()),
                usage: Self::usage(plugin),
            });
        }
        for (index, text) in open.into_iter().zip(positional) {
            given[index] = Some(text.clone());
        }

        let mut params = Vec::with_capacity(decls.len());
        for (decl, text) in decls.iter().zip(given) {
            let value = match (text, &decl.default) {
                (Some(text), _) => {
                    decl.parse_value(&text)
                        .map_err(|reason| SpecError::BadValue {
                            input: input.to_string(),
                            param: decl.name.to_string(),
                            value: text.clone(),
                            reason,
                            expects: decl.expects(),
                        })?
                }
                (None, Some(default)) => default.clone(),
                (None, None) => unreachable!("every required parameter was filled above"),
            };
            params.push((decl.clone(), value));
        }
        let spec = TerrainSpec::new(name.to_string(), params);
        plugin
            .validate(&spec)
            .map_err(|reason| SpecError::Invalid {
                input: input.to_string(),
                reason,
            })?;
        Ok(spec)
    }

    /// Parses and creates in one go.
    pub fn create(&self, input: &str, ctx: &BuildContext) -> Result<Box<dyn Terrain>, SpecError> {
        let spec = self.parse(input)?;
        self.create_from_spec(&spec, ctx)
    }

    /// Creates the terrain a parsed spec describes. A spec parsed by another
    /// registry whose plugin this one lacks (a run made by a binary with
    /// more plugins) is [`SpecError::UnknownPlugin`], naming the plugin.
    pub fn create_from_spec(
        &self,
        spec: &TerrainSpec,
        ctx: &BuildContext,
    ) -> Result<Box<dyn Terrain>, SpecError> {
        let plugin = self
            .get(spec.plugin())
            .ok_or_else(|| SpecError::UnknownPlugin {
                input: spec.to_string(),
                name: spec.plugin().to_string(),
                known: self.known(),
            })?;
        Ok(plugin.create(spec, ctx))
    }
}

impl Default for Registry {
    fn default() -> Self {
        Self::builtin()
    }
}

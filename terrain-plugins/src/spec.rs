//! Terrain specs: `name:arg:arg:key=value`, their declared parameters, values
//! in SI units, and errors that keep the input.
//!
//! A spec is parsed against a plugin's declared parameters by the
//! [`Registry`](crate::Registry). Positional arguments fill the required
//! parameters in order; optional parameters are given as `key=value`
//! (`elastic:5cm:travel=12cm:length=30m`). Every parameter is stored resolved
//! (defaults filled in), in SI units, so two specs that mean the same terrain
//! compare equal however they were written. [`TerrainSpec`]'s `Display` prints
//! the canonical form: positional values, then the optional ones that differ
//! from their default; parsing that text gives back an equal spec.

use std::fmt;

use crate::units::{
    LengthUnit, format_length, format_mass, parse_finite, parse_length_m, parse_mass_kg,
    split_number_unit,
};

/// What a parameter holds, and so how its text is parsed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    /// A length with a unit (`5cm`), stored in metres; must be > 0.
    Length,
    /// A mass with a unit (`25kg`), stored in kilograms; must be > 0.
    Mass,
    /// A dimensionless number (`0.5`); must be >= 0.
    Number,
    /// A sinking depth (`5cm`), or a range of them (`2..5cm`, `2cm..5cm`)
    /// from which each tile draws its own; stored in metres, > 0.
    Depth,
    /// A comma-separated list of surfaces, each a sinking depth or `rigid`
    /// (`2,3,4,5cm,rigid`). A bare number takes the next unit written after
    /// it in the list, so `2,3cm` is 2 cm and 3 cm.
    Surfaces,
}

impl ParamKind {
    fn describe(self) -> &'static str {
        match self {
            Self::Length => "a length such as 5cm, 0.05m or 50mm",
            Self::Mass => "a mass such as 25kg",
            Self::Number => "a number such as 0.5",
            Self::Depth => "a depth such as 5cm, or a range such as 2..5cm",
            Self::Surfaces => {
                "a list of depths, depth ranges, `rigid` and (spec)s of rigid, elastic, soil, rough, slope or steps ground, such as 2,3,4,5cm,rigid or 2..5cm,(soil:4cm),(rough:1cm),(slope:10)"
            }
        }
    }
}

/// What the ground of a region is made of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Ground {
    /// Rigid ground.
    Rigid,
    /// Elastic tiles that sink this much (metres) under the standing robot.
    Elastic {
        /// nominal sinking depth, metres
        depth_m: f64,
    },
    /// Elastic tiles, each with its own depth drawn uniformly from
    /// [min, max] with the world's seed (per-tile domain randomisation).
    ElasticRange {
        /// smallest depth, metres
        min_depth_m: f64,
        /// largest depth, metres
        max_depth_m: f64,
    },
    /// Tiles of soil that yield and stay down (see [`crate::soil`]).
    Soil(crate::soil::SoilParams),
    /// Rigid ground with random heights (see [`crate::relief`]).
    Rough {
        /// heights are drawn uniformly in [-amplitude, amplitude], m
        amplitude_m: f64,
        /// grid spacing, m
        cell_m: f64,
    },
    /// A rigid hill (see [`crate::relief::RegionRelief::Hill`]): rises at
    /// this angle from the region's start to its middle, falls to its end.
    Slope {
        /// inclination, degrees
        degrees: f64,
    },
    /// Rigid stairs (see [`crate::relief::RegionRelief::Stairs`]): up to the
    /// region's middle and down to its end.
    Steps {
        /// rise of each step, m
        height_m: f64,
        /// run of each step along x, m
        length_m: f64,
    },
}

impl Ground {
    /// The deepest nominal sink of this ground, metres (0 for rigid).
    pub fn max_depth_m(&self) -> f64 {
        match *self {
            Self::Rigid | Self::Rough { .. } | Self::Slope { .. } | Self::Steps { .. } => 0.0,
            Self::Elastic { depth_m } => depth_m,
            Self::ElasticRange { max_depth_m, .. } => max_depth_m,
            Self::Soil(soil) => soil.depth_m,
        }
    }
}

/// One surface of a [`ParamKind::Surfaces`] list, or of a tiled terrain:
/// its ground and, if it has its own, its friction coefficient and the
/// inclination of its tiles.
///
/// In a list a surface is written `5cm`, `2..5cm`, `rigid`, or as a spec of
/// the `rigid`, `elastic`, `soil`, `rough`, `slope` or `steps` plugin in
/// parentheses, which may name the region's friction and, for tiles, their
/// slope: `(rigid:friction=0.1)`, `(soil:4cm:yield=0.4)`,
/// `(elastic:5cm:friction=0.5)`, `(elastic:5cm:slope=10)`, `(slope:10)`,
/// `(steps:5cm:30cm)`. In a TOML list the parentheses may be left out:
/// `surfaces = ["5cm", "soil:4cm", "rigid:friction=0.1"]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Surface {
    /// what the ground is made of
    pub ground: Ground,
    /// the region's friction coefficient; `None`: the terrain's
    pub friction: Option<f64>,
    /// tiles only: the inclination of the region's rest surface, degrees (a
    /// hill up to the region's middle and down to its end, see
    /// [`crate::tiles`]); `None`: the terrain's
    pub slope_deg: Option<f64>,
}

impl Surface {
    /// Rigid ground with the terrain's friction.
    pub fn rigid() -> Self {
        Self {
            ground: Ground::Rigid,
            friction: None,
            slope_deg: None,
        }
    }

    /// Elastic tiles sinking `depth_m` with the terrain's friction.
    pub fn elastic(depth_m: f64) -> Self {
        Self {
            ground: Ground::Elastic { depth_m },
            friction: None,
            slope_deg: None,
        }
    }

    /// The surface a depth parameter describes: one depth or a range.
    pub fn from_depth_range(min_depth_m: f64, max_depth_m: f64) -> Self {
        let ground = if min_depth_m == max_depth_m {
            Ground::Elastic {
                depth_m: min_depth_m,
            }
        } else {
            Ground::ElasticRange {
                min_depth_m,
                max_depth_m,
            }
        };
        Self {
            ground,
            friction: None,
            slope_deg: None,
        }
    }

    /// The deepest nominal sink of this surface, metres (0 for rigid).
    pub fn max_depth_m(&self) -> f64 {
        self.ground.max_depth_m()
    }

    /// The surface as a spec of its own (`rigid`, `elastic:5cm`,
    /// `soil:4cm:...`, with `:friction=` and `:slope=` if it has its own): a
    /// region's label.
    pub fn label(&self) -> String {
        let text = match self.ground {
            Ground::Rigid => "rigid".to_string(),
            Ground::Elastic { .. } | Ground::ElasticRange { .. } => format!(
                "elastic:{}",
                Self {
                    friction: None,
                    slope_deg: None,
                    ..*self
                }
            ),
            Ground::Soil(soil) => soil.to_string(),
            Ground::Rough {
                amplitude_m,
                cell_m,
            } => {
                let cell = if cell_m == crate::relief::DEFAULT_CELL_M {
                    String::new()
                } else {
                    format!(":cell={}", format_length(cell_m))
                };
                format!("rough:{}{cell}", format_length(amplitude_m))
            }
            Ground::Slope { degrees } => format!("slope:{degrees}"),
            Ground::Steps { height_m, length_m } => format!(
                "steps:{}:{}",
                format_length(height_m),
                format_length(length_m)
            ),
        };
        let text = match self.friction {
            Some(mu) => format!("{text}:friction={mu}"),
            None => text,
        };
        match self.slope_deg {
            Some(degrees) => format!("{text}:slope={degrees}"),
            None => text,
        }
    }

    /// The surface a `rigid`, `elastic`, `soil`, `rough`, `slope` or
    /// `steps` spec describes. A spec that sets a parameter of the whole
    /// field (tile, gap, travel, damping, tile_mass, length, back, width,
    /// extent) is refused: a region takes those from the terrain it is part
    /// of (`steps`' `length`, the run of a step, is the region's own).
    pub fn from_spec(spec: &TerrainSpec) -> Result<Self, String> {
        const REGION_PARAMS: [&str; 10] = [
            "depth",
            "friction",
            "slope",
            "elastic",
            "yield",
            "recovery",
            "amplitude",
            "cell",
            "degrees",
            "height",
        ];
        let own = |name: &str| {
            REGION_PARAMS.contains(&name) || (spec.plugin() == "steps" && name == "length")
        };
        if let Some((decl, _)) = spec
            .params()
            .find(|(d, v)| !own(d.name) && d.default.as_ref() != Some(*v))
        {
            return Err(format!(
                "region ({spec}) sets {}, which belongs to the whole terrain: a region takes its depth, its friction and its shape's parameters",
                decl.name
            ));
        }
        let own_number = |name: &str| {
            spec.params()
                .find(|(d, _)| d.name == name)
                .and_then(|(d, v)| (d.default.as_ref() != Some(v)).then(|| spec.number(name)))
        };
        let friction = own_number("friction");
        let slope_deg = own_number("slope");
        let ground = match spec.plugin() {
            "rigid" => Ground::Rigid,
            "elastic" => {
                let (min_m, max_m) = spec.depth_range_m("depth");
                Self::from_depth_range(min_m, max_m).ground
            }
            "soil" => Ground::Soil(crate::soil::SoilParams::from_spec(spec)),
            "rough" => Ground::Rough {
                amplitude_m: spec.length_m("amplitude"),
                cell_m: spec.length_m("cell"),
            },
            "slope" => Ground::Slope {
                degrees: spec.number("degrees"),
            },
            "steps" => Ground::Steps {
                height_m: spec.length_m("height"),
                length_m: spec.length_m("length"),
            },
            other => {
                return Err(format!("a region is {REGION_KINDS}, not {other}"));
            }
        };
        Ok(Self {
            ground,
            friction,
            slope_deg,
        })
    }
}

impl fmt::Display for Surface {
    /// The short forms (`rigid`, `5cm`, `2cm..5cm`) where they say it all,
    /// else the spec in parentheses.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.ground, self.friction.or(self.slope_deg)) {
            (Ground::Rigid, None) => f.write_str("rigid"),
            (Ground::Elastic { depth_m }, None) => f.write_str(&format_length(*depth_m)),
            (
                Ground::ElasticRange {
                    min_depth_m,
                    max_depth_m,
                },
                None,
            ) => write!(
                f,
                "{}..{}",
                format_length(*min_depth_m),
                format_length(*max_depth_m)
            ),
            _ => write!(f, "({})", self.label()),
        }
    }
}

/// A parameter value, in SI units.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// metres
    Length(f64),
    /// kilograms
    Mass(f64),
    /// dimensionless
    Number(f64),
    /// a depth or a range of depths, metres (min == max: one depth)
    Depth {
        /// smallest depth, metres
        min_m: f64,
        /// largest depth, metres
        max_m: f64,
    },
    /// a list of surfaces
    Surfaces(Vec<Surface>),
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Length(v) => f.write_str(&format_length(*v)),
            Self::Mass(v) => f.write_str(&format_mass(*v)),
            Self::Number(v) => write!(f, "{v}"),
            Self::Depth { min_m, max_m } => {
                write!(f, "{}", Surface::from_depth_range(*min_m, *max_m))
            }
            Self::Surfaces(list) => {
                let items: Vec<String> = list.iter().map(Surface::to_string).collect();
                f.write_str(&items.join(","))
            }
        }
    }
}

/// A parameter a plugin declares: its name, kind, default (`None` makes it
/// required and positional) and a one-line description with its unit.
#[derive(Debug, Clone)]
pub struct ParamDecl {
    /// name used in `key=value` and in TOML tables
    pub name: &'static str,
    /// how its text is parsed
    pub kind: ParamKind,
    /// `None`: required, given positionally in declaration order
    pub default: Option<ParamValue>,
    /// one line for `quadwalk terrain list`
    pub doc: &'static str,
}

impl ParamDecl {
    /// A required parameter, given positionally.
    pub fn required(name: &'static str, kind: ParamKind, doc: &'static str) -> Self {
        Self {
            name,
            kind,
            default: None,
            doc,
        }
    }

    /// An optional `key=value` parameter with a default.
    pub fn optional(
        name: &'static str,
        kind: ParamKind,
        default: ParamValue,
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            kind,
            default: Some(default),
            doc,
        }
    }

    /// Parses this parameter's text into an SI value, checking its range.
    pub fn parse_value(&self, text: &str) -> Result<ParamValue, String> {
        let text = text.trim();
        let positive = |v: f64, what: &str| {
            if v > 0.0 {
                Ok(v)
            } else {
                Err(format!("{what} must be greater than zero, got {text:?}"))
            }
        };
        match self.kind {
            ParamKind::Length => parse_length_m(text)
                .and_then(|v| positive(v, "length"))
                .map(ParamValue::Length),
            ParamKind::Mass => parse_mass_kg(text)
                .and_then(|v| positive(v, "mass"))
                .map(ParamValue::Mass),
            ParamKind::Number => {
                let v = parse_finite(text)?;
                if v < 0.0 {
                    return Err(format!("must not be negative, got {text:?}"));
                }
                Ok(ParamValue::Number(v))
            }
            ParamKind::Depth => {
                parse_depth_range(text).map(|(min_m, max_m)| ParamValue::Depth { min_m, max_m })
            }
            ParamKind::Surfaces => parse_surfaces(text).map(ParamValue::Surfaces),
        }
    }

    /// What this parameter expects, for error messages.
    pub fn expects(&self) -> &'static str {
        self.kind.describe()
    }
}

/// Parses `5cm` (one depth) or `2..5cm` / `2cm..5cm` (a range; a bare lower
/// bound takes the upper bound's unit) into (min, max) metres.
fn parse_depth_range(text: &str) -> Result<(f64, f64), String> {
    let Some((lower, upper)) = text.split_once("..") else {
        let depth_m = parse_length_m(text)?;
        return if depth_m > 0.0 {
            Ok((depth_m, depth_m))
        } else {
            Err(format!("depth must be greater than zero, got {text:?}"))
        };
    };
    let max_m = parse_length_m(upper.trim())?;
    let (number, unit) = split_number_unit(lower);
    let min_m = if unit.is_empty() {
        let (_, upper_unit) = split_number_unit(upper);
        let unit = LengthUnit::parse(upper_unit)
            .ok_or_else(|| format!("{text:?}: the range's upper bound has no known unit"))?;
        unit.to_m(parse_finite(number)?)
    } else {
        parse_length_m(lower.trim())?
    };
    if min_m <= 0.0 || min_m >= max_m {
        return Err(format!(
            "range {text:?} must run from a depth greater than zero to a larger one"
        ));
    }
    Ok((min_m, max_m))
}

/// Splits `text` at each `separator` outside parentheses.
pub(crate) fn split_top_level(text: &str, separator: char) -> Vec<&str> {
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, c) in text.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            c if c == separator && depth == 0 => {
                parts.push(&text[start..i]);
                start = i + c.len_utf8();
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

/// What a region of a surfaces list may be, for error messages.
const REGION_KINDS: &str = "rigid, elastic, soil or rough ground, a slope or steps";

/// The plugins a region of a surfaces list may name.
fn surface_registry() -> crate::Registry {
    let mut registry = crate::Registry::empty();
    for plugin in [
        Box::new(crate::rigid::RigidPlugin) as Box<dyn crate::TerrainPlugin>,
        Box::new(crate::elastic::ElasticPlugin),
        Box::new(crate::soil::SoilPlugin),
        Box::new(crate::relief::RoughPlugin),
        Box::new(crate::relief::SlopePlugin),
        Box::new(crate::relief::StepsPlugin),
    ] {
        registry
            .register(plugin)
            .expect("the surface plugins' names are unique and valid");
    }
    registry
}

/// One nested surface spec, `(soil:4cm)` or (in TOML lists) `soil:4cm`.
fn parse_nested_surface(item: &str) -> Result<Surface, String> {
    let inner = item
        .strip_prefix('(')
        .map(|rest| {
            rest.strip_suffix(')')
                .ok_or_else(|| format!("item {item:?} opens a parenthesis it does not close"))
        })
        .transpose()?
        .unwrap_or(item);
    let plugin = inner.split(':').next().unwrap_or_default().trim();
    if !["rigid", "elastic", "soil", "rough", "slope", "steps"].contains(&plugin) {
        return Err(format!(
            "item {item:?}: a region is {REGION_KINDS}, not {plugin:?}"
        ));
    }
    let spec = surface_registry()
        .parse(inner)
        .map_err(|e| format!("item {item:?}: {e}"))?;
    Surface::from_spec(&spec).map_err(|e| format!("item {item:?}: {e}"))
}

fn parse_surfaces(text: &str) -> Result<Vec<Surface>, String> {
    if text.is_empty() {
        return Err("the list is empty".to_string());
    }
    let depth = text.chars().fold(0i32, |d, c| match c {
        '(' => d + 1,
        ')' => d - 1,
        _ => d,
    });
    if depth != 0 {
        return Err(format!("{text:?} has unbalanced parentheses"));
    }
    let items: Vec<&str> = split_top_level(text, ',')
        .into_iter()
        .map(str::trim)
        .collect();
    let mut out = vec![None; items.len()];
    // Walk backwards so a bare number picks up the next unit written after it.
    let mut pending_unit: Option<LengthUnit> = None;
    for (i, item) in items.iter().enumerate().rev() {
        if item.is_empty() {
            return Err(format!("item {} of {text:?} is empty", i + 1));
        }
        if item.eq_ignore_ascii_case("rigid") {
            out[i] = Some(Surface::rigid());
            continue;
        }
        if item.starts_with('(') || item.contains(':') {
            out[i] = Some(parse_nested_surface(item)?);
            continue;
        }
        if item.contains("..") {
            let (min_m, max_m) =
                parse_depth_range(item).map_err(|e| format!("item {item:?}: {e}"))?;
            let (lower, _) = item.split_once("..").unwrap_or_default();
            let (_, unit) = split_number_unit(lower);
            let unit = if unit.is_empty() {
                split_number_unit(item.rsplit_once("..").unwrap_or_default().1).1
            } else {
                unit
            };
            pending_unit = LengthUnit::parse(unit);
            out[i] = Some(Surface::from_depth_range(min_m, max_m));
            continue;
        }
        let (number, unit) = split_number_unit(item);
        let value = parse_finite(number).map_err(|e| format!("item {item:?}: {e}"))?;
        let unit = if unit.is_empty() {
            pending_unit.ok_or_else(|| {
                format!("item {item:?} has no unit and no unit follows it (write e.g. {item}cm)")
            })?
        } else {
            let parsed = LengthUnit::parse(unit).ok_or_else(|| {
                format!("item {item:?} has unknown unit {unit:?} (known: m, cm, mm)")
            })?;
            pending_unit = Some(parsed);
            parsed
        };
        let depth_m = unit.to_m(value);
        if depth_m <= 0.0 {
            return Err(format!("depth {item:?} must be greater than zero"));
        }
        out[i] = Some(Surface::elastic(depth_m));
    }
    Ok(out.into_iter().flatten().collect())
}

/// A parsed terrain spec: the plugin name and every declared parameter with
/// its resolved value, in declaration order.
#[derive(Debug, Clone)]
pub struct TerrainSpec {
    plugin: String,
    params: Vec<(ParamDecl, ParamValue)>,
}

impl TerrainSpec {
    pub(crate) fn new(plugin: String, params: Vec<(ParamDecl, ParamValue)>) -> Self {
        Self { plugin, params }
    }

    /// The plugin's name (`elastic`).
    pub fn plugin(&self) -> &str {
        &self.plugin
    }

    /// The value of parameter `name`, if the plugin declares it.
    pub fn get(&self, name: &str) -> Option<&ParamValue> {
        self.params
            .iter()
            .find(|(d, _)| d.name == name)
            .map(|(_, v)| v)
    }

    /// All parameters with their values, in declaration order.
    pub fn params(&self) -> impl Iterator<Item = (&ParamDecl, &ParamValue)> {
        self.params.iter().map(|(d, v)| (d, v))
    }

    /// A length parameter in metres. Panics if the plugin did not declare
    /// `name` as a length: that is a bug in the plugin, not bad input.
    pub fn length_m(&self, name: &str) -> f64 {
        match self.get(name) {
            Some(ParamValue::Length(v)) => *v,
            other => panic!(
                "plugin {} has no length parameter {name} (found {other:?})",
                self.plugin
            ),
        }
    }

    /// A mass parameter in kilograms (see [`Self::length_m`] on panics).
    pub fn mass_kg(&self, name: &str) -> f64 {
        match self.get(name) {
            Some(ParamValue::Mass(v)) => *v,
            other => panic!(
                "plugin {} has no mass parameter {name} (found {other:?})",
                self.plugin
            ),
        }
    }

    /// A dimensionless parameter (see [`Self::length_m`] on panics).
    pub fn number(&self, name: &str) -> f64 {
        match self.get(name) {
            Some(ParamValue::Number(v)) => *v,
            other => panic!(
                "plugin {} has no number parameter {name} (found {other:?})",
                self.plugin
            ),
        }
    }

    /// A depth parameter as (min, max) metres, equal for one depth (see
    /// [`Self::length_m`] on panics).
    pub fn depth_range_m(&self, name: &str) -> (f64, f64) {
        match self.get(name) {
            Some(ParamValue::Depth { min_m, max_m }) => (*min_m, *max_m),
            other => panic!(
                "plugin {} has no depth parameter {name} (found {other:?})",
                self.plugin
            ),
        }
    }

    /// A surfaces-list parameter (see [`Self::length_m`] on panics).
    pub fn surfaces(&self, name: &str) -> &[Surface] {
        match self.get(name) {
            Some(ParamValue::Surfaces(v)) => v,
            other => panic!(
                "plugin {} has no surfaces parameter {name} (found {other:?})",
                self.plugin
            ),
        }
    }
}

impl PartialEq for TerrainSpec {
    fn eq(&self, other: &Self) -> bool {
        self.plugin == other.plugin
            && self.params.len() == other.params.len()
            && self
                .params
                .iter()
                .zip(&other.params)
                .all(|((da, va), (db, vb))| da.name == db.name && va == vb)
    }
}

impl fmt::Display for TerrainSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.plugin)?;
        for (decl, value) in &self.params {
            match &decl.default {
                None => write!(f, ":{value}")?,
                Some(default) if default != value => write!(f, ":{}={value}", decl.name)?,
                Some(_) => {}
            }
        }
        Ok(())
    }
}

impl std::str::FromStr for TerrainSpec {
    type Err = SpecError;

    /// Parses against the built-in plugins; use
    /// [`Registry::parse`](crate::Registry::parse) for a registry with your own.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        crate::Registry::builtin().parse(s)
    }
}

/// Why a spec was refused. Every variant keeps the whole input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecError {
    /// Nothing was given.
    #[error("terrain spec {input:?} is empty (known terrains: {known})")]
    Empty {
        /// the input
        input: String,
        /// known plugin names, comma-separated
        known: String,
    },
    /// No plugin has this name.
    #[error(
        "terrain spec {input:?}: unknown terrain {name:?} (known terrains: {known}); a terrain plugin from another crate is registered in the binary that runs it (quadwalk_cli::App::new().add_terrain(...), or Registry::register)"
    )]
    UnknownPlugin {
        /// the input
        input: String,
        /// the name that was not found
        name: String,
        /// known plugin names, comma-separated
        known: String,
    },
    /// Too many or too few positional arguments.
    #[error(
        "terrain spec {input:?}: {plugin} takes {expected} positional argument(s), got {got} (usage: {usage})"
    )]
    Arity {
        /// the input
        input: String,
        /// plugin name
        plugin: String,
        /// how many it takes
        expected: usize,
        /// how many were given
        got: usize,
        /// e.g. `elastic:<depth>[:key=value...]`
        usage: String,
    },
    /// A `key=value` names no parameter of the plugin, or names one twice.
    #[error("terrain spec {input:?}: {plugin} {problem} {name:?} (its parameters: {known})")]
    BadKey {
        /// the input
        input: String,
        /// plugin name
        plugin: String,
        /// "has no parameter" or "was given twice"
        problem: &'static str,
        /// the key
        name: String,
        /// the plugin's parameter names
        known: String,
    },
    /// A value does not parse or is out of range.
    #[error("terrain spec {input:?}: parameter {param} = {value:?}: {reason} (expected {expects})")]
    BadValue {
        /// the input
        input: String,
        /// parameter name
        param: String,
        /// the text given
        value: String,
        /// what is wrong
        reason: String,
        /// what the parameter expects
        expects: &'static str,
    },
    /// The values parse but do not make a terrain (e.g. depth beyond travel).
    #[error("terrain spec {input:?}: {reason}")]
    Invalid {
        /// the input
        input: String,
        /// what is wrong
        reason: String,
    },
}

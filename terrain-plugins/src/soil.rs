//! `soil:<depth>`: tiles that yield and stay down, the tile model of sand,
//! mud or snow (elasto-plastic with linear hardening).
//!
//! Each tile hangs on the same sprung prismatic joint as an elastic tile,
//! but the spring's rest point moves down with the tile's permanent sink
//! s_p. For a tile pushed down s (positive down) by a load F:
//!
//! - elastic branch (unloading and reloading): F = k_r (s - s_p);
//! - the tile yields while F exceeds the yield load F_y(s_p) = F_y0 + k_h s_p:
//!   the permanent sink grows to s_p = (k_r s - F_y0) / (k_r + k_h), so the
//!   yield load hardens as the tile goes down, and a load above F_y0 keeps
//!   a tile sinking until F_y(s_p) has risen to it;
//! - optional recovery: ds_p/dt = -s_p / tau (tau = `recovery`, 0 = never).
//!
//! Quasi-static loading of a fresh tile gives the load-sink curve
//! s(F) = F / k_r for F <= F_y0 and F / k_r + (F - F_y0) / k_h above;
//! unloading from F_max leaves s_p = (F_max - F_y0) / k_h.
//!
//! Parameters name what the standing robot does, as `elastic` does: the
//! robot's weight on four tiles, F_s = m g / 4, sinks a fresh tile `depth`,
//! of which `elastic` springs back when the robot steps off; a tile first
//! yields at `yield` x F_s. So k_r = F_s / elastic, F_y0 = yield F_s and
//! k_h = (F_s - F_y0) / (depth - elastic).

use std::fmt;

use crate::spec::{Ground, ParamDecl, ParamKind, ParamValue, Surface, TerrainSpec};
use crate::tiles::{RegionLayout, TileParams, TiledTerrain, tile_param_decls};
use crate::units::format_length;
use crate::{BuildContext, Terrain, TerrainPlugin};

/// Default elastic part of the sink, m.
const DEFAULT_ELASTIC_M: f64 = 0.01;
/// Default yield load, a fraction of the standing load.
const DEFAULT_YIELD_FRACTION: f64 = 0.5;

/// A soil as a spec names it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoilParams {
    /// sink of a fresh tile under a quarter of the standing robot's weight, m
    pub depth_m: f64,
    /// the part of `depth_m` that springs back on unloading, m
    pub elastic_m: f64,
    /// load at which a fresh tile first yields, as a fraction of a quarter
    /// of the robot's weight
    pub yield_fraction: f64,
    /// time constant of the permanent sink's recovery, s (0: never)
    pub recovery_secs: f64,
}

impl SoilParams {
    /// Reads `soil`'s parameters.
    pub fn from_spec(spec: &TerrainSpec) -> Self {
        Self {
            depth_m: spec.length_m("depth"),
            elastic_m: spec.length_m("elastic"),
            yield_fraction: spec.number("yield"),
            recovery_secs: spec.number("recovery"),
        }
    }

    /// Checks the relations between the parameters.
    pub fn validate(&self) -> Result<(), String> {
        if self.elastic_m >= self.depth_m {
            return Err(format!(
                "elastic {} must be less than depth {} (the rest of the depth is the permanent sink)",
                format_length(self.elastic_m),
                format_length(self.depth_m)
            ));
        }
        if !(self.yield_fraction > 0.0 && self.yield_fraction < 1.0) {
            return Err(format!(
                "yield {} must lie strictly between 0 and 1 (a fraction of the standing load)",
                self.yield_fraction
            ));
        }
        Ok(())
    }

    /// The model's constants for the robot of `ctx`.
    pub fn model(&self, ctx: &BuildContext) -> SoilModel {
        let standing_load_n = ctx.supported_mass_kg * ctx.gravity_m_per_s2 / 4.0;
        let yield_load_n = self.yield_fraction * standing_load_n;
        SoilModel {
            reload_stiffness_n_per_m: standing_load_n / self.elastic_m,
            yield_load_n,
            hardening_n_per_m: (standing_load_n - yield_load_n) / (self.depth_m - self.elastic_m),
            recovery_secs: self.recovery_secs,
        }
    }
}

impl fmt::Display for SoilParams {
    /// As a `soil` spec in canonical form (defaults left out).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "soil:{}", format_length(self.depth_m))?;
        if self.elastic_m != DEFAULT_ELASTIC_M {
            write!(f, ":elastic={}", format_length(self.elastic_m))?;
        }
        if self.yield_fraction != DEFAULT_YIELD_FRACTION {
            write!(f, ":yield={}", self.yield_fraction)?;
        }
        if self.recovery_secs > 0.0 {
            write!(f, ":recovery={}", self.recovery_secs)?;
        }
        Ok(())
    }
}

/// The constants of the elasto-plastic tile (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoilModel {
    /// k_r, stiffness of the elastic (unloading and reloading) branch, N/m
    pub reload_stiffness_n_per_m: f64,
    /// F_y0, the load at which a fresh tile yields, N
    pub yield_load_n: f64,
    /// k_h, rise of the yield load per metre of permanent sink, N/m
    pub hardening_n_per_m: f64,
    /// tau, time constant of recovery, s (0: never)
    pub recovery_secs: f64,
}

impl SoilModel {
    /// Sink of a fresh tile loaded quasi-statically to `load_n`, m.
    pub fn loading_sink_m(&self, load_n: f64) -> f64 {
        load_n / self.reload_stiffness_n_per_m + self.permanent_sink_m(load_n)
    }

    /// Permanent sink left by loading a fresh tile to `max_load_n` and
    /// unloading it, m.
    pub fn permanent_sink_m(&self, max_load_n: f64) -> f64 {
        (max_load_n - self.yield_load_n).max(0.0) / self.hardening_n_per_m
    }

    /// The permanent sink after a step in which the tile is pushed down
    /// `sink_m`, from `plastic_m` before it, with `dt_secs` of recovery.
    pub fn advance(&self, plastic_m: f64, sink_m: f64, dt_secs: f64) -> f64 {
        let recovered_m = if self.recovery_secs > 0.0 {
            plastic_m * (-dt_secs / self.recovery_secs).exp()
        } else {
            plastic_m
        };
        let k = self.reload_stiffness_n_per_m;
        let yielded_m = (k * sink_m - self.yield_load_n) / (k + self.hardening_n_per_m);
        recovered_m.max(yielded_m).max(0.0)
    }
}

/// The `soil` plugin.
pub struct SoilPlugin;

impl TerrainPlugin for SoilPlugin {
    fn name(&self) -> &'static str {
        "soil"
    }

    fn summary(&self) -> &'static str {
        "tiles that yield and stay down (sand, mud, snow); the standing robot sinks <depth> (e.g. soil:4cm)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        let mut params = vec![
            ParamDecl::required(
                "depth",
                ParamKind::Length,
                "sink of fresh tiles under the standing robot (elastic + permanent)",
            ),
            ParamDecl::optional(
                "elastic",
                ParamKind::Length,
                ParamValue::Length(DEFAULT_ELASTIC_M),
                "the part of the sink that springs back when unloaded, default 1cm",
            ),
            ParamDecl::optional(
                "yield",
                ParamKind::Number,
                ParamValue::Number(DEFAULT_YIELD_FRACTION),
                "load at which a fresh tile yields, as a fraction of the standing load, default 0.5",
            ),
            ParamDecl::optional(
                "recovery",
                ParamKind::Number,
                ParamValue::Number(0.0),
                "time constant of the permanent sink's recovery in seconds, default 0 (never)",
            ),
        ];
        params.extend(tile_param_decls());
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        let soil = SoilParams::from_spec(spec);
        soil.validate()?;
        TileParams::from_spec(spec).validate([soil.depth_m], [])
    }

    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
        let layout = RegionLayout::Uniform(Surface {
            ground: Ground::Soil(SoilParams::from_spec(spec)),
            friction: None,
            slope_deg: None,
        });
        Box::new(TiledTerrain::new(
            spec.clone(),
            TileParams::from_spec(spec),
            layout,
            ctx,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> SoilModel {
        SoilParams {
            depth_m: 0.04,
            elastic_m: 0.01,
            yield_fraction: 0.5,
            recovery_secs: 0.0,
        }
        .model(&BuildContext::default())
    }

    #[test]
    fn the_standing_load_sinks_a_fresh_tile_the_named_depth() {
        let m = model();
        let standing_n = 25.567 * 9.81 / 4.0;
        assert!((m.loading_sink_m(standing_n) - 0.04).abs() < 1e-12);
        assert!((m.permanent_sink_m(standing_n) - 0.03).abs() < 1e-12);
        // below the yield load the tile is elastic and leaves nothing
        assert_eq!(m.permanent_sink_m(0.4 * standing_n), 0.0);
        assert!((m.loading_sink_m(0.4 * standing_n) - 0.004).abs() < 1e-12);
    }

    #[test]
    fn the_permanent_sink_only_grows_past_the_hardened_yield_load_and_recovers() {
        let m = model();
        // at equilibrium under the standing load: s = depth
        let s_p = m.advance(0.0, 0.04, 1.0 / 240.0);
        assert!((s_p - 0.03).abs() < 1e-12);
        // unloaded (sink back to s_p) nothing changes; reloaded up to the
        // same load nothing changes either
        assert_eq!(m.advance(s_p, s_p, 1.0 / 240.0), s_p);
        assert_eq!(m.advance(s_p, 0.04, 1.0 / 240.0), s_p);
        // a heavier load yields further
        assert!(m.advance(s_p, 0.05, 1.0 / 240.0) > s_p);
        let slow = SoilModel {
            recovery_secs: 2.0,
            ..m
        };
        let after = slow.advance(0.03, 0.0, 2.0);
        assert!((after - 0.03 / std::f64::consts::E).abs() < 1e-12);
    }
}

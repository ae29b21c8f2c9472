//! The parameters every tiled terrain takes (the spec grammar's
//! declarations and their SI values), their checks, and the spring rule
//! k = m g / (4 d).

use crate::BuildContext;
use crate::spec::{ParamDecl, ParamKind, ParamValue, TerrainSpec};
use crate::units::format_length;

use super::GROUND_FRICTION;
use super::layout::TileSpring;

/// Default extent of a field along x (its `length`), metres: room for 400
/// phases (`quadwalk eval`'s default episode) of a 5 cm-per-phase gait from
/// the start (the tiles end at x = 38 m). A 20 m field, the default until
/// 2026-12-01, ended at x = 18 m under a walking policy's 365th phase; past the
/// tiles the ground is the fixed base, 20 cm down, and the robot falls there.
pub const DEFAULT_LENGTH_M: f64 = 40.0;

/// The optional `friction` parameter of every built-in terrain but
/// `varying`'s regions' own (see [`GROUND_FRICTION`]).
pub fn friction_decl() -> ParamDecl {
    ParamDecl::optional(
        "friction",
        ParamKind::Number,
        ParamValue::Number(f64::from(GROUND_FRICTION)),
        "friction coefficient of the ground (the contact's, min with the robot's 1.0), default 1",
    )
}

/// The optional `slope` parameter of every tiled terrain and of each tiled
/// region of `varying` (see [`super`]: a hill of tiles on vertical springs).
pub fn slope_decl() -> ParamDecl {
    ParamDecl::optional(
        "slope",
        ParamKind::Number,
        ParamValue::Number(0.0),
        "inclination of the tiles' rest surface, degrees: a hill rising at this angle to the region's middle and falling to its end, default 0 (flat)",
    )
}

/// The steepest slope a tiled surface may have, degrees (as rigid `slope`).
pub const MAX_SLOPE_DEG: f64 = 45.0;

/// The optional parameters every tiled terrain takes, with their defaults.
pub fn tile_param_decls() -> Vec<ParamDecl> {
    use ParamKind::*;
    use ParamValue as V;
    vec![
        ParamDecl::optional(
            "tile",
            Length,
            V::Length(0.2),
            "distance between tile centres (pitch), default 20cm",
        ),
        ParamDecl::optional(
            "gap",
            Length,
            V::Length(0.002),
            "gap between neighbouring tiles, default 2mm",
        ),
        ParamDecl::optional(
            "travel",
            Length,
            V::Length(0.15),
            "how far a tile can sink, default 15cm",
        ),
        ParamDecl::optional(
            "damping",
            Number,
            V::Number(0.5),
            "damping ratio of a loaded tile, default 0.5",
        ),
        ParamDecl::optional(
            "tile_mass",
            Mass,
            V::Mass(0.5),
            "mass of one tile, default 0.5kg",
        ),
        friction_decl(),
        slope_decl(),
        ParamDecl::optional(
            "crest",
            Length,
            V::Length(0.0),
            "length of the rounded top of every hill (slope=), a parabola that turns the slope from up to down over this length instead of at a point, default 0 (a sharp crest)",
        ),
        ParamDecl::optional(
            "length",
            Length,
            V::Length(DEFAULT_LENGTH_M),
            "extent along x (walking direction), default 40m",
        ),
        ParamDecl::optional(
            "back",
            Length,
            V::Length(2.0),
            "how far the tiles reach behind x = 0, default 2m",
        ),
        ParamDecl::optional(
            "width",
            Length,
            V::Length(3.0),
            "extent across (y), centred on y = 0, default 3m",
        ),
    ]
}

/// Tile-field parameters in SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileParams {
    /// distance between tile centres, m
    pub pitch_m: f64,
    /// gap between neighbouring tiles, m
    pub gap_m: f64,
    /// maximum sink, m
    pub travel_m: f64,
    /// damping ratio of a loaded tile
    pub damping_ratio: f64,
    /// mass of one tile, kg
    pub tile_mass_kg: f64,
    /// friction coefficient of the tiles and the ground
    pub friction: f64,
    /// inclination of the tiles' rest surface, degrees (0: flat)
    pub slope_deg: f64,
    /// length of each hill's rounded top, m (0: a sharp crest)
    pub crest_m: f64,
    /// extent along x, m
    pub length_m: f64,
    /// extent behind x = 0, m
    pub back_m: f64,
    /// extent across, m
    pub width_m: f64,
}

impl TileParams {
    /// Reads the parameters declared by [`tile_param_decls`].
    pub fn from_spec(spec: &TerrainSpec) -> Self {
        Self {
            pitch_m: spec.length_m("tile"),
            gap_m: spec.length_m("gap"),
            travel_m: spec.length_m("travel"),
            damping_ratio: spec.number("damping"),
            tile_mass_kg: spec.mass_kg("tile_mass"),
            friction: spec.number("friction"),
            slope_deg: spec.number("slope"),
            crest_m: spec.length_m("crest"),
            length_m: spec.length_m("length"),
            back_m: spec.length_m("back"),
            width_m: spec.length_m("width"),
        }
    }

    /// Checks the relations between the parameters and the given depths and
    /// slopes (degrees, of the regions' hills; the terrain's own is checked
    /// too).
    pub fn validate(
        &self,
        depths_m: impl IntoIterator<Item = f64>,
        slopes_deg: impl IntoIterator<Item = f64>,
    ) -> Result<(), String> {
        let mut any_hill = false;
        for degrees in std::iter::once(self.slope_deg).chain(slopes_deg) {
            if degrees >= MAX_SLOPE_DEG {
                return Err(format!(
                    "a slope of {degrees} degrees is too steep for tiles (below {MAX_SLOPE_DEG})"
                ));
            }
            any_hill |= degrees > 0.0;
        }
        if self.crest_m > 0.0 && !any_hill {
            return Err(format!(
                "crest={} rounds the crests of hills, and this terrain has none (give it or a region slope=<degrees>)",
                format_length(self.crest_m)
            ));
        }
        if self.gap_m >= self.pitch_m {
            return Err(format!(
                "gap {} must be smaller than the tile pitch {}",
                format_length(self.gap_m),
                format_length(self.pitch_m)
            ));
        }
        if self.length_m < self.pitch_m || self.width_m < self.pitch_m {
            return Err(format!(
                "length and width must hold at least one tile of {}",
                format_length(self.pitch_m)
            ));
        }
        if self.back_m >= self.length_m {
            return Err(format!(
                "back {} must be shorter than the length {}",
                format_length(self.back_m),
                format_length(self.length_m)
            ));
        }
        let tiles = (self.length_m / self.pitch_m).round() * (self.width_m / self.pitch_m).round();
        if tiles > 200_000.0 {
            return Err(format!(
                "{tiles} tiles is more than the 200000 a world may hold; use fewer or larger tiles"
            ));
        }
        for depth_m in depths_m {
            if depth_m > self.travel_m {
                return Err(format!(
                    "depth {} is beyond the tile travel {} (raise travel=...)",
                    format_length(depth_m),
                    format_length(self.travel_m)
                ));
            }
        }
        Ok(())
    }

    /// Spring stiffness (N/m) for a sinking depth under `ctx`'s standing robot.
    pub fn stiffness_n_per_m(depth_m: f64, ctx: &BuildContext) -> f64 {
        ctx.supported_mass_kg * ctx.gravity_m_per_s2 / (4.0 * depth_m)
    }

    /// The spring of a tile that sinks `depth_m` under a quarter of `ctx`'s
    /// standing robot: k = m g / (4 d), damped with the damping ratio.
    pub fn spring(&self, depth_m: f64, ctx: &BuildContext) -> TileSpring {
        let k = Self::stiffness_n_per_m(depth_m, ctx);
        TileSpring {
            depth_m,
            stiffness_n_per_m: k,
            damping_n_s_per_m: self.damping_n_s_per_m(k, ctx),
        }
    }

    /// Spring damping (N s/m) for a stiffness, see the module docs.
    pub fn damping_n_s_per_m(&self, stiffness_n_per_m: f64, ctx: &BuildContext) -> f64 {
        let loaded_mass_kg = self.tile_mass_kg + ctx.supported_mass_kg / 4.0;
        2.0 * self.damping_ratio * (stiffness_n_per_m * loaded_mass_kg).sqrt()
    }
}

/// The defaults of [`tile_param_decls`]: 20 cm pitch on a 40 m x 3 m field
/// reaching 2 m behind x = 0 (for the tile tests, without a spec).
#[cfg(test)]
pub(super) fn default_params() -> TileParams {
    TileParams {
        pitch_m: 0.2,
        gap_m: 0.002,
        travel_m: 0.15,
        damping_ratio: 0.5,
        tile_mass_kg: 0.5,
        friction: 1.0,
        slope_deg: 0.0,
        crest_m: 0.0,
        length_m: 40.0,
        back_m: 2.0,
        width_m: 3.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> TileParams {
        default_params()
    }

    #[test]
    fn the_spring_carries_a_quarter_of_the_robot_at_its_depth_with_the_damping_ratio() {
        let ctx = BuildContext::default();
        let k = TileParams::stiffness_n_per_m(0.05, &ctx);
        assert!((k * 0.05 - ctx.supported_mass_kg * ctx.gravity_m_per_s2 / 4.0).abs() < 1e-9);
        let p = params();
        let c = p.damping_n_s_per_m(k, &ctx);
        let loaded_kg = p.tile_mass_kg + ctx.supported_mass_kg / 4.0;
        let zeta = c / (2.0 * (k * loaded_kg).sqrt());
        assert!((zeta - 0.5).abs() < 1e-12);
    }

    #[test]
    fn relations_between_parameters_are_checked_with_the_values_named() {
        assert_eq!(params().validate([0.05], []), Ok(()));
        let cases = [
            (
                TileParams {
                    gap_m: 0.2,
                    ..params()
                },
                "gap 20cm must be smaller than the tile pitch 20cm",
            ),
            (
                TileParams {
                    width_m: 0.1,
                    ..params()
                },
                "must hold at least one tile",
            ),
            (
                TileParams {
                    back_m: 40.0,
                    ..params()
                },
                "back 40m must be shorter than the length 40m",
            ),
            (
                TileParams {
                    pitch_m: 0.01,
                    gap_m: 0.001,
                    ..params()
                },
                "more than the 200000",
            ),
        ];
        for (p, expected) in cases {
            let err = p.validate([0.05], []).unwrap_err();
            assert!(err.contains(expected), "{err}");
        }
        let err = params().validate([0.05, 0.2], []).unwrap_err();
        assert!(
            err.contains("depth 20cm is beyond the tile travel 15cm"),
            "{err}"
        );
    }
}

//! `varying:<every>:<surfaces>`: the terrain type changes every `every`
//! metres along x (the paper's T_v2 and T_v8). The region around the start
//! takes the first surface of the list (the paper starts training on 2 cm);
//! every later region draws one surface uniformly from the whole list with
//! the world's seed. `rigid` may appear in the list:
//! `varying:2m:2,3,4,5cm,rigid`, and any surface spec in parentheses:
//! `varying:2m:5cm,(soil:4cm),(rough:1cm),(slope:10),(steps:5cm:30cm)`.
//! A slope region is a hill and a steps region a flight of stairs, each up
//! to the region's middle and down to its end, so that regions join at
//! z = 0 (legged_gym's pyramid terrains, along x). Tiles may lie on such a
//! hill too: `(elastic:5cm:slope=10)`, `(soil:4cm:slope=5)`, or `slope=` on
//! the whole spec for every tiled region without its own.

use crate::relief::RegionRelief;
use crate::spec::{Ground, ParamDecl, ParamKind, Surface, TerrainSpec};
use crate::tiles::{RegionLayout, TileParams, TiledTerrain, tile_param_decls};
use crate::units::format_length;
use crate::{BuildContext, Terrain, TerrainPlugin};

/// The `varying` plugin.
pub struct VaryingPlugin;

impl TerrainPlugin for VaryingPlugin {
    fn name(&self) -> &'static str {
        "varying"
    }

    fn summary(&self) -> &'static str {
        "terrain type changes every <every> along x, drawn from <surfaces> (e.g. varying:2m:2,3,4,5cm,rigid)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        let mut params = vec![
            ParamDecl::required("every", ParamKind::Length, "length of each region along x"),
            ParamDecl::required(
                "surfaces",
                ParamKind::Surfaces,
                "surfaces to draw from (depths, `rigid`, (spec)s of other ground); the first is where the robot starts",
            ),
        ];
        params.extend(tile_param_decls());
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        let params = TileParams::from_spec(spec);
        let every_m = spec.length_m("every");
        if every_m < params.pitch_m {
            return Err(format!(
                "regions of {} are shorter than one tile ({})",
                format_length(every_m),
                format_length(params.pitch_m)
            ));
        }
        for surface in spec.surfaces("surfaces") {
            if let Ground::Steps { length_m, .. } = surface.ground
                && RegionRelief::stair_levels(every_m, length_m) == 0
            {
                return Err(format!(
                    "region {surface} has no room for a step in regions of {}: a steps region climbs to its middle and back down, so a step's run must be shorter than half a region",
                    format_length(every_m)
                ));
            }
        }
        let surfaces = spec.surfaces("surfaces");
        let depths = surfaces.iter().map(Surface::max_depth_m);
        // tiled hills and rigid `slope` regions
        let slopes = surfaces.iter().filter_map(|s| match s.ground {
            Ground::Slope { degrees } => Some(degrees),
            _ => s.slope_deg,
        });
        params.validate(depths, slopes)
    }

    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
        let layout = RegionLayout::Varying {
            every_m: spec.length_m("every"),
            surfaces: spec.surfaces("surfaces").to_vec(),
        };
        Box::new(TiledTerrain::new(
            spec.clone(),
            TileParams::from_spec(spec),
            layout,
            ctx,
        ))
    }
}

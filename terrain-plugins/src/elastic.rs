//! `elastic:<depth>`: flat elastic terrain, the paper's model. 20 cm tiles,
//! each on a vertical prismatic joint with a spring whose stiffness makes the
//! standing robot sink `depth` (see [`crate::tiles`] for the derivation).
//! `elastic:2..5cm` gives each tile its own depth, drawn uniformly from the
//! range with the world's seed (per-tile domain randomisation).
//! `elastic:5cm:slope=10` lays the tiles on a hill: rising at 10 degrees from
//! the field's back edge to its middle, falling to its far end (springs
//! still vertical, see [`crate::tiles`]).

use crate::spec::{ParamDecl, ParamKind, Surface, TerrainSpec};
use crate::tiles::{RegionLayout, TileParams, TiledTerrain, tile_param_decls};
use crate::{BuildContext, Terrain, TerrainPlugin};

/// The `elastic` plugin.
pub struct ElasticPlugin;

impl TerrainPlugin for ElasticPlugin {
    fn name(&self) -> &'static str {
        "elastic"
    }

    fn summary(&self) -> &'static str {
        "tiles on springs; the standing robot sinks <depth> (e.g. elastic:5cm)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        let mut params = vec![ParamDecl::required(
            "depth",
            ParamKind::Depth,
            "mean sink of the four loaded tiles under the standing robot; a range a..b draws each tile's own",
        )];
        params.extend(tile_param_decls());
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        TileParams::from_spec(spec).validate([spec.depth_range_m("depth").1], [])
    }

    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
        let (min_depth_m, max_depth_m) = spec.depth_range_m("depth");
        let layout = RegionLayout::Uniform(Surface::from_depth_range(min_depth_m, max_depth_m));
        Box::new(TiledTerrain::new(
            spec.clone(),
            TileParams::from_spec(spec),
            layout,
            ctx,
        ))
    }
}

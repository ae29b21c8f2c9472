//! `elastic:<depth>`: flat elastic terrain, the paper's model. 20 cm tiles,
//! each on a vertical prismatic joint with a spring whose stiffness makes the
//! standing robot sink `depth` (see [`crate::tiles`] for the derivation).

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
            ParamKind::Length,
            "mean sink of the four loaded tiles under the standing robot",
        )];
        params.extend(tile_param_decls());
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        TileParams::from_spec(spec).validate([spec.length_m("depth")])
    }

    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
        let layout = RegionLayout::Uniform(Surface::Elastic {
            depth_m: spec.length_m("depth"),
        });
        Box::new(TiledTerrain::new(
            spec.clone(),
            TileParams::from_spec(spec),
            layout,
            ctx,
        ))
    }
}

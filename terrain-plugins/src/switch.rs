//! `switch:<depth>:<then>:<at>`: elastic tiles whose stiffness changes
//! under the robot's feet. The field is `elastic:<depth>`; `at` seconds of
//! simulated time after each reset (an episode's start, its settle
//! included) every tile's spring becomes the spring of `then` at once, the
//! loaded ones mid-stride. A test terrain for how a controller responds to a
//! sudden change of stiffness (the paper's closing limitation: the motion
//! is planned once per phase while the ground moves): `switch:2cm:5cm:30`
//! softens the ground a third into the task's 40th phase (settle 0.5 s,
//! phases of 0.75 s), `switch:5cm:2cm:30` stiffens it.
//!
//! The switch keeps each tile's rest position: the new spring's preload
//! holds the tile's own weight at rest as the old one did, so unloaded
//! tiles stay where they are and loaded ones move to the sink the new
//! spring gives their load.

use crate::spec::{ParamDecl, ParamKind, Surface, TerrainSpec};
use crate::tiles::{RegionLayout, TileParams, TiledTerrain, tile_param_decls};
use crate::{BuildContext, Terrain, TerrainPlugin};

/// The `switch` plugin.
pub struct SwitchPlugin;

/// When and to what the springs of a [`TiledTerrain`] switch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StiffnessSwitch {
    /// simulated time after a reset at which the springs switch, s
    pub at_secs: f64,
    /// the depth whose spring every tile takes then, m
    pub depth_m: f64,
}

impl TerrainPlugin for SwitchPlugin {
    fn name(&self) -> &'static str {
        "switch"
    }

    fn summary(&self) -> &'static str {
        "elastic tiles that all switch to another depth's spring <at> seconds after each reset (e.g. switch:2cm:5cm:30)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        let mut params = vec![
            ParamDecl::required(
                "depth",
                ParamKind::Length,
                "the standing robot's sink before the switch",
            ),
            ParamDecl::required(
                "then",
                ParamKind::Length,
                "the standing robot's sink after it",
            ),
            ParamDecl::required(
                "at",
                ParamKind::Number,
                "seconds of simulated time after each reset (an episode's settle included)",
            ),
        ];
        params.extend(tile_param_decls());
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        if !(spec.number("at") > 0.0 && spec.number("at").is_finite()) {
            return Err(format!(
                "at = {} must be a positive number of seconds",
                spec.number("at")
            ));
        }
        TileParams::from_spec(spec).validate([spec.length_m("depth"), spec.length_m("then")], [])
    }

    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
        let layout = RegionLayout::Uniform(Surface::elastic(spec.length_m("depth")));
        let switch = StiffnessSwitch {
            at_secs: spec.number("at"),
            depth_m: spec.length_m("then"),
        };
        Box::new(
            TiledTerrain::new(spec.clone(), TileParams::from_spec(spec), layout, ctx)
                .with_switch(switch),
        )
    }
}

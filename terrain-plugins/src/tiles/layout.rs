//! The pure layout of a tile field: which region each column is in, each
//! region's surface, model and report, and each cell's spring. No rapier:
//! [`super::TiledTerrain`] inserts the bodies this describes.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::params::TileParams;
use crate::relief::{HeightGrid, RegionRelief};
use crate::soil::SoilModel;
use crate::spec::{Ground, Surface};
use crate::{BuildContext, Region};

/// Seed offset between the height draws of rough regions.
const ROUGH_REGION_STRIDE: u64 = 0x9e37_79b9_7f4a_7c15;
/// Stream of the per-tile depth draw (mixed into the build seed).
const TILE_DEPTH_STREAM: u64 = 0x7469_6c65_2d64_6570;

/// How the tile field's columns are grouped into regions.
#[derive(Debug, Clone, PartialEq)]
pub enum RegionLayout {
    /// One surface everywhere.
    Uniform(Surface),
    /// The surface changes every `every_m` along x: the region around the
    /// start (x < every) takes the first surface of the list, each later one
    /// a surface drawn uniformly from the whole list with the build seed.
    Varying {
        /// region length along x, m
        every_m: f64,
        /// surfaces to draw from; the first is the starting one
        surfaces: Vec<Surface>,
    },
}

/// How the tiles of one region respond to load.
#[derive(Debug, Clone)]
pub(super) enum RegionModel {
    /// no tiles: a solid block
    Rigid,
    /// every tile on the same spring
    Elastic {
        stiffness_n_per_m: f64,
        damping_n_s_per_m: f64,
    },
    /// each tile its own depth, drawn in [min, max]
    ElasticRange { min_depth_m: f64, max_depth_m: f64 },
    /// elasto-plastic tiles
    Soil {
        model: SoilModel,
        damping_n_s_per_m: f64,
    },
    /// no tiles: rigid relief, rough, a hill or stairs
    Relief(RegionRelief),
}

/// One tile's spring, fixed when the terrain is laid out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileSpring {
    /// the depth the tile sinks under a quarter of the standing robot, m
    pub depth_m: f64,
    /// N/m
    pub stiffness_n_per_m: f64,
    /// N s/m
    pub damping_n_s_per_m: f64,
}

/// The rest top of a column of tiles on a hill: the chord of the region's
/// hill over the column's cell, so that neighbouring tiles' tops meet at
/// their cells' edges (on the hill's straight sides the chord is the hill
/// itself; a cell across the crest is flat, the crest cut by
/// tan(angle) x pitch / 2 at most).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileRest {
    /// the top's height at the column's centre, m
    pub top_m: f64,
    /// the top's rise along x, dz/dx (the tangent of its inclination)
    pub slope: f64,
}

impl TileRest {
    /// The rest top at `x_m` of a tile centred at `center_x_m`, m.
    pub fn top_at_m(&self, x_m: f64, center_x_m: f64) -> f64 {
        self.top_m + self.slope * (x_m - center_x_m)
    }

    /// The top's inclination, radians (positive: rising along +x).
    pub fn angle_rad(&self) -> f64 {
        self.slope.atan()
    }
}

/// Where a field's regions, cells and springs lie.
#[derive(Debug, Clone)]
pub(super) struct FieldLayout {
    /// the regions along x, in order
    pub regions: Vec<Region>,
    /// each region's model
    pub models: Vec<RegionModel>,
    /// each region's friction coefficient
    pub frictions: Vec<f64>,
    /// one entry per cell, row-major by column: `None` for rigid cells
    pub cell_springs: Vec<Option<TileSpring>>,
    /// region index of each column
    pub column_region: Vec<usize>,
    /// each column's rest top if its tiles lie on a hill (`None`: flat, at
    /// z = 0, or no tiles)
    pub column_rest: Vec<Option<TileRest>>,
    /// columns along x
    pub columns: usize,
    /// rows across
    pub rows: usize,
    /// the first cell's centre (x, y), m
    pub first_center_m: [f64; 2],
}

impl FieldLayout {
    /// Lays out a field of `params` grouped by `layout`; the draws (the
    /// surfaces of a varying field, rough heights, per-tile depths) come
    /// from `ctx.seed`.
    pub fn new(params: &TileParams, layout: &RegionLayout, ctx: &BuildContext) -> Self {
        let pitch = params.pitch_m;
        let columns = ((params.length_m / pitch).round() as usize).max(1);
        let rows = ((params.width_m / pitch).round() as usize).max(1);
        let first_x = (pitch * ((-params.back_m + pitch / 2.0) / pitch).round()).min(0.0);
        let first_y = -(rows as f64 - 1.0) * pitch / 2.0;
        let column_x = |ix: usize| first_x + ix as f64 * pitch;

        // Which region each column is in, and each region's surface.
        let mut region_surfaces: Vec<Surface> = Vec::new();
        let mut column_region = Vec::with_capacity(columns);
        match layout {
            RegionLayout::Uniform(surface) => {
                region_surfaces.push(*surface);
                column_region.resize(columns, 0);
            }
            RegionLayout::Varying { every_m, surfaces } => {
                let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
                for ix in 0..columns {
                    // Region r holds the columns whose centre lies in [r every, (r+1) every);
                    // columns behind x = 0 belong to region 0.
                    let r = (column_x(ix) / every_m).floor().max(0.0) as usize;
                    while region_surfaces.len() <= r {
                        let surface = if region_surfaces.is_empty() {
                            surfaces[0]
                        } else {
                            surfaces[rng.random_range(0..surfaces.len())]
                        };
                        region_surfaces.push(surface);
                    }
                    column_region.push(r);
                }
            }
        }

        let half = pitch / 2.0;
        let mut regions = Vec::new();
        let mut models = Vec::new();
        let mut tile_hills = Vec::new();
        let half_width_m = rows as f64 * pitch / 2.0;
        let frictions: Vec<f64> = region_surfaces
            .iter()
            .map(|s| s.friction.unwrap_or(params.friction))
            .collect();
        for (index, surface) in region_surfaces.iter().enumerate() {
            let first = column_region.iter().position(|&r| r == index).unwrap_or(0);
            let last = column_region.iter().rposition(|&r| r == index).unwrap_or(0);
            let x_range_m = (column_x(first) - half, column_x(last) + half);
            // Tiles take the region's own slope, else the terrain's.
            let tiled = matches!(
                surface.ground,
                Ground::Elastic { .. } | Ground::ElasticRange { .. } | Ground::Soil(_)
            );
            let field_slope = (params.slope_deg > 0.0).then_some(params.slope_deg);
            let surface = &Surface {
                slope_deg: surface.slope_deg.or(field_slope).filter(|_| tiled),
                ..*surface
            };
            tile_hills.push(surface.slope_deg.map(|degrees| RegionRelief::Hill {
                x_m: x_range_m,
                y_m: (-half_width_m, half_width_m),
                tan: degrees.to_radians().tan(),
                crest_m: params.crest_m,
            }));
            let spring_at = |depth_m: f64| {
                let s = params.spring(depth_m, ctx);
                (s.stiffness_n_per_m, s.damping_n_s_per_m)
            };
            // What `terrain show` reports: for a range, the springs of its
            // middle depth.
            let (label, model, reported, expected_sink_m) = match surface.ground {
                Ground::Rigid => (surface.label(), RegionModel::Rigid, None, 0.0),
                Ground::Rough {
                    amplitude_m,
                    cell_m,
                } => {
                    // each rough region its own draw
                    let seed = ctx
                        .seed
                        .wrapping_add((index as u64 + 1).wrapping_mul(ROUGH_REGION_STRIDE));
                    let grid = HeightGrid::random(
                        x_range_m,
                        (-half_width_m, half_width_m),
                        cell_m,
                        amplitude_m,
                        seed,
                    );
                    let model = RegionModel::Relief(RegionRelief::Grid(grid));
                    (surface.label(), model, None, 0.0)
                }
                Ground::Slope { degrees } => {
                    let model = RegionModel::Relief(RegionRelief::Hill {
                        x_m: x_range_m,
                        y_m: (-half_width_m, half_width_m),
                        tan: degrees.to_radians().tan(),
                        crest_m: params.crest_m,
                    });
                    (surface.label(), model, None, 0.0)
                }
                Ground::Steps { height_m, length_m } => {
                    let model = RegionModel::Relief(RegionRelief::Stairs {
                        x_m: x_range_m,
                        y_m: (-half_width_m, half_width_m),
                        height_m,
                        length_m,
                    });
                    (surface.label(), model, None, 0.0)
                }
                Ground::Elastic { depth_m } => {
                    let (k, c) = spring_at(depth_m);
                    (
                        surface.label(),
                        RegionModel::Elastic {
                            stiffness_n_per_m: k,
                            damping_n_s_per_m: c,
                        },
                        Some((k, c)),
                        depth_m,
                    )
                }
                Ground::ElasticRange {
                    min_depth_m,
                    max_depth_m,
                } => {
                    let middle_m = (min_depth_m + max_depth_m) / 2.0;
                    (
                        surface.label(),
                        RegionModel::ElasticRange {
                            min_depth_m,
                            max_depth_m,
                        },
                        Some(spring_at(middle_m)),
                        middle_m,
                    )
                }
                Ground::Soil(soil) => {
                    let model = soil.model(ctx);
                    let c = params.damping_n_s_per_m(model.reload_stiffness_n_per_m, ctx);
                    (
                        surface.label(),
                        RegionModel::Soil {
                            model,
                            damping_n_s_per_m: c,
                        },
                        Some((model.reload_stiffness_n_per_m, c)),
                        soil.depth_m,
                    )
                }
            };
            regions.push(Region {
                index,
                label,
                x_range_m,
                stiffness_n_per_m: reported.map(|(k, _)| k),
                damping_n_s_per_m: reported.map(|(_, c)| c),
                expected_sink_m,
            });
            models.push(model);
        }

        // Each cell's spring; a depth range draws one per tile, in cell
        // order, from the build seed (its own stream, apart from the
        // region draw).
        let mut depth_rng = ChaCha8Rng::seed_from_u64(ctx.seed ^ TILE_DEPTH_STREAM);
        let mut cell_springs = Vec::with_capacity(columns * rows);
        for &region in &column_region {
            for _ in 0..rows {
                let spring = match models[region] {
                    RegionModel::Rigid | RegionModel::Relief(_) => None,
                    RegionModel::Elastic {
                        stiffness_n_per_m,
                        damping_n_s_per_m,
                    } => Some(TileSpring {
                        depth_m: regions[region].expected_sink_m,
                        stiffness_n_per_m,
                        damping_n_s_per_m,
                    }),
                    RegionModel::ElasticRange {
                        min_depth_m,
                        max_depth_m,
                    } => {
                        let depth_m = depth_rng.random_range(min_depth_m..=max_depth_m);
                        Some(params.spring(depth_m, ctx))
                    }
                    RegionModel::Soil {
                        model,
                        damping_n_s_per_m,
                    } => Some(TileSpring {
                        depth_m: regions[region].expected_sink_m,
                        stiffness_n_per_m: model.reload_stiffness_n_per_m,
                        damping_n_s_per_m,
                    }),
                };
                cell_springs.push(spring);
            }
        }

        let column_rest = column_region
            .iter()
            .enumerate()
            .map(|(ix, &r)| {
                tile_hills[r].as_ref().map(|hill| {
                    let (left_m, right_m) = (
                        hill.height_m(column_x(ix) - half, 0.0),
                        hill.height_m(column_x(ix) + half, 0.0),
                    );
                    TileRest {
                        top_m: (left_m + right_m) / 2.0,
                        slope: (right_m - left_m) / pitch,
                    }
                })
            })
            .collect();

        Self {
            regions,
            models,
            frictions,
            cell_springs,
            column_region,
            column_rest,
            columns,
            rows,
            first_center_m: [first_x, first_y],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> TileParams {
        super::super::params::default_params()
    }

    fn elastic(depth_m: f64) -> Surface {
        Surface {
            ground: Ground::Elastic { depth_m },
            friction: None,
            slope_deg: None,
        }
    }

    #[test]
    fn cells_sit_on_multiples_of_the_pitch_and_every_spring_sinks_its_depth() {
        let ctx = BuildContext::default();
        let field = FieldLayout::new(&params(), &RegionLayout::Uniform(elastic(0.05)), &ctx);
        assert_eq!((field.columns, field.rows), (200, 15));
        assert_eq!(field.cell_springs.len(), 200 * 15);
        // centres on multiples of the pitch, reaching 2 m behind x = 0; the
        // rows centred on y = 0
        let columns_from_zero = field.first_center_m[0] / 0.2;
        assert!((columns_from_zero - columns_from_zero.round()).abs() < 1e-9);
        assert!((-2.0..=-1.79).contains(&field.first_center_m[0]));
        assert!((field.first_center_m[1] + 1.4).abs() < 1e-12);
        // k = m g / (4 d): the four loaded springs carry the robot at sink d
        let k = ctx.supported_mass_kg * ctx.gravity_m_per_s2 / (4.0 * 0.05);
        for spring in &field.cell_springs {
            let spring = spring.expect("every cell of an elastic field has a tile");
            assert_eq!(spring.depth_m, 0.05);
            assert!((spring.stiffness_n_per_m - k).abs() < 1e-9 * k);
            let sink_m = ctx.supported_mass_kg * ctx.gravity_m_per_s2 / (4.0 * k);
            assert!((sink_m - 0.05).abs() < 1e-12);
        }
        assert_eq!(field.regions.len(), 1);
        assert_eq!(
            field.regions[0].stiffness_n_per_m,
            Some(field.cell_springs[0].unwrap().stiffness_n_per_m)
        );
    }

    #[test]
    fn varying_regions_start_with_the_first_surface_and_repeat_with_the_seed() {
        let surfaces = vec![elastic(0.02), elastic(0.05), Surface::rigid()];
        let layout = RegionLayout::Varying {
            every_m: 2.0,
            surfaces,
        };
        let at = |seed| {
            FieldLayout::new(
                &params(),
                &layout,
                &BuildContext {
                    seed,
                    ..BuildContext::default()
                },
            )
        };
        let a = at(7);
        // 2 m regions from x = 0 to the last column (centred at 38 m, alone
        // in the 20th); the tiles behind x = 0 join region 0
        assert_eq!(a.regions.len(), 20);
        assert_eq!(a.regions[0].label, "elastic:2cm");
        assert!(a.regions[0].x_range_m.0 < -1.8);
        for pair in a.regions[..19].windows(2) {
            assert!((pair[0].x_range_m.1 - pair[1].x_range_m.0).abs() < 1e-9);
            let length_m = pair[1].x_range_m.1 - pair[1].x_range_m.0;
            assert!((1.79..=2.21).contains(&length_m), "{length_m}");
        }
        // rigid regions have no tiles, tiled ones a spring per cell
        for (ix, &r) in a.column_region.iter().enumerate() {
            let cell = a.cell_springs[ix * a.rows];
            assert_eq!(cell.is_none(), a.regions[r].label == "rigid", "column {ix}");
        }
        let labels = |f: &FieldLayout| {
            f.regions
                .iter()
                .map(|r| r.label.clone())
                .collect::<Vec<_>>()
        };
        assert_eq!(labels(&a), labels(&at(7)), "the same seed, the same field");
        assert_ne!(labels(&a), labels(&at(8)), "another seed, another draw");
    }

    #[test]
    fn a_depth_range_draws_each_tile_within_it() {
        let range = Surface {
            ground: Ground::ElasticRange {
                min_depth_m: 0.02,
                max_depth_m: 0.05,
            },
            friction: None,
            slope_deg: None,
        };
        let ctx = BuildContext::default();
        let field = FieldLayout::new(&params(), &RegionLayout::Uniform(range), &ctx);
        let depths: Vec<f64> = field
            .cell_springs
            .iter()
            .map(|s| s.unwrap().depth_m)
            .collect();
        assert!(depths.iter().all(|d| (0.02..=0.05).contains(d)));
        let mean = depths.iter().sum::<f64>() / depths.len() as f64;
        assert!((mean - 0.035).abs() < 0.002, "uniform draw, mean {mean}");
        assert!(
            (field.regions[0].expected_sink_m - 0.035).abs() < 1e-12,
            "reported: the middle"
        );
    }
}

//! Rigid relief, the terrains of legged_gym's curriculum: `slope:<degrees>`
//! (a plane rising along +x), `steps:<height>:<length>` (stairs up along +x
//! from x = 0) and `rough:<amplitude>` (random heights on a grid, drawn with
//! the world's seed). Each takes `friction=` as `rigid` does.
//!
//! The surface height h(x, y) a terrain answers is the collider's own: the
//! plane, the step tops, and for `rough` the same two triangles per grid cell
//! the collider's mesh is made of (split along the cell's diagonal from
//! (x0, y0) to (x1, y1)).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rapier3d::prelude::*;

use crate::spec::{ParamDecl, ParamKind, ParamValue, TerrainSpec};
use crate::tiles::friction_decl;
use crate::units::format_length;
use crate::{
    BuildContext, GroundMesh, Rect, Region, Terrain, TerrainPlugin, TileState, terrain_collider,
};

/// Stream of the `rough` height draw (mixed into the build seed).
const ROUGH_STREAM: u64 = 0x726f_7567_6821;
/// `rough`'s default grid spacing, m.
pub const DEFAULT_CELL_M: f64 = 0.1;
/// How far below its lowest point the relief's solid reaches, m.
const BASE_DEPTH_M: f64 = 1.0;

fn extent_decls() -> Vec<ParamDecl> {
    vec![
        ParamDecl::optional(
            "length",
            ParamKind::Length,
            ParamValue::Length(crate::tiles::DEFAULT_LENGTH_M),
            "extent along x from x = 0, default 40m",
        ),
        ParamDecl::optional(
            "back",
            ParamKind::Length,
            ParamValue::Length(2.0),
            "how far the ground reaches behind x = 0, default 2m",
        ),
        ParamDecl::optional(
            "width",
            ParamKind::Length,
            ParamValue::Length(3.0),
            "extent across (y), centred on y = 0, default 3m",
        ),
    ]
}

/// Heights on a grid of square cells, the ground of `rough` and of rough
/// `varying` regions: a triangle mesh, two triangles per cell split along
/// the diagonal from (x0, y0) to (x1, y1).
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    /// cell side, m
    pub cell_m: f64,
    /// the grid's corner of smallest x and y, m
    pub origin_m: [f64; 2],
    /// cells along x
    pub columns: usize,
    /// cells along y
    pub rows: usize,
    /// (columns + 1) x (rows + 1) heights, row-major by x, m
    pub heights_m: Vec<f64>,
}

impl HeightGrid {
    /// A grid over [x0, x1] x [y0, y1] with heights drawn uniformly in
    /// [-amplitude, amplitude] from `seed`.
    pub fn random(
        x_m: (f64, f64),
        y_m: (f64, f64),
        cell_m: f64,
        amplitude_m: f64,
        seed: u64,
    ) -> Self {
        let columns = ((x_m.1 - x_m.0) / cell_m).ceil().max(1.0) as usize;
        let rows = ((y_m.1 - y_m.0) / cell_m).ceil().max(1.0) as usize;
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ ROUGH_STREAM);
        let heights_m = (0..(columns + 1) * (rows + 1))
            .map(|_| rng.random_range(-amplitude_m..=amplitude_m))
            .collect();
        Self {
            cell_m,
            origin_m: [x_m.0, (y_m.0 + y_m.1) / 2.0 - rows as f64 * cell_m / 2.0],
            columns,
            rows,
            heights_m,
        }
    }

    /// The mesh's height at (x, y) (clamped to the grid), m.
    pub fn height_m(&self, x_m: f64, y_m: f64) -> f64 {
        let (columns, rows) = (self.columns, self.rows);
        let gx = ((x_m - self.origin_m[0]) / self.cell_m).clamp(0.0, columns as f64);
        let gy = ((y_m - self.origin_m[1]) / self.cell_m).clamp(0.0, rows as f64);
        let (i, j) = ((gx as usize).min(columns - 1), (gy as usize).min(rows - 1));
        let (fx, fy) = (gx - i as f64, gy - j as f64);
        let h = |a: usize, b: usize| self.heights_m[a * (rows + 1) + b];
        let (h00, h10, h01, h11) = (h(i, j), h(i + 1, j), h(i, j + 1), h(i + 1, j + 1));
        if fx >= fy {
            h00 + fx * (h10 - h00) + fy * (h11 - h10)
        } else {
            h00 + fy * (h01 - h00) + fx * (h11 - h01)
        }
    }

    /// The lowest height, m.
    pub fn lowest_m(&self) -> f64 {
        self.heights_m.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// The grid as triangles, world frame.
    pub fn mesh(&self) -> GroundMesh {
        let mut mesh = GroundMesh::default();
        let rows = self.rows;
        for i in 0..=self.columns {
            for j in 0..=rows {
                mesh.vertices_m.push([
                    self.origin_m[0] + i as f64 * self.cell_m,
                    self.origin_m[1] + j as f64 * self.cell_m,
                    self.heights_m[i * (rows + 1) + j],
                ]);
            }
        }
        let index = |i: usize, j: usize| (i * (rows + 1) + j) as u32;
        for i in 0..self.columns {
            for j in 0..rows {
                // counter-clockwise seen from above: normals point up
                mesh.triangles
                    .push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
                mesh.triangles
                    .push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
            }
        }
        mesh
    }

    /// The mesh as a collider (friction and groups still to set).
    pub fn collider(&self) -> ColliderBuilder {
        let mesh = self.mesh();
        let vertices = mesh
            .vertices_m
            .iter()
            .map(|v| Vector::new(v[0] as f32, v[1] as f32, v[2] as f32))
            .collect();
        ColliderBuilder::trimesh(vertices, mesh.triangles)
            .expect("a grid of at least one cell makes a valid mesh")
    }
}

/// Chords of a hill's rounded crest in its mesh and collider.
const CREST_SEGMENTS: usize = 16;

/// How far a region's relief solid reaches below z = 0, m (it overlaps the
/// region's block, whose top is 1 cm below the relief's lowest point).
const REGION_SOLID_BOTTOM_M: f64 = -0.02;

/// The rigid relief of one `varying` region, over its x range and the
/// field's width. Hills and stairs start and end at z = 0, so that regions
/// join without a step (legged_gym's pyramid terrains, along x only).
#[derive(Debug, Clone, PartialEq)]
pub enum RegionRelief {
    /// random heights (`rough`)
    Grid(HeightGrid),
    /// `slope`: h = tan(angle) min(x - x0, x1 - x), up to the region's
    /// middle and down to its end; with a rounded crest of length w, the
    /// parabola h = tan (L/2 - w/4) - tan s^2 / w over |s| < w/2 around the
    /// middle (s = x - middle, L = x1 - x0), which meets both slopes with
    /// their height and gradient (radius of curvature w / (2 tan))
    Hill {
        /// the region's ends along x, m
        x_m: (f64, f64),
        /// the field's sides, m
        y_m: (f64, f64),
        /// tangent of the inclination
        tan: f64,
        /// length of the rounded crest, m (0: sharp; at most the region's)
        crest_m: f64,
    },
    /// `steps`: h = height min(floor((x - x0) / run), floor((x1 - x) / run),
    /// levels), stairs up to the region's middle and down to its end;
    /// `levels` is the most steps whose top tread keeps a positive length,
    /// ceil((x1 - x0) / (2 run)) - 1
    Stairs {
        /// the region's ends along x, m
        x_m: (f64, f64),
        /// the field's sides, m
        y_m: (f64, f64),
        /// rise of each step, m
        height_m: f64,
        /// run of each step, m
        length_m: f64,
    },
}

impl RegionRelief {
    /// Steps up (and down) of a region `region_length_m` long whose steps
    /// run `length_m`: ceil(region / (2 run)) - 1, at least 0.
    pub fn stair_levels(region_length_m: f64, length_m: f64) -> usize {
        // the small tolerance keeps an exact multiple from gaining a
        // zero-length top tread through rounding
        ((region_length_m / (2.0 * length_m) - 1e-9).ceil() - 1.0).max(0.0) as usize
    }

    /// The surface height at (x, y), m (x clamped to the region).
    pub fn height_m(&self, x_m: f64, y_m: f64) -> f64 {
        match self {
            Self::Grid(grid) => grid.height_m(x_m, y_m),
            Self::Hill {
                x_m: (x0, x1),
                tan,
                crest_m,
                ..
            } => {
                let x = x_m.clamp(*x0, *x1);
                let from_end = (x - x0).min(x1 - x);
                let (half, crest) = ((x1 - x0) / 2.0, crest_m.min(x1 - x0));
                if crest > 0.0 && from_end > half - crest / 2.0 {
                    let s = half - from_end;
                    tan * (half - crest / 4.0) - tan * s * s / crest
                } else {
                    tan * from_end
                }
            }
            Self::Stairs {
                x_m: (x0, x1),
                height_m,
                length_m,
                ..
            } => {
                let x = x_m.clamp(*x0, *x1);
                let levels = Self::stair_levels(x1 - x0, *length_m);
                let up = ((x - x0) / length_m).floor();
                let down = ((x1 - x) / length_m).floor();
                height_m * up.min(down).clamp(0.0, levels as f64)
            }
        }
    }

    /// The lowest surface height, m.
    pub fn lowest_m(&self) -> f64 {
        match self {
            Self::Grid(grid) => grid.lowest_m(),
            Self::Hill { .. } | Self::Stairs { .. } => 0.0,
        }
    }

    /// The profile (x, z) along x of a hill or stairs, from x0 to x1 (a riser
    /// is two points at the same x); empty for a grid.
    fn profile_m(&self) -> Vec<[f64; 2]> {
        match self {
            Self::Grid(_) => Vec::new(),
            Self::Hill {
                x_m: (x0, x1),
                tan,
                crest_m,
                ..
            } => {
                let middle = (x0 + x1) / 2.0;
                let crest = crest_m.min(x1 - x0);
                if crest == 0.0 {
                    return vec![[*x0, 0.0], [middle, tan * (middle - x0)], [*x1, 0.0]];
                }
                // the parabola in chords, its ends on the slopes
                let top = (0..=CREST_SEGMENTS).map(|k| {
                    let x = middle - crest / 2.0 + crest * k as f64 / CREST_SEGMENTS as f64;
                    [x, self.height_m(x, 0.0)]
                });
                std::iter::once([*x0, 0.0])
                    .chain(top)
                    .chain(std::iter::once([*x1, 0.0]))
                    .collect()
            }
            Self::Stairs {
                x_m: (x0, x1),
                height_m,
                length_m,
                ..
            } => {
                let levels = Self::stair_levels(x1 - x0, *length_m);
                let mut points = vec![[*x0, 0.0]];
                for k in 1..=levels {
                    let x = x0 + k as f64 * length_m;
                    points.push([x, (k - 1) as f64 * height_m]);
                    points.push([x, k as f64 * height_m]);
                }
                for k in (1..=levels).rev() {
                    let x = x1 - k as f64 * length_m;
                    points.push([x, k as f64 * height_m]);
                    points.push([x, (k - 1) as f64 * height_m]);
                }
                points.push([*x1, 0.0]);
                points
            }
        }
    }

    /// The surface as triangles, world frame (risers included).
    pub fn mesh(&self) -> GroundMesh {
        let (y0, y1) = match self {
            Self::Grid(grid) => return grid.mesh(),
            Self::Hill { y_m, .. } | Self::Stairs { y_m, .. } => *y_m,
        };
        let mut mesh = GroundMesh::default();
        for pair in self.profile_m().windows(2) {
            let ([xa, za], [xb, zb]) = (pair[0], pair[1]);
            // counter-clockwise seen from the side the surface faces
            mesh.push_quad([[xa, y0, za], [xb, y0, zb], [xb, y1, zb], [xa, y1, za]]);
        }
        mesh
    }

    /// Solid colliders of the relief (friction and groups still to set): the
    /// grid's mesh; a hill's prism; the stairs' nested blocks, block k over
    /// [x0 + k run, x1 - k run] up to k height.
    pub fn colliders(&self) -> Vec<ColliderBuilder> {
        let bottom = REGION_SOLID_BOTTOM_M;
        match self {
            Self::Grid(grid) => vec![grid.collider()],
            Self::Hill { y_m: (y0, y1), .. } => {
                let mut points = Vec::new();
                for [x, z] in self.profile_m() {
                    for y in [*y0, *y1] {
                        points.push(Vector::new(x as f32, y as f32, z as f32));
                        points.push(Vector::new(x as f32, y as f32, bottom as f32));
                    }
                }
                vec![ColliderBuilder::convex_hull(&points).expect("a hill's prism has volume")]
            }
            Self::Stairs {
                x_m: (x0, x1),
                y_m: (y0, y1),
                height_m,
                length_m,
            } => (0..=Self::stair_levels(x1 - x0, *length_m))
                .map(|k| {
                    let (a, b) = (x0 + k as f64 * length_m, x1 - k as f64 * length_m);
                    let top = k as f64 * height_m;
                    ColliderBuilder::cuboid(
                        ((b - a) / 2.0) as f32,
                        ((y1 - y0) / 2.0) as f32,
                        ((top - bottom) / 2.0) as f32,
                    )
                    .translation(Vector::new(
                        ((a + b) / 2.0) as f32,
                        ((y0 + y1) / 2.0) as f32,
                        ((top + bottom) / 2.0) as f32,
                    ))
                })
                .collect(),
        }
    }
}

/// The shape of a relief.
#[derive(Debug, Clone, PartialEq)]
enum Shape {
    /// h = x tan(angle)
    Slope { tan: f64 },
    /// h = height floor(x / length) for 0 <= x, 0 behind
    Steps { height_m: f64, length_m: f64 },
    /// heights on a grid
    Rough(HeightGrid),
}

/// A rigid relief.
pub struct Relief {
    spec: TerrainSpec,
    shape: Shape,
    extent: Rect,
    friction: f64,
    regions: Vec<Region>,
}

impl Relief {
    /// `length_key` names the extent along x (`length`, or `extent` for
    /// `steps`, whose `length` is a step's).
    fn new(spec: &TerrainSpec, shape: Shape, length_key: &str) -> Self {
        let (length_m, back_m, width_m) = (
            spec.length_m(length_key),
            spec.length_m("back"),
            spec.length_m("width"),
        );
        let extent = Rect {
            min_m: [-back_m, -width_m / 2.0],
            max_m: [length_m, width_m / 2.0],
        };
        Self {
            spec: spec.clone(),
            shape,
            extent,
            friction: spec.number("friction"),
            regions: vec![Region {
                index: 0,
                label: spec.to_string(),
                x_range_m: (extent.min_m[0], extent.max_m[0]),
                stiffness_n_per_m: None,
                damping_n_s_per_m: None,
                expected_sink_m: 0.0,
            }],
        }
    }

    /// The surface height at (x, y), metres (the shape continued past the
    /// extent's ends along x; clamped to the grid for `rough`).
    pub fn height_m(&self, x_m: f64, y_m: f64) -> f64 {
        match &self.shape {
            Shape::Slope { tan } => x_m * tan,
            Shape::Steps { height_m, length_m } => {
                let x = x_m.clamp(0.0, self.extent.max_m[0]);
                height_m * (x / length_m).floor()
            }
            Shape::Rough(grid) => grid.height_m(x_m, y_m),
        }
    }

    fn collider(&self, builder: ColliderBuilder) -> ColliderBuilder {
        terrain_collider(builder, self.friction)
    }
}

impl Terrain for Relief {
    fn spec(&self) -> &TerrainSpec {
        &self.spec
    }

    fn build(&mut self, world: &mut PhysicsWorld) {
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let e = self.extent;
        let half_y = ((e.max_m[1] - e.min_m[1]) / 2.0) as f32;
        match &self.shape {
            Shape::Slope { tan } => {
                let angle = tan.atan();
                let normal = Vector::new(-angle.sin() as f32, 0.0, angle.cos() as f32);
                let plane = ColliderBuilder::halfspace(rapier3d::na::Unit::new_unchecked(
                    normal.normalize(),
                ));
                world.insert_collider(self.collider(plane), Some(ground));
            }
            Shape::Steps { height_m, length_m } => {
                // behind x = 0 and each step: a block from below the base to its top
                let steps = (e.max_m[0] / length_m).ceil() as usize;
                let mut blocks = vec![(e.min_m[0] - 50.0, 0.0, 0.0)];
                for k in 0..steps {
                    let x0 = k as f64 * length_m;
                    blocks.push((x0, (x0 + length_m).min(e.max_m[0]), k as f64 * height_m));
                }
                if let Some(&(_, last_end, top)) = blocks.last() {
                    blocks.push((last_end, last_end + 50.0, top)); // the landing beyond
                }
                for (x0, x1, top) in blocks {
                    let bottom = -BASE_DEPTH_M - height_m.abs() * steps as f64;
                    let block = ColliderBuilder::cuboid(
                        ((x1 - x0) / 2.0) as f32,
                        half_y + 50.0,
                        ((top - bottom) / 2.0) as f32,
                    )
                    .translation(Vector::new(
                        ((x0 + x1) / 2.0) as f32,
                        0.0,
                        ((top + bottom) / 2.0) as f32,
                    ));
                    world.insert_collider(self.collider(block), Some(ground));
                }
            }
            Shape::Rough(grid) => {
                world.insert_collider(self.collider(grid.collider()), Some(ground));
                // a floor under the whole grid, and flat ground beyond it
                let floor = ColliderBuilder::cuboid(100.0, 100.0, 0.5).translation(Vector::new(
                    0.0,
                    0.0,
                    (grid.lowest_m() - 0.05 - 0.5) as f32,
                ));
                world.insert_collider(self.collider(floor), Some(ground));
            }
        }
    }

    fn surface_height_m(&self, _world: &PhysicsWorld, x_m: f64, y_m: f64) -> f64 {
        self.height_m(x_m, y_m)
    }

    fn rest_height_m(&self, x_m: f64, y_m: f64) -> f64 {
        self.height_m(x_m, y_m)
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }

    fn region_index_at(&self, _x_m: f64, _y_m: f64) -> usize {
        0
    }

    fn tiles_in(&self, _world: &PhysicsWorld, _area: Rect, _out: &mut Vec<TileState>) {}

    fn extent(&self) -> Rect {
        self.extent
    }

    fn tile_count(&self) -> usize {
        0
    }

    fn ground_mesh(&self) -> Option<GroundMesh> {
        let e = self.extent;
        let (x0, x1, y0, y1) = (e.min_m[0], e.max_m[0], e.min_m[1], e.max_m[1]);
        let mut mesh = GroundMesh::default();
        match &self.shape {
            Shape::Slope { .. } => mesh.push_quad([
                [x0, y0, self.height_m(x0, y0)],
                [x1, y0, self.height_m(x1, y0)],
                [x1, y1, self.height_m(x1, y1)],
                [x0, y1, self.height_m(x0, y1)],
            ]),
            Shape::Steps { height_m, length_m } => {
                mesh.push_quad([[x0, y0, 0.0], [0.0, y0, 0.0], [0.0, y1, 0.0], [x0, y1, 0.0]]);
                let steps = (x1 / length_m).ceil() as usize;
                for k in 0..steps {
                    let (a, b) = (k as f64 * length_m, ((k + 1) as f64 * length_m).min(x1));
                    let z = k as f64 * height_m;
                    if k > 0 {
                        // the riser, facing -x
                        let below = z - height_m;
                        mesh.push_quad([[a, y1, below], [a, y0, below], [a, y0, z], [a, y1, z]]);
                    }
                    mesh.push_quad([[a, y0, z], [b, y0, z], [b, y1, z], [a, y1, z]]);
                }
            }
            Shape::Rough(grid) => mesh = grid.mesh(),
        }
        Some(mesh)
    }

    fn details(&self) -> Vec<String> {
        match &self.shape {
            Shape::Rough(HeightGrid { heights_m, .. }) => {
                let n = heights_m.len() as f64;
                let mean = heights_m.iter().sum::<f64>() / n;
                let rms = (heights_m.iter().map(|h| (h - mean).powi(2)).sum::<f64>() / n).sqrt();
                vec![format!(
                    "{} grid heights, mean {:.2} cm, rms {:.2} cm (seed draw)",
                    heights_m.len(),
                    mean * 100.0,
                    rms * 100.0
                )]
            }
            Shape::Slope { tan } => vec![format!("rises {:.1} cm per metre along x", tan * 100.0)],
            Shape::Steps { height_m, length_m } => vec![format!(
                "{} steps of {} every {}",
                (self.extent.max_m[0] / length_m).ceil(),
                format_length(*height_m),
                format_length(*length_m)
            )],
        }
    }
}

/// The `slope` plugin.
pub struct SlopePlugin;

impl TerrainPlugin for SlopePlugin {
    fn name(&self) -> &'static str {
        "slope"
    }

    fn summary(&self) -> &'static str {
        "rigid ground rising along x at <degrees> (e.g. slope:10)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        let mut params = vec![
            ParamDecl::required(
                "degrees",
                ParamKind::Number,
                "inclination, degrees (rising along +x)",
            ),
            friction_decl(),
        ];
        params.extend(extent_decls());
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        let degrees = spec.number("degrees");
        if degrees >= 45.0 {
            return Err(format!(
                "a slope of {degrees} degrees is too steep (below 45)"
            ));
        }
        Ok(())
    }

    fn create(&self, spec: &TerrainSpec, _ctx: &BuildContext) -> Box<dyn Terrain> {
        let tan = spec.number("degrees").to_radians().tan();
        Box::new(Relief::new(spec, Shape::Slope { tan }, "length"))
    }
}

/// The `steps` plugin.
pub struct StepsPlugin;

impl TerrainPlugin for StepsPlugin {
    fn name(&self) -> &'static str {
        "steps"
    }

    fn summary(&self) -> &'static str {
        "rigid stairs up along x from x = 0: <height> every <length> (e.g. steps:5cm:1m)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        let mut params = vec![
            ParamDecl::required("height", ParamKind::Length, "rise of each step"),
            ParamDecl::required("length", ParamKind::Length, "run of each step along x"),
            friction_decl(),
        ];
        let mut extent = extent_decls();
        extent[0].name = "extent";
        extent[0].doc = "how far the stairs reach along x from x = 0, default 40m";
        params.extend(extent);
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        let (height, length) = (spec.length_m("height"), spec.length_m("length"));
        if height > 0.3 {
            return Err(format!(
                "steps of {} are higher than the robot can climb (at most 30cm)",
                format_length(height)
            ));
        }
        if length < 0.1 {
            return Err(format!(
                "steps of {} are shorter than 10cm",
                format_length(length)
            ));
        }
        Ok(())
    }

    fn create(&self, spec: &TerrainSpec, _ctx: &BuildContext) -> Box<dyn Terrain> {
        let shape = Shape::Steps {
            height_m: spec.length_m("height"),
            length_m: spec.length_m("length"),
        };
        Box::new(Relief::new(spec, shape, "extent"))
    }
}

/// The `rough` plugin.
pub struct RoughPlugin;

impl TerrainPlugin for RoughPlugin {
    fn name(&self) -> &'static str {
        "rough"
    }

    fn summary(&self) -> &'static str {
        "rigid ground with random heights in +-<amplitude> on a grid, drawn with the seed (e.g. rough:2cm)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        let mut params = vec![
            ParamDecl::required(
                "amplitude",
                ParamKind::Length,
                "heights are drawn uniformly in [-amplitude, amplitude]",
            ),
            ParamDecl::optional(
                "cell",
                ParamKind::Length,
                ParamValue::Length(DEFAULT_CELL_M),
                "grid spacing, default 10cm",
            ),
            friction_decl(),
        ];
        params.extend(extent_decls());
        params
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        let (amplitude, cell) = (spec.length_m("amplitude"), spec.length_m("cell"));
        if amplitude > 0.15 {
            return Err(format!(
                "amplitude {} is more than the robot can walk on (at most 15cm)",
                format_length(amplitude)
            ));
        }
        let cells = (spec.length_m("length") + spec.length_m("back")) / cell
            * (spec.length_m("width") / cell);
        if cells > 500_000.0 {
            return Err(format!(
                "{cells:.0} grid cells is more than 500000; use a larger cell"
            ));
        }
        Ok(())
    }

    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
        let (amplitude_m, cell_m) = (spec.length_m("amplitude"), spec.length_m("cell"));
        let (length_m, back_m, width_m) = (
            spec.length_m("length"),
            spec.length_m("back"),
            spec.length_m("width"),
        );
        let grid = HeightGrid::random(
            (-back_m, length_m),
            (-width_m / 2.0, width_m / 2.0),
            cell_m,
            amplitude_m,
            ctx.seed,
        );
        let shape = Shape::Rough(grid);
        Box::new(Relief::new(spec, shape, "length"))
    }
}

//! One frame of a rollout drawn on the CPU: a side view (x right, z up,
//! seen from the robot's right) above a top view (x right, y up), both
//! centred on the base at the same scale, the robot's collision shapes
//! projected and filled, the tiles coloured by their sink (the colour scale
//! at the right), the swing foot's target landing point, the base's path
//! and a caption.

use anyhow::{Result, anyhow};
use nalgebra::{Isometry3, Point3, Vector3};
use plotters::prelude::*;
use robot::model::{Geometry, LegName, RobotModel};
use terrain_plugins::TileState;

/// The font of the caption and labels (the one `eval`'s figures use).
const FONT: &str = crate::eval::plots::FONT;

/// Heights the side view shows above and below the ground at the base, m.
const SIDE_VIEW_Z_RANGE_M: (f64, f64) = (-0.2, 0.8);

/// Everything one frame shows, world frame, metres.
pub struct FrameState<'a> {
    /// the robot
    pub model: &'a RobotModel,
    /// each model body's pose
    pub body_poses: &'a [Isometry3<f64>],
    /// the tiles near the base
    pub tiles: &'a [TileState],
    /// the ground's surface along the base's y, (x, z), increasing x
    pub ground_profile_m: &'a [(f64, f64)],
    /// the base's path so far
    pub base_path_m: &'a [Vector3<f64>],
    /// the swinging leg and where it is sent to land
    pub swing: Option<(LegName, Vector3<f64>)>,
    /// the text above the views
    pub caption: &'a str,
}

fn plot_error(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow!("drawing a video frame: {e}")
}

/// The convex hull of `points` (Andrew's monotone chain), counter-clockwise.
fn convex_hull(mut points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    points.dedup();
    if points.len() < 3 {
        return points;
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(2 * points.len());
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in ordered {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Points on a circle of `radius_m` around `centre` in the plane of `u`
/// and `v` (unit, orthogonal).
fn ring(
    centre: Vector3<f64>,
    u: Vector3<f64>,
    v: Vector3<f64>,
    radius_m: f64,
) -> Vec<Vector3<f64>> {
    (0..16)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 16.0;
            centre + radius_m * (a.cos() * u + a.sin() * v)
        })
        .collect()
}

/// World points whose projection's hull is the shape's silhouette in a
/// view whose screen axes are `right` and `up`.
fn silhouette_points(
    pose: &Isometry3<f64>,
    geometry: &Geometry,
    right: Vector3<f64>,
    up: Vector3<f64>,
) -> Vec<Vector3<f64>> {
    let at = |p: Vector3<f64>| (pose * Point3::from(p)).coords;
    let axis = |a: Vector3<f64>| pose.rotation * a;
    match geometry {
        Geometry::Box { half_extents_m: h } => (0..8)
            .map(|k| {
                let sign = |bit: usize| if k >> bit & 1 == 1 { 1.0 } else { -1.0 };
                at(Vector3::new(sign(0) * h.x, sign(1) * h.y, sign(2) * h.z))
            })
            .collect(),
        Geometry::Sphere { radius_m } => ring(at(Vector3::zeros()), right, up, *radius_m),
        Geometry::Cylinder {
            radius_m,
            half_length_m,
        } => [-1.0, 1.0]
            .into_iter()
            .flat_map(|s| {
                ring(
                    at(Vector3::z() * (s * *half_length_m)),
                    axis(Vector3::x()),
                    axis(Vector3::y()),
                    *radius_m,
                )
            })
            .collect(),
        Geometry::Capsule {
            radius_m,
            half_length_m,
        } => [-1.0, 1.0]
            .into_iter()
            .flat_map(|s| {
                ring(
                    at(Vector3::z() * (s * *half_length_m)),
                    right,
                    up,
                    *radius_m,
                )
            })
            .collect(),
        Geometry::ConvexHull { points_m } => points_m.iter().map(|p| at(*p)).collect(),
    }
}

/// One of the two views: which world axes map to the screen and where.
struct View {
    /// world direction of screen right
    right: Vector3<f64>,
    /// world direction of screen up
    up: Vector3<f64>,
    /// world direction away from the viewer (depth)
    depth: Vector3<f64>,
    /// the world point at the view's centre
    centre: Vector3<f64>,
    /// pixels per metre
    scale: f64,
    /// the view's size, pixels
    size_px: (i32, i32),
}

impl View {
    fn px(&self, p: &Vector3<f64>) -> (i32, i32) {
        let d = p - self.centre;
        (
            (f64::from(self.size_px.0) / 2.0 + d.dot(&self.right) * self.scale).round() as i32,
            (f64::from(self.size_px.1) / 2.0 - d.dot(&self.up) * self.scale).round() as i32,
        )
    }

    fn px_hull(&self, points: &[Vector3<f64>]) -> Vec<(i32, i32)> {
        let flat = points
            .iter()
            .map(|p| {
                let d = p - self.centre;
                (d.dot(&self.right), d.dot(&self.up))
            })
            .collect();
        convex_hull(flat)
            .into_iter()
            .map(|(r, u)| {
                (
                    (f64::from(self.size_px.0) / 2.0 + r * self.scale).round() as i32,
                    (f64::from(self.size_px.1) / 2.0 - u * self.scale).round() as i32,
                )
            })
            .collect()
    }
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

/// Which leg each body belongs to (`None`: the base and other bodies).
fn body_legs(model: &RobotModel) -> Vec<Option<LegName>> {
    let mut legs = vec![None; model.bodies.len()];
    for leg in &model.legs {
        for &j in &leg.joints {
            legs[model.joints[j].child] = Some(leg.name);
        }
        legs[leg.foot_body] = Some(leg.name);
    }
    legs
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Ground that is not a tile (a colour the GIF palette holds exactly).
const SAND: RGBColor = RGBColor(204, 204, 153);
const BASE_COLOUR: RGBColor = RGBColor(70, 110, 170);
const NEAR_LEG: RGBColor = RGBColor(55, 60, 70);
const FAR_LEG: RGBColor = RGBColor(150, 155, 165);
const SWING_LEG: RGBColor = RGBColor(235, 140, 20);
const TARGET: RGBColor = RGBColor(200, 0, 0);
const PATH: RGBColor = RGBColor(90, 90, 200);

/// A shape as drawn: its mean depth along the view, its outline in pixels
/// and its colour.
type Silhouette = (f64, Vec<(i32, i32)>, RGBColor);

/// The robot's shapes in `view`, far ones first.
fn draw_robot(area: &Area, view: &View, state: &FrameState) -> Result<()> {
    let legs = body_legs(state.model);
    let mut shapes: Vec<Silhouette> = Vec::new();
    for (k, (body, pose)) in state.model.bodies.iter().zip(state.body_poses).enumerate() {
        for shape in &body.collisions {
            let shape_pose = pose * shape.shape_in_body;
            let points = silhouette_points(&shape_pose, &shape.geometry, view.right, view.up);
            let depth =
                points.iter().map(|p| p.dot(&view.depth)).sum::<f64>() / points.len().max(1) as f64;
            let colour = match legs[k] {
                None => BASE_COLOUR,
                Some(leg) if state.swing.is_some_and(|(s, _)| s == leg) => SWING_LEG,
                // seen from the right (side view) or from above (top view):
                // the left legs are the far ones from the side
                Some(leg) if view.depth.y > 0.5 && leg.side_sign() > 0.0 => FAR_LEG,
                Some(_) => NEAR_LEG,
            };
            shapes.push((depth, view.px_hull(&points), colour));
        }
    }
    shapes.sort_by(|a, b| b.0.total_cmp(&a.0));
    for (_, hull, colour) in shapes {
        if hull.len() >= 3 {
            area.draw(&Polygon::new(hull.clone(), colour.filled()))
                .map_err(plot_error)?;
            let mut closed = hull;
            closed.push(closed[0]);
            area.draw(&PathElement::new(closed, BLACK.mix(0.5)))
                .map_err(plot_error)?;
        }
    }
    Ok(())
}

/// The base's path in `view`.
fn draw_path(area: &Area, view: &View, state: &FrameState) -> Result<()> {
    if state.base_path_m.len() >= 2 {
        let points: Vec<(i32, i32)> = state.base_path_m.iter().map(|p| view.px(p)).collect();
        area.draw(&PathElement::new(points, PATH.stroke_width(2)))
            .map_err(plot_error)?;
    }
    Ok(())
}

/// The swing foot's target landing point in `view`, a cross.
fn draw_target(area: &Area, view: &View, state: &FrameState) -> Result<()> {
    if let Some((_, landing)) = state.swing {
        let (x, y) = view.px(&landing);
        for (dx, dy) in [(1, 1), (1, -1)] {
            area.draw(&PathElement::new(
                vec![(x - 6 * dx, y - 6 * dy), (x + 6 * dx, y + 6 * dy)],
                TARGET.stroke_width(2),
            ))
            .map_err(plot_error)?;
        }
    }
    Ok(())
}

/// A tile between the pixel corners `corners`, coloured by its sink.
fn draw_tile(area: &Area, corners: [(i32, i32); 2], sink_m: f64) -> Result<()> {
    area.draw(&Rectangle::new(
        corners,
        rgb(viz::sink_colour(sink_m)).filled(),
    ))
    .map_err(plot_error)?;
    area.draw(&Rectangle::new(corners, BLACK.mix(0.35)))
        .map_err(plot_error)?;
    Ok(())
}

fn draw_side(area: &Area, view: &View, state: &FrameState) -> Result<()> {
    // the ground along the base's y, filled below
    if state.ground_profile_m.len() >= 2 {
        let (w, h) = view.size_px;
        let mut ground: Vec<(i32, i32)> = state
            .ground_profile_m
            .iter()
            .map(|&(x, z)| view.px(&Vector3::new(x, view.centre.y, z)))
            .collect();
        ground.push((w, h));
        ground.push((0, h));
        area.draw(&Polygon::new(ground, SAND.filled()))
            .map_err(plot_error)?;
    }
    // the row of tiles under the robot, deepest drawn last
    let mut row: Vec<&TileState> = state
        .tiles
        .iter()
        .filter(|t| (t.center_m[1] - view.centre.y).abs() <= 0.3)
        .collect();
    row.sort_by(|a, b| a.sink_m.total_cmp(&b.sink_m));
    for tile in row {
        let top = tile.rest_top_m - tile.sink_m;
        let half = tile.side_m / 2.0;
        if tile.rest_slope == 0.0 {
            let a = view.px(&Vector3::new(tile.center_m[0] - half, view.centre.y, top));
            let b = view.px(&Vector3::new(
                tile.center_m[0] + half,
                view.centre.y,
                top - 0.04,
            ));
            draw_tile(area, [a, b], tile.sink_m)?;
        } else {
            // a tile on a hill: its inclined top and a 4 cm side below it
            let rise = tile.rest_slope * half;
            let corners: Vec<(i32, i32)> = [
                (-half, top - rise),
                (half, top + rise),
                (half, top + rise - 0.04),
                (-half, top - rise - 0.04),
            ]
            .iter()
            .map(|&(dx, z)| view.px(&Vector3::new(tile.center_m[0] + dx, view.centre.y, z)))
            .collect();
            area.draw(&Polygon::new(
                corners.clone(),
                rgb(viz::sink_colour(tile.sink_m)).filled(),
            ))
            .map_err(plot_error)?;
            let mut outline = corners;
            outline.push(outline[0]);
            area.draw(&PathElement::new(outline, BLACK.mix(0.35)))
                .map_err(plot_error)?;
        }
    }
    draw_path(area, view, state)?;
    draw_robot(area, view, state)?;
    draw_target(area, view, state)?;
    // a half-metre scale bar, bottom left
    let (_, h) = view.size_px;
    let bar = (0.5 * view.scale).round() as i32;
    area.draw(&PathElement::new(
        vec![(10, h - 10), (10 + bar, h - 10)],
        BLACK.stroke_width(2),
    ))
    .map_err(plot_error)?;
    area.draw(&Text::new("0.5 m", (12, h - 28), (FONT, 14)))
        .map_err(plot_error)?;
    Ok(())
}

fn draw_top(area: &Area, view: &View, state: &FrameState) -> Result<()> {
    area.fill(&SAND).map_err(plot_error)?;
    for tile in state.tiles {
        let half = tile.side_m / 2.0;
        let a = view.px(&Vector3::new(
            tile.center_m[0] - half,
            tile.center_m[1] + half,
            0.0,
        ));
        let b = view.px(&Vector3::new(
            tile.center_m[0] + half,
            tile.center_m[1] - half,
            0.0,
        ));
        draw_tile(area, [a, b], tile.sink_m)?;
    }
    draw_path(area, view, state)?;
    draw_robot(area, view, state)?;
    draw_target(area, view, state)
}

/// The tiles' colour scale, 0 to 10 cm of sink, top to bottom.
fn draw_colour_scale(area: &Area) -> Result<()> {
    let h = area.dim_in_pixel().1 as i32;
    let (top, bottom) = (28, h - 24);
    let x0 = 8;
    area.draw(&Text::new("sink, cm", (4, 6), (FONT, 12)))
        .map_err(plot_error)?;
    for y in top..bottom {
        let sink = viz::FULL_COLOUR_SINK_M * f64::from(y - top) / f64::from(bottom - top - 1);
        area.draw(&PathElement::new(
            vec![(x0, y), (x0 + 14, y)],
            rgb(viz::sink_colour(sink)),
        ))
        .map_err(plot_error)?;
    }
    for (label, at) in [
        ("0", top),
        ("5", (top + bottom) / 2 - 6),
        ("10", bottom - 12),
    ] {
        area.draw(&Text::new(label, (x0 + 17, at), (FONT, 12)))
            .map_err(plot_error)?;
    }
    Ok(())
}

/// Where the parts of a frame lie, pixels.
struct Layout {
    /// the caption's height
    caption_px: u32,
    /// the colour scale's width
    scale_bar_px: u32,
    /// each view's size
    view_px: (u32, u32),
    /// pixels per metre in both views
    px_per_m: f64,
}

impl Layout {
    fn of(size_px: (u32, u32)) -> Self {
        let (w, h) = size_px;
        let caption_px = (h / 16).max(22);
        let scale_bar_px = (w / 12).max(56);
        let view_px = (w - scale_bar_px, (h - caption_px) / 2);
        Self {
            caption_px,
            scale_bar_px,
            view_px,
            px_per_m: f64::from(view_px.1) / (SIDE_VIEW_Z_RANGE_M.1 - SIDE_VIEW_Z_RANGE_M.0),
        }
    }
}

/// Draws `state` into an RGB buffer of `size_px`.
pub fn draw(state: &FrameState, size_px: (u32, u32)) -> Result<Vec<u8>> {
    crate::eval::plots::register_font()?;
    let (w, h) = size_px;
    let layout = Layout::of(size_px);
    let mut rgb_buffer = vec![255u8; (3 * w * h) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb_buffer, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let (caption, rest) = root.split_vertically(layout.caption_px);
        let (views, scale_area) = rest.split_horizontally(w - layout.scale_bar_px);
        let (side_area, top_area) = views.split_vertically(layout.view_px.1);
        let font_px = (w / 40).clamp(10, 18);
        caption
            .draw(&Text::new(
                state.caption.to_string(),
                (6, (layout.caption_px as i32 - font_px as i32) / 2),
                (FONT, f64::from(font_px)),
            ))
            .map_err(plot_error)?;
        let base = state.body_poses[0].translation.vector;
        let view_size = (layout.view_px.0 as i32, layout.view_px.1 as i32);
        let ground_z = state
            .ground_profile_m
            .iter()
            .min_by(|a, b| (a.0 - base.x).abs().total_cmp(&(b.0 - base.x).abs()))
            .map_or(0.0, |p| p.1);
        let side = View {
            right: Vector3::x(),
            up: Vector3::z(),
            depth: Vector3::y(),
            centre: Vector3::new(
                base.x,
                base.y,
                ground_z + (SIDE_VIEW_Z_RANGE_M.0 + SIDE_VIEW_Z_RANGE_M.1) / 2.0,
            ),
            scale: layout.px_per_m,
            size_px: view_size,
        };
        let top = View {
            right: Vector3::x(),
            up: Vector3::y(),
            depth: -Vector3::z(),
            centre: Vector3::new(base.x, base.y, 0.0),
            scale: layout.px_per_m,
            size_px: view_size,
        };
        draw_side(&side_area, &side, state)?;
        draw_top(&top_area, &top, state)?;
        top_area
            .draw(&PathElement::new(
                vec![(0, 0), (view_size.0, 0)],
                BLACK.stroke_width(1),
            ))
            .map_err(plot_error)?;
        draw_colour_scale(&scale_area)?;
        root.present().map_err(plot_error)?;
    }
    Ok(rgb_buffer)
}

/// Half the width of ground either view shows for a frame of `size_px`, m
/// (what the recorder gathers tiles and ground for).
pub fn half_width_shown_m(size_px: (u32, u32)) -> f64 {
    let layout = Layout::of(size_px);
    f64::from(layout.view_px.0) / 2.0 / layout.px_per_m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hull_of_a_square_and_its_centre_is_the_square() {
        let hull = convex_hull(vec![
            (0.0, 0.0),
            (1.0, 0.0),
            (0.5, 0.5),
            (1.0, 1.0),
            (0.0, 1.0),
        ]);
        assert_eq!(hull, [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
    }

    #[test]
    fn a_box_seen_from_the_side_is_its_x_z_rectangle() {
        let pose = Isometry3::translation(1.0, 2.0, 3.0);
        let points = silhouette_points(
            &pose,
            &Geometry::Box {
                half_extents_m: Vector3::new(0.2, 0.1, 0.05),
            },
            Vector3::x(),
            Vector3::z(),
        );
        let view = View {
            right: Vector3::x(),
            up: Vector3::z(),
            depth: Vector3::y(),
            centre: Vector3::new(1.0, 0.0, 3.0),
            scale: 100.0,
            size_px: (200, 100),
        };
        // 40 x 10 cm around the view's centre (100, 50), y up on screen
        assert_eq!(
            view.px_hull(&points),
            [(80, 55), (120, 55), (120, 45), (80, 45)]
        );
    }
}

//! The Rerun implementation of [`RolloutLogger`] (feature `rerun`).

use std::net::{TcpStream, ToSocketAddrs};
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use nalgebra::{Isometry3, Vector3};
use rerun::RecordingStream;
use rerun::sink::{GrpcSink, GrpcSinkConnectionState, LogSink, SinkFlushError};
use robot::RobotModel;
use robot::model::Geometry;
use robot::snapshot::{PhaseObserver, PhaseStart, StepSnapshot};
use robot::task::{PhaseOutcome, RewardTerms, Task};
use terrain_plugins::Terrain;

use crate::{APPLICATION_ID, RerunSink, VizError, VizSettings, sink_colour};

/// A live gRPC sink the logger keeps an eye on: when its viewer goes away the
/// logger warns once and stops logging, so the run goes on.
struct WatchedGrpcSink(Arc<GrpcSink>);

impl LogSink for WatchedGrpcSink {
    fn send(&self, msg: rerun::log::LogMsg) {
        self.0.send(msg);
    }

    fn send_all(&self, messages: Vec<rerun::log::LogMsg>) {
        self.0.send_all(messages);
    }

    fn flush_blocking(&self, timeout: Duration) -> Result<(), SinkFlushError> {
        self.0.flush_blocking(timeout)
    }

    fn default_batcher_config(&self) -> rerun::log::ChunkBatcherConfig {
        self.0.default_batcher_config()
    }
}

/// Streams rollouts of a [`Task`] to Rerun. With [`RerunSink::Off`] every
/// call returns at once.
pub struct RolloutLogger {
    rec: Option<RecordingStream>,
    live: Option<(Arc<GrpcSink>, String)>,
    settings: VizSettings,
    body_paths: Vec<String>,
    joint_paths: Vec<String>,
    trajectory_m: Vec<[f32; 3]>,
    frames: usize,
    /// (phase, step in phase) of the last logged frame
    last_frame: Option<(usize, usize)>,
    iteration: Option<i64>,
    warnings: Vec<String>,
}

impl RolloutLogger {
    /// Opens `sink` for `model`'s robot. `default_file` is the file
    /// `save` without a path writes. A viewer that cannot be started or
    /// reached is a warning (see [`Self::warnings`]), not an error: the
    /// logger is then off. An unwritable file is an error.
    pub fn open(
        sink: &RerunSink,
        settings: VizSettings,
        model: &RobotModel,
        default_file: &Path,
        recording_name: &str,
    ) -> Result<Self, VizError> {
        let mut logger = Self {
            rec: None,
            live: None,
            settings,
            body_paths: model
                .bodies
                .iter()
                .map(|b| format!("world/robot/{}", path_part(&b.name)))
                .collect(),
            joint_paths: model
                .joints
                .iter()
                .map(|j| format!("torque/{}", path_part(&j.name)))
                .collect(),
            trajectory_m: Vec::new(),
            frames: 0,
            last_frame: None,
            iteration: None,
            warnings: Vec::new(),
        };
        let builder = rerun::RecordingStreamBuilder::new(APPLICATION_ID)
            .recording_name(recording_name.to_string());
        let sink_error = |e: rerun::RecordingStreamError| VizError::Sink {
            sink: sink.to_string(),
            message: e.to_string(),
        };
        let rec = match sink {
            RerunSink::Off => return Ok(logger),
            RerunSink::Save(path) => {
                let path = path.clone().unwrap_or_else(|| default_file.to_path_buf());
                // Rerun opens the file on its own thread; find out here, with
                // the path in the message, whether it can be written.
                std::fs::File::create(&path).map_err(|source| VizError::Unwritable {
                    path: path.clone(),
                    source,
                })?;
                builder.save(&path).map_err(sink_error)?
            }
            RerunSink::Spawn => match builder.spawn() {
                Ok(rec) => rec,
                Err(e) => {
                    logger.warn(format!(
                        "no Rerun viewer could be started ({e}); install it with `pip install rerun-sdk==0.36.3`. Going on without logging."
                    ));
                    return Ok(logger);
                }
            },
            RerunSink::Connect(url) => {
                if let Err(why) = probe(url) {
                    logger.warn(format!(
                        "no Rerun viewer at {url} ({why}). Going on without logging."
                    ));
                    return Ok(logger);
                }
                let uri =
                    url.parse()
                        .map_err(|e: rerun::external::re_uri::Error| VizError::Sink {
                            sink: sink.to_string(),
                            message: e.to_string(),
                        })?;
                let grpc = Arc::new(GrpcSink::new(uri));
                let rec = builder.buffered().map_err(sink_error)?;
                rec.set_sink(Box::new(WatchedGrpcSink(grpc.clone())));
                logger.live = Some((grpc, url.clone()));
                rec
            }
        };
        logger.rec = Some(rec);
        logger.log_blueprint();
        logger.log_robot_shapes(model);
        Ok(logger)
    }

    /// Whether anything is being logged.
    pub fn is_active(&self) -> bool {
        self.rec.is_some()
    }

    /// The settings.
    pub fn settings(&self) -> &VizSettings {
        &self.settings
    }

    /// Frames (robot poses) logged so far.
    pub fn frames_logged(&self) -> usize {
        self.frames
    }

    /// Warnings so far (a missing viewer, a viewer that went away); the
    /// caller prints them.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Takes the warnings not yet taken.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    /// Sets the `iteration` timeline for everything logged from now on
    /// (training); `None` leaves it out.
    pub fn set_iteration(&mut self, iteration: Option<i64>) {
        self.iteration = iteration;
    }

    /// Starts a new rollout: forgets the base trajectory.
    pub fn begin_rollout(&mut self) {
        self.trajectory_m.clear();
        self.last_frame = None;
    }

    /// Logs the terrain's regions (static) once.
    pub fn log_terrain(&mut self, terrain: &dyn Terrain) {
        let Some(rec) = self.rec.clone() else { return };
        let extent = terrain.extent();
        let (y0, y1) = (extent.min_m[1], extent.max_m[1]);
        let mut centres = Vec::new();
        let mut halves = Vec::new();
        let mut labels = Vec::new();
        let mut colours = Vec::new();
        for region in terrain.regions() {
            let (x0, x1) = region.x_range_m;
            let (x0, x1) = (x0.max(extent.min_m[0]), x1.min(extent.max_m[0]));
            centres.push([((x0 + x1) / 2.0) as f32, ((y0 + y1) / 2.0) as f32, -0.16]);
            halves.push([((x1 - x0) / 2.0) as f32, ((y1 - y0) / 2.0) as f32, 0.005]);
            labels.push(region.label.clone());
            colours.push(sink_colour(region.expected_sink_m));
        }
        let boxes = rerun::Boxes3D::from_centers_and_half_sizes(centres, halves)
            .with_labels(labels)
            .with_colors(colours);
        self.check(rec.log_static("world/terrain/regions", &boxes));
        if let Some(mesh) = terrain.ground_mesh() {
            let vertices: Vec<[f32; 3]> = mesh
                .vertices_m
                .iter()
                .map(|v| [v[0] as f32, v[1] as f32, v[2] as f32])
                .collect();
            let ground = rerun::Mesh3D::new(vertices)
                .with_triangle_indices(mesh.triangles)
                .with_albedo_factor(rerun::Rgba32::from_rgb(150, 140, 120));
            self.check(rec.log_static("world/terrain/ground", &ground));
        }
    }

    /// Logs one frame of the task as it is now (the state after a reset,
    /// say). Observed phases log their own frames.
    pub fn log_now(&mut self, task: &Task) {
        self.log_frame(task, 0);
    }

    /// Logs training curves as scalars `train/<name>` on the `iteration`
    /// timeline only.
    pub fn log_training(&mut self, iteration: i64, values: &[(String, f64)]) {
        let Some(rec) = self.rec.clone() else { return };
        rec.reset_time();
        rec.set_time_sequence("iteration", iteration);
        let mut results = Vec::new();
        for (name, value) in values {
            if value.is_finite() {
                results.push(rec.log(
                    format!("train/{}", path_part(name)),
                    &rerun::Scalars::single(*value),
                ));
            }
        }
        for result in results {
            self.check(result);
        }
        self.check_connection();
    }

    /// Logs a curve as scalars at `entity`, one per point (x, y), with x on
    /// the sequence timeline `timeline` only (`eval`'s figures).
    pub fn log_curve(&mut self, entity: &str, timeline: &'static str, points: &[(i64, f64)]) {
        let Some(rec) = self.rec.clone() else { return };
        rec.reset_time();
        let mut results = Vec::new();
        for &(x, y) in points {
            if y.is_finite() {
                rec.set_time_sequence(timeline, x);
                results.push(rec.log(entity, &rerun::Scalars::single(y)));
            }
        }
        for result in results {
            self.check(result);
        }
        self.check_connection();
    }

    /// Flushes everything; call before the process ends.
    pub fn finish(&mut self) {
        if let Some(rec) = self.rec.take()
            && let Err(e) = rec.flush_with_timeout(Duration::from_secs(10))
        {
            self.warn(format!("the Rerun stream did not flush: {e}"));
        }
    }

    fn warn(&mut self, message: String) {
        self.warnings.push(message);
    }

    /// Turns logging off with a warning when the live viewer went away.
    fn check_connection(&mut self) {
        let Some((grpc, url)) = &self.live else {
            return;
        };
        if let GrpcSinkConnectionState::Disconnected(result) = grpc.status() {
            let why = match result {
                Ok(()) => "it closed the connection".to_string(),
                Err(e) => e.to_string(),
            };
            let message =
                format!("the Rerun viewer at {url} went away ({why}). Going on without logging.");
            self.live = None;
            if let Some(rec) = self.rec.take() {
                rec.disconnect();
            }
            self.warn(message);
        }
    }

    fn check(&mut self, result: rerun::RecordingStreamResult<()>) {
        if let Err(e) = result {
            self.warn(format!(
                "Rerun logging failed: {e}. Going on without logging."
            ));
            self.rec = None;
        }
    }

    fn set_times(&self, rec: &RecordingStream, sim_time_s: f64, phase: usize) {
        rec.set_duration_secs("sim_time", sim_time_s);
        rec.set_time_sequence("phase", phase as i64);
        if let Some(i) = self.iteration {
            rec.set_time_sequence("iteration", i);
        }
    }

    fn log_blueprint(&mut self) {
        let Some(rec) = &self.rec else { return };
        let result = crate::blueprint::send(rec, &self.body_paths[0]);
        self.check(result);
    }

    fn log_robot_shapes(&mut self, model: &RobotModel) {
        let Some(rec) = self.rec.clone() else { return };
        let anchor = rerun::Points3D::new(crate::blueprint::anchor_points_m())
            .with_radii([crate::blueprint::ANCHOR_RADIUS_M]);
        self.check(rec.log_static(crate::blueprint::anchor_path(&self.body_paths[0]), &anchor));
        for (body, path) in model.bodies.iter().zip(self.body_paths.clone()) {
            for (k, shape) in body.collisions.iter().enumerate() {
                let shape_path = format!("{path}/shape_{k}");
                let colour = if shape.is_foot {
                    [60, 60, 60]
                } else {
                    [200, 160, 60]
                };
                let mut pose = shape.shape_in_body;
                let result = match &shape.geometry {
                    Geometry::Box { half_extents_m: h } => rec.log_static(
                        shape_path.as_str(),
                        &rerun::Boxes3D::from_half_sizes([[h.x as f32, h.y as f32, h.z as f32]])
                            .with_colors([colour])
                            .with_fill_mode(rerun::FillMode::Solid),
                    ),
                    Geometry::Sphere { radius_m } => rec.log_static(
                        shape_path.as_str(),
                        &rerun::Ellipsoids3D::from_radii([*radius_m as f32])
                            .with_colors([colour])
                            .with_fill_mode(rerun::FillMode::Solid),
                    ),
                    Geometry::Cylinder {
                        radius_m,
                        half_length_m,
                    } => rec.log_static(
                        shape_path.as_str(),
                        &rerun::Cylinders3D::from_lengths_and_radii(
                            [2.0 * *half_length_m as f32],
                            [*radius_m as f32],
                        )
                        .with_colors([colour])
                        .with_fill_mode(rerun::FillMode::Solid),
                    ),
                    Geometry::Capsule {
                        radius_m,
                        half_length_m,
                    } => {
                        // Rerun's capsule runs from its origin along +z.
                        pose *= nalgebra::Translation3::new(0.0, 0.0, -half_length_m);
                        rec.log_static(
                            shape_path.as_str(),
                            &rerun::Capsules3D::from_lengths_and_radii(
                                [2.0 * *half_length_m as f32],
                                [*radius_m as f32],
                            )
                            .with_colors([colour]),
                        )
                    }
                    Geometry::ConvexHull { points_m } => {
                        let (vertices, triangles) = convex_hull(points_m);
                        rec.log_static(
                            shape_path.as_str(),
                            &rerun::Mesh3D::new(vertices)
                                .with_triangle_indices(triangles)
                                .with_albedo_factor(rerun::Rgba32::from_rgb(
                                    colour[0], colour[1], colour[2],
                                )),
                        )
                    }
                };
                self.check(result);
                self.check(rec.log_static(shape_path.as_str(), &transform(&pose)));
            }
        }
    }

    fn log_frame(&mut self, task: &Task, step_in_phase: usize) {
        if self.rec.is_none() {
            return;
        }
        let snap = task.snapshot(self.settings.tiles_half_side_m);
        self.log_snapshot(&snap);
        self.last_frame = Some((snap.phase, step_in_phase));
    }

    /// Logs one snapshot (a frame).
    pub fn log_snapshot(&mut self, snap: &StepSnapshot) {
        let Some(rec) = self.rec.clone() else { return };
        self.set_times(&rec, snap.sim_time_s, snap.phase);
        let mut results = Vec::new();
        for (path, pose) in self.body_paths.iter().zip(&snap.body_poses) {
            results.push(rec.log(path.as_str(), &transform(pose)));
        }
        let base = f32x3(&snap.body_poses[0].translation.vector);
        push_spaced(&mut self.trajectory_m, base, TRAJECTORY_SPACING_M);
        let strip = self.trajectory_m.iter().copied().chain([base]);
        results.push(rec.log(
            "world/base/trajectory",
            &rerun::LineStrips3D::new([strip]).with_colors([[40, 120, 220]]),
        ));
        // The goal, and what the policy steers for when that is not the goal
        // (the goals' line ahead of the base).
        for (path, point_xy_m, radius_m, colour, label) in [
            ("world/goal", snap.goal_xy_m, 0.05, [230, 180, 0], "goal"),
            (
                "world/observed_goal",
                snap.observed_goal_xy_m,
                0.03,
                [230, 110, 0],
                "line ahead",
            ),
        ] {
            if let Some([x, y]) = point_xy_m {
                results.push(
                    rec.log(
                        path,
                        &rerun::Points3D::new([[x as f32, y as f32, 0.0]])
                            .with_radii([radius_m])
                            .with_colors([colour])
                            .with_labels([label]),
                    ),
                );
            }
        }
        // The height scan's points on the ground, where the policy sees it.
        if !snap.height_scan_points_m.is_empty() {
            let points = snap
                .height_scan_points_m
                .iter()
                .map(|p| [p[0] as f32, p[1] as f32, p[2] as f32]);
            results.push(
                rec.log(
                    "world/height_scan",
                    &rerun::Points3D::new(points)
                        .with_radii([0.012])
                        .with_colors([[40, 190, 120]]),
                ),
            );
        }
        // Tiles: the top face at its rest height less the sink, 2 cm thick;
        // tiles on a hill turned about y by their top's inclination.
        let thickness = 0.02f32;
        let centres: Vec<[f32; 3]> = snap
            .tiles
            .iter()
            .map(|t| {
                let a = t.rest_slope.atan();
                [
                    (t.center_m[0] + f64::from(thickness) / 2.0 * a.sin()) as f32,
                    t.center_m[1] as f32,
                    (t.rest_top_m - t.sink_m) as f32 - thickness / 2.0 * a.cos() as f32,
                ]
            })
            .collect();
        let halves: Vec<[f32; 3]> = snap
            .tiles
            .iter()
            .map(|t| {
                [
                    (t.side_m / 2.0 / t.rest_slope.atan().cos()) as f32,
                    t.side_m as f32 / 2.0,
                    thickness / 2.0,
                ]
            })
            .collect();
        let colours: Vec<[u8; 3]> = snap.tiles.iter().map(|t| sink_colour(t.sink_m)).collect();
        let mut boxes = rerun::Boxes3D::from_centers_and_half_sizes(centres, halves)
            .with_colors(colours)
            .with_fill_mode(rerun::FillMode::Solid);
        if snap.tiles.iter().any(|t| t.rest_slope != 0.0) {
            // about y by -a: the box's x axis rises along (cos a, 0, sin a)
            boxes = boxes.with_quaternions(snap.tiles.iter().map(|t| {
                let half = -t.rest_slope.atan() / 2.0;
                rerun::Quaternion::from_xyzw([0.0, half.sin() as f32, 0.0, half.cos() as f32])
            }));
        }
        results.push(rec.log("world/terrain/tiles", &boxes));
        let sinks: Vec<f64> = snap.tiles.iter().map(|t| t.sink_m).collect();
        results.push(rec.log("tiles/sink_m", &rerun::Scalars::new(sinks)));
        let contact_points: Vec<[f32; 3]> = snap
            .contact_points_m
            .iter()
            .map(|(p, _)| f32x3(p))
            .collect();
        let contact_colours: Vec<[u8; 3]> = snap
            .contact_points_m
            .iter()
            .map(|(_, foot)| {
                if foot.is_some() {
                    [0, 200, 0]
                } else {
                    [230, 0, 0]
                }
            })
            .collect();
        results.push(
            rec.log(
                "world/contacts",
                &rerun::Points3D::new(contact_points)
                    .with_colors(contact_colours)
                    .with_radii([0.015]),
            ),
        );
        let [roll, pitch, _] = snap.base_rpy_rad;
        results.push(rec.log("base/height_m", &rerun::Scalars::single(snap.base_height_m)));
        results.push(rec.log("base/roll_deg", &rerun::Scalars::single(roll.to_degrees())));
        results.push(rec.log(
            "base/pitch_deg",
            &rerun::Scalars::single(pitch.to_degrees()),
        ));
        for (path, torque) in self.joint_paths.iter().zip(&snap.joint_torques_n_m) {
            results.push(rec.log(path.as_str(), &rerun::Scalars::single(*torque)));
        }
        self.frames += 1;
        for result in results {
            self.check(result);
        }
    }
}

impl PhaseObserver for RolloutLogger {
    fn phase_started(&mut self, _task: &Task, start: &PhaseStart) {
        let Some(rec) = self.rec.clone() else { return };
        self.set_times(&rec, start.sim_time_s, start.phase);
        let n = self.settings.curve_samples;
        let base: Vec<[f32; 3]> = start.base_curve_m(n).iter().map(f32x3).collect();
        let foot: Vec<[f32; 3]> = start.swing_foot_curve_m(n).iter().map(f32x3).collect();
        let targets = start.base_targets(10);
        let origins: Vec<[f32; 3]> = targets
            .iter()
            .map(|p| f32x3(&p.translation.vector))
            .collect();
        let ups: Vec<[f32; 3]> = targets
            .iter()
            .map(|p| f32x3(&(p.rotation * Vector3::z() * 0.1)))
            .collect();
        let results = [
            rec.log(
                "world/targets/base",
                &rerun::LineStrips3D::new([base]).with_colors([[0, 160, 255]]),
            ),
            rec.log(
                "world/targets/orientation",
                &rerun::Arrows3D::from_vectors(ups)
                    .with_origins(origins)
                    .with_colors([[120, 90, 255]]),
            ),
            rec.log(
                "world/targets/swing_foot",
                &rerun::LineStrips3D::new([foot])
                    .with_colors([[255, 80, 160]])
                    .with_labels([format!("{:?}", start.swing_leg)]),
            ),
            rec.log(
                "world/targets/landing",
                &rerun::Points3D::new([f32x3(&start.landing_m())])
                    .with_radii([0.02])
                    .with_colors([[255, 80, 160]]),
            ),
        ];
        for result in results {
            self.check(result);
        }
    }

    fn stepped(&mut self, task: &Task, step_in_phase: usize) {
        if self.rec.is_some()
            && self
                .settings
                .rate
                .logs_step(step_in_phase, task.world().steps_per_phase())
        {
            self.log_frame(task, step_in_phase);
        }
    }

    fn phase_ended(&mut self, task: &Task, outcome: &PhaseOutcome) {
        let Some(rec) = self.rec.clone() else { return };
        let phase = task.phase() - 1;
        // A phase cut short by a termination logs its last step too.
        if self.last_frame != Some((phase, outcome.steps)) {
            // The snapshot's phase is the next one now: log under the ended one.
            let mut snap = task.snapshot(self.settings.tiles_half_side_m);
            snap.phase = phase;
            self.log_snapshot(&snap);
            self.last_frame = Some((phase, outcome.steps));
        }
        self.set_times(&rec, task.world().time_secs(), phase);
        let mut results = Vec::new();
        for (name, value) in RewardTerms::NAMES.iter().zip(outcome.terms.values()) {
            results.push(rec.log(format!("reward/{name}"), &rerun::Scalars::single(value)));
        }
        results.push(rec.log("reward/total", &rerun::Scalars::single(outcome.reward)));
        for result in results {
            self.check(result);
        }
        self.check_connection();
    }
}

/// A URDF name as one entity path part (Rerun splits paths on `/`).
fn path_part(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// The base trajectory keeps a point only where the base has moved this far
/// from the last kept one (plus the current position at the end), so the
/// strip re-sent every frame grows with the path walked, not with the
/// frames logged.
const TRAJECTORY_SPACING_M: f32 = 0.01;

/// Appends `point` when it is at least `spacing_m` from the last point (or
/// the first); returns whether it did.
fn push_spaced(points: &mut Vec<[f32; 3]>, point: [f32; 3], spacing_m: f32) -> bool {
    let far = points.last().is_none_or(|last| {
        let d2: f32 = last
            .iter()
            .zip(&point)
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        d2 >= spacing_m * spacing_m
    });
    if far {
        points.push(point);
    }
    far
}

fn f32x3(v: &Vector3<f64>) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

fn transform(pose: &Isometry3<f64>) -> rerun::Transform3D {
    let q = pose.rotation.quaternion();
    rerun::Transform3D::from_translation_rotation(
        f32x3(&pose.translation.vector),
        rerun::Quaternion::from_xyzw([q.i as f32, q.j as f32, q.k as f32, q.w as f32]),
    )
}

/// Vertices and triangles of a convex hull.
fn convex_hull(points_m: &[Vector3<f64>]) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
    use terrain_plugins::rapier3d::prelude::Vector;
    let points: Vec<Vector> = points_m
        .iter()
        .map(|p| Vector::new(p.x as f32, p.y as f32, p.z as f32))
        .collect();
    let (vertices, triangles) =
        terrain_plugins::rapier3d::parry::transformation::convex_hull(&points);
    (
        vertices.iter().map(|v| [v.x, v.y, v.z]).collect(),
        triangles,
    )
}

/// Whether something listens at a gRPC URL's host and port (one TCP
/// connection, 1 s at most).
fn probe(url: &str) -> Result<(), String> {
    let authority = url
        .split_once("://")
        .map_or(url, |(_, rest)| rest)
        .trim_end_matches("/proxy");
    let addrs: Vec<_> = authority
        .to_socket_addrs()
        .map_err(|e| format!("cannot resolve {authority}: {e}"))?
        .collect();
    let mut last = String::from("no address");
    for addr in addrs {
        match TcpStream::connect_timeout(&addr, Duration::from_secs(1)) {
            Ok(_) => return Ok(()),
            Err(e) => last = e.to_string(),
        }
    }
    Err(last)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_trajectory_keeps_points_a_centimetre_apart() {
        let mut points = Vec::new();
        assert!(super::push_spaced(&mut points, [0.0, 0.0, 0.3], 0.01));
        assert!(!super::push_spaced(&mut points, [0.005, 0.0, 0.3], 0.01));
        assert!(!super::push_spaced(&mut points, [0.0, 0.009, 0.3], 0.01));
        assert!(super::push_spaced(&mut points, [0.0, 0.0, 0.311], 0.01));
        // a robot standing for 1,000 frames adds nothing more
        for _ in 0..1000 {
            super::push_spaced(&mut points, [0.0, 0.0, 0.3105], 0.01);
        }
        assert_eq!(points.len(), 2);
    }

    use std::path::PathBuf;

    use super::*;

    #[test]
    fn link_names_become_single_path_parts() {
        assert_eq!(path_part("FR_lower/leg 1"), "FR_lower_leg_1");
    }

    #[test]
    fn a_refused_connection_is_a_warning_and_logging_is_off() {
        // Find a free port, then close it: nothing listens there.
        let port = std::net::TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let sink: RerunSink = format!("connect:127.0.0.1:{port}").parse().unwrap();
        let logger = RolloutLogger::open(
            &sink,
            VizSettings::default(),
            &RobotModel::laikago(),
            Path::new("unused.rrd"),
            "test",
        )
        .unwrap();
        assert!(!logger.is_active());
        assert_eq!(logger.warnings().len(), 1);
        assert!(logger.warnings()[0].contains("no Rerun viewer at"));
    }

    #[test]
    fn an_unwritable_file_is_an_error_that_names_it() {
        let sink = RerunSink::Save(Some(PathBuf::from("/nonexistent-dir/run.rrd")));
        let err = RolloutLogger::open(
            &sink,
            VizSettings::default(),
            &RobotModel::laikago(),
            Path::new("unused.rrd"),
            "test",
        )
        .err()
        .unwrap()
        .to_string();
        assert!(err.contains("/nonexistent-dir/run.rrd"), "{err}");
    }
}

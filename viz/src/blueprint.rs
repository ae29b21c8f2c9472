//! The viewer's layout (Rerun blueprint): the 3D view of the robot beside
//! the time series, with the 3D view's eye following the robot.
//!
//! Rerun's eye follows a tracked entity by the centre of its region of
//! interest (below), keeping the direction and distance of the blueprint's
//! eye position from its look target ([`EYE_OFFSET_M`]: 2.07 m behind,
//! right of and above the base). When the entity is loaded as tracking
//! starts, the viewer sets the distance to 1.5 times the radius of the
//! bounding sphere of the entity's region of interest instead. The robot's
//! links are separate entities (the base's box alone would put the eye 0.4
//! m from the trunk, the legs outside the view), so the logger gives the
//! eye an anchor of its own: two points of [`ANCHOR_RADIUS_M`] in the
//! base's frame ([`anchor_points_m`]), which move with the base. Which of
//! the two rules applies depends on whether the viewer has the anchor's
//! data when it first draws the view, which varies from one load to the
//! next; both give the same distance (2.05 m by the anchor): far enough to
//! see the whole robot, the tiles logged around it, the swing foot's target
//! and the base's path behind it.
//!
//! The region of interest of a point cloud in Rerun 0.36 is not its
//! bounding box but each axis's mean +- 2 standard deviations
//! (`re_renderer::RobustBounds::from_points`): for two points at +-a it is
//! +-2a. The anchor's points therefore sit at half the box they frame
//! ([`ANCHOR_HALF_EXTENTS_M`]).
//!
//! The Rust SDK's [`Spatial3DView`] has no setter for its eye, so the eye
//! (`EyeControls3D`) is logged into the blueprint's own store, at the path
//! the viewer reads a view's properties from (`view/<id>/EyeControls3D`),
//! and the whole blueprint is then sent as `Blueprint::send` sends it.

use rerun::RecordingStream;
use rerun::RecordingStreamResult;
use rerun::blueprint::{
    Blueprint, BlueprintActivation, ContainerLike, Horizontal, Spatial3DView, TimeSeriesView,
    Vertical,
};
use rerun::external::re_log_types::{BlueprintActivationCommand, LogMsg, StoreKind};
use rerun::external::re_sdk_types::blueprint::archetypes::EyeControls3D;

use crate::APPLICATION_ID;

/// Half extents (x forward, y left, z up, in the base's frame) of the box
/// the viewer frames when it places the eye by the anchor, m.
pub(crate) const ANCHOR_HALF_EXTENTS_M: [f32; 3] = [0.9, 0.9, 0.5];

/// The anchor's two points, in the base's frame, m: opposite corners of a
/// box half the size of [`ANCHOR_HALF_EXTENTS_M`], so that the viewer's
/// region of interest (mean +- 2 standard deviations per axis, the standard
/// deviation of two points at +-a being a) is that box.
pub(crate) fn anchor_points_m() -> [[f32; 3]; 2] {
    let [x, y, z] = ANCHOR_HALF_EXTENTS_M.map(|h| h / 2.0);
    [[-x, -y, -z], [x, y, z]]
}

/// The anchor's points are this small: they place the eye and are not
/// meant to be seen, m.
pub(crate) const ANCHOR_RADIUS_M: f32 = 0.0005;

/// Where the eye looks from, relative to what it looks at (the base), in
/// the world frame, m: behind the robot (-x, it walks along +x), to its
/// right (-y) and above, 26 degrees down, 2.07 m away. The viewer keeps
/// this distance when it starts tracking before the anchor is loaded, and
/// the anchor's rule gives about the same (2.05 m) when it is loaded first.
const EYE_OFFSET_M: [f32; 3] = [-1.1, -1.5, 0.9];

/// The anchor entity under a base link's entity path.
pub(crate) fn anchor_path(base_path: &str) -> String {
    format!("{base_path}/eye_anchor")
}

/// Sends the layout to `rec`, the 3D view's eye tracking the anchor under
/// `base_path` (the base link's entity).
pub(crate) fn send(rec: &RecordingStream, base_path: &str) -> RecordingStreamResult<()> {
    let view_3d = ContainerLike::from(
        Spatial3DView::new("robot and terrain (the eye follows the base)").with_origin("/world"),
    );
    let ContainerLike::View(view) = &view_3d else {
        unreachable!("a Spatial3DView is a view")
    };
    let eye_path = format!("{}/EyeControls3D", view.blueprint_path());
    let blueprint = Blueprint::new(Horizontal::new([
        view_3d,
        Vertical::new([
            TimeSeriesView::new("reward per term")
                .with_origin("/reward")
                .into(),
            TimeSeriesView::new("base height, roll, pitch")
                .with_origin("/base")
                .into(),
            TimeSeriesView::new("joint torques")
                .with_origin("/torque")
                .into(),
            TimeSeriesView::new("training (per iteration)")
                .with_origin("/train")
                .into(),
        ])
        .into(),
    ]));

    // The blueprint's messages, as `Blueprint::send` would send them.
    let (capture, captured) = rerun::RecordingStreamBuilder::new(APPLICATION_ID).memory()?;
    blueprint.send(&capture, BlueprintActivation::default())?;
    let mut messages: Vec<LogMsg> = captured
        .take()
        .into_iter()
        .filter(|m| m.store_id().kind() == StoreKind::Blueprint)
        .collect();
    let Some(blueprint_id) = messages.first().map(|m| m.store_id().clone()) else {
        return Ok(());
    };
    messages.retain(|m| !matches!(m, LogMsg::BlueprintActivationCommand(_)));

    // The eye, written into the same blueprint store.
    let (eye_stream, eye_messages) = rerun::RecordingStreamBuilder::new(APPLICATION_ID)
        .recording_id(blueprint_id.recording_id().clone())
        .blueprint()
        .memory()?;
    eye_stream.set_time_sequence("blueprint", 0);
    let [dx, dy, dz] = EYE_OFFSET_M;
    let rest_base_m = [0.0, 0.0, 0.4];
    eye_stream.log(
        eye_path,
        &EyeControls3D::new()
            .with_look_target(rest_base_m)
            .with_position([
                rest_base_m[0] + dx,
                rest_base_m[1] + dy,
                rest_base_m[2] + dz,
            ])
            .with_tracking_entity(anchor_path(base_path)),
    )?;
    messages.extend(
        eye_messages
            .take()
            .into_iter()
            .filter(|m| matches!(m, LogMsg::ArrowMsg(..))),
    );
    rec.send_blueprint(
        messages,
        BlueprintActivationCommand::make_active(blueprint_id),
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Half extents of the region of interest Rerun 0.36's viewer gives a
    /// point cloud centred on the origin: per axis, 2 standard deviations
    /// of the points that lie within 2 standard deviations of the mean
    /// (`re_renderer::RobustBounds::from_points`).
    fn viewer_region_of_interest_half_extents_m(points: &[[f32; 3]]) -> [f32; 3] {
        let sigma = |axis: usize, keep: &dyn Fn(&[f32; 3]) -> bool| {
            let kept: Vec<f64> = points
                .iter()
                .filter(|p| keep(p))
                .map(|p| f64::from(p[axis]))
                .collect();
            let n = kept.len() as f64;
            let mean = kept.iter().sum::<f64>() / n;
            (kept.iter().map(|v| v * v).sum::<f64>() / n - mean * mean).sqrt()
        };
        let first = [0, 1, 2].map(|axis| sigma(axis, &|_| true));
        let within =
            |p: &[f32; 3]| (0..3).all(|axis| f64::from(p[axis]).abs() <= 2.0 * first[axis]);
        [0, 1, 2].map(|axis| (2.0 * sigma(axis, &within)) as f32)
    }

    #[test]
    fn the_anchor_points_give_the_viewer_the_anchor_box() {
        let half = viewer_region_of_interest_half_extents_m(&anchor_points_m());
        for (got, want) in half.iter().zip(ANCHOR_HALF_EXTENTS_M) {
            assert!(
                (got - want).abs() < 1e-6,
                "{half:?} against {ANCHOR_HALF_EXTENTS_M:?}"
            );
        }
    }

    #[test]
    fn the_eye_stands_back_far_enough_for_the_robot_and_its_tiles() {
        // The Laikago is about 0.9 m from front to rear foot, and the tiles
        // are logged 0.7 m around the base: at 55 degrees of vertical field
        // of view the eye must be about 1.5 m away or more.
        let [x, y, z] = viewer_region_of_interest_half_extents_m(&anchor_points_m());
        let anchored_m = 1.5 * (x * x + y * y + z * z).sqrt();
        let [x, y, z] = EYE_OFFSET_M;
        let offset_m = (x * x + y * y + z * z).sqrt();
        for distance in [anchored_m, offset_m] {
            assert!((1.8..2.5).contains(&distance), "{distance} m");
        }
        assert!(
            (anchored_m - offset_m).abs() < 0.05,
            "{anchored_m} m against {offset_m} m"
        );
    }

    #[test]
    fn the_blueprint_holds_the_eye_tracking_the_anchor() {
        let (rec, storage) = rerun::RecordingStreamBuilder::new(APPLICATION_ID)
            .memory()
            .unwrap();
        send(&rec, "world/robot/trunk").unwrap();
        let messages = storage.take();
        let blueprint: Vec<&LogMsg> = messages
            .iter()
            .filter(|m| m.store_id().kind() == StoreKind::Blueprint)
            .collect();
        let activations = blueprint
            .iter()
            .filter(|m| matches!(m, LogMsg::BlueprintActivationCommand(_)))
            .count();
        assert_eq!(activations, 1, "the blueprint is activated once");
        assert!(
            matches!(
                blueprint.last(),
                Some(LogMsg::BlueprintActivationCommand(_))
            ),
            "the activation comes after the whole blueprint"
        );
        let eye_chunks: Vec<_> = blueprint
            .iter()
            .filter_map(|m| match m {
                LogMsg::ArrowMsg(_, arrow) => {
                    let chunk = rerun::log::Chunk::from_arrow_msg(arrow).ok()?;
                    chunk
                        .entity_path()
                        .to_string()
                        .ends_with("/EyeControls3D")
                        .then_some(chunk)
                }
                _ => None,
            })
            .collect();
        assert_eq!(eye_chunks.len(), 1, "one EyeControls3D in the blueprint");
        let tracking = eye_chunks[0]
            .component_batch_raw(EyeControls3D::descriptor_tracking_entity().component, 0)
            .expect("the eye has a tracking entity")
            .unwrap();
        let text = format!("{tracking:?}");
        assert!(
            text.contains("world/robot/trunk/eye_anchor"),
            "tracking {text}"
        );
    }
}

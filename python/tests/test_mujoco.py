"""quadwalk's scene in MuJoCo (`quadwalk.mujoco_scene`): the same stiffness
rule gives the same standing sink, and a shipped policy walks there through
`quadwalk.Controller` with its ONNX graph."""

import numpy as np
import pytest

import quadwalk

mujoco = pytest.importorskip("mujoco", reason="the second-engine tests need mujoco (pytest_suite.rs installs it)")
ort = pytest.importorskip("onnxruntime", reason="the second-engine tests need onnxruntime")
from quadwalk.mujoco_scene import MujocoRobot  # noqa: E402


@pytest.mark.parametrize("depth_cm", [2, 5])
def test_tiles_sink_the_named_depth_under_the_standing_robot(depth_cm):
    robot = MujocoRobot(f"elastic:{depth_cm}cm", length_m=2.0, width_m=1.0)
    assert robot.robot_mass_kg == pytest.approx(25.567)
    controller = quadwalk.Controller()
    robot.reset([0.0, 0.0], controller.squat_joint_angles_rad, controller.hips_in_base_m)
    for _ in range(5 * 240):
        robot.step(controller.squat_joint_angles_rad)
    sinks = robot.foot_sinks_m()
    assert np.mean(sinks) == pytest.approx(depth_cm / 100, abs=5e-4), sinks
    assert robot.fall() is None


def test_the_rigid_policy_walks_in_mujoco_through_the_controller(root):
    policy = root / "policies" / "rigid"
    robot = MujocoRobot("rigid", length_m=6.0, width_m=2.0)
    controller = quadwalk.Controller.for_policy(str(policy))
    session = ort.InferenceSession(str(policy / "policy.onnx"), providers=["CPUExecutionProvider"])
    robot.reset([0.0, 0.0], controller.squat_joint_angles_rad, controller.hips_in_base_m)
    state = robot.state()
    controller.begin_episode(state)
    x0 = state["base_position_m"][0]
    for _ in range(20):
        goal = [x0 + 2.0 * (1 + int((state["base_position_m"][0] - x0) // 2.0)), 0.0]
        obs = controller.observe(state, goal)
        action = session.run(["action"], {"observation": obs[None]})[0][0]
        state, fall = quadwalk.run_phase(controller, robot, action, state, stop=lambda _: robot.fall())
        assert fall is None
    assert state["base_position_m"][0] - x0 > 0.5, "20 phases of walking"


def test_an_unknown_terrain_is_named():
    with pytest.raises(ValueError, match="soil:4cm"):
        MujocoRobot("soil:4cm")

"""The phase-level controller from Python (`quadwalk.Controller`) driving
quadwalk's world as a bare robot (`quadwalk.Sim`) step by step, with the
shipped policy's ONNX graph in onnxruntime as the policy: the deployment
loop. It reproduces the environment's episode (the episode `quadwalk
rollout --seed` runs) bit for bit, given the same actions."""

import numpy as np
import pytest

import quadwalk

ort = pytest.importorskip("onnxruntime", reason="the controller test runs the ONNX policy (pytest_suite.rs installs onnxruntime)")


def test_the_controller_on_a_bare_robot_reproduces_the_environment(root):
    policy_dir = root / "policies" / "elastic-5cm"
    config = str(policy_dir / "config.toml")
    seed, phases = 1_000_007, 12
    env = quadwalk.make_env(config=config, seed=seed)
    env_obs, _ = env.reset(seed=seed)

    robot = quadwalk.Sim(config=config, seed=seed)
    robot.reset()
    controller = quadwalk.Controller.for_policy(str(policy_dir))
    assert controller.observation_size == 102
    controller.begin_episode(robot.state())
    session = ort.InferenceSession(str(policy_dir / "policy.onnx"), providers=["CPUExecutionProvider"])

    for phase in range(phases):
        state = robot.state()
        obs = controller.observe(state, list(env.goal_xy_m))
        np.testing.assert_array_equal(obs, env_obs, err_msg=f"phase {phase}")
        action = session.run(["action"], {"observation": obs[None, :]})[0][0]
        quadwalk.run_phase(controller, robot, action, state)
        env_obs, _, terminated, truncated, _ = env.step(action)
        assert not (terminated or truncated)
        assert tuple(robot.state()["base_position_m"]) == env.base_position_m
    assert controller.phase == phases
    assert env.base_position_m[0] - env.start_xy_m[0] > 0.1, "the policy walks"


def test_feet_from_joint_angles_give_the_observation_within_rounding(root):
    """A robot measures joint angles, not feet: forward kinematics puts the
    feet where rapier's single-precision bodies are, to ~1e-6 m."""
    policy_dir = root / "policies" / "elastic-5cm"
    robot = quadwalk.Sim(config=str(policy_dir / "config.toml"), seed=3)
    robot.reset()
    state = robot.state()
    by_kinematics = {k: v for k, v in state.items() if k != "feet_in_world_m"}
    simulated, measured = (quadwalk.Controller.for_policy(str(policy_dir)) for _ in range(2))
    simulated.begin_episode(state)
    measured.begin_episode(by_kinematics)
    a = simulated.observe(state, [2.0, 0.0])
    b = measured.observe(by_kinematics, [2.0, 0.0])
    np.testing.assert_allclose(a, b, atol=1e-4, rtol=0)


def test_bad_states_and_calls_are_named():
    controller = quadwalk.Controller()
    robot = quadwalk.Sim(terrain="rigid")
    robot.reset()
    state = robot.state()
    with pytest.raises(ValueError, match="base_orientation_xyzw"):
        controller.observe({**state, "base_orientation_xyzw": [0, 0, 0, 2]}, [2.0, 0.0])
    with pytest.raises(ValueError, match="hip_heights_m.*takes 4"):
        controller.observe({**state, "hip_heights_m": [0.3] * 3}, [2.0, 0.0])
    bare = {k: v for k, v in state.items() if k not in ("feet_in_world_m", "joint_angles_rad")}
    with pytest.raises(ValueError, match="feet_in_world_m.*joint_angles_rad"):
        controller.observe(bare, [2.0, 0.0])
    with pytest.raises(ValueError, match="plan_phase first"):
        controller.joint_targets(1)
    controller.plan_phase(np.zeros(27, np.float32), state)
    with pytest.raises(ValueError, match="samples 1 to 180"):
        controller.joint_targets(181)
    with pytest.raises(ValueError, match="26 values"):
        controller.plan_phase(np.zeros(26, np.float32), state)
    with pytest.raises(ValueError, match="12 joints"):
        robot.step(np.zeros(11))


def test_the_controller_steps_at_its_configs_rate_and_run_phase_refuses_another(tmp_path):
    """A config's `[physics] step_rate_hz` sets the controller's control
    steps and the bare robot's step; `run_phase` refuses a robot that steps
    otherwise than the controller plans."""
    assert quadwalk.Controller().samples_per_phase == 180
    assert quadwalk.Controller().control_step_secs == pytest.approx(1 / 240)
    config = tmp_path / "coarse.toml"
    config.write_text('[terrain]\nspec = "rigid"\n\n[physics]\nstep_rate_hz = 120\n')
    coarse = quadwalk.Controller(config=str(config))
    assert coarse.samples_per_phase == 90
    assert coarse.control_step_secs == pytest.approx(1 / 120)
    robot = quadwalk.Sim(config=str(config))
    assert robot.dt_secs == pytest.approx(1 / 120)
    robot.reset()
    state = robot.state()
    coarse.begin_episode(state)
    quadwalk.run_phase(coarse, robot, np.zeros(27, np.float32), state)
    with pytest.raises(ValueError, match="samples 1 to 90"):
        coarse.joint_targets(91)
    paper = quadwalk.Controller()
    paper.begin_episode(robot.state())
    with pytest.raises(ValueError, match="the robot steps .* the controller plans steps"):
        quadwalk.run_phase(paper, robot, np.zeros(27, np.float32), robot.state())


def test_a_height_scan_controller_observes_the_states_scan_and_names_it_missing(tmp_path):
    """With `height_scan` on, the observation ends with the state's 18
    scanned heights, as the environment's does; a state without them is
    refused by name."""
    config = tmp_path / "scan.toml"
    config.write_text('[terrain]\nspec = "slope:10"\n\n[task.observation]\nheight_scan = true\n')
    env = quadwalk.make_env(config=str(config), seed=5)
    env_obs, _ = env.reset(seed=5)
    robot = quadwalk.Sim(config=str(config), seed=5)
    robot.reset()
    controller = quadwalk.Controller(config=str(config))
    assert controller.observation_size == 102 + 18
    state = robot.state()
    controller.begin_episode(state)
    obs = controller.observe(state, list(env.goal_xy_m))
    np.testing.assert_array_equal(obs, env_obs)
    scan = np.asarray(state["height_scan_m"])
    np.testing.assert_array_equal(obs[-18:], scan.astype(np.float32))
    # the ground rises ahead: each row 0.2 m further is ~3.5 cm nearer the base
    rows = scan.reshape(6, 3)
    assert np.all(np.abs(rows[:-1] - rows[1:] - np.tan(np.radians(10)) * 0.2) < 2e-3)
    without = {k: v for k, v in state.items() if k != "height_scan_m"}
    with pytest.raises(ValueError, match="height_scan_m.*height scan"):
        controller.observe(without, [2.0, 0.0])

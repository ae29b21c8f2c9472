"""quadwalk from Python: quadruped locomotion on ground that gives way.

The worlds, the paper's task (27-value phase action, 102-value observation,
rewards, termination) and the terrains are quadwalk's Rust code; this package
wraps them in Gymnasium's interfaces:

- ``make_env(terrain="elastic:5cm", config=None, seed=None)``: a
  ``gymnasium.Env`` (one 0.75 s phase per step);
- ``make_vec_env(num_envs, ...)``: a ``gymnasium.vector.VectorEnv`` whose
  worlds are stepped in parallel in Rust with the GIL released;
- environment ids ``quadwalk/Elastic5cm-v0``, ``quadwalk/Tv2-v0``,
  ``quadwalk/Rigid-v0`` and ``quadwalk/Terrain-v0`` (any ``terrain=`` or
  ``config=``) for ``gymnasium.make``;
- ``terrains()``: the terrain plugins and their parameters;
- ``Policy.load(dir)``: a quadwalk checkpoint's mean action on numpy
  observations;
- ``Controller.for_policy(dir)``: the phase-level controller a robot runs
  around a policy (its observation from the measured state, the phase plan,
  the joint targets of each 240 Hz control step), ``run_phase`` its loop
  over one phase on any robot, and ``Sim``: quadwalk's world as a bare robot
  it drives step by step.

A bad terrain spec, experiment file or action raises ``ValueError`` with a
message that names it.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

from ._quadwalk import ACTION_SIZE, LAIKAGO_URDF, PHASE_SECS, REWARD_TERMS, Controller, Policy, Sim, terrains
from ._quadwalk import Env as _NativeEnv
from ._quadwalk import VecEnv as _NativeVecEnv

__all__ = [
    "ACTION_SIZE",
    "LAIKAGO_URDF",
    "PHASE_SECS",
    "REWARD_TERMS",
    "Controller",
    "Policy",
    "QuadwalkEnv",
    "QuadwalkVectorEnv",
    "Sim",
    "make_env",
    "make_vec_env",
    "run_phase",
    "terrains",
]

#: The paper's baseline: the terrain changes every 2 m.
TV2 = "varying:2m:2,3,4,5cm,rigid"


def _spaces(observation_size: int) -> tuple[spaces.Box, spaces.Box]:
    observation = spaces.Box(-np.inf, np.inf, (observation_size,), np.float32)
    action = spaces.Box(-1.0, 1.0, (ACTION_SIZE,), np.float32)
    return observation, action


class QuadwalkEnv(gym.Env):
    """The paper's task on one quadwalk world: each step is one 0.75 s phase.

    ``terrain`` is a spec (``quadwalk.terrains()``; default ``elastic:5cm``);
    ``config`` an experiment file (TOML; its terrain unless ``terrain`` is
    also given); ``seed`` the world's draw and start positions (``reset(seed=S)``
    builds the world of ``quadwalk rollout --seed S``); ``max_phases`` the
    episode length (the episode is ``truncated`` at it). ``info`` holds the
    reward terms, the termination cause (``None`` unless terminated), the
    terrain region under the base, the phase and the goals reached.
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        terrain: str | None = None,
        config: str | None = None,
        seed: int | None = None,
        max_phases: int | None = None,
    ) -> None:
        self._env = _NativeEnv(terrain, _path(config), 0 if seed is None else seed, max_phases)
        self.observation_space, self.action_space = _spaces(self._env.observation_size)
        self.spec_terrain = self._env.terrain
        self.max_phases = self._env.max_phases

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        obs = self._env.reset(seed)
        return obs, {"seed": self._env.seed}

    def step(self, action):
        action = np.asarray(action, dtype=np.float32).reshape(-1)
        obs, reward, terminated, truncated, info = self._env.step(action.tolist())
        return obs, float(reward), bool(terminated), bool(truncated), info

    @property
    def base_position_m(self) -> tuple[float, float, float]:
        """The robot's base position, world frame, metres."""
        return tuple(self._env.base_position_m)

    @property
    def start_xy_m(self) -> tuple[float, float]:
        """Where the episode started (x, y), world frame, metres."""
        return tuple(self._env.start_xy_m)

    @property
    def goal_xy_m(self) -> tuple[float, float]:
        """The current goal (x, y), world frame, metres."""
        return tuple(self._env.goal_xy_m)


def _autoreset_metadata(same_step: bool = False) -> dict[str, Any]:
    mode = getattr(gym.vector, "AutoresetMode", None)
    if mode is None:
        return {"autoreset_mode": "SameStep" if same_step else "NextStep"}
    return {"autoreset_mode": mode.SAME_STEP if same_step else mode.NEXT_STEP}


class QuadwalkVectorEnv(gym.vector.VectorEnv):
    """``num_envs`` quadwalk worlds stepped in parallel in Rust (GIL released).

    Environment i draws its world and starts from ``seed + i``: it equals
    ``QuadwalkEnv(seed=seed + i)`` step for step. ``autoreset_mode`` is
    Gymnasium's ``"next_step"`` (default: the step after an episode ends
    resets that environment, its action ignored, reward 0) or
    ``"same_step"`` (the ending step resets it and returns the new episode's
    first observation; the last one is in ``infos["final_obs"]``, where
    ``infos["_final_obs"]`` is true). ``infos`` holds ``reward_terms``
    (num_envs x 5, ``REWARD_TERMS`` order), ``termination``, ``region``,
    ``phase`` and ``autoreset``.
    """

    metadata = _autoreset_metadata()

    def __init__(
        self,
        num_envs: int,
        terrain: str | None = None,
        config: str | None = None,
        seed: int | None = None,
        max_phases: int | None = None,
        threads: int | None = None,
        autoreset_mode: str = "next_step",
    ) -> None:
        self._env = _NativeVecEnv(
            num_envs,
            terrain,
            _path(config),
            0 if seed is None else seed,
            max_phases,
            threads,
            str(autoreset_mode),
        )
        self.metadata = _autoreset_metadata(same_step=autoreset_mode == "same_step")
        self.num_envs = num_envs
        self.single_observation_space, self.single_action_space = _spaces(
            self._env.observation_size
        )
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.spec_terrain = self._env.terrain

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        if isinstance(seed, (list, tuple)):
            raise ValueError(
                "seed: give one int; environment i then uses seed + i"
            )
        super().reset(seed=seed)
        return self._env.reset(seed), {}

    def step(self, actions):
        actions = np.ascontiguousarray(actions, dtype=np.float32)
        if actions.ndim != 2:
            raise ValueError(
                f"actions have shape {list(actions.shape)}; expected "
                f"[{self.num_envs}, {ACTION_SIZE}] (num_envs x the phase action)"
            )
        obs, rewards, terminated, truncated, infos = self._env.step(actions)
        return obs, rewards, terminated, truncated, infos


def run_phase(controller: Controller, robot, action, state: dict, stop=None) -> tuple[dict, Any]:
    """One phase of a deployed policy: ``controller`` plans it from
    ``action`` and the measured ``state``, then drives ``robot`` through the
    phase's joint targets, one per step at the controller's rate (240 Hz
    unless its policy trained at another): ``robot.step(targets)``, then
    ``robot.state()`` (``Sim``, ``quadwalk.mujoco_scene.MujocoRobot`` or a
    real robot's interface). ``stop(state)``, called after each step, ends the phase
    early when it returns something true (a fall's cause). Returns the last
    state and what ``stop`` returned (``None`` when the phase ran to its
    end). A robot with a ``dt_secs`` attribute (``Sim``, ``MujocoRobot``)
    must take steps as long as the controller's (``control_step_secs``)."""
    robot_dt_secs = getattr(robot, "dt_secs", None)
    if robot_dt_secs is not None and abs(robot_dt_secs - controller.control_step_secs) > 1e-12:
        raise ValueError(
            f"the robot steps {robot_dt_secs} s but the controller plans steps of "
            f"{controller.control_step_secs} s (its policy's [physics] step_rate_hz): "
            "step the robot at the policy's rate"
        )
    controller.plan_phase(action, state)
    stopped = None
    for sample in range(1, controller.samples_per_phase + 1):
        targets = controller.joint_targets(sample)
        controller.record_step(state)
        robot.step(targets)
        state = robot.state()
        if stop is not None:
            stopped = stop(state) or None
            if stopped is not None:
                break
    controller.end_phase()
    return state, stopped


def _path(config) -> str | None:
    return None if config is None else str(config)


def make_env(
    terrain: str | None = None,
    config: str | None = None,
    seed: int | None = None,
    max_phases: int | None = None,
) -> QuadwalkEnv:
    """A ``gymnasium.Env`` on ``terrain`` (default ``elastic:5cm``), or with
    the experiment file ``config`` (its terrain unless ``terrain`` is given)."""
    return QuadwalkEnv(terrain=terrain, config=config, seed=seed, max_phases=max_phases)


def make_vec_env(
    num_envs: int,
    terrain: str | None = None,
    config: str | None = None,
    seed: int | None = None,
    max_phases: int | None = None,
    threads: int | None = None,
    autoreset_mode: str = "next_step",
) -> QuadwalkVectorEnv:
    """A ``gymnasium.vector.VectorEnv`` of ``num_envs`` worlds stepped in Rust
    (terrain and config as in ``make_env``; ``autoreset_mode`` as in
    ``QuadwalkVectorEnv``)."""
    return QuadwalkVectorEnv(num_envs, terrain, config, seed, max_phases, threads, autoreset_mode)


def _register() -> None:
    for env_id, terrain in [
        ("quadwalk/Elastic5cm-v0", "elastic:5cm"),
        ("quadwalk/Tv2-v0", TV2),
        ("quadwalk/Rigid-v0", "rigid"),
        ("quadwalk/Terrain-v0", None),
    ]:
        if env_id in gym.registry:
            continue
        kwargs = {} if terrain is None else {"terrain": terrain}
        gym.register(
            id=env_id,
            entry_point="quadwalk:QuadwalkEnv",
            vector_entry_point="quadwalk:QuadwalkVectorEnv",
            kwargs=kwargs,
        )


_register()

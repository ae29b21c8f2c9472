"""quadwalk's vector env for Stable-Baselines3 (``pip install stable-baselines3``).

Stable-Baselines3 takes its own ``VecEnv`` interface, not Gymnasium's vector
API. ``Sb3VecEnv`` is that interface over quadwalk's native vector env, so
SB3's PPO and SAC step N worlds in parallel in Rust (GIL released) instead of
one Python env after another::

    from stable_baselines3 import PPO
    from quadwalk.sb3 import Sb3VecEnv

    env = Sb3VecEnv(16, terrain="elastic:5cm", seed=0)
    PPO("MlpPolicy", env).learn(100_000)

SB3's conventions: an environment whose episode ends is reset within the
same step (quadwalk's same-step autoreset); ``infos[i]["terminal_observation"]``
holds the episode's last observation and ``infos[i]["TimeLimit.truncated"]``
says whether it ended at the phase limit rather than by a fall.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from . import REWARD_TERMS, QuadwalkVectorEnv


class Sb3VecEnv(VecEnv):
    """``num_envs`` quadwalk worlds as a Stable-Baselines3 ``VecEnv``.

    ``terrain``, ``config``, ``seed``, ``max_phases`` and ``threads`` are
    ``quadwalk.make_vec_env``'s: environment i uses seed ``seed + i``.
    ``infos[i]`` holds the reward terms (dict), the termination cause and
    the region, as ``QuadwalkEnv``'s ``info`` does.
    """

    def __init__(
        self,
        num_envs: int,
        terrain: str | None = None,
        config: str | None = None,
        seed: int | None = None,
        max_phases: int | None = None,
        threads: int | None = None,
    ) -> None:
        self.vec = QuadwalkVectorEnv(
            num_envs, terrain, config, seed, max_phases, threads, autoreset_mode="same_step"
        )
        super().__init__(
            num_envs, self.vec.single_observation_space, self.vec.single_action_space
        )
        self._actions: np.ndarray | None = None
        self._next_seed: int | None = seed

    def reset(self) -> np.ndarray:
        obs, _ = self.vec.reset(seed=self._next_seed)
        self._next_seed = None
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)

    def step_wait(self):
        if self._actions is None:
            raise RuntimeError("step_wait() without step_async()")
        obs, rewards, terminated, truncated, infos = self.vec.step(self._actions)
        self._actions = None
        dones = terminated | truncated
        out: list[dict[str, Any]] = []
        for i in range(self.num_envs):
            info: dict[str, Any] = {
                "reward_terms": dict(zip(REWARD_TERMS, infos["reward_terms"][i].tolist())),
                "termination": infos["termination"][i],
                "region": infos["region"][i],
                "TimeLimit.truncated": bool(truncated[i] and not terminated[i]),
            }
            if dones[i]:
                info["terminal_observation"] = infos["final_obs"][i].copy()
            out.append(info)
        return obs, rewards.astype(np.float32), dones, out

    def close(self) -> None:
        self.vec.close()

    def seed(self, seed: int | None = None) -> Sequence[None]:
        """The next ``reset()`` builds environment i's world from ``seed + i``."""
        self._next_seed = seed
        return [None] * self.num_envs

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [getattr(self.vec, attr_name) for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        raise AttributeError(
            f"set_attr({attr_name!r}): quadwalk's worlds live in Rust; "
            "build a new Sb3VecEnv to change them"
        )

    def env_method(self, method_name: str, *args, indices=None, **kwargs) -> list[Any]:
        raise AttributeError(
            f"env_method({method_name!r}): quadwalk's worlds live in Rust and have no "
            "per-environment Python methods"
        )

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._indices(indices)]

    def _indices(self, indices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, int):
            return [indices]
        return list(indices)

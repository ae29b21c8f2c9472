"""What sb3_ppo.py and sb3_sac.py share: the environment flags, the vector
env (quadwalk's worlds stepped in Rust, observations normalised by SB3's
``VecNormalize``) and the evaluation of the trained policy."""

from __future__ import annotations

import argparse
import pathlib

import numpy as np


def add_env_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--terrain", default="elastic:5cm", help="terrain spec (quadwalk.terrains())")
    p.add_argument("--config", default=None, help="a quadwalk experiment file (TOML)")
    p.add_argument("--envs", type=int, default=16, help="worlds stepped in parallel")
    p.add_argument("--threads", type=int, default=None, help="threads that step them (default: all cores)")
    p.add_argument("--max-phases", type=int, default=None, help="episode length (default: the task's, 40)")
    p.add_argument("--seed", type=int, default=0, help="world i uses seed + i")
    p.add_argument("--out", default=None, help="directory to save the model in")
    p.add_argument("--eval-episodes", type=int, default=2, help="episodes of the trained policy at the end")
    p.add_argument("--eval-phases", type=int, default=400, help="phases per evaluation episode")


def make_vec_env(args: argparse.Namespace):
    """``args.envs`` worlds as an SB3 VecEnv with normalised observations
    (raises ValueError for a bad terrain spec or config)."""
    from stable_baselines3.common.vec_env import VecNormalize

    from quadwalk.sb3 import Sb3VecEnv

    if args.envs < 1:
        raise ValueError(f"--envs {args.envs}: at least 1")
    env = Sb3VecEnv(
        args.envs,
        terrain=args.terrain,
        config=args.config,
        seed=args.seed,
        max_phases=args.max_phases,
        threads=args.threads,
    )
    return VecNormalize(env, norm_obs=True, norm_reward=False, clip_obs=10.0, gamma=0.95)


def train_save_and_evaluate(model, env, args: argparse.Namespace) -> list[float]:
    """Trains ``model`` for ``args.timesteps`` phases; with ``args.out``
    saves ``model.zip`` and the observation normaliser ``vecnormalize.pkl``
    there; then evaluates it (``evaluate``)."""
    model.learn(total_timesteps=args.timesteps)
    if args.out:
        out = pathlib.Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        model.save(out / "model.zip")
        env.save(str(out / "vecnormalize.pkl"))
        print(f"saved {out / 'model.zip'} and {out / 'vecnormalize.pkl'}")
    return evaluate(model, env, args)


def evaluate(model, train_env, args: argparse.Namespace) -> list[float]:
    """Runs the deterministic policy for ``args.eval_episodes`` episodes of
    ``args.eval_phases`` phases on seeds the training did not use; prints and
    returns the distance walked (m) in each."""
    import quadwalk

    distances = []
    for k in range(args.eval_episodes):
        seed = 1_000_000 + args.seed + k
        env = quadwalk.make_env(
            terrain=args.terrain, config=args.config, seed=seed, max_phases=args.eval_phases
        )
        obs, _ = env.reset(seed=seed)
        start = np.array(env.start_xy_m)
        cause, phases = None, 0
        while True:
            action, _ = model.predict(train_env.normalize_obs(obs[None, :]), deterministic=True)
            obs, _, terminated, truncated, info = env.step(action[0])
            phases += 1
            if terminated or truncated:
                cause = info["termination"]
                break
        distance = float(np.linalg.norm(np.array(env.base_position_m[:2]) - start))
        distances.append(distance)
        print(f"eval seed {seed}: {distance:.2f} m in {phases} phases ({cause or 'no fall'})")
    return distances

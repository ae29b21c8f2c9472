"""Train Stable-Baselines3's PPO on a quadwalk terrain.

    python python/examples/sb3_ppo.py --terrain elastic:5cm --envs 16 --timesteps 200000 --out runs/sb3-ppo

The worlds are stepped in parallel in Rust (``quadwalk.sb3.Sb3VecEnv``); one
timestep is one 0.75 s phase of one world. The defaults follow quadwalk's own
PPO where SB3 allows (discount 0.95 as the paper, GAE 0.95, networks
256-128, minibatch 128) and rl-baselines3-zoo's PyBullet settings elsewhere
(observation normalisation, 20 epochs). ``--out DIR`` saves ``DIR/model.zip``
and the observation normaliser ``DIR/vecnormalize.pkl``; at the end the
deterministic policy runs ``--eval-episodes`` episodes and the distance each
walked is printed.
"""

from __future__ import annotations

import argparse
import sys

from sb3_common import add_env_args, make_vec_env, train_save_and_evaluate


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_env_args(p)
    p.add_argument("--timesteps", type=int, default=200_000, help="phases to train on, all worlds together")
    p.add_argument("--n-steps", type=int, default=128, help="phases per world per rollout")
    p.add_argument("--batch-size", type=int, default=128, help="minibatch size")
    p.add_argument("--epochs", type=int, default=20, help="epochs per rollout")
    p.add_argument("--learning-rate", type=float, default=3e-4)
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    from stable_baselines3 import PPO

    try:
        env = make_vec_env(args)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    model = PPO(
        "MlpPolicy",
        env,
        n_steps=args.n_steps,
        batch_size=min(args.batch_size, args.n_steps * args.envs),
        n_epochs=args.epochs,
        learning_rate=args.learning_rate,
        gamma=0.95,
        gae_lambda=0.95,
        policy_kwargs={"net_arch": [256, 128]},
        seed=args.seed,
        device="cpu",
        verbose=1,
    )
    train_save_and_evaluate(model, env, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())

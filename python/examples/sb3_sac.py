"""Train Stable-Baselines3's SAC on a quadwalk terrain.

    python python/examples/sb3_sac.py --terrain elastic:5cm --envs 8 --timesteps 100000 --out runs/sb3-sac

The worlds are stepped in parallel in Rust (``quadwalk.sb3.Sb3VecEnv``); one
timestep is one 0.75 s phase of one world. Discount 0.95 as the paper,
networks 256-256, one gradient step per phase collected (``--gradient-steps``
per ``--envs`` phases), replay buffer of ``--buffer`` phases. ``--out DIR``
saves ``DIR/model.zip`` and the observation normaliser; at the end the
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
    p.set_defaults(envs=8)
    p.add_argument("--timesteps", type=int, default=100_000, help="phases to train on, all worlds together")
    p.add_argument("--buffer", type=int, default=200_000, help="replay buffer size, phases")
    p.add_argument("--learning-starts", type=int, default=1_000, help="phases collected before the first update")
    p.add_argument("--batch-size", type=int, default=256)
    p.add_argument("--gradient-steps", type=int, default=None, help="updates per step of all worlds (default: --envs, one per phase)")
    p.add_argument("--learning-rate", type=float, default=3e-4)
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    from stable_baselines3 import SAC

    try:
        env = make_vec_env(args)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    model = SAC(
        "MlpPolicy",
        env,
        buffer_size=args.buffer,
        learning_starts=args.learning_starts,
        batch_size=args.batch_size,
        train_freq=1,
        gradient_steps=args.gradient_steps or args.envs,
        learning_rate=args.learning_rate,
        gamma=0.95,
        policy_kwargs={"net_arch": [256, 256]},
        seed=args.seed,
        device="cpu",
        verbose=1,
    )
    train_save_and_evaluate(model, env, args)
    return 0


if __name__ == "__main__":
    sys.exit(main())

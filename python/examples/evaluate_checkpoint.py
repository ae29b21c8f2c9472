"""Evaluate a quadwalk checkpoint from Python: its mean action on episodes of
unseen seeds, the distance walked and how each episode ended.

    python python/examples/evaluate_checkpoint.py policies/rigid --episodes 4 --phases 400

Each episode is the one `quadwalk rollout --policy DIR --config DIR/config.toml
--seed S` runs (the same world, start and actions, bit for bit).
"""

import argparse

import quadwalk


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("policy", help="a run directory, checkpoint or exported policy")
    parser.add_argument("--terrain", help="terrain spec (default: the policy's own)")
    parser.add_argument("--episodes", type=int, default=4)
    parser.add_argument("--phases", type=int, default=400)
    parser.add_argument("--seed", type=int, default=1_000_000, help="first seed")
    args = parser.parse_args()

    policy = quadwalk.Policy.load(args.policy)
    env = quadwalk.make_env(
        terrain=args.terrain, config=policy.config_path, max_phases=args.phases
    )
    print(f"{args.policy} on {env.spec_terrain}, {args.episodes} episodes of {args.phases} phases")
    falls = 0
    for episode in range(args.episodes):
        seed = args.seed + episode
        obs, _ = env.reset(seed=seed)
        start_x, phases, ret = env.base_position_m[0], 0, 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step(policy.act(obs))
            phases, ret = phases + 1, ret + reward
            if terminated or truncated:
                break
        falls += terminated
        how = info["termination_detail"] if terminated else "no fall"
        print(
            f"seed {seed}: {env.base_position_m[0] - start_x:6.2f} m in {phases} phases, "
            f"return {ret:8.2f}, {how}"
        )
    print(f"{args.episodes - falls}/{args.episodes} episodes without a fall")


if __name__ == "__main__":
    main()

"""Train Ray RLlib's PPO on a quadwalk terrain, on one machine or a Ray cluster.

One machine (Ray starts itself):

    python python/examples/rllib_ppo.py --terrain elastic:5cm --env-runners 2 --iterations 50

A cluster: start Ray on each machine first (docs/guide/python.md), e.g.

    ray start --head --port 6379                                        # head
    ray start --address HEAD_IP:6379 --resources '{"quadwalk_runner": 8}'  # each worker

then, on the head:

    python python/examples/rllib_ppo.py --address HEAD_IP:6379 --env-runners 8 \\
        --runner-resource quadwalk_runner --iterations 200 --out runs/rllib-ppo

``--runner-resource NAME`` makes every env runner ask for one unit of the
custom resource NAME, so they run only on nodes started with it (the workers),
while the learner stays with this driver. Every node needs quadwalk installed
(``pip install ./python``) in the Python that ``ray start`` ran from.

Each iteration prints one line (or a JSON object with ``--json``): the
iteration, phases sampled, mean episode return and length, and the Ray node
of each env runner, of the driver and of the head. ``--out DIR`` saves the algorithm (RLlib checkpoint).
"""

from __future__ import annotations

import argparse
import json
import sys


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--terrain", default="elastic:5cm", help="terrain spec (quadwalk.terrains())")
    p.add_argument("--config", default=None, help="a quadwalk experiment file (TOML)")
    p.add_argument("--address", default=None, help="an existing Ray cluster (HOST:PORT); default: start Ray here")
    p.add_argument("--env-runners", type=int, default=2, help="remote env runners (each one CPU)")
    p.add_argument("--envs-per-runner", type=int, default=1, help="worlds stepped by each env runner")
    p.add_argument("--runner-resource", default=None, help="custom Ray resource each env runner needs (places them on nodes that have it)")
    p.add_argument("--iterations", type=int, default=10, help="training iterations")
    p.add_argument("--train-batch", type=int, default=2048, help="phases per iteration")
    p.add_argument("--minibatch", type=int, default=256, help="minibatch size")
    p.add_argument("--epochs", type=int, default=10, help="epochs per iteration")
    p.add_argument("--max-phases", type=int, default=None, help="episode length (default: the task's, 40)")
    p.add_argument("--seed", type=int, default=0, help="seed of the worlds (runner r, world v: seed + 1000 r + v)")
    p.add_argument("--out", default=None, help="directory to save the trained algorithm in")
    p.add_argument("--json", action="store_true", help="print one JSON object per iteration")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    import quadwalk  # noqa: F401 (fails early, with its message, if not installed)
    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    if args.env_runners < 1:
        print("--env-runners: at least 1", file=sys.stderr)
        return 2
    try:  # a bad terrain spec or config is reported here, before Ray starts
        quadwalk.make_env(terrain=args.terrain, config=args.config, max_phases=args.max_phases)
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    ray.init(address=args.address, include_dashboard=False, log_to_driver=False)

    def make(env_config):
        import quadwalk

        seed = env_config["seed"] + 1000 * env_config.worker_index + env_config.vector_index
        return quadwalk.make_env(
            terrain=env_config["terrain"],
            config=env_config["config"],
            seed=seed,
            max_phases=env_config["max_phases"],
        )

    register_env("quadwalk", make)
    resources = {args.runner_resource: 1} if args.runner_resource else {}
    config = (
        PPOConfig()
        .environment(
            "quadwalk",
            env_config={
                "terrain": args.terrain,
                "config": args.config,
                "seed": args.seed,
                "max_phases": args.max_phases,
            },
        )
        .env_runners(
            num_env_runners=args.env_runners,
            num_envs_per_env_runner=args.envs_per_runner,
            num_cpus_per_env_runner=1,
            custom_resources_per_env_runner=resources,
            create_local_env_runner=False,
            rollout_fragment_length="auto",
        )
        .training(
            train_batch_size_per_learner=args.train_batch,
            minibatch_size=min(args.minibatch, args.train_batch),
            num_epochs=args.epochs,
            gamma=0.95,
            lambda_=0.95,
            lr=3e-4,
        )
        .learners(num_learners=0)
        .debugging(seed=args.seed)
    )
    algo = config.build_algo()
    nodes = algo.env_runner_group.foreach_env_runner(
        lambda runner: ray.get_runtime_context().get_node_id(), local_env_runner=False
    )
    head = [n["NodeID"] for n in ray.nodes() if n["Alive"] and "node:__internal_head__" in n["Resources"]]
    for _ in range(args.iterations):
        result = algo.train()
        runners = result.get("env_runners", {})
        line = {
            "iteration": result.get("training_iteration"),
            "phases_sampled": result.get("num_env_steps_sampled_lifetime"),
            "episode_return_mean": runners.get("episode_return_mean"),
            "episode_len_mean": runners.get("episode_len_mean"),
            "env_runner_nodes": nodes,
            "driver_node": ray.get_runtime_context().get_node_id(),
            "head_node": head[0] if head else None,
        }
        if args.json:
            print(json.dumps(line), flush=True)
        else:
            print(
                f"iter {line['iteration']} | phases {line['phases_sampled']} | "
                f"return {line['episode_return_mean']} | length {line['episode_len_mean']} | "
                f"env runners on {len(set(nodes))} node(s)",
                flush=True,
            )
    if args.out:
        path = algo.save_to_path(args.out)
        print(f"saved to {path}", flush=True)
    algo.stop()
    ray.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())

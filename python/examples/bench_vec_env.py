"""What the Python layer costs: phases per second of the vector env seen
from Python, against the time its step spends stepping the worlds in Rust.

    python python/examples/bench_vec_env.py --terrain elastic:5cm --envs 16 --threads 2 --steps 40

Actions are the zero action (the squat held through each phase); episodes
that end are reset by the next step (Gymnasium's next-step autoreset), and
those steps are left out of both sums.
"""

import argparse
import time

import numpy as np

import quadwalk


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--terrain", default="elastic:5cm")
    parser.add_argument("--envs", type=int, default=16)
    parser.add_argument("--threads", type=int, default=None)
    parser.add_argument("--steps", type=int, default=40)
    args = parser.parse_args()

    venv = quadwalk.make_vec_env(args.envs, args.terrain, seed=0, threads=args.threads)
    venv.reset(seed=0)
    actions = np.zeros((args.envs, quadwalk.ACTION_SIZE), np.float32)
    python_secs = rust_secs = 0.0
    phases = 0
    for _ in range(args.steps):
        start = time.perf_counter()
        _, _, _, _, infos = venv.step(actions)
        elapsed = time.perf_counter() - start
        if infos["autoreset"].any():
            continue
        python_secs += elapsed
        rust_secs += venv._env.last_step_secs
        phases += args.envs
    overhead = (python_secs - rust_secs) / python_secs
    print(
        f"{args.terrain}, {args.envs} envs, {args.threads or 'all'} threads: "
        f"{phases / python_secs:.1f} phases/s from Python, {phases / rust_secs:.1f} in Rust; "
        f"the Python layer {100 * overhead:.2f} % of a step"
    )


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""quadwalk's policies in a second engine: the scene in MuJoCo
(``quadwalk.mujoco_scene``), driven through ``quadwalk.Controller`` with
the policy's ONNX graph, beside quadwalk's own figures for the same runs.

    python python/examples/mujoco_transfer.py physics            # standing sink, scripted crawl
    python python/examples/mujoco_transfer.py policies --episodes 10 --phases 400

``physics``: the standing sink per terrain after 10 s in the squat (quadwalk:
``quadwalk stand --seconds 10 --json``) and the scripted crawl's distance
in ``--crawl-phases`` phases on rigid ground and 2 cm tiles (quadwalk:
``quadwalk rollout --policy scripted``). ``policies``: each policy on each
terrain, ``--episodes`` episodes of ``--phases`` phases (quadwalk: ``quadwalk
eval`` with the same seeds; MuJoCo: starts drawn from the same ranges with
the episode's seed, the goals' line at the start's y, goals every 2 m),
success, distance, speed and falls by cause. Needs ``mujoco``,
``onnxruntime`` and the ``quadwalk`` binary (``--quadwalk``, default on
PATH or ``target/release``). Prints markdown tables; ``--json FILE``
writes every figure.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import tomllib
from collections import Counter

import numpy as np
import onnxruntime as ort

import quadwalk
from quadwalk.mujoco_scene import MujocoRobot

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))


def quadwalk_json(binary: str, *args: str) -> dict:
    out = subprocess.run([binary, *args, "--json"], check=True, capture_output=True, text=True)
    return json.loads(out.stdout)


def scene_for(terrain: str, task: dict) -> MujocoRobot:
    return MujocoRobot(
        terrain,
        settle_secs=task.get("settle_secs", 0.5),
        min_base_height_m=task.get("min_base_height_m", 0.2),
        max_pitch_deg=task.get("max_pitch_deg", 15.0),
    )


def run_episode(robot: MujocoRobot, controller, act, task: dict, phases: int, seed: int) -> dict:
    """One episode: the controller's loop on the MuJoCo robot."""
    rng = np.random.default_rng(seed)
    (x0, x1), (y0, y1) = task.get("start_x_range_m", [0, 0]), task.get("start_y_range_m", [0, 0])
    start = [rng.uniform(x0, x1) if x1 > x0 else x0, rng.uniform(y0, y1) if y1 > y0 else y0]
    robot.reset(start, controller.squat_joint_angles_rad, controller.hips_in_base_m)
    state = robot.state()
    controller.begin_episode(state)
    spacing, reached_m = task.get("goal_spacing_m", 2.0), task.get("goal_reached_m", 0.3)
    goal = [state["base_position_m"][0] + spacing, state["base_position_m"][1]]
    x_start = state["base_position_m"][0]
    fall, done = None, 0
    for _ in range(phases):
        obs = controller.observe(state, goal)
        state, fall = quadwalk.run_phase(controller, robot, act(obs), state, stop=lambda _: robot.fall())
        done += 1
        if fall:
            break
        x, y = state["base_position_m"][:2]
        while np.hypot(goal[0] - x, goal[1] - y) < reached_m or x > goal[0]:
            goal[0] += spacing
    distance = float(state["base_position_m"][0] - x_start)
    return dict(phases=done, fall=fall, distance_m=distance,
                speed_m_per_s=distance / (done * quadwalk.PHASE_SECS))


def physics(args) -> dict:
    rows = []
    for terrain in ["rigid", "elastic:2cm", "elastic:5cm"]:
        robot = scene_for(terrain, {})
        controller = quadwalk.Controller()
        robot.reset([0.0, 0.0], controller.squat_joint_angles_rad, controller.hips_in_base_m)
        for _ in range(10 * 240):
            robot.step(controller.squat_joint_angles_rad)
        q = quadwalk_json(args.quadwalk, "stand", "--terrain", terrain, "--seconds", "10")
        rows.append(dict(check="standing sink (cm)", terrain=terrain,
                         quadwalk=100 * q["mean_loaded_sink_m"] if terrain != "rigid" else 0.0,
                         mujoco=100 * float(np.mean(robot.foot_sinks_m()))))
        rows.append(dict(check="standing base height above the rest surface (cm)", terrain=terrain,
                         quadwalk=100 * q.get("base_height_m", float("nan")),
                         mujoco=100 * float(robot.base_pose()[0][2])))
    for terrain in ["rigid", "elastic:2cm"]:
        with tempfile.NamedTemporaryFile("w", suffix=".toml", delete=False) as f:
            f.write(f'[terrain]\nspec = "{terrain}"\n[task]\naction_prior = "scripted_crawl"\n')
            crawl_config = f.name
        controller = quadwalk.Controller(crawl_config)
        os.unlink(crawl_config)
        robot = scene_for(terrain, {})
        result = run_episode(robot, controller, lambda obs: np.zeros(27, np.float32), {}, args.crawl_phases, 0)
        q = quadwalk_json(args.quadwalk, "rollout", "--policy", "scripted", "--terrain", terrain,
                          "--phases", str(args.crawl_phases))
        rows.append(dict(check=f"scripted crawl, {args.crawl_phases} phases: distance (m)", terrain=terrain,
                         quadwalk=q["distance_m"], mujoco=result["distance_m"],
                         mujoco_fall=result["fall"]))
    print("| check | terrain | quadwalk (rapier) | MuJoCo |\n| --- | --- | ---: | ---: |")
    for r in rows:
        fall = f" (fell: {r['mujoco_fall']})" if r.get("mujoco_fall") else ""
        print(f"| {r['check']} | `{r['terrain']}` | {r['quadwalk']:.2f} | {r['mujoco']:.2f}{fall} |")
    return dict(physics=rows)


def policies(args) -> dict:
    rows = []
    for policy in args.policy:
        path = os.path.join(ROOT, policy) if not os.path.isabs(policy) else policy
        with open(os.path.join(path, "config.toml"), "rb") as f:
            task = tomllib.load(f).get("task", {})
        session = ort.InferenceSession(os.path.join(path, "policy.onnx"), providers=["CPUExecutionProvider"])
        act = lambda obs: session.run(["action"], {"observation": obs[None]})[0][0]  # noqa: E731
        for terrain in args.terrain:
            robot = scene_for(terrain, task)
            controller = quadwalk.Controller.for_policy(path)
            episodes = [run_episode(robot, controller, act, task, args.phases, args.seed + k)
                        for k in range(args.episodes)]
            q = quadwalk_json(args.quadwalk, "eval", "--policy", path, "--terrain", terrain,
                              "--episodes", str(args.episodes), "--phases", str(args.phases),
                              "--seed", str(args.seed), "--out", tempfile.mkdtemp())
            qs = q["summary"]
            falls = Counter(e["fall"] for e in episodes if e["fall"])
            rows.append(dict(
                policy=policy, terrain=terrain,
                quadwalk=dict(success=qs["successes"], episodes=qs["episodes"],
                              distance_m=qs["distance_m"]["mean"],
                              speed_m_per_s=qs["mean_speed_m_per_s"]["mean"],
                              falls=qs["falls_by_cause"]),
                mujoco=dict(success=sum(e["fall"] is None for e in episodes), episodes=len(episodes),
                            distance_m=float(np.mean([e["distance_m"] for e in episodes])),
                            speed_m_per_s=float(np.mean([e["speed_m_per_s"] for e in episodes])),
                            phases=float(np.mean([e["phases"] for e in episodes])),
                            falls=dict(falls)),
            ))
            r = rows[-1]
            print(f"| {policy} | `{terrain}` | {r['quadwalk']['success']}/{r['quadwalk']['episodes']}, "
                  f"{r['quadwalk']['distance_m']:.2f} m | {r['mujoco']['success']}/{r['mujoco']['episodes']}, "
                  f"{r['mujoco']['distance_m']:.2f} m, {r['mujoco']['phases']:.0f} phases, "
                  f"falls {dict(falls) or '-'} |", flush=True)
    return dict(policies=rows)


def markdown(result: dict, command: str) -> str:
    """The page of a run's figures (physics check and/or policies)."""
    out = [f"Generated by `{command}`; every figure is that run's.", ""]
    if "physics" in result:
        out += ["| check | terrain | quadwalk (rapier) | MuJoCo |", "| --- | --- | ---: | ---: |"]
        for r in result["physics"]:
            fall = f" (fell: {r['mujoco_fall']})" if r.get("mujoco_fall") else ""
            out.append(f"| {r['check']} | `{r['terrain']}` | {r['quadwalk']:.2f} | {r['mujoco']:.2f}{fall} |")
        out.append("")
    if "policies" in result:
        out += ["| policy | terrain | quadwalk: success, mean distance, speed, falls | MuJoCo: success, mean distance, speed, mean phases, falls |",
                "| --- | --- | --- | --- |"]

        def speed(v):
            return "-" if v is None else f"{v:.3f} m/s"

        def falls(v):
            if v is None:
                return "-"
            return ", ".join(f"{k} {n}" for k, n in sorted(v.items())) or "none"

        for r in result["policies"]:
            q, m = r["quadwalk"], r["mujoco"]
            out.append(f"| {r['policy']} | `{r['terrain']}` | {q['success']}/{q['episodes']}, {q['distance_m']:.2f} m, "
                       f"{speed(q['speed_m_per_s'])}, {falls(q['falls'])} "
                       f"| {m['success']}/{m['episodes']}, {m['distance_m']:.2f} m, {speed(m['speed_m_per_s'])}, "
                       f"{m['phases']:.0f}, {falls(m['falls'])} |")
        out.append("")
        if any(r["quadwalk"]["falls"] is None for r in result["policies"]):
            out.append("(-: not recorded by the version of the script that made this run.)")
        out.append("")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("what", choices=["physics", "policies", "markdown"],
                    help="markdown: print the page of the --json files given as --from")
    ap.add_argument("--from", dest="sources", nargs="+", default=[], help="JSON files of earlier runs (markdown)")
    ap.add_argument("--quadwalk", default=shutil.which("quadwalk") or os.path.join(ROOT, "target", "release", "quadwalk"))
    ap.add_argument("--crawl-phases", type=int, default=160)
    ap.add_argument("--policy", nargs="+", default=["policies/rigid", "policies/elastic-5cm-line", "policies/tv2"])
    ap.add_argument("--terrain", nargs="+", default=["rigid", "elastic:2cm", "elastic:5cm"])
    ap.add_argument("--episodes", type=int, default=10)
    ap.add_argument("--phases", type=int, default=400)
    ap.add_argument("--seed", type=int, default=1_000_000)
    ap.add_argument("--json", help="also write every figure to this file")
    args = ap.parse_args()
    if args.what == "markdown":
        print("# quadwalk's scene and policies in MuJoCo\n")
        print("The same Laikago URDF, PD gains, effort limits, friction and spring tiles "
              "(k = m g / (4 d)) in MuJoCo (`quadwalk.mujoco_scene`), each policy run through "
              "`quadwalk.Controller` with its `policy.onnx` in onnxruntime; quadwalk's own figures "
              "beside, from `quadwalk stand`, `rollout` and `eval` (seeds s to s + n - 1; "
              "MuJoCo's starts are drawn from the task's ranges with the same seeds by numpy, so the "
              "start positions differ). Regenerate the page: "
              "`python python/examples/mujoco_transfer.py markdown --from "
              + " ".join(args.sources) + "`.\n")
        result = {}
        for path in args.sources:
            with open(path) as f:
                data = json.load(f)
            for key, value in data.items():
                if key != "command":
                    result[key] = value
            print(markdown({k: v for k, v in data.items() if k != "command"}, data.get("command", "?")))
        return
    if not os.path.isfile(args.quadwalk):
        sys.exit(f"--quadwalk {args.quadwalk}: no such binary (cargo build --release -p cli)")
    if args.what == "policies":
        print("| policy | terrain | quadwalk: success, distance | MuJoCo: success, distance, phases, falls |\n| --- | --- | --- | --- |")
    result = physics(args) if args.what == "physics" else policies(args)
    result["command"] = "python python/examples/mujoco_transfer.py " + " ".join(sys.argv[1:])
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()

"""Real trainers on quadwalk: Stable-Baselines3 (PPO, SAC) through the
examples, the SB3 vector env's conventions, and RLlib's PPO on a two-node Ray
cluster started here on 127.0.0.1 with the env runners on the worker node."""

import json
import os
import socket
import subprocess
import sys
import time

import numpy as np
import pytest

import quadwalk

pytest.importorskip("torch", reason="the trainer tests need torch (pytest_suite.rs installs it)")


def run_example(root, name, *args, timeout=600):
    return subprocess.run(
        [sys.executable, str(root / "python/examples" / name), *args],
        check=True, capture_output=True, text=True, timeout=timeout,
        cwd=root / "python/examples",
    ).stdout


def test_sb3_vec_env_follows_sb3_conventions():
    pytest.importorskip("stable_baselines3")
    from quadwalk.sb3 import Sb3VecEnv

    env = Sb3VecEnv(2, terrain="rigid", seed=5, max_phases=2, threads=2)
    obs = env.reset()
    assert obs.shape == (2, env.observation_space.shape[0]) and obs.dtype == np.float32
    single = [quadwalk.make_env("rigid", seed=5 + i, max_phases=2) for i in range(2)]
    for i, e in enumerate(single):
        np.testing.assert_array_equal(obs[i], e.reset(seed=5 + i)[0])
    actions = np.zeros((2, quadwalk.ACTION_SIZE), np.float32)
    for _ in range(2):
        obs, rewards, dones, infos = env.step(actions)
    # the phase limit (2) ends every episode on the second step: same-step reset
    assert dones.all() and rewards.dtype == np.float32
    for i, e in enumerate(single):
        e.step(actions[i])
        last, *_ = e.step(actions[i])
        np.testing.assert_array_equal(infos[i]["terminal_observation"], last)
        np.testing.assert_array_equal(obs[i], e.reset()[0])
        assert infos[i]["TimeLimit.truncated"] == (infos[i]["termination"] is None)
        assert set(infos[i]["reward_terms"]) == set(quadwalk.REWARD_TERMS)
    with pytest.raises(AttributeError, match="live in Rust"):
        env.env_method("render")


def test_sb3_ppo_example_trains_and_saves_a_model(root, tmp_path):
    pytest.importorskip("stable_baselines3")
    out = run_example(
        root, "sb3_ppo.py", "--terrain", "rigid", "--envs", "2", "--threads", "2",
        "--max-phases", "10", "--timesteps", "256", "--n-steps", "64", "--batch-size", "64",
        "--epochs", "2", "--eval-episodes", "1", "--eval-phases", "5", "--out", str(tmp_path / "ppo"),
    )
    assert (tmp_path / "ppo/model.zip").is_file(), out
    assert "eval seed 1000000:" in out, out
    from stable_baselines3 import PPO

    model = PPO.load(tmp_path / "ppo/model.zip", device="cpu")
    assert model.num_timesteps >= 256
    action, _ = model.predict(np.zeros((1, 102), np.float32), deterministic=True)
    assert action.shape == (1, quadwalk.ACTION_SIZE)


def test_sb3_sac_example_trains_and_saves_a_model(root, tmp_path):
    pytest.importorskip("stable_baselines3")
    out = run_example(
        root, "sb3_sac.py", "--terrain", "rigid", "--envs", "2", "--threads", "2",
        "--max-phases", "10", "--timesteps", "200", "--learning-starts", "100",
        "--batch-size", "64", "--buffer", "1000",
        "--eval-episodes", "1", "--eval-phases", "5", "--out", str(tmp_path / "sac"),
    )
    assert (tmp_path / "sac/model.zip").is_file(), out
    from stable_baselines3 import SAC

    model = SAC.load(tmp_path / "sac/model.zip", device="cpu")
    assert model.num_timesteps >= 200
    # one gradient step per phase collected after learning_starts
    assert model._n_updates >= 90, model._n_updates


def test_sb3_examples_reject_a_bad_terrain(root):
    pytest.importorskip("stable_baselines3")
    done = subprocess.run(
        [sys.executable, str(root / "python/examples/sb3_ppo.py"), "--terrain", "elastic:5xx"],
        capture_output=True, text=True, cwd=root / "python/examples",
    )
    assert done.returncode == 2 and "elastic:5xx" in done.stderr, done.stderr


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# Ray's command line through this interpreter (not the venv's `ray` script,
# whose first line names the interpreter by an absolute path).
RAY = [sys.executable, "-m", "ray.scripts.scripts"]


def ray_cmd(*args, env):
    return subprocess.run([*RAY, *args], check=True, capture_output=True, text=True, env=env, timeout=180)


def test_rllib_ppo_trains_on_a_two_node_ray_cluster(root, tmp_path):
    pytest.importorskip("ray.rllib")
    port = free_port()
    address = f"127.0.0.1:{port}"
    env = dict(os.environ, RAY_USAGE_STATS_ENABLED="0")
    common = ["--disable-usage-stats", "--object-store-memory", str(150 * 1024 * 1024)]
    ray_cmd(
        "start", "--head", "--node-ip-address", "127.0.0.1", "--port", str(port),
        "--num-cpus", "1", "--include-dashboard", "false", *common, env=env,
    )
    try:
        ray_cmd(
            "start", "--address", address, "--node-ip-address", "127.0.0.1",
            "--num-cpus", "1", "--resources", json.dumps({"quadwalk_runner": 1}), *common, env=env,
        )
        out = subprocess.run(
            [sys.executable, str(root / "python/examples/rllib_ppo.py"), "--address", address,
             "--terrain", "rigid", "--env-runners", "1", "--runner-resource", "quadwalk_runner",
             "--iterations", "1", "--train-batch", "64", "--minibatch", "32", "--epochs", "1",
             "--max-phases", "8", "--json", "--out", str(tmp_path / "rllib")],
            check=True, capture_output=True, text=True, env=env, timeout=600,
        )
        lines = [json.loads(l) for l in out.stdout.splitlines() if l.startswith("{")]
        assert len(lines) == 1, out.stdout + out.stderr
        result = lines[0]
        assert result["iteration"] == 1 and result["phases_sampled"] >= 64, result
        # the env runner ran on the worker node, not on the head
        assert len(result["env_runner_nodes"]) == 1 and result["head_node"], result
        assert result["env_runner_nodes"][0] != result["head_node"], result
        assert (tmp_path / "rllib").is_dir()
    finally:
        subprocess.run([*RAY, "stop", "--force"], capture_output=True, env=env, timeout=120)

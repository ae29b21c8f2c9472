"""quadwalk's Python package: Gymnasium's checks, bit-identity with the Rust
command line, the vector env, errors, the GIL, and checkpoints."""

import json
import subprocess
import sys
import threading
import time

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import quadwalk


def test_check_env_passes():
    env = quadwalk.make_env("rigid", seed=1, max_phases=5)
    check_env(env, skip_render_check=True)
    assert env.observation_space.shape == (102,)
    assert env.observation_space.dtype == np.float32
    assert env.action_space.shape == (27,)
    assert (env.action_space.low == -1).all() and (env.action_space.high == 1).all()


def test_registered_ids_make_the_named_terrains():
    assert gym.make("quadwalk/Elastic5cm-v0").unwrapped.spec_terrain == "elastic:5cm"
    assert gym.make("quadwalk/Tv2-v0").unwrapped.spec_terrain == "varying:2m:2cm,3cm,4cm,5cm,rigid"
    env = gym.make("quadwalk/Terrain-v0", terrain="soil:4cm", max_phases=3)
    assert env.unwrapped.spec_terrain == "soil:4cm"


def test_info_and_truncation():
    env = quadwalk.make_env("rigid", seed=2, max_phases=3)
    obs, _ = env.reset(seed=2)
    zero = np.zeros(27, np.float32)
    for phase in range(1, 4):
        obs, reward, terminated, truncated, info = env.step(zero)
        assert set(info["reward_terms"]) == set(quadwalk.REWARD_TERMS)
        if terminated:
            assert info["termination"] in ("base_too_low", "pitch_too_large", "non_foot_contact")
            return
        assert info["termination"] is None
        assert info["region"] == "rigid"
        assert info["phase"] == phase
        assert truncated == (phase == 3)
        assert abs(reward - sum(info["reward_terms"].values())) < 1e-9
    with pytest.raises(RuntimeError, match="reset"):
        env.step(zero)


def _episode(env, seed, actions):
    obs, _ = env.reset(seed=seed)
    trace = [obs.copy()]
    for action in actions:
        obs, reward, terminated, truncated, info = env.step(action)
        trace.append((obs.copy(), reward, terminated, truncated, info["termination"]))
        if terminated or truncated:
            break
    return trace


def _same(a, b):
    assert len(a) == len(b)
    np.testing.assert_array_equal(a[0], b[0])
    for x, y in zip(a[1:], b[1:]):
        np.testing.assert_array_equal(x[0], y[0])
        assert x[1:] == y[1:]


def test_reset_with_a_seed_repeats_the_episode_bit_for_bit():
    rng = np.random.default_rng(7)
    actions = rng.uniform(-0.3, 0.3, (6, 27)).astype(np.float32)
    env = quadwalk.make_env("varying:2m:2,5cm,rigid", seed=11, max_phases=6)
    first = _episode(env, 11, actions)
    _episode(env, 12, actions)  # another world in between
    _same(first, _episode(env, 11, actions))
    _same(first, _episode(quadwalk.make_env("varying:2m:2,5cm,rigid", max_phases=6), 11, actions))


def test_vector_env_equals_single_envs():
    n, seed, steps = 3, 20, 5
    rng = np.random.default_rng(3)
    actions = rng.uniform(-0.4, 0.4, (steps, n, 27)).astype(np.float32)
    venv = quadwalk.make_vec_env(n, "elastic:5cm", seed=seed, max_phases=4, threads=2)
    obs, _ = venv.reset(seed=seed)
    singles = [quadwalk.make_env("elastic:5cm", seed=seed + i, max_phases=4) for i in range(n)]
    single_obs = [env.reset(seed=seed + i)[0] for i, env in enumerate(singles)]
    np.testing.assert_array_equal(obs, np.stack(single_obs))
    done = [False] * n
    for t in range(steps):
        obs, rewards, terminated, truncated, infos = venv.step(actions[t])
        for i, env in enumerate(singles):
            if done[i]:  # next-step autoreset
                expected = env.reset()[0]
                assert infos["autoreset"][i] and rewards[i] == 0.0
                done[i] = False
            else:
                expected, r, term, trunc, info = env.step(actions[t, i])
                assert rewards[i] == r and terminated[i] == term and truncated[i] == trunc
                np.testing.assert_array_equal(infos["reward_terms"][i], [info["reward_terms"][k] for k in quadwalk.REWARD_TERMS])
                done[i] = term or trunc
            np.testing.assert_array_equal(obs[i], expected)


def test_same_step_autoreset_returns_the_final_observation():
    n, seed, steps = 2, 30, 6
    rng = np.random.default_rng(4)
    actions = rng.uniform(-0.4, 0.4, (steps, n, 27)).astype(np.float32)
    venv = quadwalk.make_vec_env(n, "rigid", seed=seed, max_phases=2, threads=2, autoreset_mode="same_step")
    assert venv.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP
    obs, _ = venv.reset(seed=seed)
    singles = [quadwalk.make_env("rigid", seed=seed + i, max_phases=2) for i in range(n)]
    for i, env in enumerate(singles):
        env.reset(seed=seed + i)
    ended = 0
    for t in range(steps):
        obs, rewards, terminated, truncated, infos = venv.step(actions[t])
        for i, env in enumerate(singles):
            expected, r, term, trunc, _ = env.step(actions[t, i])
            assert rewards[i] == r and terminated[i] == term and truncated[i] == trunc
            assert infos["_final_obs"][i] == (term or trunc)
            if term or trunc:  # the step returns the next episode's first observation
                ended += 1
                np.testing.assert_array_equal(infos["final_obs"][i], expected)
                expected = env.reset()[0]
            np.testing.assert_array_equal(obs[i], expected)
    assert ended >= n * (steps // 2 - 1)
    with pytest.raises(ValueError, match="autoreset"):
        quadwalk.make_vec_env(1, "rigid", autoreset_mode="sometimes")


def test_bad_specs_configs_and_actions_raise_value_error(tmp_path):
    with pytest.raises(ValueError, match="elastic:99cm"):
        quadwalk.make_env("elastic:99cm")
    with pytest.raises(ValueError, match="sand"):
        quadwalk.make_env("sand:5cm")
    missing = tmp_path / "missing.toml"
    with pytest.raises(ValueError, match="missing.toml"):
        quadwalk.make_env(config=missing)
    bad = tmp_path / "bad.toml"
    bad.write_text("[task]\nmax_phases = -3\n")
    with pytest.raises(ValueError, match="bad.toml"):
        quadwalk.make_env(config=bad)
    lower = tmp_path / "lower.toml"
    lower.write_text('[terrain]\nspec = "rigid"\n[residual]\nphase_policy = "scripted"\n')
    with pytest.raises(ValueError, match=r"lower.toml \[residual\]: the Python environment steps whole phases"):
        quadwalk.make_env(config=lower)
    env = quadwalk.make_env("rigid")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="26 values"):
        env.step(np.zeros(26, np.float32))
    venv = quadwalk.make_vec_env(2, "rigid")
    venv.reset(seed=0)
    with pytest.raises(ValueError, match=r"\[2, 27\]"):
        venv.step(np.zeros((3, 27), np.float32))
    with pytest.raises(ValueError, match="num_envs 0"):
        quadwalk.make_vec_env(0, "rigid")


def test_a_step_releases_the_gil():
    venv = quadwalk.make_vec_env(8, "elastic:5cm", seed=0, threads=1)
    venv.reset(seed=0)
    ticks = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.0005)

    worker = threading.Thread(target=count)
    worker.start()
    try:
        during = []
        for _ in range(3):
            before = ticks[0]
            venv.step(np.zeros((8, 27), np.float32))  # 8 phases on one thread: ~0.2 s
            during.append(ticks[0] - before)
    finally:
        stop.set()
        worker.join()
    # with the GIL held through the step the other thread could not run
    assert max(during) >= 5, during


def test_terrains_lists_the_plugins():
    names = {t["name"]: t for t in quadwalk.terrains()}
    assert {"rigid", "elastic", "varying", "soil", "slope", "steps", "rough"} <= set(names)
    depth = next(p for p in names["elastic"]["params"] if p["name"] == "depth")
    assert depth["default"] is None and "sink" in depth["doc"]


def test_policy_load_runs_the_checkpoint_as_the_command_line_does(root, quadwalk_bin, tmp_path):
    policy_dir = root / "policies" / "rigid"
    if not policy_dir.is_dir():
        pytest.skip(f"{policy_dir} is absent")
    policy = quadwalk.Policy.load(str(policy_dir))
    seed, phases = 1_000_003, 30
    out = tmp_path / "eval"
    subprocess.run(
        [quadwalk_bin, "eval", "--policy", str(policy_dir), "--config", policy.config_path,
         "--episodes", "1", "--phases", str(phases), "--seed", str(seed), "--threads", "1",
         "--json", "--out", str(out)],
        check=True, capture_output=True,
    )
    reference = json.loads((out / "eval.json").read_text())["episodes"][0]
    env = quadwalk.make_env(config=policy.config_path, seed=seed, max_phases=phases)
    obs, _ = env.reset(seed=seed)
    assert env.start_xy_m == tuple(reference["start_xy_m"])
    total, log, x = 0.0, [], env.base_position_m[0]
    for _ in range(phases):
        obs, reward, terminated, truncated, info = env.step(policy.act(obs))
        total += reward
        # eval's per-phase distance: the base's move along x in the phase
        log.append((info["mean_base_height_m"], env.base_position_m[0] - x))
        x = env.base_position_m[0]
        if terminated or truncated:
            break
    assert len(log) == reference["phases"]
    assert total == reference["reward_total"]
    for (height, distance), phase in zip(log, reference["phase_log"]):
        assert height == phase["mean_base_height_m"]
        assert distance == phase["distance_m"]
    assert (reference["fall"] is None) == (not terminated)
    # a batch gives each row's action
    batch = np.stack([obs, obs * 0.5])
    np.testing.assert_array_equal(policy.act_batch(batch)[1], policy.act(batch[1]))
    with pytest.raises(ValueError, match="101 values"):
        policy.act(np.zeros(101, np.float32))
    with pytest.raises(ValueError, match="no-such-dir"):
        quadwalk.Policy.load("no-such-dir")


def test_the_evaluation_example_runs(root):
    policy_dir = root / "policies" / "rigid"
    if not policy_dir.is_dir():
        pytest.skip(f"{policy_dir} is absent")
    out = subprocess.run(
        [sys.executable, str(root / "python/examples/evaluate_checkpoint.py"), str(policy_dir),
         "--episodes", "2", "--phases", "20"],
        check=True, capture_output=True, text=True,
    ).stdout
    assert "seed 1000000:" in out and "seed 1000001:" in out, out
    assert "episodes without a fall" in out, out

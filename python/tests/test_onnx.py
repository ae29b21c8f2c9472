"""The shipped policies as ONNX graphs (`quadwalk onnx`): onnxruntime gives
the actions quadwalk gives, on 1,000 observations recorded from the shipped
policies' own episodes (the same number from each in turn, the last one's
share cut to reach 1,000) and on values far outside them."""

import subprocess

import numpy as np
import pytest

import quadwalk

onnx = pytest.importorskip("onnx", reason="the ONNX tests need onnx (pytest_suite.rs installs it)")
ort = pytest.importorskip("onnxruntime", reason="the ONNX tests need onnxruntime (pytest_suite.rs installs it)")

SHIPPED = [
    "rigid",
    "elastic-5cm-margin",
    "elastic-5cm",
    "elastic-5cm-line",
    "tv2",
    "tv2-levels",
    "tv8",
    "tc2",
    "tc5",
]


def own_observations(policy, worlds: int = 10, phases: int = 17, seed: int = 2_000_000):
    """`worlds x phases` observations of the policy acting on its own
    experiment's terrain (episodes restart as they end)."""
    venv = quadwalk.make_vec_env(worlds, config=policy.config_path, seed=seed, threads=2)
    obs, _ = venv.reset(seed=seed)
    rows = []
    for _ in range(phases):
        rows.append(obs)
        obs, *_ = venv.step(policy.act_batch(obs))
    return np.concatenate(rows)


@pytest.fixture(scope="module")
def recorded(root):
    """1,000 observations: 10 worlds x ceil(100 / policies) phases of each
    shipped policy's episodes, the first 1,000 kept."""
    phases = -(-100 // len(SHIPPED))
    rows = [
        own_observations(quadwalk.Policy.load(str(root / "policies" / n)), phases=phases)
        for n in SHIPPED
    ]
    return np.concatenate(rows)[:1000]


@pytest.mark.parametrize("name", SHIPPED)
def test_the_shipped_onnx_graph_acts_as_quadwalk(root, quadwalk_bin, tmp_path, recorded, name):
    policy_dir = root / "policies" / name
    shipped = policy_dir / "policy.onnx"
    # the shipped file is what `quadwalk onnx` writes from the policy today
    fresh = tmp_path / "fresh.onnx"
    subprocess.run(
        [quadwalk_bin, "onnx", "--policy", str(policy_dir), "--out", str(fresh)],
        check=True, capture_output=True,
    )
    assert fresh.read_bytes() == shipped.read_bytes(), f"regenerate {shipped} with `quadwalk onnx`"
    model = onnx.load(str(shipped))
    onnx.checker.check_model(model, full_check=True)
    assert {p.key: p.value for p in model.metadata_props}["quadwalk.algo"] == "ppo"

    policy = quadwalk.Policy.load(str(policy_dir))
    session = ort.InferenceSession(str(shipped), providers=["CPUExecutionProvider"])
    obs = recorded
    assert obs.shape == (1000, 102)
    got = session.run(["action"], {"observation": obs})[0]
    expected = policy.act_batch(obs)
    assert np.abs(got - expected).max() < 1e-5
    assert np.abs(expected).max() > 0.5, "the policy acts, not only near zero"
    # far outside the data: the normaliser's clip and the action bound
    wild = np.random.default_rng(0).normal(scale=50.0, size=(64, 102)).astype(np.float32)
    np.testing.assert_allclose(
        session.run(["action"], {"observation": wild})[0], policy.act_batch(wild), atol=1e-5, rtol=0
    )
    assert np.abs(session.run(["action"], {"observation": wild})[0]).max() <= 1.0

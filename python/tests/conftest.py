"""Shared fixtures: the repository root and the `quadwalk` binary to compare with."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def quadwalk_bin() -> str:
    """The `quadwalk` command line: $QUADWALK_BIN, else the workspace's build."""
    candidates = [os.environ.get("QUADWALK_BIN")]
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    candidates += [str(target / p / "quadwalk") for p in ("debug", "release")]
    candidates.append(shutil.which("quadwalk"))
    for path in candidates:
        if path and pathlib.Path(path).is_file():
            return path
    pytest.skip("no quadwalk binary (set QUADWALK_BIN or run cargo build -p cli)")

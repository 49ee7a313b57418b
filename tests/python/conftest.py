"""Shared fixtures for the Python tests: the repository root and the bundled calibration."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

from wetclutch import calibration  # noqa: E402

TABLE1 = ROOT / "tools" / "calibrations" / "table1.toml"


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def cal():
    return calibration.load(TABLE1)


@pytest.fixture(scope="session")
def tcu() -> Path:
    """The TCU program (host-release build). Missing: a skip for a developer
    running pytest alone, a failure in CI, where scripts/test.sh builds it."""
    path = ROOT / "build" / "host-release" / "src" / "port" / "wc_tcu"
    if not path.is_file():
        message = f"{path} not built (cmake --preset host-release && cmake --build --preset host-release)"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    return path

"""Shared fixtures for the Python tests: the repository root and the bundled calibration."""
from __future__ import annotations

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

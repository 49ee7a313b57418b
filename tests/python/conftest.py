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



# --------------------------------------------------------------------------- how scripts/test.sh runs them
# slow: left out by `scripts/test.sh --quick` (the edit-compile-test loop); the full command runs all.
# vcan: boots a QEMU guest (or uses the host's vcan).
# With pytest-xdist (`-n 2 --dist loadscope`) each module runs on one worker, so a module's fixtures
# (a replay, the shift matrix) run once; the longest modules are handed out first (LONGEST_FIRST,
# longest first as measured on a 2-core machine), so the two workers end together. (Not --dist
# loadgroup: pytest-xdist 3.8 groups by rewriting item._nodeid, which pytest 9 no longer reads.)
SLOW_MODULES = {"test_hil_replay", "test_vcan_integration", "test_vcan_port_faults", "test_vcan_runner",
                "test_shift", "test_film_study", "test_identify", "test_replay_inproc"}
VCAN_MODULES = {"test_hil_replay", "test_vcan_integration", "test_vcan_port_faults", "test_vcan_runner"}
VCAN_TESTS = {"test_vcan_shift_equals_in_process"}
LONGEST_FIRST = ("test_hil_replay", "test_shift", "test_vcan_integration", "test_identify", "test_cli_output_faults",
                 "test_vcan_port_faults", "test_replay_inproc", "test_vcan_runner", "test_film_study", "test_lut",
                 "test_cli_bad_input", "test_bench")


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: left out by scripts/test.sh --quick")
    config.addinivalue_line("markers", "vcan: needs a vcan (natively or in a QEMU guest)")


def _module(item) -> str:
    return item.module.__name__.rsplit(".", 1)[-1]


def pytest_collection_modifyitems(config, items):
    for item in items:
        module = _module(item)
        if module in SLOW_MODULES:
            item.add_marker(pytest.mark.slow)
        if module in VCAN_MODULES or (item.originalname or item.name) in VCAN_TESTS:
            item.add_marker(pytest.mark.vcan)
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(_module(item), len(rank)))   # stable: file order otherwise

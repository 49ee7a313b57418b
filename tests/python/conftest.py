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


def built_program(build: str, rel: str) -> Path:
    """A program of a CMake preset's build (build/BUILD/REL). Missing: a skip for a developer running
    pytest alone, a failure in CI, where scripts/test.sh builds it."""
    path = ROOT / "build" / build / rel
    if not path.is_file():
        message = f"{path} not built (cmake --preset {build} && cmake --build --preset {build})"
        if os.environ.get("CI"):
            pytest.fail(message)
        pytest.skip(message)
    return path


@pytest.fixture(scope="session")
def tcu() -> Path:
    """The TCU program (host-release build)."""
    return built_program("host-release", "src/port/wc_tcu")



# --------------------------------------------------------------------------- how scripts/test.sh runs them
# slow: left out by `scripts/test.sh --quick` (the edit-compile-test loop); the full command runs all.
# vcan: runs on a vcan (natively, or in the one QEMU guest that scripts/test.sh boots for them all).
# With pytest-xdist (`-n 2 --dist loadgroup --no-loadscope-reorder`): the vcan tests are one group, run
# in turn by one worker (they would only queue for the one guest on two), handed out first; every other
# module is a group of its own (its fixtures, a replay or the shift matrix, run once), the longest first
# (LONGEST_FIRST, as measured on a 2-core machine), so the other worker's work ends with the guest's.
SLOW_MODULES = {"test_hil_replay", "test_vcan_integration", "test_vcan_port_faults", "test_vcan_runner", "test_xcp_session",
                "test_uds_session", "test_shift", "test_film_study", "test_identify", "test_replay_inproc", "test_adaptation_study",
                "test_adaptation_reference", "test_whole_shift", "test_cycle_run"}
VCAN_MODULES = {"test_vcan_integration", "test_vcan_port_faults", "test_vcan_runner",
                "test_xcp_session", "test_uds_session"}
VCAN_TESTS = {"test_vcan_whole_shift_equals_in_process"}
LONGEST_FIRST = ("vcan", "test_cycle_run", "test_adaptation_study", "test_identify", "test_adaptation_reference", "test_replay_inproc",
                 "test_film_study", "test_hil_replay", "test_whole_shift", "test_shift", "test_cli_output_faults",
                 "test_lut", "test_bench", "test_cli_bad_input")


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: left out by scripts/test.sh --quick")
    config.addinivalue_line("markers", "vcan: runs on a vcan (natively or in a QEMU guest)")


def _group(item) -> str:
    module = item.module.__name__.rsplit(".", 1)[-1]
    vcan = module in VCAN_MODULES or (item.originalname or item.name) in VCAN_TESTS
    return "vcan" if vcan else module


def pytest_itemcollected(item):
    """The marks, as each test is collected (pytest-xdist reads xdist_group in a
    pytest_collection_modifyitems that runs before this file's)."""
    if item.module.__name__.rsplit(".", 1)[-1] in SLOW_MODULES:
        item.add_marker(pytest.mark.slow)
    group = _group(item)
    if group == "vcan":
        item.add_marker(pytest.mark.vcan)
    item.add_marker(pytest.mark.xdist_group(group))


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(_group(item), len(rank)))   # stable: file order otherwise

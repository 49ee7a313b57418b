"""The TCU's output frames against the double-precision reference of its loop
(wetclutch.hil.replay.loop_reference), step by step: shared by the vcan test and
the in-process test, so both hold the firmware to the same tolerances."""
from __future__ import annotations

import numpy as np

from wetclutch.hil import replay
from wetclutch.util import canlog


def _half_step(name: str, signal: str) -> float:
    return canlog.database().get_message_by_name(name).get_signal_by_name(signal).scale / 2.0


def assert_frames_match_reference(ref: dict, frames: dict, steps: int | None = None) -> None:
    cmd, est = frames[canlog.COMMAND], frames[canlog.ESTIMATE]
    n = ref["steps"] if steps is None else steps
    assert ref["steps"] == n and len(cmd["VfsCurrent"]) == n and len(est["ModelTorque"]) == n
    # Tolerance: half a raw step of the signal (the encoder rounds to nearest)
    # plus the float32 model against the double reference (1e-4 relative:
    # LUT error 3.9e-5, inverse tolerance 0.01 N, observer float rounding; the film below).
    checks = [
        ("VfsCurrent", cmd["VfsCurrent"], ref["current_mA"], _half_step(canlog.COMMAND, "VfsCurrent")),
        ("PressureCommand", cmd["PressureCommand"], ref["pressure_command_Pa"] * 1e-3,
         _half_step(canlog.COMMAND, "PressureCommand")),
        ("EstimatedClutchTemp", est["EstimatedClutchTemp"], ref["theta_degC"],
         _half_step(canlog.ESTIMATE, "EstimatedClutchTemp")),
        ("ModelTorque", est["ModelTorque"], ref["torque_Nm"], _half_step(canlog.ESTIMATE, "ModelTorque")),
        ("MuF", est["MuF"], ref["mu_f"], _half_step(canlog.ESTIMATE, "MuF")),
        ("FilmThickness", est["FilmThickness"], ref["hbar_m"] * 1e6, _half_step(canlog.ESTIMATE, "FilmThickness")),
    ]
    # With the squeeze-film state on (DESIGN 9) the torque and the film carry its float table inverse and
    # secant step against the reference's exact eq. 9/15: 1e-3 relative (tests/c/test_clutch.c, engagement edges).
    film_rel = 1e-3 if ref.get("film_state") else 1e-4
    for name, got, want, half in checks:
        rel = film_rel if name in ("ModelTorque", "FilmThickness") else 1e-4
        excess = np.abs(got - want) - (half * 1.0001 + rel * np.abs(want))
        k = int(np.argmax(excess))
        assert excess[k] <= 0.0, f"{name}: worst at step {k}: {got[k]} vs {want[k]}"
    # The lock-up state (DESIGN 9) in both frames.
    locked = (ref["status_bits"] & replay.BIT["StatusLocked"]) != 0
    assert np.array_equal(est["LockState"] == 1, locked), "LockState differs from the reference's lock-up"
    # Every status bit as the documented policy and the model say.
    mismatch = np.flatnonzero((cmd["status"] & ~replay.BIT["StatusDeadlineMiss"]) != ref["status_bits"])
    assert mismatch.size == 0, f"status differs at steps {mismatch[:10]}"

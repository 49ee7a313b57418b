"""The 8-speed's fault matrix (issue 29 item 2; wetclutch.shift.faults8): a lost input (both speeds NaN, the
loop's safe state) in each phase of each of the four shift types, on the 8-speed plant with the firmware's
transmission in process, against the fallback wc_shift.h and wc_transmission.h document."""
import pytest

from wetclutch.shift import faults8
from wetclutch.shift import transmission8 as t8


@pytest.mark.parametrize("oil_degC", [20.0, 80.0])
def test_every_type_falls_back_as_documented(oil_degC):
    rows = faults8.run_faults("nominal", oil_degC)
    assert len(rows) == 16                         # 4 types x 4 faults (faults8.FAMILY_FAULTS)
    assert {r["type"] for r in rows} == set(t8.LIMITS_JERK)
    missed = [r for r in rows if not r["ok"]]
    assert not missed, missed
    # every documented fallback is exercised: handed back before the gear is the on-coming element's, finished on
    # the model after it, released (then the gear held at the maximum) when the loss outlasts fallback_time_s
    assert {r["fallback"] for r in rows} == {"handed back", "finished on the model", "released"}
    for r in rows:
        src, tgt = r["shift"].split("->")
        assert r["end_gear"] == (src if r["fallback"] == "handed back" else tgt), r


def test_a_wrong_fallback_is_a_missed_row(monkeypatch):
    """The row checks what the shift did: told to expect a finish where the shift hands back, it misses."""
    monkeypatch.setattr(faults8, "expected", lambda kind, fault, source, target: (faults8.FINISH, str(target)))
    row = faults8.run_row("nominal", 3, 4, "power-on upshift", 1.0, "torque", 80.0)
    assert row["fallback"] == "handed back" and row["end_gear"] == "3"
    assert not row["ok"]


def test_a_phase_the_shift_never_reaches_is_a_missed_row(monkeypatch):
    """A fault in a phase the shift does not go through (a tip-out's hand-over is its torque phase; it has no
    lock-up phase) injects nothing, and the row says so instead of passing."""
    monkeypatch.setitem(faults8.FAULTS, "lockup", ("lock-up", 0.0, 0.05))
    row = faults8.run_row("nominal", 3, 4, "power-off upshift", 1.0, "lockup", 80.0)
    assert row["phases_while_lost"] is None and not row["ok"]

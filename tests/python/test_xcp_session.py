"""A calibration engineer's XCP session against wc_tcu on vcan (DESIGN 13, issue 21), with a master nobody
here wrote: pyxcp over python-can (in the QEMU guest where the host kernel has no CAN), the addresses from
the A2L as pya2ldb reads it. wc_tcu runs on a calibration image; canplayer plays a locked clutch holding
100 Nm; candump captures ClutchSensors, VfsCommand and the XCP frames. hil/xcp_guest.sh runs it,
hil/xcp_master.py is the master's side, tools/wetclutch/hil/xcp_session.py the host's."""
from __future__ import annotations

import json
import re
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest

from vcan_support import needs_vcan
from wetclutch.calibration import cal_image, image_layout
from wetclutch.generate import a2l
from wetclutch.hil import xcp_session
from wetclutch.util import canlog

pytestmark = [pytest.mark.slow, needs_vcan]
ROOT = Path(__file__).resolve().parents[2]
STEPS = 4000             # the input log's periods (a multiple of 16: the alive counters run on across loops)
TORQUE_NM, OIL_DEGC = 100.0, 60.0
XCP_COMMAND, XCP_RESPONSE = 0x7F0, 0x7F1


def _enum_code(header: str, name: str) -> int:
    """The value of an enumerator of a C enum that counts from 0 without gaps (wc_cal_error_t)."""
    text = (ROOT / header).read_text()
    body = text[:text.index(name)]
    body = body[body.rindex("typedef enum"):]
    return len(re.findall(r"^\s+WC_\w+", body, flags=re.M))


@pytest.fixture(scope="module")
def session(tmp_path_factory, tcu):
    work = tmp_path_factory.mktemp("xcp")
    cal_image.write_file(work / "cal.img", cal_image.build(ROOT / "tools" / "calibrations" / "table1.toml"))
    a2l_path = a2l.write_a2l(a2l.read_layout(tcu=tcu), work / "wetclutch.a2l")
    xcp_session.write_plan(a2l_path, work / "cal.img", work / "plan.json")
    t = np.arange(STEPS) * 1e-3
    canlog.write_log(work / "input.log", canlog.input_log(t, np.zeros(STEPS), np.full(STEPS, OIL_DEGC),
                                                          np.full(STEPS, OIL_DEGC - 5.0), np.full(STEPS, TORQUE_NM)))
    code = xcp_session.run_on_vcan(work, tcu)
    result = json.loads((work / "result.json").read_text()) if (work / "result.json").is_file() else {}
    assert code == 0, f"the XCP session failed: {result.get('failed')}; see {work}/session.txt, tcu.txt"
    return work, result, canlog.read_log(work / "capture.log")


def _currents(messages) -> list[tuple[int, float]]:
    """(index in the capture, VfsCommand current in mA) of every VfsCommand."""
    spec = canlog.database().get_message_by_name("VfsCommand")
    return [(i, float(spec.decode(bytes(m.data))["VfsCurrent"])) for i, m in enumerate(messages)
            if m.arbitration_id == spec.frame_id]


def _download_index(messages, value: float) -> int:
    """Index of the response to the DOWNLOAD of a 4-byte float value (the page is checked in that step)."""
    data = bytes([0xF0, 4]) + struct.pack("<f", value)
    for i, m in enumerate(messages):
        if m.arbitration_id == XCP_COMMAND and bytes(m.data[:6]) == data:
            for j in range(i + 1, len(messages)):
                if messages[j].arbitration_id == XCP_RESPONSE:
                    return j
    raise AssertionError(f"no DOWNLOAD of {value} in the capture")


def _force_N(current_mA: float) -> float:
    """Apply force of a steady VFS current (DESIGN 2): F = K i A_p - F_s, Table 1."""
    return 2300.0 * current_mA * 0.004981 - 593.3


def test_connect_identity_and_checksum(session):
    work, r, _ = session
    assert r["connect"]["max_cto"] == 8 and r["connect"]["max_dto"] == 8
    assert r["connect"]["cal_pag"] and r["connect"]["daq"]
    assert r["identity"] == "wetclutch TCU" and r["a2l_name"] == "wetclutch"
    payload = (work / "cal.img").read_bytes()[16:16 + image_layout.payload_bytes()]
    assert r["checksum"] == zlib.crc32(payload)


def test_every_characteristic_reads_back_the_image(session):
    _, r, _ = session
    assert r["characteristics_read"] == len(image_layout.FIELDS)
    assert r["characteristic_mismatches"] == []
    assert r["holding_margin_read"] == pytest.approx(0.2, rel=1e-7)   # table1's margin (float32)


def test_new_holding_margin_in_the_next_vfs_command(session):
    """The page is accepted in the step that answers the DOWNLOAD; the next VfsCommand holds the locked
    clutch with the new margin: F_new / F_old = (1 + 0.5) / (1 + 0.2)."""
    _, r, messages = session
    assert r["after_download"] == {"page_result": 0, "accepted": 1, "margin": 0.5}
    k = _download_index(messages, 0.5)
    currents = _currents(messages)
    before = [c for i, c in currents if i < k][-1]
    after = [c for i, c in currents if i > k][0]
    # VfsCurrent's resolution is 0.1 mA (DBC): 0.05 mA in ~230 N of force per mA is about 1e-3 relative
    assert _force_N(after) / _force_N(before) == pytest.approx(1.5 / 1.2, rel=2e-3)


def test_invalid_margin_refused_and_control_unaffected(session):
    _, r, messages = session
    holding_margin = _enum_code("include/wetclutch/wc_calibration.h", "WC_CAL_HOLDING_MARGIN")
    assert r["after_invalid"]["page_result"] == 7      # WC_CAL_IMAGE_BAD_CLUTCH (wc_cal_image.h)
    assert r["after_invalid"]["page_error"] == holding_margin
    assert r["after_invalid"]["margin_in_page"] == 5.0    # the page holds it, the loop does not use it
    assert r["after_restore"]["page_result"] == 0
    k_bad = _download_index(messages, 5.0)
    k_restore = k_bad + _download_index(messages[k_bad:], 0.5)
    events = [bytes(m.data[:5]) for m in messages[k_bad:k_restore] if m.arbitration_id == XCP_RESPONSE
              and m.data[0] == 0xFD]
    assert events == [bytes([0xFD, 0xFE, 7, holding_margin, 0])]   # EV_USER: BAD_CLUTCH, the field
    currents = _currents(messages)
    held = [c for i, c in currents if i < k_bad][-1]
    window = [c for i, c in currents if k_bad < i < k_restore]
    assert window and all(c == held for c in window), "the refused page changed the command"


def test_daq_8_signals_1ms_no_loss(session):
    _, r, _ = session
    daq = r["daq"]
    assert len(daq["signals"]) >= 8
    assert daq["samples"] >= 5000, daq        # 5 s at the 1 ms control step
    assert daq["gaps"] == 0 and daq["lost"] == 0, daq
    currents = daq["current_mA"]
    assert currents and all(c == pytest.approx(currents[0], abs=1e-3) for c in currents), \
        "the DAQ's current_mA is the locked clutch's steady command"


def test_no_late_vfs_command(session):
    """Frame clock: every ClutchSensors frame has its VfsCommand before the next one, DAQ or not."""
    work, r, messages = session
    stats = json.loads((work / "stats.json").read_text())
    sensors = [i for i, m in enumerate(messages) if m.arbitration_id == 0x110]
    vfs = set(i for i, m in enumerate(messages) if m.arbitration_id == 0x120)
    late = sum(1 for a, b in zip(sensors, sensors[1:]) if not any(i in vfs for i in range(a + 1, b)))
    assert stats["rx_dropped_by_kernel"] == 0
    assert late == 0, f"{late} ClutchSensors frames without their VfsCommand before the next one"


def test_error_packets_for_bad_commands(session):
    _, r, _ = session
    assert r["errors"] == {"short_upload_outside": 0x24, "short_upload_straddling": 0x24,
                           "download_measurement": 0x23, "upload_too_long": 0x22, "checksum_too_long": 0x22,
                           "copy_to_reference": 0x23, "cal_page_invalid": 0x26}
    raw = r["raw"]
    assert raw["before_connect"] == [] and raw["empty"] == [] and raw["remote_frame"] == []
    assert raw["connect"][0].startswith("ff05")
    assert raw["unknown_command"] == ["fe20000000000000"]
    assert raw["short_set_mta"] == ["fe21000000000000"] and raw["download_dlc_short"] == ["fe21000000000000"]
    assert raw["upload_zero"] == ["fe22000000000000"] and raw["daq_ptr_unallocated"] == ["fe22000000000000"]
    assert raw["write_daq_without_ptr"] == ["fe29000000000000"]
    assert raw["synch"] == ["fe00000000000000"] and raw["disconnect"] == ["ff00000000000000"]


def test_daq_overload_is_reported_not_felt(session):
    _, r, messages = session
    assert r["overload"]["overloads"] > 0
    assert any(m.arbitration_id == XCP_RESPONSE and bytes(m.data[:2]) == b"\xfd\x06" for m in messages)
    # control went on: no safe state after the start-up's recovery (20 periods) in the whole session
    assert r["counters"]["loop_safe_steps"] <= 40, r["counters"]

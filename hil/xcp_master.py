#!/usr/bin/env python3
"""The XCP master's side of a calibration session against ``wc_tcu --xcp`` (DESIGN 13), run where the
SocketCAN interface is (natively, or inside the QEMU guest of hil/vcan_run.sh) by hil/xcp_guest.sh:

    python hil/xcp_master.py --plan PLAN.json --out RESULT.json --secret-file SECRET [--iface vcan0]
                             [--daq-samples 5000]

The master is pyxcp over python-can, nobody's code here. PLAN.json is written on the host by
tools/wetclutch/hil/xcp_session.py: the A2L's addresses as pya2ldb reads them and the bytes the calibration
image holds at each characteristic. This script imports nothing else (no wetclutch, no A2L parser): on an
emulated CPU every import costs seconds. It records what it saw in RESULT.json (as far as it got, if a step
fails); tests/python/test_xcp_session.py checks it with the bus capture. The session: connect, a DOWNLOAD
refused while CAL/PAG is locked (ERR_ACCESS_LOCKED), the unlock by pyxcp's seed & key (cond_unlock with a
seed_n_key_function: the key is HMAC-SHA256(device secret, seed), its first bytes), identity, checksum of
the calibration page, every characteristic read back at its A2L address, a new holding margin
downloaded, an invalid one refused, DAQ of 8 signals at the control step's 1 ms event, error packets for
out-of-region and malformed commands, a DAQ overload, disconnect, and raw frames no master would send.
Every wait is on the TCU's steps (its loop_steps counter, its VfsCommand frames) or on a sample count, never
on the clock: the inputs come in lockstep with the TCU (hil/xcp_guest.sh), so a slower guest makes the
session slower, never different (DESIGN 5)."""
from __future__ import annotations

import argparse
import hashlib
import hmac
import json
import os
import struct
import sys
import time

_STARTED = time.monotonic()   # the phases' clock (_lap) starts before the heavy imports
from pathlib import Path

# python-can's MF4 writer imports asammdf, pyxcp's recorder pandas when they are installed (the project's
# tools use both): neither is used here, and on the emulated CPU they cost a minute of imports.
sys.modules.setdefault("asammdf", None)
sys.modules.setdefault("pandas", None)

import can  # noqa: E402

XCP_COMMAND_ID, XCP_RESPONSE_ID, VFS_COMMAND_ID = 0x7F0, 0x7F1, 0x120   # hil/wetclutch.dbc
DAQ_WINDOW_STEPS = 200  # flow control: the inputs may run this many steps ahead of the last decoded DAQ sample
SETTLE_STEPS = 400      # the new margin is downloaded once the TCU has stepped this far (frame clock: the same step on
                        # any guest): the clutch locked (StatusLocked from period 197 of test_xcp_session's input.log,
                        # in-process; the margin is the locked clutch's holding force) and its current steady (from
                        # period 19), so the old current is the held one and the new one the margin's
WAIT_LIMIT_S = 600.0    # no progress for this long (no step, no DAQ sample): the TCU stopped (a failure, said so);
                        # a limit on progress, not on the whole wait, so a slow guest only takes longer
DAQ_SIGNALS = ("current_mA", "pressure_model_Pa", "force_command_N", "contact_force_N", "theta_degC",
               "model_torque_Nm", "slip_rad_s", "torque_request_Nm")


def _master(iface: str, seed_n_key):
    from pyxcp.config import create_application_from_config, set_application
    from pyxcp.master import Master
    app = create_application_from_config({
        "Transport": {"CAN": {"interface": "socketcan", "channel": iface, "can_id_master": XCP_COMMAND_ID,
                              "can_id_slave": XCP_RESPONSE_ID, "max_dlc_required": False}},
        "General": {"disable_error_handling": True, "seed_n_key_function": seed_n_key}}, log_level=30)
    app.transport.timeout = 30.0   # an emulated CPU decoding 8 DAQ frames a millisecond sees answers late
    set_application(app)   # pyxcp's DAQ processor asks for the application (else it parses sys.argv)
    return Master("can", config=app)


class _Samples:
    """DAQ samples as pyxcp decodes them: (slave timestamp, values) per sample."""

    def __init__(self):
        from pyxcp.daq_stim import DaqOnlinePolicy

        outer = self

        class Policy(DaqOnlinePolicy):
            def initialize(self):
                pass

            def finalize(self):
                pass

            def on_daq_list(self, daq_list, timestamp0, timestamp1, payload):
                outer.rows.append((int(timestamp1), [float(v) for v in payload]))

        self.rows: list = []
        self.policy_class = Policy


def _u32(xcp, address: int) -> int:
    return struct.unpack("<I", bytes(xcp.shortUpload(4, address)))[0]


def _f32(xcp, address: int) -> float:
    return struct.unpack("<f", bytes(xcp.shortUpload(4, address)))[0]


class _Inputs:
    """The player's flow control (wc_canplay --limit-fifo; hil/xcp_guest.sh holds it at --settle-steps from
    the start): the inputs are let through as far as the session needs steps and held between (XCP commands
    are answered without steps), so the guest's CPU goes to the master, not to steps nothing waits for. A
    limit is a step count mod 65536; without a FIFO (no flow control) every call does nothing."""

    def __init__(self, limit_fifo: str | None):
        # opened once: blocks until the player has it open
        self.fd = os.open(limit_fifo, os.O_WRONLY) if limit_fifo else None

    def hold_at(self, step: int | None) -> None:
        """The last step the inputs may reach, None: no limit."""
        if self.fd is not None:
            os.write(self.fd, b"none\n" if step is None else f"{step & 0xFFFF}\n".encode())

    def close(self) -> None:
        if self.fd is not None:
            os.close(self.fd)
            self.fd = None


def _wait_steps(xcp, meas: dict, steps: int, inputs: _Inputs, until: int | None = None) -> None:
    """Until the TCU's loop_steps counter has advanced by steps (each upload is answered between two steps),
    or with until, has reached until (a step count since the start) if that is later; the inputs are let
    through that far and held there."""
    address = meas["loop_steps"][0]
    start, end = _u32(xcp, address), time.monotonic() + WAIT_LIMIT_S
    if until is not None:
        steps = max(steps, until - start)
    inputs.hold_at(start + steps)
    last = start
    while ((now := _u32(xcp, address)) - start) % (1 << 32) < steps:
        if now != last:   # progress: the limit starts again
            last, end = now, time.monotonic() + WAIT_LIMIT_S
        if time.monotonic() > end:
            raise TimeoutError(f"the TCU made no step in {WAIT_LIMIT_S} s ({(now - start) % (1 << 32)} of {steps}):"
                               " are its inputs played?")


def _error_code(call) -> int | None:
    """The XCP error code a command is answered with, None when it succeeds."""
    from pyxcp.types import XcpResponseError
    try:
        call()
    except XcpResponseError as e:
        return int(e.get_error_code())
    return None


def _raw(bus: can.BusABC, data: bytes, steps: int = 3, **kw) -> list[bytes]:
    """Send one raw frame on the XCP command id and collect the slave's answers until the TCU has sent
    steps VfsCommands after it. wc_tcu answers a command in the iteration that receives it, and the frames
    queued before it hold at most one step (the player in lockstep, on this process's CPU: --cpu): by the
    third VfsCommand every answer is on the bus. 'After it' is in the bus's order, not by a clock: from the
    command's own echo on this socket (receive_own_messages), which the kernel queues to it in the same
    delivery as to the TCU's socket, so before any answer. Kernel timestamps against time.time() missed
    answers sent 30 us after their command in the emulated guest."""
    command = can.Message(arbitration_id=XCP_COMMAND_ID, data=data, is_extended_id=False, **kw)
    bus.send(command)
    got, seen, echoed, end = [], 0, False, time.monotonic() + WAIT_LIMIT_S
    while seen < steps:
        m = bus.recv(1.0)
        if time.monotonic() > end:
            raise TimeoutError(f"the TCU sent fewer than {steps} VfsCommands in {WAIT_LIMIT_S} s after the command")
        if m is None or m.is_extended_id:
            continue
        if not echoed:   # what was queued before the command's echo is not its answer
            echoed = (m.arbitration_id == XCP_COMMAND_ID and m.is_remote_frame == command.is_remote_frame
                      and bytes(m.data) == data)
            continue
        if m.arbitration_id == XCP_RESPONSE_ID:
            got.append(bytes(m.data))
        elif m.arbitration_id == VFS_COMMAND_ID:
            seen += 1
    return got


KEY_BYTES = 6   # WC_XCP_KEY_MAX_BYTES: the key in one UNLOCK frame


def _seed_and_key(secret: bytes, seeds: list):
    """pyxcp's seed_n_key_function (a plain function: pyxcp logs its __name__): the key of a seed is the
    first KEY_BYTES bytes of HMAC-SHA256(device secret, seed), as wc_tcu computes it (OpenSSL there,
    Python's hmac here); each (resource, seed) seen is appended to seeds."""
    def hmac_key(resource: int, seed: bytes) -> bytes:
        seeds.append((int(resource), bytes(seed).hex()))
        return hmac.new(secret, bytes(seed), hashlib.sha256).digest()[:KEY_BYTES]
    return hmac_key


def _protection(status) -> dict:
    """GET_STATUS's resource protection status: the resources still locked."""
    p = status.resourceProtectionStatus
    return {"calpag": bool(p.calpag), "daq": bool(p.daq)}


def _lap(result: dict, phase: str) -> None:
    """The wall seconds of each phase since the previous one (printed by the test, never asserted)."""
    now = time.monotonic()
    seconds = result.setdefault("seconds", {})
    seconds[phase] = round(now - result.get("_since", _STARTED), 1)
    result["_since"] = now


def run_session(plan: dict, iface: str, daq_samples: int, result: dict, limit_fifo: str | None = None,
                secret: bytes = b"", settle_steps: int = SETTLE_STEPS) -> dict:
    """Fills result as it goes (a failure leaves what was seen before it)."""
    _lap(result, "start-up")
    inputs = _Inputs(limit_fifo)
    try:
        _xcp_session(plan, iface, daq_samples, result, inputs, secret, settle_steps)
    finally:
        inputs.close()
    return result


def _xcp_session(plan: dict, iface: str, daq_samples: int, result: dict, inputs: _Inputs, secret: bytes,
                 settle_steps: int) -> None:
    chars, meas = plan["characteristics"], plan["measurements"]
    cal_base, cal_size = plan["segments"]["calibration"]
    margin_address = chars["clutch.holding_margin"][0]
    seeds: list = []
    with _master(iface, _seed_and_key(secret, seeds)) as xcp:
        t = time.monotonic()
        connect = xcp.connect()
        result["connect"] = {"max_cto": connect.maxCto, "max_dto": connect.maxDto, "seconds": time.monotonic() - t,
                             "cal_pag": bool(connect.resource.calpag), "daq": bool(connect.resource.daq)}
        status = xcp.getStatus()
        result["daq_running_at_connect"] = bool(status.sessionStatus.daqRunning)
        # seed & key: a write before the unlock refused, then pyxcp's unlock with the HMAC key
        result["protection_at_connect"] = _protection(status)
        xcp.setMta(margin_address)
        result["download_before_unlock"] = _error_code(lambda: xcp.download(struct.pack("<f", 0.5)))
        xcp.cond_unlock("calpag")
        result["unlock_seeds"] = seeds
        result["protection_after_unlock"] = _protection(xcp.getStatus())
        idents = {}
        for kind in (0, 1):
            gid = xcp.getId(kind)
            idents[kind] = bytes(xcp.pull(gid.length)).decode("ascii") if gid.length else ""
        result["identity"], result["a2l_name"] = idents[0], idents[1]
        xcp.setMta(cal_base)
        result["checksum"] = int(xcp.buildChecksum(cal_size).checksum)
        # every characteristic at its A2L address against the image (arrays: their first element)
        mismatches = []
        for name, (address, want_hex) in chars.items():
            got = bytes(xcp.shortUpload(4, address))
            want = bytes.fromhex(want_hex)
            if got != want:
                mismatches.append((name, got.hex(), want.hex()))
        result["characteristics_read"] = len(chars)
        result["characteristic_mismatches"] = mismatches
        result["holding_margin_read"] = _f32(xcp, margin_address)
        # a new holding margin: downloaded, the whole page checked, used from the next control step
        # the capture's old current: the page in use for a few steps, the current settled
        _wait_steps(xcp, meas, 20, inputs, until=settle_steps)
        xcp.setMta(margin_address)
        xcp.download(struct.pack("<f", 0.5))
        _wait_steps(xcp, meas, 20, inputs)
        result["after_download"] = {"page_result": _u32(xcp, meas["xcp_page_result"][0]),
                                    "accepted": _u32(xcp, meas["xcp_pages_accepted"][0]),
                                    "margin": _f32(xcp, margin_address)}
        # above its limit: written into the page, the page refused, the loop keeps the last good one
        xcp.setMta(margin_address)
        xcp.download(struct.pack("<f", 5.0))
        _wait_steps(xcp, meas, 20, inputs)
        result["after_invalid"] = {"page_result": _u32(xcp, meas["xcp_page_result"][0]),
                                   "page_error": _u32(xcp, meas["xcp_page_error"][0]),
                                   "rejected": _u32(xcp, meas["xcp_pages_rejected"][0]),
                                   "margin_in_page": _f32(xcp, margin_address)}
        xcp.setMta(margin_address)
        xcp.download(struct.pack("<f", 0.5))      # the page valid again (the margin in use)
        _wait_steps(xcp, meas, 20, inputs)
        result["after_restore"] = {"page_result": _u32(xcp, meas["xcp_page_result"][0]),
                                   "accepted": _u32(xcp, meas["xcp_pages_accepted"][0])}
        # DAQ of 8 signals at the control step's event (no command beside it: on an emulated CPU pyxcp's
        # Python cannot answer commands while it decodes 8 frames a millisecond)
        _lap(result, "connect, identity, calibration")
        with _Daq(xcp, meas, inputs) as daq:
            daq.run_until(daq_samples)
        result["daq"] = daq.summary()
        _lap(result, "daq")
        # malformed and out-of-region commands: error packets, nothing else
        result["errors"] = {
            "short_upload_outside": _error_code(lambda: xcp.shortUpload(4, 0x00500000)),
            "short_upload_straddling": _error_code(lambda: xcp.shortUpload(4, cal_base + cal_size - 2)),
            "download_measurement": _error_code(lambda: (xcp.setMta(meas["current_mA"][0]),
                                                         xcp.download(b"\0\0\0\0"))),
            "upload_too_long": _error_code(lambda: (xcp.setMta(cal_base), xcp.upload(8))),
            "checksum_too_long": _error_code(lambda: (xcp.setMta(cal_base), xcp.buildChecksum(1 << 20))),
            "copy_to_reference": _error_code(lambda: xcp.copyCalPage(0, 0, 0, 1)),
            "cal_page_invalid": _error_code(lambda: xcp.setCalPage(0x01, 0, 7)),
        }
        _lap(result, "error packets")
        result["overload"] = _overload(xcp, meas, inputs)
        result["counters"] = {name: _u32(xcp, meas[name][0]) for name in
                              ("xcp_errors", "xcp_ignored", "xcp_daq_overloads", "xcp_pages_accepted",
                               "xcp_pages_rejected", "loop_deadline_misses", "loop_steps", "loop_safe_steps")}
        xcp.disconnect()
    result["disconnected"] = True
    _lap(result, "overload, counters")
    inputs.hold_at(None)   # _raw counts the steps after each frame: the inputs flow again
    # frames pyxcp would never send, on a socket of our own (pyxcp's would queue their answers as its own)
    with can.Bus(interface="socketcan", channel=iface, receive_own_messages=True,   # _raw: its command's echo
                 can_filters=[{"can_id": XCP_COMMAND_ID, "can_mask": 0x7FF},
                              {"can_id": XCP_RESPONSE_ID, "can_mask": 0x7FF},
                              {"can_id": VFS_COMMAND_ID, "can_mask": 0x7FF}]) as bus:   # _raw counts the steps
        raw = {"before_connect": _raw(bus, bytes([0xFD]))}   # GET_STATUS while disconnected: no answer
        raw["connect"] = _raw(bus, bytes([0xFF, 0x00]))
        for name, data in (("unknown_command", bytes([0xC9])), ("short_set_mta", bytes([0xF6, 0, 0])),
                           ("empty", b""), ("download_dlc_short", bytes([0xF0, 4, 1, 2])),
                           ("upload_zero", bytes([0xF5, 0])), ("daq_ptr_unallocated", bytes([0xE2, 0, 9, 0, 0, 0])),
                           ("write_daq_without_ptr", bytes([0xE1, 0xFF, 4, 0, 0, 0, 0x10, 0])),
                           ("synch", bytes([0xFC])), ("disconnect", bytes([0xFE]))):
            raw[name] = _raw(bus, data)
        raw["remote_frame"] = _raw(bus, b"", is_remote_frame=True)
        result["raw"] = {k: [b.hex() for b in v] for k, v in raw.items()}
    _lap(result, "raw frames")
    result.pop("_since", None)


class _Daq:
    """One DAQ list of DAQ_SIGNALS at event 0 (the control step), set up and started
    by pyxcp's DaqProcessor; the samples (slave timestamp, values) as its policy receives them. With
    the player's flow control (_Inputs), the inputs are held DAQ_WINDOW_STEPS ahead of the last decoded
    sample: a master slower than the TCU holds the TCU's steps instead of losing frames or its answers
    queueing behind seconds of samples (DESIGN 5)."""

    def __init__(self, xcp, meas: dict, inputs: _Inputs):
        self.inputs = inputs
        from pyxcp.daq_stim import DaqList
        self.xcp, self.meas = xcp, meas
        self.names = list(DAQ_SIGNALS)
        self.daq_list = DaqList("signals", 0, False, True, [(n, meas[n][0], 0, "F32") for n in DAQ_SIGNALS])
        self.samples = _Samples()
        self.policy = self.samples.policy_class([self.daq_list])
        xcp.transport.policy = self.policy
        self.policy.xcp_master = xcp

    def _hold_at(self, step: int) -> None:
        """The last step the inputs may reach (mod 65536, the DAQ timestamp's range)."""
        self.inputs.hold_at(step)

    def __enter__(self):
        # held from here (commands are answered without steps), until DAQ runs
        self._hold_at(_u32(self.xcp, self.meas["loop_steps"][0]) + DAQ_WINDOW_STEPS)
        self.misses_before = _u32(self.xcp, self.meas["loop_deadline_misses"][0])
        self.policy.setup()
        self.policy.start()
        # the first sample comes no earlier than the step after this one: sample i is at step >= this + i + 1,
        # so a limit of this + i + 1 + window is never behind the samples the TCU has sent (no deadlock)
        self.steps_at_start = _u32(self.xcp, self.meas["loop_steps"][0])
        self.started = time.monotonic()
        return self

    def run_until(self, samples: int) -> None:
        """Until pyxcp has decoded samples samples (its receive thread appends them)."""
        end, held = time.monotonic() + WAIT_LIMIT_S, None
        while (decoded := len(self.samples.rows)) < samples:
            if time.monotonic() > end:
                raise TimeoutError(f"{decoded} DAQ samples of {samples}, none new in {WAIT_LIMIT_S} s")
            if decoded != held:   # the inputs at most DAQ_WINDOW_STEPS ahead of what is decoded
                self._hold_at(self.steps_at_start + decoded + DAQ_WINDOW_STEPS)
                held, end = decoded, time.monotonic() + WAIT_LIMIT_S   # progress: the limit starts again
            time.sleep(0.02)

    def __exit__(self, *exc):
        self.policy.stop()
        self._hold_at(_u32(self.xcp, self.meas["loop_steps"][0]))   # held: error packets and counters need no step
        self.misses = _u32(self.xcp, self.meas["loop_deadline_misses"][0]) - self.misses_before
        return False

    def summary(self) -> dict:
        rows = self.samples.rows
        # pyxcp gives the slave's timestamp in ns (ticks x GET_DAQ_RESOLUTION_INFO's unit): one tick a step
        stamps = [round(ts / 1e6) for ts, _ in rows]
        steps = [((b - a) % 65536) for a, b in zip(stamps, stamps[1:])]
        # pyxcp hands the values in its optimised ODT order, named by the list's headers
        order = [h[0] for h in self.daq_list.headers]
        current = [v[order.index("current_mA")] for _, v in rows]
        return {"signals": self.names, "samples": len(rows), "gaps": sum(1 for d in steps if d != 1),
                "lost": sum(d - 1 for d in steps), "first": stamps[:1], "last": stamps[-1:],
                "deadline_misses": self.misses,
                "currents": sorted(set(current))}


def _overload(xcp, meas: dict, inputs: _Inputs) -> dict:
    """A DAQ list of more ODTs than a step may send: it is never sampled, counted, EV_DAQ_OVERLOAD sent."""
    before = _u32(xcp, meas["xcp_daq_overloads"][0])
    odts = 16
    xcp.freeDaq()
    xcp.allocDaq(1)
    xcp.allocOdt(0, odts)
    for j in range(odts):
        xcp.allocOdtEntry(0, j, 1)
    for j in range(odts):
        xcp.setDaqPtr(0, j, 0)
        xcp.writeDaq(0xFF, 4, 0, meas["current_mA"][0])
    xcp.setDaqListMode(0x10, 0, 0, 1, 0)
    xcp.startStopDaqList(0x02, 0)
    xcp.startStopSynch(0x01)
    _wait_steps(xcp, meas, 50, inputs)
    xcp.startStopSynch(0x00)
    return {"odts": odts, "overloads": _u32(xcp, meas["xcp_daq_overloads"][0]) - before}


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--plan", required=True, help="the session's plan (tools/wetclutch/hil/xcp_session.py)")
    p.add_argument("--out", required=True)
    p.add_argument("--iface", default="vcan0")
    p.add_argument("--daq-samples", type=int, default=5000, help="DAQ samples to collect (one a control step)")
    p.add_argument("--limit-fifo", help="the input player's flow control (wc_canplay --limit-fifo)")
    p.add_argument("--secret-file", required=True, help="the device secret wc_tcu --secret-file keys XCP with")
    p.add_argument("--cpu", type=int, help="keep to this CPU, the input player's (wc_canplay --cpu): a raw command"
                                           " and the inputs then reach the TCU in the order sent (one CPU's vcan"
                                           " backlog), whichever CPU the emulator stalls")
    args = p.parse_args(argv)
    if args.cpu is not None:
        os.sched_setaffinity(0, {args.cpu})
    result: dict = {}
    try:
        run_session(json.loads(Path(args.plan).read_text()), args.iface, args.daq_samples, result, args.limit_fifo,
                    Path(args.secret_file).read_bytes())
    except Exception as e:   # the session's record says where it stopped; the test shows it
        result["failed"] = f"{type(e).__name__}: {e}"
        raise
    finally:
        Path(args.out).write_text(json.dumps(result, indent=1, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

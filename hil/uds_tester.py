#!/usr/bin/env python3
"""A service technician's tester against ``wc_tcu --uds`` (DESIGN 17), run where the SocketCAN interface is
(natively, or inside the QEMU guest of hil/vcan_run.sh) by hil/uds_guest.sh:

    python hil/uds_tester.py --secret SECRET_FILE --out RESULT.json [--iface vcan0] [--phase session|restart]

The tester is udsoncan over python-can-isotp (the pure-Python ISO-TP stack on a python-can socketcan bus),
nobody's code here. It records what it saw in RESULT.json (as far as it got, if a step fails);
tests/python/test_uds_session.py checks it with the bus capture. The session: identity and calibration
DIDs, the learned values and temperatures; ClearDiagnosticInformation and the adaptation reset refused
while locked (0x33); the extended session; SecurityAccess with a wrong key (0x35) then the right one
(HMAC-SHA256 of the seed with the device secret, Python's hmac); the adaptation reset routine; the request
timeout injected by the played log read as a DTC with its snapshot; an ECUReset (softReset): the default
session, locked, the start's security delay, a new operation cycle; unlocked again, the DTCs cleared;
three wrong keys (0x35, 0x35, 0x36), the delay (0x37), then unlocked again; the hot clutch of the played
log read as a confirmed DTC with its snapshot. The restart phase (wc_tcu started again on the fault
memory's image, fault-free inputs): that DTC still confirmed with the same snapshot, then ECUResets, each
an operation cycle without the fault, until it ages out. Every wait is on the TCU's answers, bounded by a
count of requests, never on the clock; the timeouts are generous (an emulated guest is slow): a slower
guest makes the session slower, never different (DESIGN 5)."""
from __future__ import annotations

import argparse
import hashlib
import hmac
import json
import struct
import sys
import time
import traceback

_STARTED = time.monotonic()
# python-can's MF4 writer imports asammdf, udsoncan nothing heavy; on the emulated CPU imports cost seconds
sys.modules.setdefault("asammdf", None)
sys.modules.setdefault("pandas", None)

import can  # noqa: E402
import isotp  # noqa: E402
import udsoncan  # noqa: E402
from udsoncan import exceptions  # noqa: E402
from udsoncan.client import Client  # noqa: E402
from udsoncan.connections import PythonIsoTpConnection  # noqa: E402

REQUEST_ID, FUNCTIONAL_ID, RESPONSE_ID = 0x7E1, 0x7DF, 0x7E9   # hil/wetclutch.dbc
KEY_BYTES = 16                                               # src/port/wc_tcu_diag.c
REQUEST_TIMEOUT_DTC = 0xD10187                               # U1101-87 TorqueRequest missing
OVER_TEMPERATURE_DTC = 0x170098                              # P1700-98 clutch over temperature
AGING_CYCLES = 5                                             # wc_tcu --dtc-aging-cycles, hil/uds_guest.sh
ADAPTATION_RESET = 0x0201
SNAPSHOT_DID = 0xDD00
NODES = 5                                                    # WC_ADAPT_NODES
POLLS = 20000          # a wait on the TCU: at most this many requests (each a few TCU steps)


class _Struct(udsoncan.DidCodec):
    """A DID of fixed layout (struct format, big-endian)."""

    def __init__(self, fmt: str):
        self.fmt = fmt

    def encode(self, *values):
        return struct.pack(self.fmt, *values)

    def decode(self, data):
        return list(struct.unpack(self.fmt, bytes(data)))

    def __len__(self):
        return struct.calcsize(self.fmt)


def _config(secret: bytes) -> dict:
    config = dict(udsoncan.configs.default_client_config)
    config["data_identifiers"] = {
        0xF18C: udsoncan.AsciiCodec(12), 0xF195: udsoncan.AsciiCodec(15), 0xF197: udsoncan.AsciiCodec(13),
        0xFD00: _Struct(">IH"), 0xFD01: _Struct(">3f"), 0xFD02: _Struct(f">{2 * NODES + 2}fI"),
        0xFD03: _Struct(">25I"), SNAPSHOT_DID: _Struct(">8fBB"),
    }
    config["security_algo"] = lambda level, seed, params: hmac.new(secret, bytes(seed), hashlib.sha256).digest()[:KEY_BYTES]
    config["exception_on_negative_response"] = True
    config["use_server_timing"] = False   # the server's P2 is in its steps; an emulated guest takes longer
    config["p2_timeout"] = 60.0
    config["p2_star_timeout"] = 120.0
    config["request_timeout"] = 120.0
    config["dtc_snapshot_did_size"] = 2
    return config


def _nrc(call) -> int:
    """The NRC of a request that must be refused (0: it was accepted)."""
    try:
        call()
    except exceptions.NegativeResponseException as e:
        return int(e.response.code)
    return 0


def _delay_answers(client) -> int:
    """How many requestSeed were answered requiredTimeDelayNotExpired (0x37) before the delay ended."""
    answers = 0
    for _ in range(POLLS):
        if _nrc(lambda: client.request_seed(1)) != 0x37:
            break
        answers += 1
    return answers


def _dtcs(client, mask: int) -> dict:
    response = client.get_dtc_by_status_mask(mask)
    return {d.id: d.status.get_byte_as_int() for d in response.service_data.dtcs}


def _snapshot(client, dtc: int) -> list:
    """The DTC's snapshot records (empty: none stored)."""
    records = client.get_dtc_snapshot_by_dtc_number(dtc, record_number=1).service_data.dtcs[0].snapshots
    return [{"record": s.record_number, "did": s.did, "values": list(s.data)} for s in records]


def _await_status(client, dtc: int, bits: int):
    """Polls reportDTCByStatusMask until the DTC's status has every bit of bits; its status then (or the
    last one seen)."""
    status = None
    for _ in range(POLLS):
        status = _dtcs(client, 0xFF).get(dtc)
        if status is not None and status & bits == bits:
            break
    return status


def _soft_reset(client) -> int:
    """ECUReset softReset: 0, or the NRC."""
    return _nrc(lambda: client.ecu_reset(udsoncan.services.ECUReset.ResetType.softReset))


def session(client, secret: bytes, result: dict) -> None:
    lap = time.monotonic()

    def mark(name):
        nonlocal lap
        now = time.monotonic()
        result.setdefault("seconds", {})[name] = round(now - lap, 2)
        lap = now

    read = lambda did: client.read_data_by_identifier(did).service_data.values[did]  # noqa: E731
    result["identity"] = {"serial": read(0xF18C), "software": read(0xF195), "name": read(0xF197)}
    crc, version = read(0xFD00)
    result["calibration"] = {"crc32": crc, "layout_version": version}
    result["temperatures_degC"] = read(0xFD01)
    learned = read(0xFD02)
    result["learned"] = {"friction_scale": learned[:NODES], "confidence": learned[NODES:2 * NODES],
                         "film_factor": learned[2 * NODES], "kiss_offset_Pa": learned[2 * NODES + 1],
                         "shifts_learned": learned[2 * NODES + 2]}
    mark("identity")
    # locked: the clear and the routine are refused (securityAccessDenied)
    result["locked"] = {"clear": _nrc(lambda: client.clear_dtc(0xFFFFFF)),
                        "routine": _nrc(lambda: client.start_routine(ADAPTATION_RESET)),
                        "seed_in_default_session": _nrc(lambda: client.request_seed(1))}
    client.change_session(udsoncan.services.DiagnosticSessionControl.Session.extendedDiagnosticSession)
    # the delay after start (a restart buys no attempts): requestSeed answered 0x37 until it ends
    result["delay_at_start_answers"] = _delay_answers(client)
    seed = bytes(client.request_seed(1).service_data.seed)
    result["seed_bytes"] = len(seed)
    good = hmac.new(secret, seed, hashlib.sha256).digest()[:KEY_BYTES]
    result["bad_key"] = _nrc(lambda: client.send_key(2, bytes(b ^ 0x5A for b in good)))
    seed = bytes(client.request_seed(1).service_data.seed)
    result["good_key"] = _nrc(lambda: client.send_key(2, hmac.new(secret, seed, hashlib.sha256).digest()[:KEY_BYTES]))
    result["seed_when_unlocked"] = bytes(client.request_seed(1).service_data.seed).hex()
    mark("unlock")
    result["routine_start"] = _nrc(lambda: client.start_routine(ADAPTATION_RESET))
    pending = 1
    for _ in range(POLLS):
        pending = client.get_routine_result(ADAPTATION_RESET).service_data.routine_status_record[0]
        if pending == 0:
            break
    result["routine_result"] = pending
    result["learned_after_reset"] = read(0xFD02)
    mark("routine")
    # the played log's request timeout: seen failed (testFailed), then passed again; the clear comes right
    # after that, so a whole log's loop away from the next one
    seen_failed, status = False, None
    for _ in range(POLLS):
        status = _dtcs(client, 0xFF).get(REQUEST_TIMEOUT_DTC)
        if status is not None and status & 0x01:
            seen_failed = True
        elif seen_failed and status is not None and not status & 0x01:
            break
    result["dtc_seen_failed"] = seen_failed
    result["dtc_status"] = status
    result["dtcs"] = {f"{k:06X}": v for k, v in _dtcs(client, 0xFF).items()}
    result["confirmed_count"] = client.get_number_of_dtc_by_status_mask(0x08).service_data.dtc_count
    result["snapshot"] = _snapshot(client, REQUEST_TIMEOUT_DTC)
    mark("dtc")
    # a soft reset, right after the request timeout passed (the next one is a log's loop away): answered,
    # then the loop restarts (the capture shows it) and the server as after a start: the default session,
    # locked, the start's security delay; a new operation cycle (testFailedThisOperationCycle 0)
    reset = {"answer": _soft_reset(client)}
    reset["seed_in_default_session"] = _nrc(lambda: client.request_seed(1))
    reset["clear"] = _nrc(lambda: client.clear_dtc(0xFFFFFF))
    reset["dtc_status"] = _dtcs(client, 0xFF).get(REQUEST_TIMEOUT_DTC)
    client.change_session(udsoncan.services.DiagnosticSessionControl.Session.extendedDiagnosticSession)
    reset["delay_answers"] = _delay_answers(client)
    client.unlock_security_access(1)
    result["soft_reset"] = reset
    mark("soft_reset")
    result["clear"] = _nrc(lambda: client.clear_dtc(0xFFFFFF))
    # reportDTCByStatusMask lists a DTC whose status has a bit of the mask: a status of 0 (tested and
    # passed since the clear) is not listed
    result["status_after_clear"] = _dtcs(client, 0xFF).get(REQUEST_TIMEOUT_DTC, 0)
    mark("clear")
    # three wrong keys in a new extended session: 0x35, 0x35, 0x36, then the delay
    client.change_session(udsoncan.services.DiagnosticSessionControl.Session.defaultSession)
    client.change_session(udsoncan.services.DiagnosticSessionControl.Session.extendedDiagnosticSession)
    wrong = []
    for _ in range(3):
        seed = bytes(client.request_seed(1).service_data.seed)
        wrong.append(_nrc(lambda: client.send_key(2, bytes(KEY_BYTES))))
    result["three_wrong_keys"] = wrong
    result["routine_after_wrong_keys"] = _nrc(lambda: client.start_routine(ADAPTATION_RESET))
    result["delay_answers"] = _delay_answers(client)
    client.unlock_security_access(1)   # udsoncan's own seed & key exchange with security_algo
    result["unlocked_after_delay"] = True
    mark("delay")
    # the played log's hot clutch (since the clear, in this operation cycle): confirmed, with its snapshot
    # (the restart phase finds the same)
    status = _await_status(client, OVER_TEMPERATURE_DTC, 0x08 | 0x02)
    result["over_temperature"] = {"status": status, "snapshot": _snapshot(client, OVER_TEMPERATURE_DTC)}
    mark("over_temperature")


def restart(client, result: dict) -> None:
    """After wc_tcu's restart on the fault memory's image: the hot clutch's DTC as it was stored, then
    soft resets (each an operation cycle without the fault: fault-free inputs) until it ages out."""
    result["dtcs"] = {f"{k:06X}": v for k, v in _dtcs(client, 0xFF).items()}
    result["snapshot"] = _snapshot(client, OVER_TEMPERATURE_DTC)
    cycles, status = 0, result["dtcs"].get(f"{OVER_TEMPERATURE_DTC:06X}", 0)
    answers = []
    while status & 0x08 and cycles < AGING_CYCLES + 5:
        answers.append(_soft_reset(client))
        cycles += 1
        status = _dtcs(client, 0xFF).get(OVER_TEMPERATURE_DTC, 0)
    result["reset_answers"] = sorted(set(answers))
    result["cycles_until_aged"] = cycles
    result["status_aged"] = status
    result["snapshot_aged"] = _snapshot(client, OVER_TEMPERATURE_DTC)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--secret", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--iface", default="vcan0")
    ap.add_argument("--phase", choices=("session", "restart"), default="session")
    args = ap.parse_args()
    secret = open(args.secret, "rb").read()
    result: dict = {"imports_s": round(time.monotonic() - _STARTED, 2)}
    bus = can.Bus(interface="socketcan", channel=args.iface,
                  can_filters=[{"can_id": RESPONSE_ID, "can_mask": 0x7FF}])
    notifier = can.Notifier(bus, [], timeout=0.1)
    address = isotp.Address(isotp.AddressingMode.Normal_11bits, txid=REQUEST_ID, rxid=RESPONSE_ID)
    params = {"stmin": 0, "blocksize": 0, "tx_data_min_length": 8, "tx_padding": 0xCC,
              "rx_flowcontrol_timeout": 60000, "rx_consecutive_frame_timeout": 60000, "max_frame_size": 4095}
    stack = isotp.NotifierBasedCanStack(bus=bus, notifier=notifier, address=address, params=params)
    rc = 0
    try:
        with Client(PythonIsoTpConnection(stack), config=_config(secret)) as client:
            if args.phase == "session":
                session(client, secret, result)
            else:
                restart(client, result)
        result["ok"] = True
    except Exception as e:  # noqa: BLE001 (recorded for the test's message)
        result["failed"] = f"{type(e).__name__}: {e}"
        traceback.print_exc()
        rc = 1
    finally:
        notifier.stop()
        bus.shutdown()
        with open(args.out, "w") as f:
            json.dump(result, f, indent=1)
    return rc


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Write the hand-made seed corpora of the libFuzzer harnesses.

    python3 tests/fuzz/make_seeds.py            # rewrites tests/fuzz/corpus/{model,loop,calibration}/

Standard library only, deterministic (the committed seeds are its output: a
file in those folders that it no longer makes is removed).

The byte formats are described at the top of each harness (fuzz_model.c,
fuzz_loop.c, fuzz_calibration.c); the CAN frames follow hil/wetclutch.dbc
(little-endian signals, CRC-8 SAE J1850 over the data id and bytes 1..7,
alive counter in the low nibble of byte 1: src/can/wc_e2e.h).
"""
import math
import pathlib
import struct
import zlib

HERE = pathlib.Path(__file__).resolve().parent
CORPUS = HERE / "corpus"


# shared: fz_float encodings (wc_fuzz_common.h)

def f_raw(x):
    """tag 0: the float's raw bit pattern, whatever the argument's range."""
    return bytes([0]) + struct.pack("<f", x)


def f_bits(bits):
    return bytes([0]) + struct.pack("<I", bits)


# model harness

OP_TORQUE, OP_INVERSE, OP_THERMAL, OP_FRICTION, OP_VISCOSITY, OP_FILM, OP_HYDRAULICS, OP_STEP = range(8)
MODE_OPEN, MODE_TORQUE, MODE_LOCKED = 0, 1, 2
NAN_BITS, INF_BITS, NINF_BITS, DENORMAL_BITS = 0x7FC00000, 0x7F800000, 0xFF800000, 0x00000001


def step(slip, oil, housing, request, mode, bench=None):
    flags = 0x02 if bench else 0x00
    out = bytes([OP_STEP, flags]) + slip + oil + housing + request + bytes([mode])
    if bench:
        out += bench[0] + bench[1]
    return out


def model_seeds():
    seeds = {}
    # a normal engagement: open, torque ramp while the slip falls, locked
    b = f_raw(60.0)
    for k in range(8):
        b += step(f_raw(150.0), f_raw(60.0), f_raw(55.0), f_raw(0.0), MODE_OPEN)
    for k in range(24):
        b += step(f_raw(150.0 * (1 - k / 24)), f_raw(60.0), f_raw(55.0), f_raw(8.0 * k), MODE_TORQUE)
    for k in range(4):
        b += step(f_raw(0.0), f_raw(60.0), f_raw(55.0), f_raw(200.0), MODE_LOCKED)
    seeds["engagement"] = b
    # every public function once at a nominal point (DESIGN.md section 2 references)
    b = f_raw(40.0)
    b += bytes([OP_TORQUE]) + f_raw(78.54) + f_raw(65.0) + f_raw(1188.0)
    b += bytes([OP_INVERSE]) + f_raw(78.54) + f_raw(90.0) + f_raw(150.0)
    b += bytes([OP_THERMAL, 0x00]) + f_raw(50.0) + f_raw(1000.0) + f_raw(40.0) + f_raw(30.0)
    b += bytes([OP_FRICTION]) + f_raw(0.5) + f_raw(90.0)
    b += bytes([OP_VISCOSITY]) + f_raw(65.0)
    b += bytes([OP_FILM]) + f_raw(293117.0) + f_raw(398038.0)
    b += bytes([OP_HYDRAULICS, 0]) + f_raw(1214.8)
    b += bytes([OP_HYDRAULICS, 1]) + f_raw(363000.0)
    b += bytes([OP_HYDRAULICS, 2]) + f_raw(363000.0)
    b += bytes([OP_HYDRAULICS, 3]) + f_raw(0.0) + f_raw(157.8)
    seeds["every_function"] = b
    # bad numbers: NaN, +-Inf, denormals, out of range; unknown modes
    b = f_bits(NAN_BITS)
    b += step(f_bits(NAN_BITS), f_bits(INF_BITS), f_bits(NINF_BITS), f_bits(NAN_BITS), MODE_TORQUE)
    b += step(f_raw(2000.0), f_raw(-50.0), f_raw(300.0), f_raw(-1.0), 240)  # mode 3
    b += step(f_bits(DENORMAL_BITS), f_raw(20.0), f_raw(20.0), f_raw(1e6), 244)  # mode -1
    b += bytes([OP_TORQUE]) + f_bits(NAN_BITS) + f_bits(INF_BITS) + f_raw(-1.0)
    b += bytes([OP_INVERSE]) + f_raw(1047.2) + f_raw(250.0) + f_raw(1e5)
    b += bytes([OP_FILM]) + f_bits(NAN_BITS) + f_raw(-1.0)
    b += bytes([OP_HYDRAULICS, 2]) + f_bits(NAN_BITS)
    seeds["bad_numbers"] = b
    # a hot clutch: locked at high slip until the over-temperature bit, then cooling
    b = f_raw(180.0)
    for k in range(12):
        b += step(f_raw(1000.0), f_raw(150.0), f_raw(150.0), f_raw(0.0), MODE_LOCKED)
    for k in range(4):
        b += step(f_raw(0.0), f_raw(20.0), f_raw(20.0), f_raw(0.0), MODE_OPEN)
    seeds["hot_clutch"] = b
    # on a bench: load cell and torque sensor, once implausible
    b = f_raw(40.0)
    for k in range(6):
        b += step(f_raw(-80.0), f_raw(70.0), f_raw(60.0), f_raw(100.0), MODE_TORQUE,
                  bench=(f_raw(900.0 + 50 * k), f_raw(-120.0)))
    b += step(f_raw(-80.0), f_raw(70.0), f_raw(60.0), f_raw(100.0), MODE_TORQUE,
              bench=(f_raw(-5.0), f_bits(NAN_BITS)))
    seeds["bench"] = b
    return seeds


# loop harness

ID_SENSORS, ID_REQUEST, ID_BENCH = 0x110, 0x111, 0x130
SEL_SENSORS, SEL_REQUEST, SEL_BENCH, SEL_OTHER = 0, 3, 6, 7


def crc8_j1850(data):
    crc = 0xFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1D) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc ^ 0xFF


assert crc8_j1850(b"123456789") == 0x4B


def pack(fields):
    """fields: (start bit, length, raw value); little-endian (Intel) signals."""
    word = 0
    for start, length, raw in fields:
        word |= (raw & ((1 << length) - 1)) << start
    return bytearray(word.to_bytes(8, "little"))


def protect(frame_id, data):
    data[0] = crc8_j1850(bytes([frame_id & 0xFF]) + bytes(data[1:8]))
    return bytes(data)


def sensors_frame(alive, slip_rpm, oil_degC, housing_degC):
    data = pack([(8, 4, alive), (16, 16, round(slip_rpm / 0.25)),
                 (32, 12, round((oil_degC + 50) / 0.1)), (44, 12, round((housing_degC + 50) / 0.1))])
    return protect(ID_SENSORS, data)


def request_frame(alive, torque_Nm, mode):
    data = pack([(8, 4, alive), (12, 4, mode), (16, 16, round(torque_Nm / 0.05))])
    return protect(ID_REQUEST, data)


def bench_frame(force_N, torque_Nm, temp_degC):
    return bytes(pack([(0, 20, round(force_N / 0.1)), (20, 20, round(torque_Nm / 0.01)),
                       (40, 12, round((temp_degC + 50) / 0.1))]))


def rec_frame(sel, data, tick=False, kind=1, fault=0, fmt=0x00, other_id=None, ext_bits=None):
    """One record of fuzz_loop.c: command byte, [16-bit id for SEL_OTHER],
    format byte, [16 more id bits for an extended frame], data."""
    c = kind | (0x04 if tick else 0) | (sel << 3) | (fault << 6)
    out = bytes([c])
    if sel == SEL_OTHER:
        out += struct.pack("<H", other_id)
    out += bytes([fmt])
    if fmt & 0x80 and (fmt >> 4) & 0x01:
        out += struct.pack("<H", ext_bits or 0)
    return out + data


def engagement_profile(periods=80):
    """(slip rpm, oil, housing, request Nm, mode) per 1 ms period."""
    out = []
    for k in range(periods):
        if k < 30:
            out.append((1500.0, 80.0, 75.0, 0.0, MODE_OPEN))
        elif k < 70:
            u = (k - 30) / 40
            out.append((1500.0 * (1 - u), 80.0, 75.0, 150.0 * u, MODE_TORQUE))
        else:
            out.append((0.0, 80.0, 75.0, 200.0, MODE_LOCKED))
    return out


def loop_engagement(clock_frame, bench=False):
    options = (0x01 if clock_frame else 0x00) | (0x02 if bench else 0x00)
    b = bytes([options])
    for k, (slip, oil, housing, req, mode) in enumerate(engagement_profile()):
        alive = k % 16
        if bench:
            b += rec_frame(SEL_BENCH, bench_frame(800.0 + 5 * k, 120.0, 85.0))
        if clock_frame:  # the request first: the ClutchSensors frame ends the period
            b += rec_frame(SEL_REQUEST, request_frame(alive, req, mode))
            b += rec_frame(SEL_SENSORS, sensors_frame(alive, slip, oil, housing))
        else:
            b += rec_frame(SEL_SENSORS, sensors_frame(alive, slip, oil, housing))
            b += rec_frame(SEL_REQUEST, request_frame(alive, req, mode), tick=True)
    return b


def u16_of(x, lo, hi):
    return struct.pack("<H", max(0, min(65535, round((x - lo) / (hi - lo) * 65535))))


def loop_plausible():
    """'make valid' + 'plausible': the harness writes CRC and counters."""
    b = bytes([0x04 | 0x08])
    for slip, oil, housing, req, mode in engagement_profile():
        b += bytes([1 | (SEL_SENSORS << 3), 0x00]) + u16_of(slip, -8000, 8000) + u16_of(oil, -40, 200) + \
            u16_of(housing, -40, 200)
        b += bytes([1 | 0x04 | (SEL_REQUEST << 3), 0x00]) + u16_of(req, 0, 2000) + bytes([mode])
    return b


def loop_faults():
    """A good start, then one of each fault of the README's matrix, then silence."""
    b = bytes([0x04])  # make valid, raw signals
    good_s = sensors_frame(0, 800.0, 60.0, 60.0)
    good_q = request_frame(0, 50.0, MODE_TORQUE)
    for k in range(26):
        b += rec_frame(SEL_SENSORS, good_s)
        b += rec_frame(SEL_REQUEST, good_q, tick=True)
    b += rec_frame(SEL_SENSORS, good_s, fault=2) + bytes([0x5A])          # CRC error
    b += rec_frame(SEL_REQUEST, good_q, tick=True)
    b += rec_frame(SEL_SENSORS, good_s, fault=1) + bytes([0])             # repeated counter
    b += rec_frame(SEL_REQUEST, good_q, tick=True)
    b += rec_frame(SEL_SENSORS, good_s, fault=1) + bytes([5])             # counter jump
    b += rec_frame(SEL_REQUEST, good_q, tick=True)
    b += rec_frame(SEL_SENSORS, sensors_frame(0, 0, 4095 * 0.1 - 50, 60.0))  # OilTemp SNA
    b += rec_frame(SEL_REQUEST, request_frame(0, 50.0, 7), tick=True)      # reserved Mode
    b += rec_frame(SEL_SENSORS, good_s, fmt=0x84)                         # DLC 4
    b += rec_frame(SEL_OTHER, bytes(8), other_id=0x7FF)                     # unknown id
    b += rec_frame(SEL_REQUEST, good_q, fmt=0x98, tick=True, ext_bits=0x111)  # extended flag, DLC 8
    b += bytes([3 | (0 << 2), 3]) + bytes([3 | (1 << 2), 1]) + bytes([3 | (3 << 2), 2])  # port events
    for k in range(14):
        b += bytes([0])                                                   # ticks only: timeouts
    for k in range(30):
        b += rec_frame(SEL_SENSORS, good_s)
        b += rec_frame(SEL_REQUEST, good_q, tick=True)
    return b


def loop_overflow():
    """40 frames between two steps: the ring (32) overflows."""
    b = bytes([0x04])
    for k in range(40):
        b += rec_frame(SEL_SENSORS, sensors_frame(0, 100.0, 40.0, 40.0))
    b += bytes([0])
    return b


# XCP records (fuzz_loop.c): c = 3 | 0x10 | (0x20: a tick with it) | (0x40: no wc_xcp_step after it), the selector (index into xcp_codes,
# 0x20 "aimed"), 7 data bytes after the command code.
XCP = {name: i for i, name in enumerate([
    "CONNECT", "DISCONNECT", "GET_STATUS", "SYNCH", "GET_COMM_MODE_INFO", "GET_ID", "SET_MTA", "UPLOAD",
    "SHORT_UPLOAD", "BUILD_CHECKSUM", "DOWNLOAD", "DOWNLOAD2", "SET_CAL_PAGE", "GET_CAL_PAGE",
    "GET_PAG_PROCESSOR_INFO", "COPY_CAL_PAGE", "SET_DAQ_PTR", "WRITE_DAQ", "SET_DAQ_LIST_MODE",
    "START_STOP_DAQ_LIST", "START_STOP_SYNCH", "GET_DAQ_CLOCK", "GET_DAQ_PROCESSOR_INFO", "GET_DAQ_RESOLUTION_INFO",
    "GET_DAQ_EVENT_INFO", "FREE_DAQ", "ALLOC_DAQ", "ALLOC_ODT", "ALLOC_ODT_ENTRY"])}
HOLDING_MARGIN_OFFSET = 112  # src/can/generated/wc_cal_image_layout.h


def rec_xcp(name, *data, aimed=False, tick=False, wait=False):
    return bytes([3 | 0x10 | (0x20 if tick else 0) | (0x40 if wait else 0), XCP[name] | (0x20 if aimed else 0)]) + \
        bytes(list(data) + [0] * (7 - len(data)))


def xcp_session(commands, periods=80):
    """'make valid' + 'plausible' engagement, one XCP command after each period's frames."""
    b = bytes([0x04 | 0x08])
    profile = engagement_profile(periods)
    for k, (slip, oil, housing, req, mode) in enumerate(profile):
        b += bytes([1 | (SEL_SENSORS << 3), 0x00]) + u16_of(slip, -8000, 8000) + u16_of(oil, -40, 200) + \
            u16_of(housing, -40, 200)
        b += bytes([1 | 0x04 | (SEL_REQUEST << 3), 0x00]) + u16_of(req, 0, 2000) + bytes([mode])
        if k < len(commands):
            b += commands[k]
    return b


def xcp_seeds():
    mta_margin = rec_xcp("SET_MTA", 0, 0, 0, 0, *struct.pack("<H", HOLDING_MARGIN_OFFSET), aimed=True)
    downloads = xcp_session([
        rec_xcp("CONNECT"), rec_xcp("GET_STATUS"), mta_margin,
        rec_xcp("DOWNLOAD", 0, 64, aimed=True),            # margin x 1.5: accepted
        rec_xcp("GET_STATUS"), mta_margin,
        rec_xcp("DOWNLOAD", 0, 0x80, aimed=True),          # margin x 0: refused (EV_USER)
        mta_margin, rec_xcp("DOWNLOAD", 4, 0x9A, 0x99, 0x99, 0x3E),  # 0.3 raw: accepted again
        rec_xcp("SET_CAL_PAGE", 0, 0, 1, aimed=True),      # a page 1 access
        rec_xcp("SET_CAL_PAGE", 0x01, 0, 1),               # the ECU on the reference page
        rec_xcp("SET_CAL_PAGE", 0x03, 0, 0),               # back on the working page
        rec_xcp("COPY_CAL_PAGE", 0, 1, 0, 0),
        rec_xcp("SET_MTA", 0, 0, 0, 0, 0, aimed=True), rec_xcp("BUILD_CHECKSUM", 0, 0, 0, 0x40, 0x04, aimed=True),
        rec_xcp("SHORT_UPLOAD", 7, 0, 0, 1, 8, 0, aimed=True), rec_xcp("UPLOAD", 7),
        rec_xcp("GET_ID", 0), rec_xcp("UPLOAD", 7), rec_xcp("DISCONNECT"),
    ])
    daq = xcp_session([
        rec_xcp("CONNECT"), rec_xcp("FREE_DAQ"), rec_xcp("ALLOC_DAQ", 0, 2, 0), rec_xcp("ALLOC_ODT", 0, 0, 0, 2),
        rec_xcp("ALLOC_ODT", 0, 1, 0, 13),                     # more ODTs than a step's frames: overload
        rec_xcp("ALLOC_ODT_ENTRY", 0, 0, 0, 0, 2), rec_xcp("ALLOC_ODT_ENTRY", 0, 0, 0, 1, 1),
        rec_xcp("SET_DAQ_PTR", 0, 0, 0, 0, 0),
        rec_xcp("WRITE_DAQ", 0xFF, 4, 0, 1, 0x40, 0, aimed=True),  # 4 bytes of the loop
        rec_xcp("WRITE_DAQ", 0xFF, 1, 0, 2, 0x10, 0, aimed=True),  # 1 byte of the slave's status
        rec_xcp("SET_DAQ_PTR", 0, 0, 0, 1, 0), rec_xcp("WRITE_DAQ", 0xFF, 4, 0, 1, 0x80, 0, aimed=True),
        rec_xcp("SET_DAQ_LIST_MODE", 0x10, 0, 0, 0, 0, 1), rec_xcp("SET_DAQ_LIST_MODE", 0x10, 1, 0, 0, 0, 3),
        rec_xcp("START_STOP_DAQ_LIST", 2, 0, 0), rec_xcp("START_STOP_DAQ_LIST", 2, 1, 0),
        rec_xcp("START_STOP_SYNCH", 1), rec_xcp("GET_DAQ_CLOCK"), rec_xcp("GET_DAQ_PROCESSOR_INFO"),
        rec_xcp("GET_DAQ_RESOLUTION_INFO"), rec_xcp("GET_DAQ_EVENT_INFO", 0, 0, 0),
        rec_xcp("SET_DAQ_PTR", 0, 0, 0, 0, 0),                 # a running list: ERR_DAQ_ACTIVE
        rec_xcp("START_STOP_DAQ_LIST", 0, 1, 0), rec_xcp("START_STOP_SYNCH", 0),
    ])
    errors = xcp_session([
        rec_xcp("GET_STATUS"),                                  # before CONNECT: ignored
        rec_xcp("CONNECT"), bytes([3 | 0x10, 31, 0xC0]) + bytes(6),  # an unknown code
        bytes([3 | 0x10, XCP["SET_MTA"] | 0x40, 0x84]) + bytes(7),   # DLC 4: too short
        bytes([3 | 0x10, XCP["GET_STATUS"] | 0x40, 0x98]) + bytes(7),  # extended flag: ignored
        rec_xcp("UPLOAD", 8), rec_xcp("SHORT_UPLOAD", 4, 0, 0, 0, 0x3E, 0x04, aimed=True),  # past the page's end
        rec_xcp("SET_MTA", 0, 0, 0, 1, 0, 0, aimed=True), rec_xcp("DOWNLOAD", 2, 1, 2),  # the loop: read-only
        rec_xcp("COPY_CAL_PAGE", 0, 0, 0, 1), rec_xcp("SET_CAL_PAGE", 0x03, 0, 2),
        rec_xcp("ALLOC_ODT", 0, 0, 0, 1), rec_xcp("FREE_DAQ"), rec_xcp("ALLOC_DAQ", 0, 9, 0),
    ] + [rec_xcp("GET_STATUS")] * 6)                            # then a full ring between two steps
    # six commands between two steps: the ring (4) overflows, then ticks answer the rest one a step
    errors += b"".join(rec_xcp("GET_COMM_MODE_INFO", wait=True) for _ in range(6)) + bytes([0] * 5)
    return {"xcp_downloads": downloads, "xcp_daq": daq, "xcp_errors": errors}


# The whole shift (fuzz_loop.c: byte 0 bit 7 shift control, then the shift-options byte, bit 0 the whole shift):
# the third ClutchSensors choice is OffgoingSensors. A 1->2 upshift at a constant output speed: the turbine at
# i1 w_o = 3000 rpm, the on-coming slip (i1 - i2) w_o, the off-going slip 0, until the inertia phase pulls the
# turbine down to i2 w_o (on-coming slip 0, off-going slip -(i1 - i2) w_o).
SEL_OFFGOING = 2
MODE_SHIFT = 3
W_O_RPM = 3000.0 / 4.7
SLIP_12_RPM = (4.7 - 3.1) * W_O_RPM
WHOLE_CONFIG = bytes([25, 25, 2, 2, 5])  # sensor/request timeout 25, MaxDeltaCounter 2, SyncCounter 2, recovery 5


def p_sensors(slip, tick=True, fault=0, oil=80.0, housing=75.0):
    return bytes([1 | (0x04 if tick else 0) | (SEL_SENSORS << 3) | (fault << 6), 0x00]) + u16_of(slip, -8000, 8000) + \
        u16_of(oil, -40, 200) + u16_of(housing, -40, 200)


def p_offgoing(slip, fault=0):
    return bytes([1 | (SEL_OFFGOING << 3) | (fault << 6), 0x00]) + u16_of(slip, -8000, 8000)


def p_shift(request, turbine_Nm=150.0, time_ms=250.0):
    # ShiftRequest, AdaptationReset, TargetGear byte (% 8 + 1: 1 -> gear 2), TurbineTorque, TargetInertiaTime
    return bytes([1 | (SEL_BENCH << 3), 0x00, request, 0, 1]) + u16_of(turbine_Nm, -1000, 1000) + \
        u16_of(time_ms, 50, 2000)


def p_request(torque_Nm=0.0, mode=MODE_SHIFT):
    return bytes([1 | (SEL_REQUEST << 3), 0x00]) + u16_of(torque_Nm, 0, 2000) + bytes([mode])


def smoothstep(x):
    x = min(max(x, 0.0), 1.0)
    return x * x * (3 - 2 * x)


def whole_periods(b, first, last, request, inertia_start=None, inertia_ms=250.0, offgoing_every=4, lost=()):
    """Periods first..last-1: ClutchSensors (with the tick) every 2nd period, a bare tick between, OffgoingSensors
    every offgoing_every, ShiftCommand and TorqueRequest (Shift mode) every 10th. lost: inputs not sent."""
    for k in range(first, last):
        x = 0.0 if inertia_start is None else (k - inertia_start) / inertia_ms
        slip = SLIP_12_RPM * (1 - smoothstep(x))
        if k % 10 == 0:
            if "shift" not in lost:
                b += p_shift(request)
            if "request" not in lost:
                b += p_request()
        if k % offgoing_every == 0 and "offgoing" not in lost:
            b += p_offgoing(slip - SLIP_12_RPM)
        if k % 2 == 0 and "sensors" not in lost:
            b += p_sensors(slip)
        else:
            b += bytes([0])
    return b


# Starts inside the whole shift (fuzz_loop.c, "Starts inside the whole shift"): shift-options bits 1-4 = k picks
# the harness's snapshot k, which a scripted prefix left: the scenario of loop_whole_shift below (SCRIPT_NOMINAL,
# in the frames of whole_periods), or the same with every input lost from period 400 (inertia phase: START
# lost_inertia, fallback_end) or 200 (torque phase: handback). A seed that starts there continues the same script
# from the snapshot's period. fuzz_loop.c start_points: the same table (the harness runs the prefixes).
SCRIPT_NOMINAL = ((0, 30, 0, None), (30, 300, 1, None), (300, 640, 1, 300), (640, 660, 0, 300))
START = {  # name: (k, the snapshot's script period)
    "idle": (1, 30), "torque": (2, 90), "torque_end": (3, 280), "inertia": (4, 305), "inertia_mid": (5, 430),
    "lockup": (6, 560), "locked": (7, 620), "lost_inertia": (8, 430), "fallback_end": (9, 1390), "handback": (10, 230),
}
LOST_ALL = ("shift", "request", "offgoing", "sensors")


def whole_start(name):
    """'make valid' + 'plausible' (the snapshot's configuration, no configuration bytes), the whole shift from
    snapshot START[name]."""
    return bytes([0x80 | 0x08 | 0x04, 0x01 | (START[name][0] << 1)])


def nominal_periods(b, first, last, **kw):
    """SCRIPT_NOMINAL's periods first..last-1 (whole_periods with the request and inertia start of each)."""
    for seg_first, seg_last, request, inertia_start in SCRIPT_NOMINAL:
        lo, hi = max(first, seg_first), min(last, seg_last)
        if lo < hi:
            b = whole_periods(b, lo, hi, request, inertia_start=inertia_start, **kw)
    return b


def loop_whole_shift():
    """'make valid' + 'plausible', the whole shift from wc_loop_init: Shift mode idle (the off-going clutch holds
    1st gear), the request edge, fill, torque phase, inertia phase, lock-up, locked (ShiftReport), request
    withdrawn: SCRIPT_NOMINAL, the harness's prefix. With frames every 20 periods (bare ticks between; the
    timeouts are 25): 1.5 KB instead of 4.6 KB with frames every 2nd period."""
    b = bytes([0x80 | 0x40 | 0x08 | 0x04]) + WHOLE_CONFIG + bytes([0x01])
    for seg_first, seg_last, request, inertia_start in SCRIPT_NOMINAL:
        for k in range(seg_first, seg_last):
            x = 0.0 if inertia_start is None else (k - inertia_start) / 250.0
            slip = SLIP_12_RPM * (1 - smoothstep(x))
            if k % 20 == 0:
                b += p_shift(request) + p_request() + p_offgoing(slip - SLIP_12_RPM) + p_sensors(slip)
            else:
                b += bytes([0])
    return b


def loop_whole_starts():
    """Seeds from the snapshots, each through a part of the shift (at most ~150 periods, ~1 KB)."""
    seeds = {}
    # the request edge: fill pulse, prepare, into the torque phase
    seeds["whole_start_idle"] = nominal_periods(whole_start("idle"), 30, 120)
    # the torque phase, with OffgoingSensors faults: a wrong CRC, a repeated and a jumped counter, as fuzzed
    b = nominal_periods(whole_start("torque"), 90, 120)
    b += p_offgoing(0.0, fault=2) + bytes([0x5A]) + bytes([0])       # CRC error
    b += p_offgoing(0.0, fault=1) + bytes([0]) + bytes([0])          # repeated counter
    b += p_offgoing(0.0, fault=1) + bytes([5]) + bytes([0])          # counter jump
    b += bytes([1 | (SEL_OFFGOING << 3) | (3 << 6), 0x00]) + bytes(8) + bytes([0])  # as fuzzed: all zero, CRC wrong
    seeds["whole_start_torque_faults"] = nominal_periods(b, 124, 200)
    # OffgoingSensors lost in the torque phase: timeout, safe state, handed back (the off-going clutch at its
    # maximum); back, the request withdrawn, a new edge
    b = nominal_periods(whole_start("torque"), 90, 150, lost=("offgoing",))
    b = whole_periods(b, 150, 180, 0)
    seeds["whole_start_torque_lost"] = whole_periods(b, 180, 240, 1)
    # the torque phase's end: the hand-over into the inertia phase (the off-going slip falls below -1 rad/s)
    seeds["whole_start_torque_end"] = nominal_periods(whole_start("torque_end"), 280, 380)
    # the inertia phase from its start: the off-going clutch's hand-over, the PI on the reference
    seeds["whole_start_inertia"] = nominal_periods(whole_start("inertia"), 305, 440)
    # OffgoingSensors lost as the inertia phase begins (README: released at once; finished on the model), back
    b = nominal_periods(whole_start("inertia"), 305, 345, lost=("offgoing",))
    seeds["whole_start_inertia_lost"] = nominal_periods(b, 345, 420)
    # the inertia phase's second half: synchronous, into the lock-up hand-over
    seeds["whole_start_inertia_mid"] = nominal_periods(whole_start("inertia_mid"), 430, 580)
    # the lock-up hand-over, locked, the request withdrawn (IDLE, the off-going clutch back)
    seeds["whole_start_lockup"] = nominal_periods(whole_start("lockup"), 560, 660)
    # locked, then every input lost: the fallback finish in LOCKED
    b = nominal_periods(whole_start("locked"), 620, 630)
    seeds["whole_start_locked_lost"] = whole_periods(b, 630, 680, 1, inertia_start=300, lost=LOST_ALL)
    # the fallback finish (inputs lost in the inertia phase): the inputs come back (E2E sync, recovery)
    b = whole_periods(whole_start("lost_inertia"), 430, 440, 1, inertia_start=300, lost=LOST_ALL)
    seeds["whole_start_finish_back"] = whole_periods(b, 440, 520, 1, inertia_start=300)
    # the fallback finish's end: released after fallback_time_s, then the inputs back and the request withdrawn
    b = whole_periods(whole_start("fallback_end"), 1390, 1430, 1, inertia_start=300, lost=LOST_ALL)
    b = whole_periods(b, 1430, 1470, 1, inertia_start=300)
    seeds["whole_start_released"] = whole_periods(b, 1470, 1500, 0, inertia_start=300)
    # handed back (inputs lost in the torque phase): back, withdrawn, a new shift's edge
    b = whole_periods(whole_start("handback"), 230, 260, 1)
    b = whole_periods(b, 260, 290, 0)
    seeds["whole_start_handback"] = whole_periods(b, 290, 400, 1)
    return seeds


def raw_offgoing(slip_raw):
    return bytes(pack([(16, 16, slip_raw)]))


def loop_whole_shift_raw():
    """'make valid' with raw signals, the whole shift in Shift mode: OffgoingSensors in range, SNA (-32768),
    out of range, DLC 4, extended; the TCU's frames every step."""
    b = bytes([0x80 | 0x04]) + bytes([0x01])
    good_s = sensors_frame(0, SLIP_12_RPM, 80.0, 75.0)
    good_q = request_frame(0, 0.0, MODE_SHIFT)
    shift = bytes(pack([(16, 4, 2), (24, 16, round(150.0 / 0.05)), (40, 12, 250)]))
    for k in range(26):
        b += rec_frame(SEL_BENCH, shift)
        b += rec_frame(SEL_OFFGOING, raw_offgoing(0))
        b += rec_frame(SEL_SENSORS, good_s)
        b += rec_frame(SEL_REQUEST, good_q, tick=True)
    for raw in (-32768, 32001, -32001, 4, -40):                      # SNA, above, below the range, in range
        b += rec_frame(SEL_OFFGOING, raw_offgoing(raw))
        b += rec_frame(SEL_SENSORS, good_s)
        b += rec_frame(SEL_REQUEST, good_q, tick=True)
    b += rec_frame(SEL_OFFGOING, raw_offgoing(0), fmt=0x84)         # DLC 4
    b += rec_frame(SEL_OFFGOING, raw_offgoing(0), fmt=0x98, tick=True, ext_bits=0x113)  # extended
    for k in range(12):
        b += bytes([0])                                             # ticks only: timeouts
    return b


def loop_seeds():
    return {
        **xcp_seeds(),
        "whole_shift": loop_whole_shift(),
        **loop_whole_starts(),
        "whole_shift_raw": loop_whole_shift_raw(),
        "engagement_timer": loop_engagement(False),
        "engagement_frame_clock": loop_engagement(True),
        "engagement_bench": loop_engagement(False, bench=True),
        "engagement_plausible": loop_plausible(),
        "faults": loop_faults(),
        "overflow": loop_overflow(),
    }


# calibration harness

FLOAT_FIELDS = [
    "outer_radius_m", "inner_radius_m", "friction_area_m2", "piston_area_m2", "oil_conductance_W_per_K",
    "housing_conductance_W_per_K", "heat_capacity_J_per_K", "viscosity_a1_Pa_s", "viscosity_b1_per_K",
    "viscosity_a2_Pa_s", "viscosity_b2_per_K", "mu1", "mu2", "mu3", "stribeck_speed_m_s", "theta1_degC",
    "theta2_K", "vfs_gain_Pa_per_mA", "vfs_time_constant_s", "return_spring_force_N", "vfs_current_min_mA",
    "vfs_current_max_mA", "control_period_s", "film_squeeze_factor", "static_friction_factor", "lock_slip_rad_s",
    "breakaway_slip_rad_s", "holding_margin",
]


def set_field(name, value):
    """target byte, mutation 0 (fz_float), tag 0 (raw bits)."""
    return bytes([FLOAT_FIELDS.index(name), 0]) + f_raw(value)


def scale_field(name, eighths):
    """mutation 1: times 2^(eighths / 8)."""
    return bytes([FLOAT_FIELDS.index(name), 1, eighths & 0xFF])


def calibration_seeds():
    bench = {  # lut/wc_bench_identified_calibration.h, scalar fields
        "oil_conductance_W_per_K": 117.4738, "housing_conductance_W_per_K": 41.49914,
        "viscosity_a1_Pa_s": 0.1542595, "viscosity_b1_per_K": -0.08156193, "viscosity_a2_Pa_s": 0.06148355,
        "viscosity_b2_per_K": -0.02216161, "mu1": 0.1199572, "mu2": 0.09270761, "mu3": 0.4985932,
        "stribeck_speed_m_s": 0.02549717,
    }
    return {
        "table1": bytes([0]),
        "film_copy_64": bytes([1, 64, 0]),
        "film_even_16": bytes([1, 16, 0]),
        "film_last_8": bytes([5, 8, 56]),  # the 8 stiffest nodes: the open clutch at a thin film
        "bench_identified": bytes([0]) + b"".join(set_field(k, v) for k, v in bench.items()),
        # a 2 A solenoid at half the gain (the same pressure range), 10 ms period
        "solenoid_2A_10ms": bytes([0]) + set_field("vfs_current_max_mA", 2000.0) + set_field("vfs_current_min_mA", 50.0)
        + set_field("vfs_gain_Pa_per_mA", 1150.0) + set_field("control_period_s", 0.01)
        + set_field("vfs_time_constant_s", 0.02),
        # radii / 2, areas / 4, 4 friction pairs, 32 film nodes
        "small_clutch": bytes([1, 32, 0]) + scale_field("outer_radius_m", -8) + scale_field("inner_radius_m", -8)
        + scale_field("friction_area_m2", -16) + scale_field("piston_area_m2", -16)
        + bytes([len(FLOAT_FIELDS), 0, 4]),
        "hot_oil_map": bytes([0]) + set_field("mu3", 0.2) + set_field("theta1_degC", 90.0)
        + set_field("viscosity_b1_per_K", -0.05),
    }


# adaptation images: fuzz_calibration with byte 0 bit 7 set (fuzz_adapt_image.c)

def adapt_image(clutch_id, scales, confidences, film, kiss, shifts):
    """The adaptation image (wc_adapt_image.h): magic "WCAP", version 1, 56-byte payload, CRC-32."""
    payload = struct.pack("<I5f5fffI", clutch_id, *scales, *confidences, film, kiss, shifts)
    body = struct.pack("<IIII", 0x50414357, 1, len(payload), 0) + payload
    return body + struct.pack("<I", zlib.crc32(body))


def f_in(fraction):
    """tag 3: lo + (hi - lo) * fraction, inside the argument's range."""
    return bytes([3]) + struct.pack("<H", round(fraction * 65535))


def adapt_image_seeds():
    learned = adapt_image(2, (1.05, 0.97, 1.0, 1.125, 0.9), (0.25, 0.5, 0.0, 1.0, 0.125), 1.5, -1234.5, 42)
    fields = b"".join(f_in(0.5) + f_in(0.25) for _ in range(5))        # scales, confidences: in band
    return {
        "adapt_image_learned": bytes([0x80, 0]) + learned,                 # as is: loads
        "adapt_image_defaults": bytes([0x80, 0]) + adapt_image(0, (1.0,) * 5, (0.0,) * 5, 1.0, 0.0, 0),
        "adapt_image_payload": bytes([0x80, 1]) + learned[16:72],          # resealed payload bytes
        "adapt_image_corrupt": bytes([0x80, 2]) + learned[16:72] + bytes([30, 0x10, 76]),  # a flipped bit
        "adapt_image_values": bytes([0x80, 3, 0, 0, 0, 0]) + fields + f_in(0.5) + f_in(0.5) + bytes(4),
        # the bands read too (scale band 0.4, film 0.5..2, kiss 1e5 Pa), then every value on a band edge
        "adapt_image_bands": bytes([0x80, 0x0B]) + f_in(0.8) + f_in(0.5) + f_in(1 / 9) + f_in(0.1)
        + bytes([0, 0, 0, 0]) + b"".join(bytes([7, 1, 7, 0]) for _ in range(6)) + bytes(4),
    }


def main():
    calibration = {**calibration_seeds(), **adapt_image_seeds()}
    for name, seeds in (("model", model_seeds()), ("loop", loop_seeds()), ("calibration", calibration)):
        folder = CORPUS / name
        folder.mkdir(parents=True, exist_ok=True)
        for seed, data in sorted(seeds.items()):
            (folder / seed).write_bytes(data)
        for stale in sorted(set(f.name for f in folder.iterdir()) - set(seeds)):  # a seed no longer made
            (folder / stale).unlink()
        print(f"{folder.relative_to(HERE.parent.parent)}: {len(seeds)} seeds, "
              f"{sum(len(d) for d in seeds.values())} bytes")


if __name__ == "__main__":
    main()

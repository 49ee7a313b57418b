"""The loop harness's seeds (tests/fuzz/fuzz_loop.c and its parts: the input format at the top of each),
written by make_seeds.py: engagements as valid frames, the fault matrix, a ring overflow, XCP sessions
(fuzz_loop_xcp.c), UDS sessions (fuzz_loop_uds.c), the whole shift and its starts (fuzz_loop_starts.c).
Standard library only, deterministic. The CAN frames follow hil/wetclutch.dbc (little-endian signals,
CRC-8 SAE J1850 over the data id and bytes 1..7, alive counter in the low nibble of byte 1:
src/can/wc_e2e.h)."""
import struct

MODE_OPEN, MODE_TORQUE, MODE_LOCKED = 0, 1, 2   # TorqueRequest.Mode (hil/wetclutch.dbc), wc_clutch_mode_t

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


def engagement_profile(periods=80, open_periods=30):
    """(slip rpm, oil, housing, request Nm, mode) per 1 ms period: open, a 40-period torque ramp, locked."""
    out = []
    for k in range(periods):
        if k < open_periods:
            out.append((1500.0, 80.0, 75.0, 0.0, MODE_OPEN))
        elif k < open_periods + 40:
            u = (k - open_periods) / 40
            out.append((1500.0 * (1 - u), 80.0, 75.0, 150.0 * u, MODE_TORQUE))
        else:
            out.append((0.0, 80.0, 75.0, 200.0, MODE_LOCKED))
    return out


def loop_engagement(clock_frame, bench=False):
    """With bench input three frames a period: 68 periods (open 20), within scripts/fuzz.sh's 2048 bytes."""
    options = (0x01 if clock_frame else 0x00) | (0x02 if bench else 0x00)
    b = bytes([options])
    profile = engagement_profile(68, open_periods=20) if bench else engagement_profile()
    for k, (slip, oil, housing, req, mode) in enumerate(profile):
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


def xcp_session(commands):
    """'make valid' + 'plausible' engagement (torque control from period 5), one XCP command after each
    period's frames, 10 periods after the last command (the loop's steps are the fuzzer's cost)."""
    b = bytes([0x04 | 0x08])
    profile = engagement_profile(len(commands) + 10, open_periods=5)
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


# UDS records (fuzz_loop_uds.c): c = 3 | 0x80 | kind << 2 | (0x20: a tick with it), the selector s, [a format
# byte, a 16-bit id], 8 data bytes. Kind 2, a SingleFrame request: s picks the service from UDS_SIDS (past its
# end: the first data byte is it) and SF_DL = 1 + (s >> 4 & 7); the request's parameters follow the first
# data byte; a sendKey gets the key hook's key unless the first data byte's bit 0 is set.
UDS_SIDS = [0x10, 0x11, 0x14, 0x19, 0x22, 0x22, 0x27, 0x27, 0x31, 0x3E, 0x19]
UDS_DTC_BASE = 0xD0A000     # fuzz_loop_uds.c: DTC i tests VfsCommand status bit i
STATUS_SAFE_STATE_BIT = 8
UDS_WAIT_STEPS = 10         # fuzz_loop_uds.c UDS_WAIT_STEPS: N_Bs, N_Cr and the security delay, in steps


def rec_uds(kind, s, data, tick=False, fmt=None, other_id=None):
    out = bytes([3 | 0x80 | (kind << 2) | (0x20 if tick else 0), s])
    if kind == 3:
        out += bytes([fmt])
        if s & 3 == 3:
            out += struct.pack("<H", other_id)
    return out + bytes(list(data) + [0] * (8 - len(data)))


def uds_request(*request, functional=False, tick=False, first=0, sf_dl=None):
    """A SingleFrame request: the service id and its parameters (at most 6)."""
    sid = request[0]
    index = UDS_SIDS.index(sid) if sid in UDS_SIDS else 15
    length = len(request) if sf_dl is None else sf_dl
    s = index | ((length - 1) << 4) | (0x80 if functional else 0)
    return rec_uds(2, s, [sid if index == 15 else first] + list(request[1:]), tick=tick)


def uds_raw(*data, functional=False, tick=False):
    return rec_uds(1 if functional else 0, 0, data, tick=tick)


FC_CTS = uds_raw(0x30, 0, 0)     # the tester's flow control: ContinueToSend, no further FC, STmin 0


def uds_session(records, periods=None):
    """A loop with shift control and adaptation ('make valid' + 'plausible'), the records after each
    period's frames (one entry per period: bytes, or a tuple of them); as many periods as records and 5 more
    (the loop's steps are the fuzzer's cost: no engagement beyond the session)."""
    b = bytes([0x80 | 0x08 | 0x04 | 0x02, 0x00])
    periods = len(records) + 5 if periods is None else periods
    for k, (slip, oil, housing, req, mode) in enumerate(engagement_profile(periods)):
        b += bytes([1 | (SEL_SENSORS << 3), 0x00]) + u16_of(slip, -8000, 8000) + u16_of(oil, -40, 200) + \
            u16_of(housing, -40, 200)
        b += bytes([1 | 0x04 | (SEL_REQUEST << 3), 0x00]) + u16_of(req, 0, 2000) + bytes([mode])
        if k < len(records):
            b += b"".join(records[k]) if isinstance(records[k], tuple) else records[k]
    return b


def uds_seeds():
    dtc = UDS_DTC_BASE + STATUS_SAFE_STATE_BIT  # failed from the start: the loop's safe state

    def single(*request, **kw):  # a request answered in a SingleFrame: its period and the answer's
        return [uds_request(*request, **kw), b""]

    def segmented(*request, **kw):  # answered in FF + CFs: the FC once the FF is out (two steps on)
        return [uds_request(*request, **kw), b"", FC_CTS, b"", b"", b"", b"", b""]

    session = uds_session(
        single(0x3E, 0x00) + single(0x22, 0xFD, 0x01) + segmented(0x22, 0xF1, 0x90) + single(0x19, 0x01, 0xFF)
        + segmented(0x19, 0x02, 0xFF) + segmented(0x19, 0x0A)
        + segmented(0x19, 0x04, dtc >> 16, (dtc >> 8) & 0xFF, dtc & 0xFF, 0x01)
        + single(0x10, 0x03) + segmented(0x22, 0xFD, 0x02, 0xFD, 0x03)
        + [b""] * UDS_WAIT_STEPS                   # the security delay after init
        + single(0x10, 0x03) + single(0x27, 0x01) + single(0x27, 0x02)  # aimed: the right key
        + single(0x31, 0x01, 0x02, 0x01) + single(0x31, 0x03, 0x02, 0x01) + single(0x14, 0xFF, 0xFF, 0xFF)
        + segmented(0x19, 0x02, 0xFF) + single(0x11, 0x03) + single(0x11, 0x83) + single(0x10, 0x01))
    # a request in a FirstFrame and ConsecutiveFrames: 0x22 with five DIDs (11 bytes); our FC goes out in the
    # step that takes the FF, the answer's FF two steps after the CF
    dids = [0x22, 0xF1, 0x90, 0xFD, 0x01, 0xFD, 0x02, 0xFD, 0x03, 0xFD, 0x04]
    segmented_request = uds_session([uds_raw(0x10, len(dids), *dids[:6]), uds_raw(0x21, *dids[6:]), b"", FC_CTS]
                                    + [b""] * 10)

    def frame(*records):  # frames that get no answer, or an answer the next step: one period each
        return [r for record in records for r in (record, b"")]

    errors = uds_session(
        frame(uds_raw(0x00, 0x3E, 0x00),                       # SF_DL 0: malformed
              uds_request(0x3E, 0x00, sf_dl=8),                 # SF_DL 8: malformed
              uds_request(0x85, 0x01),                          # a service not supported: 0x11
              uds_request(0x85, 0x01, functional=True),         # ... functional: no answer
              uds_request(0x22, 0xF1),                          # odd length: 0x13
              uds_request(0x22, 0x12, 0x34, functional=True),   # an unknown DID, functional: no answer
              uds_request(0x22, 0x12, 0x34),                    # ... physical: 0x31
              uds_request(0x10, 0x05),                          # a session not supported: 0x12
              uds_request(0x27, 0x01),                          # not in the default session: 0x7F
              uds_request(0x14, 0xFF, 0xFF, 0xFF),              # locked: 0x33
              uds_request(0x31, 0x01, 0x02, 0x01),              # locked: 0x33
              uds_request(0x19, 0x04, 0x12, 0x34, 0x56, 0x01),  # an unknown DTC: 0x31
              uds_request(0x11, 0x01),                          # hardReset: 0x12
              uds_raw(0x11, 0x2C, 0x22, 0xF1, 0x90),            # FF_DL 300 > the buffer: FC Overflow
              uds_raw(0x10, 0x0A, 0x22, 0xF1, 0x90, 0xFD, 0x01), uds_raw(0x23, 0xFD),  # a CF out of sequence
              uds_raw(0x21, 0x00),                              # a CF outside a reception
              uds_raw(0x30, 0x00, 0x00),                        # an FC outside a transmission
              uds_raw(0x10, 0x08, 0x22, 0xF1, 0x90, 0xFD, 0x01, 0xFD, functional=True),  # functional FF: ignored
              rec_uds(3, 0, [0x02, 0x3E, 0x00], fmt=0x83),      # DLC 3 SF on the physical id
              rec_uds(3, 1, [0x02, 0x3E, 0x00], fmt=0x98),      # extended flag
              rec_uds(3, 2, [0x02, 0x3E, 0x00], fmt=0x88),      # on the response id: not a request
              rec_uds(3, 3, [0x02, 0x3E, 0x00], fmt=0x88, other_id=0x123))  # another id
        + [uds_request(0x22, 0xF1, 0x90), b"", uds_raw(0x31, 0x00, 0x00), b"", uds_raw(0x32, 0x00, 0x00), b""]  # Wait, Overflow
        + [uds_request(0x22, 0xF1, 0x90)] + [b""] * (UDS_WAIT_STEPS + 2)  # no FC: N_Bs ends it
        + [uds_raw(0x10, 0x0A, 0x22, 0xF1, 0x90, 0xFD, 0x01)] + [b""] * (UDS_WAIT_STEPS + 2)  # no CF: N_Cr ends it
        + [tuple(uds_raw(0x02, 0x3E, 0x00) for _ in range(20))]  # 20 frames between two steps: the ring (16) overflows
        + [b""] * UDS_WAIT_STEPS
        + frame(uds_request(0x10, 0x03), uds_request(0x27, 0x01), uds_request(0x27, 0x02, 0, 0, 0, 0, first=1),  # 0x35
                uds_request(0x27, 0x01), uds_request(0x27, 0x02, 0, 0, 0, 0, first=1),
                uds_request(0x27, 0x01), uds_request(0x27, 0x02, 0, 0, 0, 0, first=1),  # 0x36: the delay
                uds_request(0x27, 0x01),                          # 0x37
                uds_request(0x27, 0x02)))                         # no seed: 0x24
    return {"uds_session": session, "uds_segmented_request": segmented_request, "uds_errors": errors}


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
        **uds_seeds(),
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

"""The transmission harness's seeds (tests/fuzz/fuzz_gearbox.c: the input format at its top), written by
make_seeds.py: the 8HP held in a gear, a power-on upshift and a downshift with the turbine following the
target ratio, GearboxSensors lost in a gear and in the middle of a shift (the safe state), a refused
request. Standard library only, deterministic. The signals are written by the harness ("plausible": 2
bytes a signal, mapped into the DBC range) with its E2E CRC and counters ("make valid")."""
from seeds_loop import u16_of, smoothstep

RATIO = {0: -3.29679, 1: 4.69565, 2: 3.13043, 3: 2.1039, 4: 1.66667, 5: 1.28453, 6: 1.0, 7: 0.839161,
         8: 0.666667}                      # lut/wc_8hp_gearbox.h
OUTPUT_RPM = 573.0                         # 60 rad/s, as tests/c/test_loop_gearbox.c
SEL_SENSORS, SEL_COMMAND = 0, 1


def header(gear, clock_frame=True):
    """'make valid' + 'plausible', the frame clock, the start gear."""
    return bytes([(0x01 if clock_frame else 0x00) | 0x02 | 0x04 | (gear << 4)])


def sensors(turbine_rpm, output_rpm=OUTPUT_RPM, oil=80.0, housing=80.0, tick=False):
    return bytes([1 | (0x04 if tick else 0) | (SEL_SENSORS << 3), 0x00]) + u16_of(oil, -40, 200) + \
        u16_of(turbine_rpm, -8000, 8000) + u16_of(output_rpm, -8000, 8000) + u16_of(housing, -40, 200)


def command(request, current, target, torque_Nm=150.0, time_ms=250.0):
    return bytes([1 | (SEL_COMMAND << 3), 0x00, request, target, current]) + u16_of(torque_Nm, -1000, 1000) + \
        u16_of(time_ms, 50, 2000)


def periods(b, count, turbine_rpm, request, current, target, lost=False, torque_Nm=150.0, tick=False):
    """count periods: ShiftCommand every 5th (the request timeout is 10), then GearboxSensors (it steps the loop
    on the frame clock; tick: with a tick, the timer clock) or, lost, a bare tick. turbine_rpm: a number or a
    function of the period. At most 1024 records an input (fuzz_gearbox.c MAX_RECORDS)."""
    for k in range(count):
        if k % 5 == 0:
            b += command(request, current, target, torque_Nm)
        t = turbine_rpm(k) if callable(turbine_rpm) else turbine_rpm
        b += bytes([0]) if lost else sensors(t, tick=tick)
    return b


def shift(gear_from, gear_to, torque_Nm, lost_at=None):
    """Held 40 periods, the request, the turbine from the source ratio to the target's over 250 periods
    (from period 60 of the shift; the inertia phase follows the speeds), then held."""
    b = periods(header(gear_from), 40, RATIO[gear_from] * OUTPUT_RPM, 0, gear_from, gear_from, torque_Nm=torque_Nm)

    def turbine(k):
        u = smoothstep((k - 60) / 250.0)
        return (RATIO[gear_from] + (RATIO[gear_to] - RATIO[gear_from]) * u) * OUTPUT_RPM
    if lost_at is None:
        return periods(b, 420, turbine, 1, gear_from, gear_to, torque_Nm=torque_Nm)
    b = periods(b, lost_at, turbine, 1, gear_from, gear_to, torque_Nm=torque_Nm)
    b = periods(b, 60, 0.0, 1, gear_from, gear_to, lost=True, torque_Nm=torque_Nm)
    return periods(b, 60, turbine(lost_at), 0, gear_from, gear_from, torque_Nm=torque_Nm)


def gearbox_seeds():
    seeds = {}
    seeds["held_gear3"] = periods(header(3), 100, RATIO[3] * OUTPUT_RPM, 0, 3, 3, torque_Nm=200.0)
    seeds["upshift_2_3"] = shift(2, 3, 150.0)
    seeds["downshift_3_2_coast"] = shift(3, 2, -20.0)
    seeds["lost_in_gear4"] = periods(periods(header(4), 60, RATIO[4] * OUTPUT_RPM, 0, 4, 4), 60, 0.0, 0, 4, 4,
                                     lost=True) + periods(b"", 60, RATIO[4] * OUTPUT_RPM, 0, 4, 4)
    seeds["lost_mid_upshift_2_3"] = shift(2, 3, 150.0, lost_at=150)
    # refused: CurrentGear not the held gear, a skip the table has not, to reverse; then a valid one
    b = periods(header(4), 40, RATIO[4] * OUTPUT_RPM, 0, 4, 4)
    for current, target in ((2, 3), (4, 1), (4, 0), (4, 4)):
        b = periods(b, 10, RATIO[4] * OUTPUT_RPM, 1, current, target)
        b = periods(b, 10, RATIO[4] * OUTPUT_RPM, 0, 4, 4)
    seeds["refusals"] = b
    # the timer clock, reverse held
    seeds["reverse_timer"] = periods(header(0, clock_frame=False), 60, RATIO[0] * OUTPUT_RPM, 0, 0, 0, tick=True) + \
        bytes([0] * 5)
    return seeds

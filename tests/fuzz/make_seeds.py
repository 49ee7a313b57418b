#!/usr/bin/env python3
"""Write the hand-made seed corpora of the libFuzzer harnesses.

    python3 tests/fuzz/make_seeds.py            # rewrites tests/fuzz/corpus/{model,loop,calibration,gearbox}/

Standard library only, deterministic (the committed seeds are its output: a
file in those folders that it no longer makes is removed).

The byte formats are described at the top of each harness (fuzz_model.c,
fuzz_loop.c, fuzz_calibration.c, fuzz_gearbox.c). The loop's seeds are made in seeds_loop.py
(its frames follow hil/wetclutch.dbc), the transmission's in seeds_gearbox.py; the model's and the
calibration's here.
"""
import math
import pathlib
import struct
import zlib

from seeds_gearbox import gearbox_seeds
from seeds_loop import MODE_LOCKED, MODE_OPEN, MODE_TORQUE, loop_seeds

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


# calibration harness

FLOAT_FIELDS = [
    "outer_radius_m", "inner_radius_m", "friction_area_m2", "piston_area_m2", "oil_conductance_W_per_K",
    "housing_conductance_W_per_K", "heat_capacity_J_per_K", "viscosity_a1_Pa_s", "viscosity_b1_per_K",
    "viscosity_a2_Pa_s", "viscosity_b2_per_K", "mu1", "mu2", "mu3", "stribeck_speed_m_s", "theta1_degC",
    "theta2_K", "vfs_gain_Pa_per_mA", "vfs_time_constant_s", "return_spring_force_N", "vfs_current_min_mA",
    "vfs_current_max_mA", "control_period_s", "film_squeeze_factor", "static_friction_factor", "lock_slip_rad_s",
    "breakaway_slip_rad_s", "holding_margin", "open_clearance_m", "open_aeration_speed_rad_s",
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


# gearbox images: fuzz_calibration with byte 0 bits 7 and 6 set (fuzz_gearbox_image.c)

def gearbox_image_seeds():
    import sys
    sys.path.insert(0, str(HERE.parent.parent / "tools"))
    import tomllib
    from wetclutch.calibration import gearbox_image as layout
    with open(HERE.parent.parent / "tools" / "gearboxes" / "8hp_shifts.toml", "rb") as f:
        image = layout.image_bytes_of(layout.values_from_table(tomllib.load(f)))

    def word(name, index=0):
        return struct.pack("<H", layout.BY_NAME[name].offset // 4 + index)
    return {
        "gearbox_image_raw": bytes([0xC0, 0]) + image,                                           # as is: loads
        "gearbox_image_8hp": bytes([0xC0, 1]),                                                   # no edit: loads
        "gearbox_image_oncoming_259": bytes([0xC0, 1]) + word("gearbox.shift.oncoming", 5) + bytes([1])
        + struct.pack("<H", 259),                                                                # BAD_FIELD
        "gearbox_image_ratio_minus_1": bytes([0xC0, 1]) + word("gearbox.ratio", 3) + bytes([3]),  # a ulp lower
        "gearbox_image_unused": bytes([0xC0, 3]) + word("gearbox.shift.output_ratio", 40),       # BAD_FIELD
        "gearbox_image_cut": bytes([0xC0, 2]) + struct.pack("<HBH", 100, 0x10, 6000),            # TRUNCATED
        "gearbox_image_flipped": bytes([0xC0, 2]) + struct.pack("<HBH", 100, 0x10, 6280),        # BAD_CRC
    }


def main():
    calibration = {**calibration_seeds(), **adapt_image_seeds(), **gearbox_image_seeds()}
    for name, seeds in (("model", model_seeds()), ("loop", loop_seeds()), ("calibration", calibration),
                         ("gearbox", gearbox_seeds())):
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


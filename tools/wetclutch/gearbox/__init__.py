"""A clutch-to-clutch automatic described by its gear-set kinematics (DESIGN 15; issue 29, item 1).

From a gearbox description (tools/gearboxes/8hp.toml: planetary sets, the shafts joining their members, the
input and output shafts, the shift elements with their own clutch calibrations, the elements closed in each
gear) this package computes the ratios, every element's slip as a linear function of turbine and output speed,
the torques a gear's elements hold and, per single-element shift, the TCU's reduced model in the terms of
wc_shift_calibration_t (include/wetclutch/wc_shift.h), with a vehicle file's inertia on the output side.

One module per concern:

description  the file: reading, the structural checks, the element calibrations; Gearbox, GearboxError
kinematics   Willis rows, gear speeds and ratios, the 2-DOF speed map, element slips, mass matrix, statics
vehicle      the five driveline values of a vehicle plant file (any path)
reduction    per shift: held / on-coming / off-going elements, normalised ratios, diagonal inertias; refusals
table        the generated shift table (tools/gearboxes/8hp_shifts.toml), write_shift_table, main(argv)

It sits above the calibration loader and below the generators and simulators (tests/python/
test_package_layout.py), so the plant and the image generators can use it.
"""
from __future__ import annotations

from . import kinematics
from .description import Element, Gearbox, GearboxError, PlanetarySet, Shaft, read
from .vehicle import Vehicle, load_vehicle


def load(path) -> Gearbox:
    """Read a gearbox description and check it whole: the structure, every element's calibration and the
    kinematics (every gear one degree of freedom, a turning output). Raises GearboxError naming the file and
    the key."""
    gb = read(path)
    kinematics.check(gb)
    return gb


__all__ = ["Element", "Gearbox", "GearboxError", "PlanetarySet", "Shaft", "Vehicle", "load", "load_vehicle",
           "read"]

"""Calibration file (TOML): loading and validation, and writing one back.

A calibration file holds one inline table per parameter:
``name = { value = ..., unit = "...", source = "..." }``. The unit is checked
against the one this module expects, so a file written in other units (kPa
where Pa is expected) is rejected rather than silently misread.
``render_calibration`` writes a base file with some values and sources
replaced (``wetclutch identify``), keeping its layout and comments.

Validation applies the rules of the firmware's ``wc_calibration_check``
(src/model/wc_calibration.c; DESIGN.md section 8, "Calibration validity")
with the same limits (``LIMITS``, include/wetclutch/wc_calibration.h) to the
values the firmware will hold (rounded to float32), and the film-table rules
to the table ``wetclutch lut`` would write: ``load`` refuses what the firmware
would refuse. Every message names the parameter (``section.name``) and the
firmware's name for it (``wc_cal_error_name``).

One module per concern, the clutch calibration's names importable from here (``calibration.load``):

parameters   the Calibration type, the parameter table (PARAMETERS, the OPTIONAL ones a file may leave out), the
             firmware's LIMITS and RANGES
rules        the firmware's rules: one value, the relations between fields, the film table (film_problem)
film_table   the h_bar(p_c) table a calibration gives the firmware: build, check, interpolate
loader       load: TOML, units, sources, rules, film table
writer       render_calibration: a base file with values and sources replaced
shift        the shift controller's calibration (its own file format and rules)
adaptation_image  the adaptation image: one clutch's learned values (wc_adapt_image.h), read and written
"""
from __future__ import annotations

from .loader import load
from .parameters import (C_NAMES, FILM_MAX_NODES, FORCE_MAX_N, LIMITS, OPTIONAL, PARAMETERS, RANGES, THETA_MAX_DEGC,
                         THETA_MIN_DEGC, Calibration, CalibrationError, f32)
from .rules import film_problem
from .writer import render_calibration

__all__ = ["C_NAMES", "FILM_MAX_NODES", "FORCE_MAX_N", "LIMITS", "OPTIONAL", "PARAMETERS", "RANGES", "THETA_MAX_DEGC",
           "THETA_MIN_DEGC", "Calibration", "CalibrationError", "f32", "film_problem", "load", "render_calibration"]

"""Identification from bench data (``wetclutch identify``): the paper's sections 3.2-3.4.

Steps, each usable alone; ``all`` runs them in the order
thermal -> viscosity -> asperity -> mu, each using what the previous found:

thermal    k1, k2 (and C on request) by the multiple linear regression of eq. 19,
           with the thermistor lag fitted alongside            (thermal.py)
viscosity  eq. 2 fitted to the (theta, mu_v) points             (viscosity.py)
asperity   N from the viscous drag in the flat part of eq. 18   (friction.py)
mu         eq. 17 samples fitted with eq. 18, SIMEX-corrected   (friction.py)

One module per concern: campaign.py reads the data (campaign discovery,
index and measurement tables, through csvio), signals.py filters and
segments each record and names every excluded sample, statistics.py holds the
confidence intervals and fit figures, report.py and plots.py write report.md,
figures.json, exclusions.csv and the PNGs, pipeline.py runs the steps and
writes the outputs; the calibration file is rendered by calibration/writer.py.
"""
from __future__ import annotations

import json  # noqa: F401  (identify.json: the tests read figures.json through it)

from ..calibration import render_calibration
from .campaign import (MEASUREMENT_COLUMNS, OPTIONAL_COLUMNS, QUANTITY_UNIT, VISCOSITY_COLUMNS, VISCOSITY_FILE,
                       Campaign, find_campaigns, find_viscosity, prepare_campaign, read_table)
from .friction import FrictionData, friction_data, hbar_of_force, identify_asperity, identify_mu, mu_samples
from .pipeline import STEPS, read_true, run, write_outputs
from .report import PAPER, SYMBOLS, TARGET_PARAMETERS, TARGETS, write_report
from .result import WHAT, Result, identified_sources, identified_values
from .settings import IdentifyError, Settings
from .signals import REASONS, Exclusion
from .thermal import identify_thermal, simulate_thermistor
from .viscosity import identify_viscosity

__all__ = [
    "Campaign", "Exclusion", "FrictionData", "IdentifyError", "MEASUREMENT_COLUMNS", "OPTIONAL_COLUMNS", "PAPER",
    "QUANTITY_UNIT", "REASONS", "Result", "STEPS", "SYMBOLS", "Settings", "TARGETS", "TARGET_PARAMETERS",
    "VISCOSITY_COLUMNS", "VISCOSITY_FILE", "WHAT", "find_campaigns", "find_viscosity", "friction_data",
    "hbar_of_force", "identified_sources", "identified_values", "identify_asperity", "identify_mu",
    "identify_thermal", "identify_viscosity", "mu_samples", "prepare_campaign", "read_table", "read_true",
    "render_calibration", "run", "simulate_thermistor", "write_outputs", "write_report",
]

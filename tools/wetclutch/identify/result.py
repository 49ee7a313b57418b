"""What an identification run produces: the Result, and the identified values with their sources."""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..calibration import Calibration
from .settings import Settings

WHAT = {
    "thermal": "the thermal runs, eq. 19 multiple linear regression",
    "viscosity": "viscosity.csv, eq. 2 least squares",
    "asperity": "the viscous drag of the friction runs (flat-mu region, eq. 8, 9, 15)",
    "mu": "the friction runs, eq. 17 samples fitted with eq. 18",
    "film": "the engagement runs' transient, the squeeze-film state (DESIGN 9) fitted to the torque",
    "static": "the breakaway runs, the torque at breakaway over the static capacity (DESIGN 9)",
}


@dataclass
class Result:
    step: str
    data_dir: Path
    base: Calibration
    cal: Calibration                 # base with the identified values
    results: dict = field(default_factory=dict)
    exclusions: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    campaigns: list = field(default_factory=list)
    settings: Settings | None = None


def identified_values(res: Result) -> dict[str, float]:
    return {name: float(v) for r in res.results.values() for name, v in r["values"].items()}


def identified_sources(res: Result) -> dict[str, str]:
    out = {}
    for step, r in res.results.items():
        for name in r["values"]:
            extra = r.get("source_notes", {}).get(name)
            out[name] = f"identified from {res.data_dir} by wetclutch identify on {WHAT[step]}" + (
                f"; {extra}" if extra else "")
    return out

"""The runs of the adaptation study (issue 20, DESIGN 12): consecutive shifts with one TCU that learns, the
matrix from a learned image and the fault cases.

Session     one TCU (wc_replay --lockstep, the frame loop in-process) over consecutive shifts on one plant:
            the learned values stay in the TCU and its adaptation file (wc_replay --adaptation-file, written
            at each shift end); between two shifts an idle gap (below).
learn       a sequence of shifts, the oil temperature a fixed cycle (OIL_CYCLE_DEGC), seeded noise.
matrix_case one scenario of issue 13's matrix (its shifts as run_case runs them: the soak's back to back with
            runner.BETWEEN_SHIFTS_S between them) with a fresh TCU that starts from a copy of a learned image
            (what a vehicle's TCU holds after its first shifts) or from none.

The idle gap. A shift ends locked in 2nd gear; the next starts from steady 1st gear with 851 rpm of slip (a
fresh plant). For the TCU the gap is gap_s of the request withdrawn (ShiftRequest 0) at zero slip (the
clutch released while synchronised, as in the 2->1 downshift that would come between: runner.
between_shifts), the oil and housing temperatures of the next shift; the plant's pack relaxes exactly (eq.
1, no friction power) towards the same. The study's gap (STUDY_GAP_S, 4.4 pack time constants) lets the
pack follow the oil cycle: each shift starts within 0.6 K of its oil's steady state. The gap's frames do
not depend on the TCU's answers: they are written ahead (InprocTcu.run_open_loop), 8 s cost 0.06 s of CPU.
"""
from __future__ import annotations

import functools
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..calibration import adaptation_image
from ..calibration import shift as shift_calibration
from ..util import canlog
from .quality import quality
from .runner import BETWEEN_SHIFTS_S, _one_shift, between_shifts
from .scenarios import SHIFT_TOML, TARGET_INERTIA_S, Scenario
from .tcu import InprocTcu


ADAPTATION_REPORT = "AdaptationReport"
OIL_CYCLE_DEGC = (80.0, 40.0, 110.0, 60.0, 20.0, 100.0, 50.0, 90.0)   # the matrix's oil range, every 8 shifts
STUDY_GAP_S = 8.0            # between the study's shifts: 4.4 pack time constants C / (k1 + k2) = 1.8 s
SEED_OFFSET = 100            # the study's shift i (1-based) has plant seed params.seed + SEED_OFFSET + i
CLUTCH_ID = 0                # wc_replay's clutch (the adaptation image's clutch id)
RESULT_NAMES = {0: "off/reset", 1: "updated", 2: "aborted", 3: "input fault", 4: "excitation", 5: "implausible"}


def _copy(src: Path | None, dst: Path) -> Path:
    dst.parent.mkdir(parents=True, exist_ok=True)
    if src is not None and Path(src).is_file():
        shutil.copyfile(src, dst)
    elif dst.exists():
        dst.unlink()
    return dst


def read_values(path: Path | None) -> dict | None:
    """The learned values in an adaptation file (calibration/adaptation_image.py), or None (no file yet, or
    wc_replay without --adaptation-file)."""
    if path is None or not Path(path).is_file():
        return None
    v = adaptation_image.read_adaptation_file(path, CLUTCH_ID)
    return {"friction_scale": list(v.friction_scale), "confidence": list(v.confidence), "film_factor": v.film_factor,
            "kiss_offset_Pa": v.kiss_offset_Pa, "shifts_learned": v.shifts_learned}


def adaptation_report(rec: dict, db) -> dict | None:
    """The shift's AdaptationReport (DBC), decoded (raw numbers), or None when the TCU sent none."""
    try:
        msg = db.get_message_by_name(ADAPTATION_REPORT)
    except KeyError:
        return None
    for _, fid, data in rec["frames"]:
        if fid == msg.frame_id:
            return {k: float(v) for k, v in msg.decode(bytes.fromhex(data), decode_choices=False).items()}
    return None


def shift_calibrations() -> dict:
    return shift_calibration.load(SHIFT_TOML).variants


@functools.lru_cache(maxsize=None)
def _file_supported() -> bool:
    return InprocTcu.supports_adaptation_file()


def adaptive_supported(db=None) -> bool:
    """The firmware has the adaptation: the DBC carries AdaptationReport and wc_replay takes
    --adaptation-file (read from its usage text)."""
    db = db or canlog.database()
    if ADAPTATION_REPORT not in {m.name for m in db.messages}:
        return False
    return _file_supported()


# --------------------------------------------------------------------------------------------------- faults
@dataclass(frozen=True)
class Fault:
    """A fault injected into one shift (runner._one_shift's inject): name, what, the injector."""
    name: str
    description: str
    inject: object = field(compare=False)


def _glitch(k, k_i, signals, start_s=0.1, samples=5):
    if k_i + round(start_s * 1e3) <= k < k_i + round(start_s * 1e3) + samples:
        signals[canlog.SENSORS]["SlipSpeed"] = "SNA"


def _withdrawn(k, k_i, signals, after_s=0.2):
    if k >= k_i + round(after_s * 1e3):
        signals[canlog.SHIFT_COMMAND]["ShiftRequest"] = 0


def _torque_off(k, k_i, signals, factor=1.2):
    c = signals[canlog.SHIFT_COMMAND]
    c["TurbineTorque"] = float(np.clip(c["TurbineTorque"] * factor, -1000.0, 1000.0))


FAULTS = (
    Fault("glitch", "ClutchSensors.SlipSpeed SNA for 5 ms, 100 ms into the inertia phase (below the 10 ms timeout:"
                    " the TCU holds the last slip)", _glitch),
    Fault("sna-timeout", "ClutchSensors.SlipSpeed SNA for 12 ms, 100 ms into the inertia phase (the sensor timeout:"
                         " safe state, AbortReason 3)", functools.partial(_glitch, samples=12)),
    Fault("abort", "ShiftRequest withdrawn 200 ms into the inertia phase (AbortReason 4, cancelled)", _withdrawn),
    Fault("torque+20", "ShiftCommand.TurbineTorque 20 % above the estimate for the whole shift", _torque_off),
)


# --------------------------------------------------------------------------------------------------- session
class Session:
    """One TCU over consecutive shifts on one plant (module docstring). shift_name: a compiled-in shift
    calibration (shift_1_2_adaptive, shift_1_2_full, ...); image: an adaptation file to start from (copied to
    work_dir/adaptation.bin, which the TCU then writes); work_dir None: no adaptation file."""

    def __init__(self, params, shift_name: str, oil_degC: float, work_dir: Path | None = None,
                 image: Path | None = None, shift_cal=None, target_s: float = TARGET_INERTIA_S):
        self.params = params
        self.shift_name = shift_name
        self.shift_cal = shift_cal or shift_calibrations()[shift_name.split("shift_1_2_")[-1]]
        self.target_s = target_s
        self.file = (_copy(image, Path(work_dir) / "adaptation.bin")
                     if work_dir is not None and _file_supported() else None)
        self.tcu = InprocTcu(shift_name, oil_degC, adaptation_file=self.file)
        self.enc = canlog.Encoder()
        self.db = self.enc.db
        self.t_s = 0.0
        self.theta_degC = None           # the plant's pack at the next shift's start (None: the oil's)

    def close(self):
        self.tcu.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def values(self) -> dict | None:
        return read_values(self.file)

    def shift(self, oil_degC: float, seed: int, *, load: float = 1.0, friction_scale: float = 1.0,
              inject=None, name: str = "shift") -> dict:
        """One shift at oil_degC; returns the runner's record plus quality, the AdaptationReport and the
        learned values after it (the TCU's file)."""
        sc = Scenario(name, float(oil_degC), load, friction_scale)
        rec = _one_shift(self.params, self.tcu, self.enc, self.db, sc, self.theta_degC, self.t_s, seed,
                         self.target_s, self.shift_cal, inject)
        self.t_s += rec["t_s"][-1] + 1e-3
        self.theta_degC = rec["end_theta_degC"]
        rec["oil_degC"] = float(oil_degC)
        rec["quality"] = quality(rec, self.target_s)
        rec["adaptation"] = adaptation_report(rec, self.db)
        rec["values"] = self.values()
        return rec

    def idle(self, gap_s: float, oil_degC: float) -> None:
        """The gap before the next shift (module docstring; runner.between_shifts): the TCU at zero slip with
        the request withdrawn for gap_s, the plant's pack relaxed towards the next oil temperature's steady
        state."""
        self.theta_degC, self.t_s = between_shifts(self.params, self.tcu, self.enc, oil_degC, self.theta_degC,
                                                   self.t_s, gap_s, self.target_s)


# --------------------------------------------------------------------------------------------------- runs
def shift_entry(i: int, rec: dict) -> dict:
    """What the study keeps of a shift: its number, oil, quality (the plant's truth), the TCU's reports and
    the learned values after it, the observer's error."""
    q = dict(rec["quality"])
    q.pop("tcu_report", None)
    est, true = rec["theta_estimate_degC"], rec["true_theta_clutch_degC"]
    k0 = rec["command_step"]
    return {"shift": i, "oil_degC": rec["oil_degC"], "quality": q, "shift_report": rec["quality"]["tcu_report"],
            "adaptation": rec["adaptation"], "values": rec["values"],
            "theta_error_max_K": float(np.max(np.abs(est[k0:] - true[k0:]))),
            "theta_error_end_K": float(est[-1] - true[-1]),
            "theta_peak_error_K": float(np.max(est[k0:]) - np.max(true[k0:]))}


def learn(params, shift_name: str, shifts: int, work_dir: Path, *, cycle=OIL_CYCLE_DEGC, gap_s: float = STUDY_GAP_S,
          keep_after: int | None = None, image: Path | None = None, first: int = 1, faults: dict | None = None,
          records: list | None = None) -> dict:
    """`shifts` consecutive shifts with one TCU from `image` (None: the calibration's values), the oil
    temperature cycle[(i - 1) % len(cycle)] for shift i = first, first + 1, ...; faults {i: Fault}.
    Returns {"shifts": [shift_entry], "image_after": path of the image after shift keep_after (or None),
    "image_before": the values before the first shift}."""
    work_dir = Path(work_dir)
    out = {"shifts": [], "image_after": None}
    oil = [cycle[(i - 1) % len(cycle)] for i in range(first, first + shifts)]
    with Session(params, shift_name, oil[0], work_dir, image) as s:
        out["values_before"] = s.values()
        for j, i in enumerate(range(first, first + shifts)):
            if j:
                s.idle(gap_s, oil[j])
            fault = (faults or {}).get(i)
            rec = s.shift(oil[j], params.seed + SEED_OFFSET + i, inject=fault.inject if fault else None)
            entry = shift_entry(i, rec)
            if fault:
                entry["fault"] = fault.name
            out["shifts"].append(entry)
            if records is not None:
                records.append(rec)
            if keep_after is not None and i == keep_after and s.file is not None and s.file.is_file():
                out["image_after"] = str(_copy(s.file, work_dir / f"image_after_{i}.bin"))
    return out


def matrix_case(params, shift_name: str, scenario: Scenario, work_dir: Path | None = None,
                image: Path | None = None) -> list[dict]:
    """One scenario of the matrix as run_case runs it (the soak's shifts back to back, runner.BETWEEN_SHIFTS_S
    between them: the same frames) with a fresh TCU that starts from a copy of image (None: the
    calibration's values). Returns the records (with quality, reports and learned values)."""
    with Session(params, shift_name, scenario.oil_degC, work_dir, image) as s:
        recs = []
        for i in range(scenario.shifts):
            if i:
                s.idle(BETWEEN_SHIFTS_S, scenario.oil_degC)
            recs.append(s.shift(scenario.oil_degC, params.seed + i, load=scenario.load,
                                friction_scale=scenario.friction_scale, name=scenario.name))
        return recs

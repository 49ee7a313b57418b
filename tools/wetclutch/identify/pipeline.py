"""The command: run the steps in order (``run``) and write what they found (``write_outputs``).

``all`` runs thermal -> viscosity -> asperity -> mu -> film -> static, each step
using what the previous ones found (the calibration values and the thermistor
lag); film and static run when the data hold engagement / breakaway runs.
"""
from __future__ import annotations

import time
from pathlib import Path

from ..calibration import film_table
from ..util.atomic import Staged
from ..calibration import Calibration, CalibrationError, load as load_calibration, render_calibration
from .campaign import Campaign, find_campaigns, find_viscosity, prepare_campaign
from .edges import identify_film, identify_static, read_runs
from .friction import friction_data, identify_asperity, identify_mu
from .report import write_report
from .result import Result, identified_sources, identified_values
from .settings import IdentifyError, Settings
from .thermal import identify_thermal
from .viscosity import identify_viscosity

STEPS = ("thermal", "viscosity", "asperity", "mu", "film", "static")
EDGE_KINDS = {"film": "engagement", "static": "breakaway"}   # the engagement edges' steps and their runs


def run(step: str, data_dir: Path, base: Calibration, s: Settings) -> Result:
    """Identify; nothing is written here."""
    if step not in STEPS + ("all",):
        raise IdentifyError(f"unknown step {step!r}")
    data_dir = Path(data_dir)
    steps = STEPS if step == "all" else (step,)
    res = Result(step, data_dir, base, base, settings=s)
    clock = time.perf_counter()
    need_friction = any(x in steps for x in ("asperity", "mu"))
    need_thermal = "thermal" in steps
    need_edges = any(x in steps for x in EDGE_KINDS)
    campaigns = find_campaigns(data_dir, res.notes) if (need_friction or need_thermal or need_edges) else []
    res.campaigns = [{"index": str(c.index), "kind": c.kind, "experiments": len(c.rows)} for c in campaigns]
    cal = base
    tau = s.thermistor_lag_s
    tau_source = "--thermistor-lag" if tau is not None else None

    if need_thermal:
        cal, tau, tau_source = _run_thermal(res, campaigns, cal, s, tau, tau_source)

    if "viscosity" in steps:
        t0 = time.perf_counter()
        r = identify_viscosity(find_viscosity(data_dir), cal, res.exclusions)
        res.results["viscosity"] = r
        cal = cal.with_values(**r["values"])
        res.timings["viscosity"] = time.perf_counter() - t0

    if need_friction:
        cal = _run_friction(res, campaigns, steps, cal, s, tau, tau_source)
    for step_name, kind in EDGE_KINDS.items():
        if step_name not in steps:
            continue
        if step == "all" and not any(c.kind == kind for c in campaigns):
            res.notes.append(f"{step_name}: no {kind} runs in {data_dir}: step skipped")
            continue
        t0 = time.perf_counter()
        runs = read_runs(campaigns, kind)
        if not runs:
            raise IdentifyError(f"{data_dir}: no {kind} campaign (an index in a directory or file named '{kind}')"
                                f" for the {step_name} step")
        r = (identify_film if step_name == "film" else identify_static)(runs, cal)
        res.results[step_name] = r
        cal = cal.with_values(**r["values"])
        res.timings[step_name] = time.perf_counter() - t0
    res.cal = cal
    res.timings["total"] = time.perf_counter() - clock
    return res


def _run_thermal(res: Result, campaigns: list[Campaign], cal: Calibration, s: Settings, tau: float | None,
                 tau_source: str | None):
    """The thermal step; returns the calibration with k1, k2 and the thermistor lag (and its source)."""
    t0 = time.perf_counter()
    thermal = [c for c in campaigns if c.kind == "thermal"]
    if not thermal:
        if res.step == "thermal":
            thermal = [c for c in campaigns if c.kind == "friction"]
            res.notes.append("thermal: no campaign named 'thermal': the friction runs are used for eq. 19")
        else:
            raise IdentifyError(f"{res.data_dir}: no thermal campaign (an index in a directory or file named"
                                " 'thermal') for the thermal step")
    prepared = []
    for c in thermal:
        prepared += prepare_campaign(c, "thermal", cal, s, res.exclusions)
    r = identify_thermal(prepared, cal, s)
    r["ids"] = [p["id"] for p in prepared]
    res.results["thermal"] = r
    cal = cal.with_values(**r["values"])
    if tau is None:
        tau, tau_source = r["thermistor_lag_s"], "from the thermal step (eq. 19)"
    res.timings["thermal"] = time.perf_counter() - t0
    return cal, tau, tau_source


def _run_friction(res: Result, campaigns: list[Campaign], steps, cal: Calibration, s: Settings,
                  tau: float | None, tau_source: str | None) -> Calibration:
    """The asperity and mu steps on the friction runs (read once); returns the calibration with their values."""
    t0 = time.perf_counter()
    friction = [c for c in campaigns if c.kind == "friction"]
    if not friction:
        raise IdentifyError(f"{res.data_dir}: no friction campaign (Table 2 runs) for the {'/'.join(steps)} step")
    prepared = []
    for c in friction:
        prepared += prepare_campaign(c, "friction", cal, s, res.exclusions)
    fd = friction_data(prepared, cal, res.notes)
    res.timings["friction load"] = time.perf_counter() - t0
    if "asperity" in steps:
        t0 = time.perf_counter()
        r = identify_asperity(fd, cal, tau, s, tau_source or "given")
        tau, tau_source = r["thermistor_lag_s"], r["thermistor_lag_source"]
        res.results["asperity"] = r
        cal = cal.with_values(**r["values"])
        res.timings["asperity"] = time.perf_counter() - t0
    if "mu" in steps:
        t0 = time.perf_counter()
        r = identify_mu(fd, cal, tau, tau_source or "given", simex=s.simex)
        r["fd"] = fd
        res.results["mu"] = r
        cal = cal.with_values(**r["values"])
        res.timings["mu"] = time.perf_counter() - t0
    return cal


def read_true(path: Path) -> dict[str, float]:
    """True parameters: a calibration file (the bench's, e.g. bench_true.toml)."""
    try:
        return dict(load_calibration(path).values)
    except CalibrationError as e:
        raise IdentifyError(str(e)) from None


def write_outputs(res: Result, base_path: Path, out_dir: Path, command: str, true_path: Path | None,
                  plots: bool = True) -> dict:
    """calibration.toml (checked by calibration.load and a LUT build), report.md, figures.json, PNGs.

    All or nothing (atomic.Staged): on any failure (a rejected calibration, a full disk) none of the
    files is written and an earlier run's files in out_dir are left as they were."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    changes = identified_values(res)
    sources = identified_sources(res)
    header = (f"# Calibration identified from bench data: `{command}`\n"
              f"# Base: {base_path}; identified values carry their source below.\n")
    text = render_calibration(base_path, res.base, changes, sources, header)
    cal_path = out_dir / "calibration.toml"
    truth = read_true(true_path) if true_path else None
    with Staged() as out:
        with out.path(cal_path) as tmp:
            tmp.write_text(text, encoding="utf-8")
            try:
                check = load_calibration(tmp)
            except CalibrationError as e:
                raise IdentifyError("the identified calibration is rejected by calibration.load: "
                                    + str(e).replace(str(tmp), str(cal_path))) from None
            try:
                table = film_table.build_table(check)
            except film_table.TableError as e:
                raise IdentifyError(f"the identified calibration makes no film table: {e}") from None
        lut_error = film_table.max_relative_error(check, table)
        return write_report(res, out_dir, command, truth, str(true_path) if true_path else None,
                            {"path": str(cal_path), "lut_max_rel_error": lut_error,
                             "lut_nodes": int(table.pressure_Pa.size)}, plots)

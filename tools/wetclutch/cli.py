"""The wet-clutch tool's command line: parse, call one function of the package, print its result.

commands by role (the folder of tools/wetclutch that does the work):
  generate/   lut         calibration and h_bar(p_c) headers (a shift calibration: its header)
              cal-image   the calibration image (clutch, shift, loop) for --calibration-image, or its C header
              vectors     golden vectors for the C tests
  reference/  reference   the double-precision model on CSV, under the firmware's input rules
  simulate/   bench       the simulated test bench: measurement CSVs and CAN logs
  identify/   identify    bench data -> calibration file
  generate/   a2l         the A2L of the TCU's XCP slave (addresses from wc_tcu --xcp-layout)
  hil/        replay      bench logs to wc_tcu on vcan0, checked against the reference; the report
              convert     a Vector ASC/BLF log -> candump -L; --to mdf4: a CAN log -> MDF4
  shift/      shift       closed-loop 1->2 upshifts on the plant (simulate/plant)
  gearbox/    gearbox     a gearbox description -> its shift table (ratios, slips, per-shift models)
  studies/    film-study  the squeeze-film state over a family of bench plants
calibration/ (loading and checking calibration files) and util/ serve them all.
"""
from __future__ import annotations

import argparse
import concurrent.futures
import os
import sys
from pathlib import Path

import numpy as np

from . import calibration
from .calibration import shift as shift_calibration
from .generate import lut, shift_header, vectors
from .reference import evaluate as reference, model
from .util import atomic
from .util.csvio import CsvError, read_columns, write_columns
from .util.errors import LogError

DEFAULT_CAL = "tools/calibrations/table1.toml"


def _cmd_lut(args) -> int:
    lut.check_max_error(args.max_error)   # before any work: NaN or <= 0 would disable the check
    if shift_calibration.is_shift_calibration(args.calibration):   # a [shift] table: the shift controller's
        command = f"wetclutch lut {args.calibration} --out {args.out}"
        written = shift_header.write_header(shift_calibration.load(args.calibration), Path(args.out), command)
        print(f"wrote {written}")
        return 0
    cal = calibration.load(args.calibration)
    name = args.name or Path(args.calibration).stem
    command = f"wetclutch lut {args.calibration} --out {args.out}" + (f" --name {args.name}" if args.name else "")
    figures = lut.generate(cal, Path(args.out), name, command)
    print(f"film table: {figures['nodes']} nodes, {figures['bytes']} bytes,"
          f" max relative error {figures['max_rel_error']:.3e} (grid {lut.DENSITY}x denser)")
    for f in figures["files"]:
        print(f"wrote {f}")
    if figures["max_rel_error"] > args.max_error:
        print(f"wetclutch lut: error {figures['max_rel_error']:.3e} exceeds the bound {args.max_error:g}",
              file=sys.stderr)
        return 1
    return 0


def _cmd_cal_image(args) -> int:
    from .calibration import cal_image
    from .generate import cal_image_header
    if args.show:
        print(cal_image.describe(cal_image.read_file(args.show)))
        return 0
    if not (args.calibration and args.out):
        raise cal_image.CalImageError("give CAL.toml and --out FILE (or --show FILE)")
    loop = {"sensor_timeout_periods": args.sensor_timeout, "request_timeout_periods": args.request_timeout,
            "max_delta_counter": args.max_delta_counter, "sync_counter": args.sync_counter,
            "recovery_periods": args.recovery_periods}
    values = cal_image.build(args.calibration, args.shift_toml, args.shift_variant, loop)
    image = cal_image.write_image_bytes(values)
    if Path(args.out).suffix == ".h":
        command = " ".join(["wetclutch cal-image", args.calibration]
                           + (["--shift-toml", args.shift_toml] if args.shift_toml else [])
                           + (["--shift-variant", args.shift_variant] if args.shift_variant else [])
                           + [f"--{k.replace('_', '-')} {v}" for k, v in vars(args).items() if k in _LOOP_OPTIONS
                              and v is not None] + ["--out", args.out])
        what = f"'{Path(args.calibration).stem}' ({Path(args.calibration).name}), " + (
            f"shift calibration {args.shift_variant}" if args.shift_variant else "shift control off")
        cal_image_header.write_header(args.out, image, command, what)
    else:
        cal_image.write_file(args.out, values)
    print(f"wrote {args.out}: {len(image)} bytes (payload {cal_image.PAYLOAD_BYTES}), film table"
          f" {values['clutch.film.length']} nodes, shift control {'on' if values['loop.shift_enabled'] else 'off'}")
    return 0


_LOOP_OPTIONS = ("sensor_timeout", "request_timeout", "max_delta_counter", "sync_counter", "recovery_periods")


def _cmd_reference(args) -> int:
    cal = calibration.load(args.calibration)
    source = args.input or "<stdin>"
    stream = open(args.input, newline="", encoding="utf-8") if args.input else sys.stdin
    lines: list[int] = []
    with stream:
        cols = read_columns(stream, reference.INPUTS[args.mode], source, finite=not args.keep_rejected, lines=lines)
    try:
        out = reference.MODES[args.mode](cal, cols, lines)
    except CsvError as e:
        raise CsvError(f"{source}: {e}") from None
    rejected = np.flatnonzero(out["status"] & model.STATUS_INPUT_INVALID)
    if rejected.size and not args.keep_rejected:
        k = int(rejected[0])
        status = int(out["status"][k])
        more = f" ({rejected.size} rows rejected)" if rejected.size > 1 else ""
        raise CsvError(f"{source}: line {lines[k]}: input rejected by the firmware's input rules (status 0x{status:x}):"
                       f" {reference.rejection_text(status)}{more}; --keep-rejected writes such rows with their status")
    names = reference.OUTPUTS[args.mode] + (("status",) if args.keep_rejected and args.mode != "inverse" else ())
    out = {n: out[n] for n in names}
    if args.output:
        with atomic.open_atomic(args.output, newline="") as f:
            write_columns(f, out)
    else:
        write_columns(sys.stdout, out)
    if rejected.size:
        print(f"wetclutch reference: {source}: {rejected.size} row(s) rejected by the firmware's input rules, first"
              f" at line {lines[int(rejected[0])]}: written with their status bits and the firmware's safe outputs",
              file=sys.stderr)
    return 0


def _cmd_vectors(args) -> int:
    cal = calibration.load(args.calibration)
    command = f"wetclutch vectors {args.calibration} --out {args.out}"
    for f in vectors.generate(cal, Path(args.out), command):
        print(f"wrote {f}")
    return 0


def _analyse_replay(calibration_path: str, log: Path, run_dir: Path, reference_check: bool, where: str) -> dict:
    """report.analyse of one log in a worker process (the calibration loaded there)."""
    from .hil import report
    return report.analyse(calibration.load(calibration_path), log, run_dir, reference_check=reference_check,
                          where=where)


def _cmd_replay(args) -> int:
    from .hil import replay, report  # matplotlib and the CAN stack only when needed
    cal = calibration.load(args.calibration)
    out_root = Path(args.out)
    jobs = []
    for log in args.logs:
        log = Path(log)
        check = replay.check_log(log)   # missing or malformed: LogError, nothing runs
        for problem in check.problems():
            print(f"wetclutch replay: {log}: {problem}", file=sys.stderr)
        jobs.append((log, out_root / log.stem))
    compiled_in = lut.c_identifier(Path(args.calibration).stem)
    where = report.IN_PROCESS if args.in_process else report.ON_VCAN
    if args.in_process and not args.analyse_only:
        print(f"wetclutch replay: {len(jobs)} log(s) to the frame loop in-process (wc_replay)", file=sys.stderr,
              flush=True)
        replay.run_in_process(jobs, frame_runs=2, calibration=compiled_in)
    elif not args.analyse_only:
        print(f"wetclutch replay: {len(jobs)} log(s) on vcan0 (the VM boot takes about a minute where the"
              " kernel has no CAN)", file=sys.stderr, flush=True)
        replay.run_on_vcan(jobs, frame_runs=2, timer_runs=1, calibration=compiled_in)
    missed = []
    for log, _ in jobs:
        print(f"wetclutch replay: analysing {log.name}"
              + ("" if args.no_reference_check else " (reference check of every step)"), file=sys.stderr, flush=True)
    check = not args.no_reference_check
    # the logs' analyses are independent (each its own reference run and plots): on two cores at once
    workers = min(len(jobs), os.cpu_count() or 1, 2)
    if workers > 1:
        with concurrent.futures.ProcessPoolExecutor(max_workers=workers) as pool:
            results = list(pool.map(_analyse_replay, [args.calibration] * len(jobs), [log for log, _ in jobs],
                                    [run_dir for _, run_dir in jobs], [check] * len(jobs), [where] * len(jobs)))
    else:
        results = [report.analyse(cal, log, run_dir, reference_check=check, where=where) for log, run_dir in jobs]
    for (log, run_dir), m in zip(jobs, results):
        print((run_dir / "summary.md").read_text())
        print(f"report: {run_dir}/summary.md, metrics.json, {Path(m['mdf']['path']).name},"
              f" {', '.join(Path(p).name for p in m['plots'])}")
        if not m["all_targets_met"]:
            missed.append(f"{log.name}: " + ", ".join(k for k, v in m["targets"].items() if not v))
    if missed:
        print("wetclutch replay: targets missed: " + "; ".join(missed), file=sys.stderr)
        return 1
    return 0


def _cmd_identify(args) -> int:
    from . import identify  # scipy.optimize and matplotlib only when needed
    base = calibration.load(args.calibration)
    settings = identify.Settings(jobs=max(1, args.jobs), thermistor_lag_s=args.thermistor_lag,
                                 fit_heat_capacity=args.fit_heat_capacity, slip_min_rpm=args.slip_min,
                                 simex=not args.no_simex)
    command = " ".join(["wetclutch identify", args.step, args.data_dir, "--calibration", args.calibration,
                        "--out", args.out] + (["--true", args.true] if args.true else [])
                       + (["--fit-heat-capacity"] if args.fit_heat_capacity else [])
                       + ([f"--thermistor-lag {args.thermistor_lag:g}"] if args.thermistor_lag is not None else [])
                       + (["--no-simex"] if args.no_simex else []))
    if args.true:
        identify.read_true(Path(args.true))   # a bad --true fails before the work
    result = identify.run(args.step, Path(args.data_dir), base, settings)
    fig = identify.write_outputs(result, Path(args.calibration), Path(args.out), command,
                                 Path(args.true) if args.true else None, plots=not args.no_plots)
    print((Path(args.out) / "report.md").read_text().split("\n## Exclusions")[0])
    print(f"wrote {args.out}/calibration.toml, report.md, figures.json, exclusions.csv"
          + (f" and {len(fig['plots'])} plots" if fig["plots"] else ""))
    missed = [k for k, v in fig["targets"].items() if not v]
    if missed and args.true:
        print("wetclutch identify: targets missed: " + ", ".join(missed), file=sys.stderr)
        return 1
    return 0


def _cmd_bench(args) -> int:
    import time
    from .simulate import bench  # the simulator only when needed
    start = time.monotonic()
    out = bench.run(args.experiment, args.out, true_path=args.true, seed=args.seed, slips_rpm=args.slip,
                    logs=True if args.logs else None, thetas_degC=args.theta)
    for r in out["results"]:
        if r.experiment.kind == "engagement":
            f = bench.engagement_figures(r)
            print(f"{r.experiment.name}: contact {f['t_contact_s']:.3f} s, lock {f['t_lock_s']:.3f} s,"
                  f" peak torque {f['peak_torque_Nm']:.1f} Nm, peak viscous {f['peak_viscous_Nm']:.1f} Nm,"
                  f" 90 % contact force {f['film_90_s']:.3f} s after contact")
        elif r.experiment.kind == "breakaway":
            f = bench.breakaway_figures(r)
            print(f"{r.experiment.name}: breakaway {f['t_breakaway_s']:.3f} s at {f['static_capacity_Nm']:.1f} Nm"
                  f" (measured peak while locked {f['breakaway_torque_measured_Nm']:.1f} Nm), motor off"
                  f" {f['t_motor_off_s']:.3f} s, locked again {f['t_relock_s']:.3f} s")
    print(f"wrote {len(out['files'])} files to {args.out} ({len(out['results'])} experiment(s), seed {args.seed},"
          f" true parameters {args.true}) in {time.monotonic() - start:.1f} s")
    return 0


_SKIPPED = {"error": "error frame(s)", "remote": "remote frame(s)", "fd": "CAN FD frame(s)",
            "event": "non-CAN event line(s)"}


def _cmd_film_study(args) -> int:
    from .studies import film_study  # the bench simulator only when needed
    res = film_study.run(Path(args.out), model_path=args.calibration, true_path=args.true, seed=args.seed)
    print(film_study.markdown(res))
    print(f"wrote {args.out}/film_study.md, film_study.json")
    if not res["all_met"]:
        missed = [r for r in res["cases"] if not r["met"]]
        print(f"wetclutch film-study: {len(missed)} case(s) below the ratio {res['ratio_target']:g}", file=sys.stderr)
        return 1
    return 0


def _cmd_shift(args) -> int:
    from . import shift  # the plant and the closed loop only when needed
    from .simulate import plant
    try:
        plant.load_plant(args.plant)    # a bad plant file: one line naming it, before any work
    except plant.PlantError as e:
        print(f"wetclutch shift: {e}", file=sys.stderr)
        return 2
    if args.adaptation_study:
        return _adaptation_study(args)
    if args.tune_feedback:
        res = shift.tune_feedback(args.plant)
        for g in res["grid"]:
            print(f"kp {g['kp']:5.1f} ki {g['ki']:6.1f}: slip RMSE {g['slip_rmse_rpm']:7.1f} rpm, peak jerk"
                  f" {g['peak_jerk_m_s3']:6.1f} m/s^3, inertia time {100 * g['inertia_time_error']:+6.1f} %,"
                  f" flare {g['flare']}, tie-up {g['tie_up']}, abort {g['abort']}")
        b = res["best"]
        print(f"best ({res['criterion']}): kp {b['kp']:g} Nm/(rad/s), ki {b['ki']:g} Nm/rad"
              " -> [variants.feedback] of tools/calibrations/shift_1_2.toml")
        return 0
    out = Path(args.out or "out/shift")
    if not args.oncoming_only:   # the whole shift (issue 22, DESIGN 14) over the vehicle family
        from .shift import whole
        vehicles = tuple(args.vehicles or whole.VEHICLES)
        unknown = [v for v in vehicles if not whole.plant_path(v).is_file()]
        if unknown:
            print(f"wetclutch shift: --vehicles: no plant file for {', '.join(unknown)} in {whole.VEHICLES_DIR}"
                  f" (known: {', '.join(whole.VEHICLES)})", file=sys.stderr)
            return 2
        metrics, report_name = whole.report(out, vehicles=vehicles), "whole_shift_report.md"
    else:                        # issue 13's comparison: the on-coming clutch alone on --plant
        metrics, report_name = shift.report(out, plant_path=args.plant), "shift_report.md"
    print((out / report_name).read_text())
    print(f"wrote {out}/metrics.json, {report_name}, " + ", ".join(Path(p).name for p in metrics["plots"])
          + f" and {len(metrics['mdf'])} MDF4 files")
    if metrics["missed"]:
        print("wetclutch shift: targets missed: " + ", ".join(metrics["missed"]), file=sys.stderr)
        return 1
    return 0


def _cmd_vehicle_cal(args) -> int:
    from .shift import vehicle_cal
    argv = ([args.plants_dir] if args.plants_dir else []) + (["--out", args.out] if args.out else [])
    return vehicle_cal.main(argv)


def _cmd_gearbox(args) -> int:
    from .calibration import gearbox_image
    from .gearbox import table
    from .generate import gearbox_header
    argv = [args.gearbox] + (["--vehicle", args.vehicle] if args.vehicle else []) + (["--out", args.out] if args.out else [])
    for option, given in (("--header", args.header), ("--image", args.image)):
        if given and not args.vehicle:   # before any work: the header and the image carry the per-shift inertias
            print(f"wetclutch gearbox: {option} needs --vehicle (the reduced models' inertias)", file=sys.stderr)
            return 2
    status = table.main(argv)
    if status != 0 or not (args.header or args.image):
        return status
    out = Path(args.out) if args.out else Path(args.gearbox).with_name(Path(args.gearbox).stem + "_shifts.toml")
    try:
        if args.header:
            command = "wetclutch gearbox " + " ".join(argv) + f" --header {args.header}"
            print(gearbox_header.write_header(out, args.header, command))
        if args.image:
            n = gearbox_image.write_file(args.image, out)
            print(f"{args.image} ({n} bytes: the gearbox image, wc_gearbox_image.h; wc_tcu --gearbox-image)")
    except (gearbox_header.GearboxHeaderError, gearbox_image.GearboxImageError, OSError) as e:
        print(f"wetclutch gearbox: {e}", file=sys.stderr)
        return 1
    return 0


def _adaptation_study(args) -> int:
    """wetclutch shift --adaptation-study: the study, its report and plots; exit 1 when a target is missed."""
    from .shift import adaptation_report, adaptation_study
    from .simulate.plant import variants
    try:
        for name in args.variants or ():
            variants.variant(name)
    except KeyError as e:
        print(f"wetclutch shift: {e.args[0]}", file=sys.stderr)
        return 2
    if args.shifts < adaptation_study.LEARN_SHIFTS + 1:
        print(f"wetclutch shift: --shifts {args.shifts}: at least {adaptation_study.LEARN_SHIFTS + 1} (the learning"
              " shifts, then the comparison)", file=sys.stderr)
        return 2
    out = Path(args.out or "out/adaptation_study")
    res = adaptation_study.run_study(out, args.variants, args.shifts, plant_path=args.plant,
                                     progress=lambda text: print(text, file=sys.stderr, flush=True))
    plots = adaptation_report.write(out, res)
    print((out / "adaptation_study.md").read_text())
    print(f"wrote {out}/adaptation_study.md, adaptation_study.json, " + ", ".join(Path(p).name for p in plots))
    left = adaptation_study.missed(res["targets"])
    if left:
        print("wetclutch shift: adaptation targets missed: " + ", ".join(left), file=sys.stderr)
        return 1
    return 0


def _cmd_a2l(args) -> int:
    from .generate import a2l
    layout = a2l.read_layout(tcu=Path(args.tcu), layout_file=Path(args.layout) if args.layout else None)
    print(f"wrote {a2l.write_a2l(layout, Path(args.out))}")
    return 0


def _cmd_convert(args) -> int:
    from .hil import convert
    if args.to == "mdf4":
        return _convert_mdf4(args)
    stats = convert.convert_log(args.input, args.output, channel=args.channel)
    for where, stamp, previous in stats["out_of_order"][:5]:
        print(f"wetclutch convert: warning: {args.input}: {where}: timestamp {stamp:.6f} s is earlier than the"
              f" frame before it ({previous:.6f} s): out of order, copied as is", file=sys.stderr)
    if len(stats["out_of_order"]) > 5:
        print(f"wetclutch convert: warning: {args.input}: {len(stats['out_of_order']) - 5} more out-of-order frames",
              file=sys.stderr)
    skipped = ", ".join(f"{v} {_SKIPPED[k]}" for k, v in stats["skipped"].items() if v)
    print(f"wrote {args.output}: {stats['frames']} frames over {stats['span_s']:.3f} s"
          + (f" (skipped: {skipped})" if skipped else "")
          + (f"; {len(stats['out_of_order'])} out of order" if stats["out_of_order"] else ""))
    return 0


def _convert_mdf4(args) -> int:
    """wetclutch convert --to mdf4: one line on the frames left out (stderr), one on what was written."""
    from .hil import convert
    from .util import mdf
    res = convert.to_mdf4(args.input, args.output)
    if mdf.skipped_text(res):
        print(f"wetclutch convert: warning: {args.input}: {mdf.skipped_text(res)}", file=sys.stderr)
    print(f"wrote {args.output}: {sum(res['groups'].values())} of {res['frames']} frames over {res['span_s']:.3f} s"
          f" in {len(res['groups'])} channel groups ({', '.join(res['groups'])})")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="wetclutch", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)

    q = sub.add_parser("lut", help="write the calibration and h_bar(p_c) headers for the firmware")
    q.add_argument("calibration", help="calibration TOML file")
    q.add_argument("--out", default="lut", help="output directory (default: lut)")
    q.add_argument("--name", help="C name of the calibration (default: the file's stem)")
    q.add_argument("--max-error", type=float, default=1e-4, help="fail above this relative h_bar error")
    q.set_defaults(func=_cmd_lut)

    q = sub.add_parser("cal-image", help="write the calibration image (wc_cal_image.h) that wc_tcu and wc_replay"
                       " --calibration-image load; OUT ending in .h: a C header for a compiled-in image")
    q.add_argument("calibration", nargs="?", help="clutch calibration TOML file")
    q.add_argument("--out", help="image file to write (atomically); NAME.h: the C header of array NAME")
    q.add_argument("--shift-variant", metavar="NAME", help="shift control on with this variant (full or"
                   " shift_1_2_full); default off")
    q.add_argument("--shift-toml", help="shift calibration TOML (default tools/calibrations/shift_1_2.toml)")
    for option, limits in (("sensor-timeout", "periods, 1..1000, default 10"),
                           ("request-timeout", "periods, 1..1000, default 10"),
                           ("max-delta-counter", "E2E MaxDeltaCounter, 1..7, default 2"),
                           ("sync-counter", "E2E SyncCounter, 1..15, default 3"),
                           ("recovery-periods", "1..10000, default 20")):
        q.add_argument(f"--{option}", type=int, metavar="N", help=f"the loop's {option.replace('-', ' ')} ({limits})")
    q.add_argument("--show", metavar="FILE", help="read an image: its fields, or why the firmware refuses it")
    q.set_defaults(func=_cmd_cal_image)

    q = sub.add_parser("reference", help="evaluate the double-precision model: CSV in, CSV out")
    q.add_argument("mode", choices=sorted(reference.MODES))
    q.add_argument("--calibration", "-c", default=DEFAULT_CAL)
    q.add_argument("--input", "-i", help="input CSV (default: stdin)")
    q.add_argument("--output", "-o", help="output CSV, written atomically (default: stdout)")
    q.add_argument("--keep-rejected", action="store_true",
                   help="write rows the firmware rejects (out of range, NaN, inf) with their status bits and the"
                        " firmware's safe outputs, and a status column in every mode, instead of failing on the"
                        " first one as wc_eval does")
    q.set_defaults(func=_cmd_reference)

    q = sub.add_parser("vectors", help="write golden vectors for the C tests")
    q.add_argument("calibration", nargs="?", default=DEFAULT_CAL)
    q.add_argument("--out", default="tests/vectors")
    q.set_defaults(func=_cmd_vectors)
    q = sub.add_parser("replay", help="replay bench logs to wc_tcu on vcan0 and write the HIL report")
    q.add_argument("logs", nargs="+", help="candump -L bench logs (e.g. hil/logs/engagement_750rpm.log)")
    q.add_argument("--out", default="out/replay", help="report directory, one folder per log (default out/replay)")
    q.add_argument("--calibration", "-c", default=DEFAULT_CAL,
                   help="calibration TOML; wc_tcu runs the compiled-in calibration of the same name (its stem)")
    q.add_argument("--in-process", action="store_true",
                   help="the same frame-clock runs with the same loop in-process (wc_replay): no vcan, no guest,"
                   " no timer-clock run")
    q.add_argument("--analyse-only", action="store_true", help="do not run: analyse the captures already in --out")
    q.add_argument("--no-reference-check", action="store_true",
                   help="skip comparing every TCU step with the double-precision reference")
    q.set_defaults(func=_cmd_replay)

    q = sub.add_parser("shift", help="closed-loop 1->2 upshifts: the whole shift (off-going clutch, engine"
                       " intervention, fill; issue 22) on the vehicle family, (a) feedback, (b) 2-DOF thermal-blind,"
                       " (c) 2-DOF full model; --oncoming-only: issue 13's on-coming clutch alone on one plant;"
                       " exit 1 when a target is missed")
    q.add_argument("--oncoming-only", action="store_true",
                   help="issue 13's comparison: the on-coming clutch alone (scripted off-going release) on --plant")
    q.add_argument("--vehicles", nargs="+", metavar="NAME",
                   help="the whole shift on these vehicles of tools/plants/vehicles/ (default all)")
    q.add_argument("--plant", default=str(Path(__file__).resolve().parents[1] / "plants" / "upshift_1_2.toml"),
                   help="plant TOML (default tools/plants/upshift_1_2.toml)")
    q.add_argument("--out", help="output directory (default out/shift; with --adaptation-study out/adaptation_study)")
    q.add_argument("--tune-feedback", action="store_true",
                   help="only the gain search of (a): kp x ki grid on the nominal scenario, print the best")
    q.add_argument("--adaptation-study", action="store_true",
                   help="the adaptation study (issue 20): consecutive shifts with adaptation on plant variants that"
                        " differ from the calibration, the matrix from the learned values, faults, heat soak;"
                        " plots of the learned values against their truth; exit 1 when a target is missed")
    q.add_argument("--variants", nargs="+", metavar="NAME",
                   help="with --adaptation-study: the plant variants (default all: base, friction-20, friction-10,"
                        " friction+10, friction+20, film0.3, film3, kiss+15, aged)")
    q.add_argument("--shifts", type=int, default=16, metavar="N",
                   help="with --adaptation-study: consecutive shifts per variant (default 16; 200 for the settling"
                        " target, about 2 minutes per variant)")
    q.set_defaults(func=_cmd_shift)
    q = sub.add_parser("cycle", help="the WLTC class 3b drive cycle (issue 31; DESIGN 16): driver, shift schedule,"
                       " the firmware's transmission in process at 1 kHz on the 8-speed vehicle plant; the report"
                       " (GTR 15 speed-trace violations, every shift's quality, the observer against the truth),"
                       " plots and MDF4; exit 1 when a target is missed")
    q.add_argument("--vehicle", nargs="+", default=["nominal"], metavar="NAME|PATH",
                   help="vehicles of tools/plants/8hp (nominal, heavy, light) or 8-speed plant files anywhere"
                        " (default nominal)")
    q.add_argument("--phase", choices=("low", "medium", "high", "extra_high", "all"), default="all",
                   help="the whole cycle (default, 1800 s) or one of its phases (low: 0-589 s)")
    q.add_argument("--oil", type=float, metavar="DEGC", help="oil temperature (default the vehicle file's)")
    q.add_argument("--out", default="out/cycle", help="report directory (default out/cycle)")
    q.add_argument("--adaptation", type=int, default=0, metavar="N",
                   help="then N cycles with adaptation, each from the last one's learned values (issue 31's"
                        " targets need 3)")
    q.set_defaults(func=_cmd_cycle)
    q = sub.add_parser("vehicle-cal", help="write the TCU's driveline model of each vehicle plant"
                       " (tools/plants/vehicles/*.toml -> tools/calibrations/vehicles/*.toml, DESIGN 14)")
    q.add_argument("plants_dir", nargs="?", help="directory of vehicle plant files (default tools/plants/vehicles)")
    q.add_argument("--out", help="output directory (default tools/calibrations/vehicles)")
    q.set_defaults(func=_cmd_vehicle_cal)
    q = sub.add_parser("gearbox", help="check a gearbox description (gear sets, elements, gears) and write its shift"
                       " table: ratios from the kinematics, element slips, per-shift reduced models (DESIGN 15)")
    q.add_argument("gearbox", help="gearbox description, any path (e.g. tools/gearboxes/8hp.toml)")
    q.add_argument("--vehicle", metavar="PATH", help="vehicle plant file, any path: its inertias on the turbine and"
                   " output side (e.g. tools/plants/vehicles/nominal.toml)")
    q.add_argument("--out", metavar="PATH", help="shift table to write (default <gearbox stem>_shifts.toml beside it)")
    q.add_argument("--header", metavar="PATH", help="also the firmware's C header of the table (wc_gearbox_t,"
                   " include/wetclutch/wc_gearbox.h), e.g. lut/wc_8hp_gearbox.h; needs --vehicle")
    q.add_argument("--image", metavar="PATH", help="also the table as a gearbox image (wc_gearbox_image.h) for"
                   " wc_tcu / wc_replay --gearbox-image PATH: a gearbox the TCU did not compile in; needs --vehicle")
    q.set_defaults(func=_cmd_gearbox)
    q = sub.add_parser("film-study", help="the squeeze-film state over a family of bench plants (issue 12):"
                                          " identified on two engagements, tested on 12 others per plant")
    q.add_argument("--out", default="out/film_study", help="output directory (default out/film_study)")
    q.add_argument("--calibration", "-c", default="tools/calibrations/bench_identified.toml",
                   help="the model's calibration (its phi is re-identified per plant)")
    q.add_argument("--true", default="tools/calibrations/bench_true.toml", help="the bench's true parameters")
    q.add_argument("--seed", default=1, type=int, help="bench noise seed (default 1)")
    q.set_defaults(func=_cmd_film_study)

    q = sub.add_parser("identify", help="identify mu_f, k1/k2, viscosity, asperity density from bench data")
    q.add_argument("step", choices=["mu", "thermal", "viscosity", "asperity", "film", "static", "all"])
    q.add_argument("data_dir", help="bench data: index.csv + measurement CSVs (+ thermal/, viscosity.csv)")
    q.add_argument("--calibration", "-c", default=DEFAULT_CAL, help="base calibration TOML")
    q.add_argument("--out", default="out/identify", help="output directory (default out/identify)")
    q.add_argument("--true", help="true-parameter TOML (simulated bench): report errors against it")
    q.add_argument("--fit-heat-capacity", action="store_true", help="thermal: fit C with k1, k2")
    q.add_argument("--thermistor-lag", type=float, help="thermistor time constant (s); default: identified")
    q.add_argument("--slip-min", type=float, default=1.0, help="slip (rpm) below which the clutch counts as stuck")
    q.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1), help="worker processes for reading")
    q.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    q.add_argument("--no-simex", action="store_true", help="mu: no errors-in-variables correction of mu2, v_s")
    q.set_defaults(func=_cmd_identify)

    q = sub.add_parser("bench", help="simulate the test bench (DESIGN 7): measurement CSVs and CAN logs")
    q.add_argument("experiment", choices=("engagement", "table2", "thermal", "breakaway"),
                   help="engagement (Fig. 15), table2 (the 184-experiment campaign), thermal (Fig. 13),"
                        " breakaway (static capacity: a torque ramp on the locked clutch)")
    q.add_argument("--out", required=True, help="output directory")
    q.add_argument("--true", default="tools/calibrations/bench_true.toml",
                   help="the bench's true parameters (calibration TOML; default tools/calibrations/bench_true.toml)")
    q.add_argument("--seed", default="1", help="noise seed, a whole number >= 0 (default 1)")
    q.add_argument("--slip", type=float, action="append", metavar="RPM",
                   help="engagement initial slip, repeatable (default 750, 500 and 250 rpm)")
    q.add_argument("--theta", type=float, action="append", metavar="DEGC",
                   help="engagement/breakaway initial temperature (clutch, oil, housing), repeatable"
                        " (default 40 and 80 degC)")
    q.add_argument("--logs", action="store_true",
                   help="table2/thermal/breakaway: also write the 1 ms CAN logs (and 1 ms CSVs for table2/thermal);"
                        " slow and large for table2/thermal")
    q.set_defaults(func=_cmd_bench)

    q = sub.add_parser("a2l", help="write the A2L of the TCU's XCP slave (calibration page and measurements,"
                                   " addresses from the linked program)")
    q.add_argument("--tcu", default="build/host-release/src/port/wc_tcu",
                   help="the TCU program whose --xcp-layout gives the addresses (default the host-release build)")
    q.add_argument("--layout", help="a saved copy of its --xcp-layout output instead")
    q.add_argument("--out", default="out/xcp/wetclutch.a2l", help="A2L file to write (default out/xcp/wetclutch.a2l)")
    q.set_defaults(func=_cmd_a2l)

    q = sub.add_parser("convert", help="convert a Vector ASC/BLF log to candump -L (for canplayer), or a candump -L"
                                       " (or ASC/BLF) log to MDF4 (--to mdf4: signals decoded by hil/wetclutch.dbc)")
    q.add_argument("input", help="Vector .asc or .blf log (--to mdf4: also a candump -L log)")
    q.add_argument("output", help="candump -L log to write (--to mdf4: the .mf4 file)")
    q.add_argument("--to", choices=("candump", "mdf4"), default="candump", help="output format (default candump)")
    q.add_argument("--channel", default="vcan0", help="interface name written in the log (default vcan0)")
    q.set_defaults(func=_cmd_convert)
    return p


def _cmd_cycle(args) -> int:
    from .cycle import report
    if not 0 <= args.adaptation <= 10:
        print(f"wetclutch cycle: --adaptation {args.adaptation}: 0..10 cycles", file=sys.stderr)
        return 2
    return report.command(args.vehicle, args.phase, args.oil, Path(args.out), args.adaptation)


def os_error_text(e: OSError) -> str:
    """'path: reason' (util/atomic.py names the final path of an output), or the reason alone where the OS
    named no file."""
    reason = e.strerror or str(e)
    if e.filename is None:
        return reason
    if e.filename2 is not None:
        return f"{e.filename} -> {e.filename2}: {reason}"
    return f"{e.filename}: {reason}"


def main(argv=None) -> int:
    """Exit 0 success, 1 a target missed (lut, identify, replay), 2 a usage or input error or an I/O
    failure: one line on stderr naming the file, no traceback. Only the expected errors are caught here
    (the I/O layer turns undecodable or malformed input into them); anything else is a bug and shows
    its traceback."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (calibration.CalibrationError, shift_calibration.ShiftCalibrationError, CsvError, lut.TableError, LogError,
            RuntimeError) as e:
        if isinstance(e, (NotImplementedError, RecursionError)):
            raise                # RuntimeError's subclasses that are bugs, not input errors
        print(f"wetclutch {args.command}: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"wetclutch {args.command}: {os_error_text(e)}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

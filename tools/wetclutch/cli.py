"""Command line: ``wetclutch {lut,reference,vectors}``."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import calibration, lut, reference, vectors
from .csvio import CsvError, read_columns, write_columns
from .errors import LogError

DEFAULT_CAL = "tools/calibrations/table1.toml"


def _cmd_lut(args) -> int:
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


def _cmd_reference(args) -> int:
    cal = calibration.load(args.calibration)
    source = args.input or "<stdin>"
    stream = open(args.input, newline="") if args.input else sys.stdin
    with stream:
        cols = read_columns(stream, reference.INPUTS[args.mode], source)
    try:
        out = reference.MODES[args.mode](cal, cols)
    except CsvError as e:
        raise CsvError(f"{source}: {e}") from None
    write_columns(sys.stdout, out)
    return 0


def _cmd_vectors(args) -> int:
    cal = calibration.load(args.calibration)
    command = f"wetclutch vectors {args.calibration} --out {args.out}"
    for f in vectors.generate(cal, Path(args.out), command):
        print(f"wrote {f}")
    return 0


def _cmd_replay(args) -> int:
    from . import canlog, replay, report  # matplotlib and the CAN stack only when needed
    cal = calibration.load(args.calibration)
    out_root = Path(args.out)
    jobs = []
    for log in args.logs:
        log = Path(log)
        check = replay.check_log(log)   # missing or malformed: LogError, nothing runs
        for problem in check.problems():
            print(f"wetclutch replay: {log}: {problem}", file=sys.stderr)
        jobs.append((log, out_root / log.stem))
    if not args.analyse_only:
        print(f"wetclutch replay: {len(jobs)} log(s) on vcan0 (the VM boot takes about a minute where the"
              " kernel has no CAN)", file=sys.stderr, flush=True)
        replay.run_on_vcan(None, None, frame_runs=2, timer_runs=1, jobs=jobs)
    missed = []
    for log, run_dir in jobs:
        print(f"wetclutch replay: analysing {log.name} (reference check of every step)", file=sys.stderr, flush=True)
        m = report.analyse(cal, log, run_dir, reference_check=not args.no_reference_check)
        print((run_dir / "summary.md").read_text())
        print(f"report: {run_dir}/summary.md, metrics.json, {', '.join(Path(p).name for p in m['plots'])}")
        if not m["all_targets_met"]:
            missed.append(f"{log.name}: " + ", ".join(k for k, v in m["targets"].items() if not v))
    if missed:
        print("wetclutch replay: targets missed: " + "; ".join(missed), file=sys.stderr)
        return 1
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="wetclutch", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)

    q = sub.add_parser("lut", help="write the calibration and h_bar(p_c) headers for the firmware")
    q.add_argument("calibration", help="calibration TOML file")
    q.add_argument("--out", default="lut", help="output directory (default: lut)")
    q.add_argument("--name", help="C name of the calibration (default: the file's stem)")
    q.add_argument("--max-error", type=float, default=1e-4, help="fail above this relative h_bar error")
    q.set_defaults(func=_cmd_lut)

    q = sub.add_parser("reference", help="evaluate the double-precision model: CSV in, CSV out")
    q.add_argument("mode", choices=sorted(reference.MODES))
    q.add_argument("--calibration", "-c", default=DEFAULT_CAL)
    q.add_argument("--input", "-i", help="input CSV (default: stdin)")
    q.set_defaults(func=_cmd_reference)

    q = sub.add_parser("vectors", help="write golden vectors for the C tests")
    q.add_argument("calibration", nargs="?", default=DEFAULT_CAL)
    q.add_argument("--out", default="tests/vectors")
    q.set_defaults(func=_cmd_vectors)
    q = sub.add_parser("replay", help="replay bench logs to wc_tcu on vcan0 and write the HIL report")
    q.add_argument("logs", nargs="+", help="candump -L bench logs (e.g. hil/logs/engagement_750rpm.log)")
    q.add_argument("--out", default="out/replay", help="report directory, one folder per log (default out/replay)")
    q.add_argument("--calibration", "-c", default=DEFAULT_CAL, help="the calibration the TCU was built with")
    q.add_argument("--analyse-only", action="store_true", help="do not run: analyse the captures already in --out")
    q.add_argument("--no-reference-check", action="store_true",
                   help="skip comparing every TCU step with the double-precision reference")
    q.set_defaults(func=_cmd_replay)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (calibration.CalibrationError, CsvError, lut.TableError, LogError, RuntimeError) as e:
        print(f"wetclutch {args.command}: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"wetclutch {args.command}: {e.filename}: {e.strerror}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

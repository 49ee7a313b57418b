"""Offline tool for the wet-clutch TCU library (Shin & Choi friction model): ``wetclutch --help``.

One folder per role; dependencies run one way, each layer importing only the ones above it in this list
(tests/python/test_package_layout.py checks it):

util/         shared: atomic writes, CSV, CAN logs and the DBC codec, errors, plotting
reference/    the double-precision references: the control model (model/), the CSV evaluator, the shift
              controller
calibration/  calibration files: the Calibration type and parameter table, the firmware's rules, the film
              table, loading and writing; the shift calibration
gearbox/      a gearbox description: kinematics, element slips, per-shift reduced models, the shift table
generate/     the generated files: LUT headers, golden vectors, CAN descriptors, the shift and gearbox headers
simulate/     the simulators: the test bench (bench/), the 1->2 upshift plant (plant/)
hil/          the HIL replay (replay, report) and the ASC/BLF log converter
identify/     identification from bench data
shift/        the closed-loop shift runner and its report
studies/      studies over many simulated plants (film_study)
cycle/        the drive cycle: the WLTC class 3b trace and GTR 15's tolerance, the driver, the shift schedule
cli.py        the command line: parse, call one function, print
"""

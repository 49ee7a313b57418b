"""Hardware-in-the-loop replay (``wetclutch replay``): bench logs played to the TCU program on vcan0 and every
step checked against the double-precision reference of the frame loop.

replay   log checks, the vcan run (hil/vcan_run.sh), the frame loop's reference (loop_reference), compare
report   the metrics, summary.md, the plots and capture.mf4 (MDF4) of one replayed log
convert  a real bench's Vector ASC/BLF log to candump -L, a CAN log to MDF4 (``wetclutch convert [--to mdf4]``)
"""

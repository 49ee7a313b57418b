"""Hardware-in-the-loop replay (``wetclutch replay``): bench logs played to the TCU program on vcan0 and every
step checked against the double-precision reference of the frame loop.

replay   log checks, the vcan run (hil/vcan_run.sh), the frame loop's reference (loop_reference), compare
report   the metrics, summary.md and the plots of one replayed log
convert  a real bench's Vector ASC/BLF log to candump -L (``wetclutch convert``)
"""

"""Shared by every role, importing nothing else of wetclutch:

atomic    output files written atomically (all or nothing)
csvio     CSV in and out
canlog    CAN frames by the DBC (hil/wetclutch.dbc) and candump -L logs
mdf       CAN frames decoded by the DBC -> an MDF4 file (asammdf): convert --to mdf4, the replay and shift reports
errors    the errors the command line reports as one line
image     the firmware's persistent image format (magic, version, length, CRC-32; wc_image.h)
tomlfile  TOML files read with one-line errors (calibrations, plants)
plotting  matplotlib on the Agg backend: figures, style, saving
"""

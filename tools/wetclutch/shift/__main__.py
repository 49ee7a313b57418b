"""``python -m wetclutch.shift --vcan-guest ...``: the guest side of run_on_vcan (hil/vcan_run.sh runs it)."""
from __future__ import annotations

import sys

from .runner import _vcan_guest


if __name__ == "__main__":
    if len(sys.argv) == 6 and sys.argv[1] == "--vcan-guest":
        sys.exit(_vcan_guest(*sys.argv[2:]))
    print("usage: python -m wetclutch.shift --vcan-guest OUT_DIR SHIFT_NAME SCENARIO PLANT_TOML", file=sys.stderr)
    sys.exit(2)

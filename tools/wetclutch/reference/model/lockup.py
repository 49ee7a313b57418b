"""The lock-up state machine (DESIGN 9, wc_lockup.c)."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:   # annotations only: the model reads a calibration's attributes, the loader sits above it
    from ...calibration.parameters import Calibration


class Lockup:
    """The firmware's lock-up state machine (wc_lockup.c): slipping <-> locked (DESIGN 9)."""

    def __init__(self, cal: Calibration):
        self.cal = cal
        self.locked = False
        self.direction = 1.0
        self.dwell = 0

    def update(self, slip_rad_s: float, required_Nm: float, capacity_Nm: float) -> bool:
        cal = self.cal
        holds = abs(required_Nm) < capacity_Nm
        locks = abs(required_Nm) * (1.0 + 0.5 * cal.holding_margin) < capacity_Nm   # torque hysteresis
        if self.locked:
            if not (abs(slip_rad_s) <= cal.breakaway_slip) or not holds:
                self.locked, self.dwell = False, 0
                if abs(slip_rad_s) >= cal.lock_slip:   # the slip that broke away sets the direction
                    self.direction = -1.0 if slip_rad_s < 0.0 else 1.0
            return self.locked
        if abs(slip_rad_s) < cal.lock_slip and locks:
            self.dwell = min(self.dwell + 1, 255)
            self.locked = self.dwell >= cal.lock_dwell
        else:
            self.dwell = 0
            if abs(slip_rad_s) >= cal.lock_slip:
                self.direction = -1.0 if slip_rad_s < 0.0 else 1.0
        return self.locked

    def torque_Nm(self, required_Nm: float, capacity_Nm: float) -> float:
        """What a locked clutch transmits: the required torque in the lock direction, at most the capacity."""
        along = self.direction * required_Nm
        return self.direction * (min(along, max(capacity_Nm, 0.0)) if along > 0.0 else 0.0)

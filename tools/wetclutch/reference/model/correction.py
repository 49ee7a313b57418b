"""The adaptation's correction of the clutch model (DESIGN 12, wc_model_correction_t in
include/wetclutch/wc_clutch.h), written from the header's text:

- mu_f (eq. 18) x (1 + friction_scale_delta): in the forward torque, the inverse and the static capacity;
- the squeeze film's damping (DESIGN 9) x (1 + film_factor_delta): in the film's advance and the lag
  compensation's film lead;
- kiss_offset_N: the contact force is the apply force minus it (clamped at 0) in the forward path, and the
  inverse's wanted contact force F is commanded as the pressure of F + kiss_offset_N.

A field outside its range (NaN included) voids the whole correction: none (the calibration's model)."""
from __future__ import annotations

import math
from dataclasses import dataclass

SCALE_MAX = 0.5              # WC_CORRECTION_SCALE_MAX
FILM_DELTA_MIN, FILM_DELTA_MAX = -0.99, 19.0   # WC_CORRECTION_FILM_DELTA_MIN / _MAX
KISS_MAX_N = 5000.0          # WC_CORRECTION_KISS_MAX_N


@dataclass(frozen=True)
class Correction:
    friction_scale_delta: float = 0.0
    film_factor_delta: float = 0.0
    kiss_offset_N: float = 0.0

    @property
    def friction_factor(self) -> float:
        return 1.0 + self.friction_scale_delta

    @property
    def film_factor(self) -> float:
        return 1.0 + self.film_factor_delta


NONE = Correction()


def effective(correction: Correction | None) -> Correction:
    """The correction the clutch step applies: the given one when every field is in its range, else none
    (the firmware's rule: one field out of range voids the whole correction, no status bit)."""
    if correction is None:
        return NONE
    c = correction
    ok = (-SCALE_MAX <= c.friction_scale_delta <= SCALE_MAX and FILM_DELTA_MIN <= c.film_factor_delta <= FILM_DELTA_MAX
          and -KISS_MAX_N <= c.kiss_offset_N <= KISS_MAX_N)   # False for NaN
    return c if ok and all(math.isfinite(x) for x in (c.friction_scale_delta, c.film_factor_delta,
                                                          c.kiss_offset_N)) else NONE

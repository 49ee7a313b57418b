"""Plant variants that differ from the base calibration (issue 20, DESIGN 12), and the plant's truth of what
the TCU's adaptation learns on each.

One home for the list (VARIANTS): the on-coming clutch of the base plant (tools/plants/upshift_1_2.toml, its
true clutch bench_true.toml) with one property changed:

  base          the plant file as it is (the matched plant)
  friction-20 .. friction+20   the plant's friction_scale x 0.8, 0.9, 1.1, 1.2 (the Coulomb friction and
                the static capacity, eq. 8, DESIGN 9)
  film0.3, film3   the clutch calibration's film_squeeze_factor x 0.3 and x 3 (DESIGN 9: a more permeable
                or a tighter lining; the film state's time x the same)
  kiss+15       return_spring_force x 1.15: the piston needs 15 % more force before the plates touch, the
                kiss pressure F_s / A_p 17.9 kPa later
  aged          an aged lining: mu3 + 15 % (eq. 18's temperature slope; the friction coefficient rises
                more with the friction-surface temperature)

The truth (VariantTruth), what a perfect adaptation would learn against the TCU's own clutch calibration
(the controller's model, bench_identified.toml), in the units of wc_adapt_values_t (wc_adapt.h):

  friction scale(theta) = friction_scale_plant mu_f,plant(v, theta) / mu_f,TCU(v, theta)   (eq. 18)
      at the slip speed of the inertia phase (the Stribeck term gone: v = r_eff x TRUTH_SLIP_RAD_S), so
      the temperature factor 1 + mu3 (theta - theta1) / theta2 of each calibration gives the aged lining's
      scale a slope in theta: 1.00 at 40 degC, 1.034 at 80, 1.055 at 120;
  film factor = film_squeeze_factor_plant / film_squeeze_factor_TCU;
  kiss offset (Pa) = (F_s,plant / A_p,plant) - (F_s,TCU / A_p,TCU)   (= delta F_s / A_p for equal pistons).

The base plant's truth is not exactly 1 / 1 / 0: the TCU's calibration is identified from the bench, not
the bench's truth (friction scale 0.9995..1.0007 over 20..200 degC, film factor 0.9962).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ...reference import model
from .params import PlantParams


TRUTH_SLIP_RAD_S = 50.0      # the inertia phase's slip (89 rad/s at its start): the Stribeck term is gone


@dataclass(frozen=True)
class PlantVariant:
    """One property of the base plant changed (factors on the base's values; 1 = unchanged)."""
    name: str
    description: str
    friction_factor: float = 1.0     # x the plant file's friction_scale
    film_factor: float = 1.0         # x the true clutch's film_squeeze_factor
    spring_factor: float = 1.0       # x the true clutch's return_spring_force (the kiss point)
    mu3_factor: float = 1.0          # x the true clutch's mu3 (eq. 18's temperature slope)


VARIANTS: tuple[PlantVariant, ...] = (
    PlantVariant("base", "the base plant (matched: the calibration's clutch)"),
    PlantVariant("friction-20", "plant friction -20 %", friction_factor=0.8),
    PlantVariant("friction-10", "plant friction -10 %", friction_factor=0.9),
    PlantVariant("friction+10", "plant friction +10 %", friction_factor=1.1),
    PlantVariant("friction+20", "plant friction +20 %", friction_factor=1.2),
    PlantVariant("film0.3", "squeeze-film factor x 0.3", film_factor=0.3),
    PlantVariant("film3", "squeeze-film factor x 3", film_factor=3.0),
    PlantVariant("kiss+15", "kiss point +15 % (return spring force x 1.15)", spring_factor=1.15),
    PlantVariant("aged", "aged lining: mu3 +15 %", mu3_factor=1.15),
)
BY_NAME = {v.name: v for v in VARIANTS}


def variant(name: str) -> PlantVariant:
    """The variant of that name; KeyError naming the known ones."""
    try:
        return BY_NAME[name]
    except KeyError:
        raise KeyError(f"unknown plant variant {name!r} (known: {', '.join(BY_NAME)})") from None


def apply(params: PlantParams, v: PlantVariant) -> PlantParams:
    """The plant parameters of variant v: the base's with its true clutch calibration and friction scale
    changed (the base itself returned for a variant that changes nothing)."""
    if (v.friction_factor, v.film_factor, v.spring_factor, v.mu3_factor) == (1.0, 1.0, 1.0, 1.0):
        return params
    cal = params.clutch_cal
    clutch = cal.with_values(film_squeeze_factor=cal.film_squeeze_factor * v.film_factor,
                             return_spring_force=cal.return_spring_force * v.spring_factor,
                             mu3=cal.mu3 * v.mu3_factor)
    return dataclasses.replace(params, clutch_cal=clutch, friction_scale=params.friction_scale * v.friction_factor,
                               path=f"{params.path} [{v.name}]")


@dataclass(frozen=True)
class VariantTruth:
    """What the adaptation should learn on a plant, against the TCU's calibration (module docstring)."""
    plant_cal: object
    tcu_cal: object
    friction_scale_plant: float
    film_factor: float
    kiss_offset_Pa: float

    def friction_scale(self, theta_degC):
        """The true friction scale at the friction-surface temperature(s) theta_degC (eq. 18 ratio)."""
        v = self.plant_cal.effective_radius * TRUTH_SLIP_RAD_S
        return (self.friction_scale_plant * model.friction_coefficient(self.plant_cal, v, theta_degC)
                / model.friction_coefficient(self.tcu_cal, v, theta_degC))

    def as_dict(self, theta_nodes_degC) -> dict:
        """The truth at the adaptation's nodes, for reports: {friction_scale: [...], film_factor, kiss_offset_Pa}."""
        return {"theta_nodes_degC": [float(t) for t in theta_nodes_degC],
                "friction_scale": [float(s) for s in np.atleast_1d(self.friction_scale(np.asarray(theta_nodes_degC)))],
                "film_factor": self.film_factor, "kiss_offset_Pa": self.kiss_offset_Pa}


def clutch_truth(plant_cal, tcu_cal, friction_scale: float) -> VariantTruth:
    """The truth of a true clutch (its calibration and lining factor) against the TCU's calibration of it: the
    film factor NaN where the TCU's model has no squeeze film (factor 0: nothing to learn)."""
    return VariantTruth(plant_cal=plant_cal, tcu_cal=tcu_cal, friction_scale_plant=friction_scale,
                        film_factor=plant_cal.film_squeeze_factor / tcu_cal.film_squeeze_factor
                        if tcu_cal.film_squeeze_factor > 0.0 else math.nan,
                        kiss_offset_Pa=plant_cal.return_spring_force / plant_cal.piston_area
                        - tcu_cal.return_spring_force / tcu_cal.piston_area)


def truth(params: PlantParams, tcu_cal) -> VariantTruth:
    """The truth of a plant (a variant's parameters, apply) against the TCU's clutch calibration tcu_cal."""
    return clutch_truth(params.clutch_cal, tcu_cal, params.friction_scale)

"""Per shift, the TCU's reduced model of a gearbox (DESIGN 10, 14, 15; the paper's reduction, §2, Fig. 1).

A shift between two gears that close all but one element alike is a single-element shift: the elements both
gears close are HELD, the one only the source gear closes is the OFF-GOING element, the one only the target
closes the ON-COMING element. With the held elements closed the box has two degrees of freedom, turbine and
output speed (kinematics.speed_map), and every element's slip is

    slip_e = a_e w_t - b_e w_o            (rad/s; the element's own slip, as its clutch model sees it)

The off-going slip is 0 in the source gear, the on-coming's in the target gear. Gears that share fewer elements
would open and close two (or more) elements at once, a swap: refused, with the reason; so is a change of
direction (ratios of opposite sign: through neutral at standstill, not a powershift).

THE NORMALISATION. Today's 1->2 controller (wc_shift.c, DESIGN 10) takes the on-coming slip as
a w_t - b w_o with a = 1 and the off-going as w_t - b1 w_o: its clutch turns with the turbine. In a general box
a_e is not 1 (the 8HP's 1->2 on-coming element E slips at 1.5 w_t - 4.696 w_o = 1.5 (w_t - 3.130 w_o); its 1->3
off-going brake A at -0.812 w_t + 3.812 w_o, backwards). Dividing by a_e makes the existing law apply unchanged:

    slip_e / a_e = w_t - (b_e / a_e) w_o,     and the element's torque referred to the turbine a_e T_e

(the same virtual work: T_e slip_e = (a_e T_e)(slip_e / a_e)). So turbine_ratio a = 1, output_ratio b =
b_c / a_c (the target gear's ratio) and offgoing_ratio b1 = b_f / a_f (the source gear's ratio) in
wc_shift_calibration_t's terms, and the element's own slip and torque are a_e x the controller's slip and 1/a_e
x its torque (oncoming_slip_scale, offgoing_slip_scale: the TCU converts with them before the clutch model and
its inverse). a_e < 0 (an element slipping backwards) is normalised the same way.

THE INERTIAS. The shafts' kinetic energy in (w_t, w_o) is 1/2 q^T M q (kinematics.mass_matrix; with a vehicle,
its turbine and output inertias on those shafts and m r_w^2 / r_f^2 added to the output, gearbox.vehicle). The
controller's model is diagonal (I_t dw_t/dt = T_t - a T_c, I_o dw_o/dt = b T_c - T_s). Its diagonal reduction
here keeps the SLIP equation the feed-forward inverts exact for the element that controls it: with C = M^-1
and the normalised slip w_t - b w_o,

    1 / I_t = C_tt - b C_to,      1 / I_o = C_oo - C_to / b

gives the exact d(slip)/dt of M for every T_t, T_c and T_s (the three coefficients a T_t/I_t, a^2/I_t +
b^2/I_o and b/I_o of DESIGN 10's T_ff). turbine_inertia / output_inertia use the on-coming element's b (the
upshift's inertia phase, the coast downshift's); offgoing_turbine_inertia / offgoing_output_inertia the
off-going element's b1 (the element that controls a kickdown's or a tip-out upshift's inertia phase). The
three coefficients fix I_t and I_o uniquely, so they are effective values: where M couples the two sides
strongly (the 8HP's 6->7, M_to = -0.88 kg m^2) I_o is far above the physical output inertia (332 against 16
kg m^2 with the nominal vehicle) and still gives the exact slip. The output's own acceleration (the jerk) is
approximate in the diagonal model (exact in M). Without a vehicle the reduction is not computed (None): the
gearbox alone can couple so strongly that no positive pair exists (the 8HP's 1->3).

API: classify(gb) -> (shifts, refused) by name; shift_models(gb, vehicle=None) -> ([ShiftModel],
[RefusedShift]); diagonal_reduction(m, b) -> (I_t, I_o); forward_order(gb, ratios).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import kinematics
from .description import Gearbox, GearboxError
from .vehicle import Vehicle


@dataclass(frozen=True)
class ShiftModel:
    source: str
    target: str
    direction: str                # "up" (to a smaller ratio) or "down"
    steps: int                    # gears of the forward (or reverse) order moved across: 1 single step, > 1 skip
    held: tuple                   # elements closed in both gears
    oncoming: str
    offgoing: str
    slips: dict                   # every element: (a_e, b_e), slip_e = a_e w_t - b_e w_o (its own slip)
    mass_matrix: tuple            # ((M_tt, M_to), (M_to, M_oo)), kg m^2
    turbine_ratio: float          # 1 (normalised)
    output_ratio: float           # b = b_c / a_c: the target gear's ratio
    offgoing_ratio: float         # b1 = b_f / a_f: the source gear's ratio
    oncoming_slip_scale: float    # a_c: element slip = a_c x controller slip; element torque = request / a_c
    offgoing_slip_scale: float    # a_f
    turbine_inertia: float | None         # I_t, slip-exact for the on-coming element (module docstring);
    output_inertia: float | None          # I_o, idem; None without a vehicle
    offgoing_turbine_inertia: float | None    # slip-exact for the off-going element
    offgoing_output_inertia: float | None
    jerk_per_torque_rate: float | None   # b r_f / (m r_w) with a vehicle, else None

    @property
    def name(self) -> str:
        return f"{self.source}-{self.target}"


@dataclass(frozen=True)
class RefusedShift:
    source: str
    target: str
    reason: str

    @property
    def name(self) -> str:
        return f"{self.source}-{self.target}"


def forward_order(gb: Gearbox, ratios: dict) -> dict:
    """{gear: position} in each direction's order of falling |ratio| (forward gears 1..n, reverse gears
    separately), for the steps of a shift."""
    out = {}
    for sign in (1.0, -1.0):
        gears = sorted((g for g in gb.gears if np.sign(ratios[g]) == sign), key=lambda g: -abs(ratios[g]))
        out.update({g: k for k, g in enumerate(gears)})
    return out


def classify(gb: Gearbox, ratios: dict | None = None) -> tuple[list, list]:
    """([(source, target, held, oncoming, offgoing)], [RefusedShift]) over every ordered pair of gears, in the
    file's gear order."""
    ratios = kinematics.check(gb) if ratios is None else ratios
    single, refused = [], []
    need = gb.closed_per_gear - 1
    for src, closed_src in gb.gears.items():
        for tgt, closed_tgt in gb.gears.items():
            if src == tgt:
                continue
            if np.sign(ratios[src]) != np.sign(ratios[tgt]):
                refused.append(RefusedShift(src, tgt, f"direction change (ratio {ratios[src]:.4g} to "
                                            f"{ratios[tgt]:.4g}): through neutral at standstill, not a powershift"))
                continue
            held = tuple(e for e in closed_src if e in closed_tgt)
            opens = [e for e in closed_src if e not in closed_tgt]
            closes = [e for e in closed_tgt if e not in closed_src]
            if len(held) < need:
                refused.append(RefusedShift(src, tgt, f"{len(opens)}-element swap: {src} closes "
                                            f"{''.join(closed_src)}, {tgt} closes {''.join(closed_tgt)}, they share "
                                            f"{''.join(held) or 'none'}: {''.join(opens)} would open and "
                                            f"{''.join(closes)} close at once"))
                continue
            single.append((src, tgt, held, closes[0], opens[0]))
    return single, refused


def diagonal_reduction(m: np.ndarray, b: float, where: str = "") -> tuple[float, float]:
    """(I_t, I_o) of the diagonal model whose slip w_t - b w_o moves exactly as with the mass matrix m."""
    c = np.linalg.inv(m)
    inv_t = c[0, 0] - b * c[0, 1]
    inv_o = c[1, 1] - c[0, 1] / b
    if not (inv_t > 0 and inv_o > 0):
        raise GearboxError(f"{where}: no positive diagonal reduction of the mass matrix {m.tolist()} for the slip "
                           f"w_t - {b:.6g} w_o (1/I_t = {inv_t:.6g}, 1/I_o = {inv_o:.6g})")
    return 1.0 / inv_t, 1.0 / inv_o


def shaft_inertias(gb: Gearbox, vehicle: Vehicle | None) -> np.ndarray:
    """J per shaft: the description's, or with the vehicle's turbine and output inertias and its mass."""
    if vehicle is None:
        return kinematics.inertias(gb)
    return kinematics.inertias(gb, turbine=vehicle.turbine_inertia, output=vehicle.output_inertia,
                               output_extra=vehicle.mass_at_output)


def shift_model(gb: Gearbox, src: str, tgt: str, held: tuple, oncoming: str, offgoing: str, steps: int,
                ratios: dict, vehicle: Vehicle | None = None) -> ShiftModel:
    key = f"shift {src}-{tgt}"
    where = f"{gb.path}: {key}"
    t_map = kinematics.speed_map(gb, held, key)
    slips = {e: kinematics.slip_coefficients(gb, t_map, e) for e in gb.element_names}
    a_c, b_c = slips[oncoming]
    a_f, b_f = slips[offgoing]
    for name, a in ((oncoming, a_c), (offgoing, a_f)):
        if abs(a) <= kinematics.RANK_TOL:
            raise GearboxError(f"{where}: element {name}'s slip does not depend on the turbine speed (a = 0): "
                               "it cannot be normalised to w_t - b w_o")
    m = kinematics.mass_matrix(gb, t_map, shaft_inertias(gb, vehicle))
    b, b1 = b_c / a_c, b_f / a_f
    if vehicle is None:             # the controller's model needs the vehicle on the output side
        i_t = i_o = i_t_off = i_o_off = None
    else:
        i_t, i_o = diagonal_reduction(m, b, where)
        i_t_off, i_o_off = diagonal_reduction(m, b1, where)
    return ShiftModel(
        source=src, target=tgt, direction="up" if abs(ratios[tgt]) < abs(ratios[src]) else "down", steps=steps,
        held=held, oncoming=oncoming, offgoing=offgoing, slips=slips,
        mass_matrix=((float(m[0, 0]), float(m[0, 1])), (float(m[1, 0]), float(m[1, 1]))),
        turbine_ratio=1.0, output_ratio=b, offgoing_ratio=b1, oncoming_slip_scale=a_c, offgoing_slip_scale=a_f,
        turbine_inertia=i_t, output_inertia=i_o, offgoing_turbine_inertia=i_t_off, offgoing_output_inertia=i_o_off,
        jerk_per_torque_rate=None if vehicle is None else vehicle.jerk_per_torque_rate(b))


def shift_models(gb: Gearbox, vehicle: Vehicle | None = None) -> tuple[list, list]:
    """([ShiftModel] of every single-element shift, [RefusedShift] of every other ordered pair of gears)."""
    ratios = kinematics.check(gb)
    order = forward_order(gb, ratios)
    single, refused = classify(gb, ratios)
    models = [shift_model(gb, s, t, held, on, off, abs(order[t] - order[s]), ratios, vehicle)
              for s, t, held, on, off in single]
    return models, refused

"""The adaptation's double-precision reference (wetclutch.reference.adaptation, the model correction in
reference/model, DESIGN 12) on its own, and the firmware against it on closed-loop adaptive shifts.

On its own, on synthetic inertia-phase windows whose truth is known (generate/adapt_vectors.py): each update
moves its value towards the truth, by at most its per-shift step and inside its band, repeated shifts
converge to the truth, and an invalid shift changes nothing; the correction enters the clutch step as
wc_clutch.h says (zero: bit for bit none).

Closed loop: consecutive adaptive shifts (shift_1_2_adaptive, in-process wc_replay) on plants whose friction
differs from the TCU's calibration, each replayed by ShiftReference with the learned values and the clutch
state carried from shift to shift: the firmware's currents and the learned values its AdaptationReport
carries against the reference's.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from wetclutch import calibration, shift
from wetclutch.calibration import shift as shift_calibration
from wetclutch.generate import adapt_vectors as av
from wetclutch.reference import adaptation as A, model
from wetclutch.reference.model.correction import Correction
from wetclutch.shift import runner
from wetclutch.shift.scenarios import Scenario, TARGET_INERTIA_S
from wetclutch.simulate import plant
from wetclutch.util import canlog

ROOT = Path(__file__).resolve().parents[2]
CASES = {c.name: c for c in av.CASES}
SETTINGS = A.AdaptSettings.from_values(av.SETTINGS)


@pytest.fixture(scope="module")
def table1():
    return calibration.load(ROOT / "tools" / "calibrations" / "table1.toml")


def _shifts(cal, case, n):
    """n shifts of the same window, each starting from the values the one before learned."""
    out, values = [], case.values
    for _ in range(n):
        r = av.run_case(cal, av.Case(**{**case.__dict__, "values": values}))
        out.append(r)
        values = r["after"]
    return out


# --------------------------------------------------------------------------- the reference on its own

def test_matched_window_changes_nothing_but_the_confidence(table1):
    r = av.run_case(table1, CASES["matched"])
    ch = r["change"]
    assert ch["result"] == A.RESULT_UPDATED and abs(ch["rho"] - 1.0) < 1e-6      # float32 inputs: 1e-7 level
    assert max(abs(s - 1.0) for s in r["after"].friction_scale) < 1e-6
    assert abs(r["after"].kiss_offset_Pa) < 1.0 and abs(r["after"].film_factor - 1.0) < 1e-6
    q = [c / SETTINGS.confidence_gain for c in r["after"].confidence]            # c = gain q (1 - 0)
    assert abs(sum(q) - 1.0) < 1e-12 and r["after"].shifts_learned == 1


def test_friction_plus10_moves_the_scale_towards_1_1_by_the_step(table1):
    """+10 % Coulomb friction: the first shift moves every scale up by gain g s (rho - 1) <= the step (nodes
    without confidence follow in full: g >= 1 - c = 1); repeated shifts converge to 1.1 at the window's node
    (the window at one temperature: with theta and the force both rising over the window, the kiss point's
    least squares take a part of a scale that varies with theta, and the two settle 1 % and 2 kPa apart from
    the truth, rho = 1: not the reference's matter)."""
    runs = _shifts(table1, av.Case(**{**CASES["friction_plus10"].__dict__, "theta_degC": (100.0, 100.0)}), 10)
    first = runs[0]
    rho = first["change"]["rho"]
    assert 1.05 < rho < 1.1                    # the viscous part (not scaled) dilutes the Coulomb part's +10 %
    for s in first["after"].friction_scale:
        assert SETTINGS.scale_gain * (rho - 1.0) - 1e-12 <= s - 1.0 <= SETTINGS.scale_step
    for a, b in zip(runs, runs[1:]):           # the rate limit (a node may overshoot a little and come back:
        for s0, s1 in zip(a["after"].friction_scale, b["after"].friction_scale):   # its own share is small)
            assert abs(s1 - s0) <= SETTINGS.scale_step + 1e-12
    rhos = [r["change"]["rho"] for r in runs]
    assert all(abs(r1 - 1.0) <= abs(r0 - 1.0) + 1e-9 for r0, r1 in zip(rhos[:4], rhos[1:5]))   # the error falls
    last = runs[-1]["after"]
    assert abs(last.friction_scale[2] - 1.1) < 1e-4 and abs(runs[-1]["change"]["rho"] - 1.0) < 1e-4
    assert abs(last.kiss_offset_Pa) < 50.0 and last.confidence[2] > 0.95 and last.confidence[1] == 0.0


def test_kiss_point_is_estimated_and_learned(table1):
    """Contact force 60 N below the model's: the least squares find dF / A_p exactly (the true torque stands on
    the model's film), the offset moves by gain dP, and repeated shifts converge to dF / A_p."""
    truth_Pa = 60.0 / table1.piston_area
    runs = _shifts(table1, av.Case(**{**CASES["kiss_later"].__dict__, "theta_degC": (100.0, 100.0)}), 10)
    assert runs[0]["change"]["kiss_dP_Pa"] == pytest.approx(truth_Pa, rel=1e-4)
    assert runs[0]["after"].kiss_offset_Pa == pytest.approx(SETTINGS.kiss_gain * truth_Pa, rel=1e-4)
    assert runs[-1]["after"].kiss_offset_Pa == pytest.approx(truth_Pa, rel=2e-3)
    assert abs(runs[-1]["after"].friction_scale[2] - 1.0) < 1e-3             # the scale was not blamed


def test_slow_film_moves_the_film_factor_up_only_with_the_film_on(table1):
    slow, off = av.run_case(table1, CASES["film_slow"]), av.run_case(table1, CASES["film_off"])
    ch = slow["change"]
    assert ch["rho_early"] < ch["rho"]
    step = SETTINGS.film_gain * (ch["rho"] / ch["rho_early"] - 1.0)
    assert slow["after"].film_factor == pytest.approx(1.0 + step, rel=1e-12) and 0.0 < step < SETTINGS.film_step
    assert off["after"].film_factor == 1.0 and off["after"].friction_scale == slow["after"].friction_scale


def test_learned_values_stay_in_their_bands_and_steps(table1):
    """+40 % friction for 8 shifts from learned values: every scale rises by at most its step per shift and
    stops at 1 + band; the kiss offset never leaves its band."""
    case = av.Case(**{**CASES["learned"].__dict__, "s_true": 1.4, "theta_degC": (130.0, 130.0)})
    runs = _shifts(table1, case, 8)
    prev = case.values
    for r in runs:
        v = r["after"]
        for s0, s1 in zip(prev.friction_scale, v.friction_scale):
            assert abs(s1 - s0) <= SETTINGS.scale_step + 1e-12 and 1 - SETTINGS.scale_band <= s1 <= 1 + SETTINGS.scale_band
        assert abs(v.kiss_offset_Pa) <= SETTINGS.kiss_band_Pa
        assert abs(v.kiss_offset_Pa - prev.kiss_offset_Pa) <= SETTINGS.kiss_step_Pa + 1e-9
        assert SETTINGS.film_factor_min <= v.film_factor <= SETTINGS.film_factor_max
        assert all(0.0 <= c <= 1.0 for c in v.confidence)
        prev = v
    assert runs[-1]["after"].friction_scale[3] == 1.0 + SETTINGS.scale_band   # node 3 (130 degC): the band


def _window(ref, weights, rho: float):
    """A valid shift's window with these node weights whose measured torque ratio is rho (no kiss point, no
    film)."""
    ref.begin()
    w = ref.window
    w.started, w.samples, w.slip_start, w.slip_prev = True, 100, 100.0, 10.0
    w.sum_model, w.sum_implied = 1000.0, 1000.0 * rho
    w.weight = [1000.0 * x for x in weights]


def test_a_node_outside_every_window_takes_the_learned_level_and_does_not_sum_the_errors(table1):
    """Issue 31: 300 shifts between the 70 and 100 degC nodes (nodes 1, 2; a random share each shift), truth
    1.05, each measured with 4 % noise (seeded): node 4 (160 degC) is in no window and never learned. It takes
    the window's learned scale (the level), so from the 30th shift on it stays within the range of the two learned
    nodes (1e-9: the level is their convex combination), and over the last 100 shifts it averages within 0.03 of
    the truth (the learned nodes' own average is 0.017 off with this seed: gain 0.6 x 4 % noise). A node that took
    each shift's error, or each shift's change of the window's scale, had no feedback through rho and summed the
    noise: on the same shifts 0.144 and 0.050 from the learned nodes, its average 0.090 and 0.019 off (three low
    phases of the drive cycle under the first rule: element C's 120 degC node at 1.25 against a truth of 1.015)."""
    ref = A.AdaptationReference(SETTINGS, table1.period, table1.piston_area, film_on=False)
    rng = np.random.default_rng(7)
    last = []
    for k in range(300):
        share = rng.uniform(0.1, 0.9)
        scale = share * ref.values.friction_scale[1] + (1.0 - share) * ref.values.friction_scale[2]
        _window(ref, [0.0, share, 1.0 - share, 0.0, 0.0], 1.05 / scale * (1.0 + 0.04 * rng.standard_normal()))
        assert ref.finish(0)["result"] == A.RESULT_UPDATED
        s = ref.values.friction_scale
        if k >= 30:
            assert min(s[1], s[2]) - 1e-9 <= s[4] <= max(s[1], s[2]) + 1e-9, (k, s)
        if k >= 200:
            last.append(s[4])
    assert abs(sum(last) / len(last) - 1.05) < 0.03
    assert ref.values.confidence[4] == 0.0


@pytest.mark.parametrize("name, result", [("implausible", A.RESULT_IMPLAUSIBLE), ("excitation", A.RESULT_EXCITATION),
                                          ("input_fault", A.RESULT_INPUT_FAULT), ("aborted", A.RESULT_ABORTED),
                                          ("off", A.RESULT_OFF), ("nan_drive", A.RESULT_INPUT_FAULT)])
def test_an_invalid_shift_changes_nothing(table1, name, result):
    r = av.run_case(table1, CASES[name])
    assert r["change"]["result"] == result
    assert r["after"] == r["before"]


def test_window_closes_when_the_slip_reaches_min_start_slip(table1):
    case = CASES["slip_reenters"]
    r = av.run_case(table1, case)
    slip = r["window"]["samples"]["slip_rad_s"]
    elapsed = r["window"]["samples"]["elapsed_s"]
    first = int(np.argmax(elapsed >= SETTINGS.window_skip_s))
    below = first + int(np.argmax(slip[first:] <= SETTINGS.min_start_slip_rad_s))
    assert np.any(slip[below:] > SETTINGS.min_start_slip_rad_s)          # the slip crosses back above it
    assert r["samples"] == below - first - 1                             # pairs of the periods before it


def test_correction_interpolates_holds_and_clips(table1):
    v = av.LEARNED
    nodes = SETTINGS.theta_node_degC
    assert A.correction(v, SETTINGS, table1.piston_area, nodes[0] - 50.0).friction_scale_delta == v.friction_scale[0] - 1.0
    assert A.correction(v, SETTINGS, table1.piston_area, nodes[-1] + 50.0).friction_scale_delta == v.friction_scale[-1] - 1.0
    mid = 0.25 * nodes[1] + 0.75 * nodes[2]
    assert A.correction(v, SETTINGS, table1.piston_area, mid).friction_scale_delta == pytest.approx(
        0.25 * v.friction_scale[1] + 0.75 * v.friction_scale[2] - 1.0, abs=1e-15)
    big = A.AdaptValues(kiss_offset_Pa=5e6)
    assert A.correction(big, SETTINGS, table1.piston_area, 80.0).kiss_offset_N == 5000.0   # WC_CORRECTION_KISS_MAX_N
    off = A.AdaptSettings.from_values({**av.SETTINGS, "adaptation": 0})
    assert A.correction(v, off, table1.piston_area, 80.0) == Correction()


def _steps(cal, correction, n=400, request=150.0):
    ref = model.ClutchReference(cal, 80.0)
    return [ref.step(300.0, 80.0, 80.0, request, model.MODE_TORQUE, lag_compensation_time_s=0.015,
                     theta_from_oil=True, correction=correction) for _ in range(n)]   # theta held: a steady state


def test_zero_correction_is_bit_for_bit_none(table1):
    cal = table1.with_values(film_squeeze_factor=0.1)
    assert _steps(cal, None, 150) == _steps(cal, Correction(), 150)
    assert _steps(cal, None, 20) == _steps(cal, Correction(float("nan"), 0.0, 0.0), 20)   # out of range: none


def test_correction_enters_the_clutch_step(table1):
    """Steady state at a constant request: +10 % friction scale -> the inverse's force / 1.1 for the same
    Coulomb torque and the static capacity x 1.1 at that force; a kiss offset -> the same contact force at a
    pressure higher by offset / A_p; a larger film factor -> a slower film (more lead current early)."""
    base = _steps(table1, None)[-1]
    scaled = _steps(table1, Correction(0.1, 0.0, 0.0))[-1]
    assert scaled["torque_Nm"] == pytest.approx(base["torque_Nm"], rel=1e-9)
    assert scaled["force_command_N"] < base["force_command_N"] / 1.05
    assert scaled["static_capacity_Nm"] / scaled["contact_force_N"] == pytest.approx(
        1.1 * base["static_capacity_Nm"] / base["contact_force_N"], rel=1e-12)
    kiss = _steps(table1, Correction(0.0, 0.0, 50.0))[-1]
    assert kiss["contact_force_N"] == pytest.approx(base["contact_force_N"], rel=1e-9)
    assert kiss["pressure_command_Pa"] - base["pressure_command_Pa"] == pytest.approx(50.0 / table1.piston_area,
                                                                                      rel=1e-6)
    film = table1.with_values(film_squeeze_factor=0.1)
    slow, normal = _steps(film, Correction(0.0, 1.0, 0.0), 60), _steps(film, None, 60)
    closing = [k for k in range(60) if normal[k]["hbar_m"] != slow[k]["hbar_m"]]
    assert closing and all(slow[k]["hbar_m"] > normal[k]["hbar_m"] for k in closing)   # twice the damping: slower
    assert any(slow[k]["current_mA"] > normal[k]["current_mA"] for k in closing)  # the lead squeezes harder


# --------------------------------------------------------------------------- the firmware against it, closed loop

ADAPTIVE = "adaptive"
BETWEEN_STEPS = int(round(runner.BETWEEN_SHIFTS_S / 1e-3))


def _between(ref, params, scenario):
    """The periods run_case runs between two shifts (runner.between_shifts: no request, no slip, the oil
    and housing temperatures), as the TCU decoded them: the reference goes through them too."""
    enc = canlog.Encoder()
    msg = enc.db.get_message_by_name(canlog.SENSORS)
    frame = enc.frame(canlog.SENSORS, SlipSpeed=0.0, OilTemp=scenario.oil_degC,
                      HousingTemp=scenario.oil_degC + params.housing_offset)
    got = msg.decode(bytes(frame.data))
    for _ in range(BETWEEN_STEPS):
        ref.step(False, 2, 0.0, TARGET_INERTIA_S, False, 0.0, float(got["OilTemp"]), float(got["HousingTemp"]))


def _closed_loop(scenario):
    params = plant.load_plant(plant.DEFAULT_PLANT)
    shift_cal = shift_calibration.load(shift.SHIFT_TOML).variants[ADAPTIVE]
    clutch_cal = calibration.load(ROOT / "tools" / "calibrations" / f"{shift.TCU_CALIBRATION}.toml")
    records = shift.run_case(params, f"shift_1_2_{ADAPTIVE}", scenario)
    report = canlog.database().get_message_by_name("AdaptationReport")
    ref, out = None, []
    for rec in records:
        if ref is not None:
            _between(ref, params, scenario)
        o = shift.reference_run(rec, shift_cal, clutch_cal, scenario.oil_degC, reference=ref)
        ref = o["reference"]
        tcu = [(k, report.decode(bytes.fromhex(h), decode_choices=False)) for k, fid, h in rec["frames"]
               if fid == report.frame_id]
        out.append({**o, "tcu_adaptation": tcu, "values": ref.adapt.values.copy()})
    return out


@pytest.mark.parametrize("scenario", [Scenario("friction+10", 80.0, 1.0, 1.1, shifts=3),
                                      Scenario("friction-20_cold", 40.0, 1.0, 0.8, shifts=2)],
                         ids=lambda s: s.name)
def test_firmware_adaptive_shifts_match_the_reference(scenario):
    """Consecutive adaptive shifts on a plant whose friction differs from the TCU's calibration (the -20 %
    plant at 40 degC oil also learns a negative kiss offset: the inverse's clamp of F + offset at 0)."""
    runs = _closed_loop(scenario)
    for i, o in enumerate(runs):
        # 1 mA, as test_shift.py's single shifts: float against double, the film table against eq. 9/15, the
        # lag compensation's gain 3.9 on a pressure difference, VfsCurrent's 1/32 mA; with the learned values
        # carried over, the model differs by the float rounding of the values themselves (< 1e-6). Seen: at
        # most 0.18 mA. A learned value off by one DBC step of FrictionScale moves the currents by ~0.1 mA,
        # a wrong update rule by tens of mA (a missed kiss offset: 17 mA at the prepare phase's start).
        diff = np.abs(o["reference_mA"] - o["tcu_mA"])
        assert diff.max() <= 1.0, (i, int(diff.argmax()), float(diff.max()))
        assert o["reference_report_step"] == o["tcu_report_step"]
        ref = o["reference_report"]["adaptation"]
        assert len(o["tcu_adaptation"]) == 1 and o["tcu_adaptation"][0][0] == o["tcu_report_step"]
        tcu = o["tcu_adaptation"][0][1]
        assert int(tcu["Result"]) == ref["result"] == A.RESULT_UPDATED and int(tcu["Node"]) == ref["node"]
        # the signals' resolutions (FrictionScale 0.0005, Confidence 0.01, FilmFactor 0.005, KissOffset
        # 0.25 kPa: hil/wetclutch.dbc): half a step, plus the value's float-against-double difference from the
        # window's sums (the firmware's model torques differ from the reference's by the currents' 1e-3
        # relative at most: rho by that, the scale by gain x 1e-3 x (rho - 1) < 1e-4)
        assert abs(tcu["FrictionScale"] - ref["friction_scale"]) <= 0.00025 + 1e-4
        assert abs(tcu["Confidence"] - ref["confidence"]) <= 0.005 + 1e-4
        assert abs(tcu["FilmFactor"] - ref["film_factor"]) <= 0.0025 + 1e-4
        assert abs(tcu["KissOffset"] - 1e-3 * ref["kiss_offset_Pa"]) <= 0.125 + 0.05
    learned = runs[-1]["values"]
    truth = scenario.friction_scale
    node = runs[-1]["reference_report"]["adaptation"]["node"]
    assert abs(learned.friction_scale[node] - truth) < abs(1.0 - truth)      # learning towards the plant

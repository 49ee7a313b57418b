"""The 8-speed plant file (tools/plants/8hp/*.toml): what the vehicle file and the gearbox description do not
already say, read and checked; Plant8Params, load_plant8.

A plant file names

  vehicle = "PATH"        a vehicle plant file (tools/plants/vehicles/*.toml format, any path, relative to this
                          file): the driveline (inertias, final drive, driveshaft compliance, wheel, mass, road
                          load), the engine's lag and dead time, the fill, the oil and housing temperatures, the
                          full-load turbine torque that scales the engine's full-load curve;
  gearbox = "PATH"        a gearbox description (tools/gearboxes/*.toml): the sets, shafts, elements and gears;
  [truth] calibration     the friction material of every element's TRUE clutch (a calibration file, e.g.
                          bench_true.toml): each element's pack, piston, return spring and VFS are its own (the
                          description's overrides), the friction, viscosity, contact, thermal and film
                          parameters this file's, as the 1->2 plant's true clutch (bench_true) differs from the
                          controller's model (table1); [truth.friction_scale] NAME = { value, unit = "1",
                          source } scales an element's Coulomb friction and static capacity (default 1);
                          aeration_speed: an open element's drag peaks at this slip speed (element);
                          vfs_time_constant_scale (optional, 0.25..4, default 1): every element's true VFS lag
                          against its description's (a vehicle whose solenoids the TCU does not know);
  [inertia]               converter_turbine: the converter's turbine wheel (on the gearbox input shaft);
  [engine]                the torque map: speed axis, full-load curve (a fraction of the vehicle's
                          scenario.turbine_torque_full), drag at zero pedal; the idle governor;
  [converter]             speed-ratio axis, K-factor and torque-ratio curves, the overrun capacity;
  [lockup]                the lock-up clutch: piston, spring, friction radius and surfaces, friction, VFS.

Every number is { value, unit, source } (a list for a curve); a file may start with extends = "base.toml" and
then hold only what differs (entries replace the base's one by one; paths stay relative to the file naming them).
Every error is a PlantError naming the file and the entry.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ... import gearbox as gearbox_pkg
from ...calibration import Calibration, CalibrationError, load as load_calibration
from ...reference import model
from ...util.tomlfile import extends_path, read_toml
from ..plant import PlantError, PlantParams, load_plant

RPM = model.RAD_S_PER_RPM

# (section, name, unit, kind): kind "pos", "nonneg", "curve" (a list), "ratio_curve" (a list of values > 0)
SCHEMA: tuple[tuple[str, str, str, str], ...] = (
    ("inertia", "converter_turbine", "kg*m^2", "pos"),
    ("truth", "aeration_speed", "rpm", "pos"),
    ("engine", "speed_axis", "rpm", "axis"),
    ("engine", "full_load", "1", "curve"),
    ("engine", "drag", "N*m", "curve"),
    ("engine", "idle_speed", "rpm", "pos"),
    ("engine", "idle_gain", "N*m*s/rad", "pos"),
    ("engine", "idle_integral_gain", "N*m/rad", "nonneg"),
    ("engine", "idle_torque_max", "N*m", "pos"),
    ("converter", "speed_ratio", "1", "axis"),
    ("converter", "k_factor", "rpm/sqrt(N*m)", "pos_curve"),
    ("converter", "torque_ratio", "1", "pos_curve"),
    ("converter", "overrun_capacity", "1", "pos"),
    ("lockup", "piston_area", "m^2", "pos"),
    ("lockup", "return_spring_force", "N", "nonneg"),
    ("lockup", "effective_radius", "m", "pos"),
    ("lockup", "friction_surfaces", "1", "pos"),
    ("lockup", "friction_coefficient", "1", "pos"),
    ("lockup", "static_friction_factor", "1", "pos"),
    ("lockup", "vfs_gain", "Pa/mA", "pos"),
    ("lockup", "vfs_time_constant", "s", "pos"),
    ("lockup", "vfs_current_max", "mA", "pos"),
)
_TOP = {"extends", "vehicle", "gearbox", "truth"} | {s for s, _, _, _ in SCHEMA}


@dataclass(frozen=True)
class Plant8Params:
    """A validated 8-speed plant file (SI units: rad/s, N*m, kg*m^2, Pa, s)."""

    path: str
    vehicle: PlantParams                # the vehicle plant file (driveline, engine lag, fill, oil)
    gearbox: object                     # wetclutch.gearbox.Gearbox
    truth: dict                         # element name -> its TRUE clutch Calibration
    friction_scale: dict                # element name -> Coulomb friction / static capacity factor
    converter_turbine_inertia: float
    engine_inertia: float               # crank, flywheel, converter pump: vehicle turbine_inertia - the rest
    speed_axis: np.ndarray              # rad/s
    full_load_Nm: np.ndarray            # brake torque at full pedal (the vehicle's turbine_torque_full x shape)
    drag_Nm: np.ndarray                 # brake torque at zero pedal (fuel cut), <= 0
    idle_speed: float                   # rad/s
    idle_gain: float
    idle_integral_gain: float
    idle_torque_max: float
    speed_ratio: np.ndarray             # converter nu = w_turbine / w_pump
    capacity: np.ndarray                # T_pump / w_pump^2, N*m/(rad/s)^2 (from the K-factor); 0 at nu = 1
    torque_ratio: np.ndarray            # T_turbine / T_pump
    overrun_capacity: float
    aeration_speed: float               # rad/s: an open element's drag peaks there (element)
    lockup: dict                        # the [lockup] values
    sources: dict = field(default_factory=dict, compare=False)
    truth_path: str = ""

    @property
    def coupling_point(self) -> float:
        """The speed ratio where the torque ratio first reaches 1 (the stator freewheels above it)."""
        for nu, tr in zip(self.speed_ratio, self.torque_ratio):
            if tr <= 1.0:
                return float(nu)
        return 1.0


def _read_doc(path: Path, chain: tuple) -> dict:
    """path's document with its extends chain merged in; vehicle, gearbox and [truth].calibration made absolute."""
    doc = read_toml(path, PlantError, "8-speed plant file")
    for key in ("vehicle", "gearbox"):
        if isinstance(doc.get(key), str) and doc[key].strip():
            doc[key] = str((path.parent / doc[key]).resolve())
    truth = doc.get("truth")
    if isinstance(truth, dict) and isinstance(truth.get("calibration"), str) and truth["calibration"].strip():
        truth["calibration"] = str((path.parent / truth["calibration"]).resolve())
    base_path = extends_path(path, doc, chain, PlantError)
    if base_path is None:
        return doc
    base = _read_doc(base_path, chain + (base_path,))
    for key, value in doc.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            merged = {**base[key], **value}
            for sub in ("friction_scale",):
                if isinstance(value.get(sub), dict) and isinstance(base[key].get(sub), dict):
                    merged[sub] = {**base[key][sub], **value[sub]}
            base[key] = merged
        else:
            base[key] = value
    return base


def _entry(where: str, doc: dict, section: str, name: str, unit: str, kind: str):
    q = f"{section}.{name}"
    entry = doc.get(section, {}).get(name)
    if entry is None:
        raise PlantError(f"{where}: missing parameter '{q}' (unit {unit})")
    if not isinstance(entry, dict) or "value" not in entry:
        raise PlantError(f"{where}: parameter '{q}' must be {{ value = ..., unit = \"{unit}\", source = \"...\" }}")
    extra = set(entry) - {"value", "unit", "source"}
    if extra:
        raise PlantError(f"{where}: parameter '{q}': unknown key(s) {', '.join(sorted(extra))}")
    if entry.get("unit") != unit:
        raise PlantError(f"{where}: parameter '{q}': unit {entry.get('unit')!r}, expected {unit!r}")
    src = entry.get("source")
    if not isinstance(src, str) or not src.strip():
        raise PlantError(f"{where}: parameter '{q}': missing 'source' (reference or reasoning)")
    raw = entry["value"]
    curve = kind in ("axis", "curve", "pos_curve")
    items = raw if curve else [raw]
    if curve and (not isinstance(raw, list) or len(raw) < 2):
        raise PlantError(f"{where}: parameter '{q}': value must be a list of at least 2 numbers")
    for v in items:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise PlantError(f"{where}: parameter '{q}': value {v!r} is not a finite number")
    values = np.array(items, dtype=float)
    if kind in ("pos", "pos_curve") and not np.all(values > 0):
        raise PlantError(f"{where}: parameter '{q}': values must be > 0 {unit}")
    if kind == "nonneg" and not np.all(values >= 0):
        raise PlantError(f"{where}: parameter '{q}': value must be >= 0 {unit}")
    if kind == "axis" and not (np.all(np.diff(values) > 0) and values[0] >= 0):
        raise PlantError(f"{where}: parameter '{q}': the axis must start at >= 0 and increase strictly")
    return (values if curve else float(values[0])), src


def _truth_calibrations(where: str, doc: dict, gb) -> tuple[dict, dict, str]:
    """Each element's true clutch: the truth material file with the element's own pack, piston, spring and VFS
    (the entries its description overrides) put in; its friction scale."""
    truth = doc.get("truth", {})
    if not isinstance(truth, dict):
        raise PlantError(f"{where}: 'truth' must be a table")
    for key in truth:
        if key not in ("calibration", "friction_scale", "aeration_speed", "vfs_time_constant_scale"):
            raise PlantError(f"{where}: unknown parameter 'truth.{key}'")
    cal_path = truth.get("calibration")
    if cal_path is None:
        material, path = None, ""
    else:
        if not isinstance(cal_path, str) or not cal_path.strip():
            raise PlantError(f"{where}: parameter 'truth.calibration' must be a path string")
        try:
            material = load_calibration(cal_path)
        except CalibrationError as e:
            raise PlantError(f"{where}: parameter 'truth.calibration': {e}") from None
        path = cal_path
    # the true solenoids' lag against the description's (a vehicle whose VFS differ from those the TCU knows)
    lag_scale = 1.0
    if "vfs_time_constant_scale" in truth:
        lag_scale, _ = _entry(where, doc, "truth", "vfs_time_constant_scale", "1", "pos")
        if not 0.25 <= lag_scale <= 4.0:
            raise PlantError(f"{where}: parameter 'truth.vfs_time_constant_scale': {lag_scale!r} must be in [0.25, 4]")
    cals = {}
    for e in gb.elements:
        if material is None and lag_scale == 1.0:
            cals[e.name] = e.calibration
            continue
        base = material or e.calibration
        own = {key.split(".", 1)[1] for key in e.overrides} if material is not None else set(base.values)
        values = {**base.values, **{k: e.calibration.values[k] for k in own}}
        sources = {**base.sources, **{k: e.calibration.sources[k] for k in own}}
        values["vfs_time_constant"] *= lag_scale
        cals[e.name] = Calibration(values, sources, f"{path or gb.path} with element {e.name}'s pack, piston and VFS")
    scales = {e.name: 1.0 for e in gb.elements}
    table = truth.get("friction_scale", {})
    if not isinstance(table, dict):
        raise PlantError(f"{where}: 'truth.friction_scale' must be a table of element names")
    for name in table:
        if name not in scales:
            raise PlantError(f"{where}: 'truth.friction_scale.{name}': not an element of {gb.path}")
        value, _ = _entry(where, {"truth": table}, "truth", name, "1", "pos")
        if not 0.2 <= value <= 5.0:
            raise PlantError(f"{where}: parameter 'truth.friction_scale.{name}': {value!r} must be in [0.2, 5]")
        scales[name] = value
    return cals, scales, path


def load_plant8(path) -> Plant8Params:
    """Read and validate an 8-speed plant file (module docstring). Raises PlantError naming the file and the
    entry (a bad vehicle file or gearbox description: its own message, prefixed with this file's)."""
    path = Path(path)
    where = str(path)
    doc = _read_doc(path, (path.resolve(),))
    for key, value in doc.items():
        if key not in _TOP:
            raise PlantError(f"{where}: unknown section or key '{key}'")
        if key in {s for s, _, _, _ in SCHEMA} - {"truth"}:      # [truth]: _truth_calibrations checks it
            if not isinstance(value, dict):
                raise PlantError(f"{where}: '{key}' must be a table of parameters")
            for name in value:
                if (key, name) not in {(s, n) for s, n, _, _ in SCHEMA}:
                    raise PlantError(f"{where}: unknown parameter '{key}.{name}'")
    for key in ("vehicle", "gearbox"):
        if not isinstance(doc.get(key), str):
            raise PlantError(f"{where}: missing '{key}' (the path of the {key} file, relative to this file)")
    try:
        vehicle = load_plant(doc["vehicle"])
    except PlantError as e:
        raise PlantError(f"{where}: 'vehicle': {e}") from None
    try:
        gb = gearbox_pkg.load(doc["gearbox"])
    except gearbox_pkg.GearboxError as e:
        raise PlantError(f"{where}: 'gearbox': {e}") from None

    values, sources = {}, {}
    for section, name, unit, kind in SCHEMA:
        values[(section, name)], sources[f"{section}.{name}"] = _entry(where, doc, section, name, unit, kind)
    v = values
    axis = v[("engine", "speed_axis")] * RPM
    full = v[("engine", "full_load")] * vehicle.turbine_torque_full
    drag = v[("engine", "drag")]
    for name, curve in (("full_load", full), ("drag", drag)):
        if curve.shape != axis.shape:
            raise PlantError(f"{where}: parameter 'engine.{name}': {curve.size} values for {axis.size} speeds "
                             "(engine.speed_axis)")
    if not np.all(drag <= 0.0):
        raise PlantError(f"{where}: parameter 'engine.drag': the drag torque at zero pedal must be <= 0 N*m")
    if not np.all(full >= drag):
        raise PlantError(f"{where}: parameter 'engine.full_load': below the drag curve")
    nu = v[("converter", "speed_ratio")]
    kf = v[("converter", "k_factor")]
    tr = v[("converter", "torque_ratio")]
    for name, curve in (("k_factor", kf), ("torque_ratio", tr)):
        if curve.shape != nu.shape:
            raise PlantError(f"{where}: parameter 'converter.{name}': {curve.size} values for {nu.size} speed "
                             "ratios (converter.speed_ratio)")
    if not (nu[0] == 0.0 and nu[-1] < 1.0):
        raise PlantError(f"{where}: parameter 'converter.speed_ratio': from 0 to below 1 (the capacity is 0 at "
                         "1, the coupling's synchronism: appended, not given)")
    if not np.all(np.diff(tr) <= 0.0) or tr[-1] < 1.0 - 1e-12:
        raise PlantError(f"{where}: parameter 'converter.torque_ratio': must fall (not rise) to 1 at the coupling "
                         "point and stay at 1")
    capacity = 1.0 / (kf * RPM) ** 2           # T = (N / K)^2, N in rpm  ->  T = w^2 / (K RPM)^2
    lock = {name: v[("lockup", name)] for _, name, _, _ in (s for s in SCHEMA if s[0] == "lockup")}
    truth, scales, truth_path = _truth_calibrations(where, doc, gb)
    j_turbine = v[("inertia", "converter_turbine")]
    j_input = gb.shafts[gb.shaft_index(gb.input_shaft)].inertia
    j_engine = vehicle.turbine_inertia - j_turbine - j_input
    if not j_engine > 0.0:
        raise PlantError(f"{where}: parameter 'inertia.converter_turbine': the vehicle's turbine_inertia "
                         f"{vehicle.turbine_inertia:g} kg*m^2 leaves {j_engine:g} for the engine and pump after "
                         f"the turbine wheel and the gearbox input shaft ({j_input:g})")
    return Plant8Params(
        path=where, vehicle=vehicle, gearbox=gb, truth=truth, friction_scale=scales,
        converter_turbine_inertia=j_turbine, engine_inertia=j_engine,
        speed_axis=axis, full_load_Nm=full, drag_Nm=drag,
        idle_speed=v[("engine", "idle_speed")] * RPM, idle_gain=v[("engine", "idle_gain")],
        idle_integral_gain=v[("engine", "idle_integral_gain")], idle_torque_max=v[("engine", "idle_torque_max")],
        speed_ratio=np.append(nu, 1.0), capacity=np.append(capacity, 0.0), torque_ratio=np.append(tr, 1.0),
        overrun_capacity=v[("converter", "overrun_capacity")], aeration_speed=v[("truth", "aeration_speed")] * RPM,
        lockup=lock, sources=sources,
        truth_path=truth_path)

"""The machine model: two XYZ-3RPS machines facing each other across the blade (SPEC.md section 9).

A machine.toml holds the 3-RPS head dimensions (shared by both sides), one rigid transform per side
from that side's machine frame M to the workpiece frame W, ``p_W = origin_mm + rotation @ p_M``, and the
stroke, speed and acceleration limits of the six axes x, y, z, d1, d2, d3. ``load_machine`` reads and
validates one (every problem raises ``MachineError`` naming the key); ``machine_to_toml`` writes it
back, so that a plan can store the machine "as used" and ``load_machine`` reads it to the same values.

Keys the loader does not know are accepted and ignored (they are not written back).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from core.errors import MachineError
from core.util.files import read_toml
from core.util.resources import resources_dir

SIDES = ("left", "right")
AXES = ("x", "y", "z", "d1", "d2", "d3")
HEAD_KEYS = ("base_radius_mm", "platform_radius_mm", "home_height_mm", "gauge_length_mm", "max_tilt_deg")
LIMIT_KEYS = ("min_mm", "max_mm", "max_speed_mm_s", "max_accel_mm_s2")
#: the heads' and the clamp's geometry for the collision check (core.machine.clearance): optional keys of
#: [head] and [clamp] with these defaults (mm), the bench machines' of resources/machine.toml
HEAD_GEOMETRY = {"spindle_radius_mm": 40.0, "platform_plate_radius_mm": 75.0, "platform_thickness_mm": 15.0}
CLAMP_GEOMETRY = {"half_width_mm": 10.0}
# A rotation within this of orthonormal is accepted and snapped to the nearest rotation (so that
# hand-written entries such as 0.70710678 load); further off it is refused.
ROTATION_TOLERANCE = 1e-6
_SNAP_ABOVE = 1e-12
#: no length (mm), speed (mm/s), acceleration (mm/s^2) or angle of a bench machine is this large: a
#: larger number is a typing or unit error (and overflows the kinematics)
MAX_MAGNITUDE = 1e6
#: no length of a 3-RPS head (joint circles, home height, gauge length) is below this (mm): smaller is a
#: typing or unit error, and the mechanism degenerates (the forward kinematics no longer converges)
MIN_HEAD_MM = 1.0
#: an axis accelerating more slowly than this (mm/s^2) takes metres to reach a milling speed: a typing or
#: unit error (the machine clock would stretch a plan without end)
MIN_ACCEL_MM_S2 = 1.0


@dataclass(frozen=True)
class AxisLimit:
    """Stroke and dynamics of one axis: min_mm, max_mm : float, mm; max_speed_mm_s : float, mm/s;
    max_accel_mm_s2 : float, mm/s^2."""

    min_mm: float
    max_mm: float
    max_speed_mm_s: float
    max_accel_mm_s2: float


@dataclass(frozen=True)
class Limits:
    """The six axes' limits: x, y, z (the 3-RPS base origin o in M) and d1..d3 (leg length minus L_0)."""

    x: AxisLimit
    y: AxisLimit
    z: AxisLimit
    d1: AxisLimit
    d2: AxisLimit
    d3: AxisLimit

    def axis(self, name: str) -> AxisLimit:
        """The limit of axis ``name``, one of x, y, z, d1, d2, d3."""
        if name not in AXES:
            raise MachineError(f"unknown machine axis {name!r}: use one of {', '.join(AXES)}")
        return getattr(self, name)


@dataclass(frozen=True, eq=False)
class SideTransform:
    """Rigid transform machine frame M -> workpiece frame W of one side: p_W = origin + rotation @ p_M.

    origin : (3,) float, mm, W; rotation : (3, 3) float, proper rotation (det +1). Arrays are read-only.
    """

    origin: np.ndarray
    rotation: np.ndarray

    def to_workpiece(self, p_m: np.ndarray) -> np.ndarray:
        """(n, 3) float, mm, frame M -> (n, 3) float, mm, frame W."""
        return p_m @ self.rotation.T + self.origin

    def vectors_to_workpiece(self, v_m: np.ndarray) -> np.ndarray:
        """(n, 3) float directions, frame M -> frame W."""
        return v_m @ self.rotation.T

    def vectors_to_machine(self, v_w: np.ndarray) -> np.ndarray:
        """(n, 3) float directions, frame W -> frame M."""
        return v_w @ self.rotation


@dataclass(frozen=True, eq=False)
class Machine:
    """The double-sided XYZ-3RPS machine.

    base_radius, platform_radius : float, mm (R_b, r_p: joint circles of base and platform);
    home_height : float, mm (h_0, platform centre above the base, kept constant: h = h_0);
    gauge_length : float, mm (e, platform centre to tool tip along the tool axis, tool included);
    max_tilt_deg : float, degrees (largest angle between the tool axis and z_M);
    left, right : SideTransform; limits : Limits;
    spindle_radius : float, mm (the spindle housing, a cylinder about the tool axis from the tool's
    spindle nose up to the platform); platform_plate_radius, platform_thickness : float, mm (the moving
    platform's plate, a disc about the tool axis centred gauge_length from the tip);
    clamp_half_width : float, mm (the clamp fixture: the block X_W <= x_clamp as long along Y_W as the
    root, |Z_W| <= this: core.machine.clearance.Clamp).
    """

    base_radius: float
    platform_radius: float
    home_height: float
    gauge_length: float
    max_tilt_deg: float
    left: SideTransform
    right: SideTransform
    limits: Limits
    spindle_radius: float = HEAD_GEOMETRY["spindle_radius_mm"]
    platform_plate_radius: float = HEAD_GEOMETRY["platform_plate_radius_mm"]
    platform_thickness: float = HEAD_GEOMETRY["platform_thickness_mm"]
    clamp_half_width: float = CLAMP_GEOMETRY["half_width_mm"]

    @property
    def home_leg_length(self) -> float:
        """L_0 : float, mm, leg length at theta = 0, h = h_0: sqrt((R_b - r_p)^2 + h_0^2)."""
        return math.hypot(self.base_radius - self.platform_radius, self.home_height)

    def side(self, name: str) -> SideTransform:
        """The transform of side ``name`` ('left' or 'right')."""
        if name not in SIDES:
            raise MachineError(f"unknown machine side {name!r}: use 'left' or 'right'")
        return getattr(self, name)


def default_machine_path() -> Path:
    """The path of the shipped default machine.toml (resources/machine.toml)."""
    return resources_dir() / "machine.toml"


def load_machine(path: str | Path | None = None) -> Machine:
    """Read and validate a machine.toml; ``None`` loads the shipped default.

    Raises MachineError (file missing or unreadable, TOML syntax, or a bad key, named in the message).
    """
    p = default_machine_path() if path is None else Path(path)
    data = read_toml(p, MachineError, "machine file")
    return parse_machine(data, source=str(p))


def parse_machine(data: dict, source: str = "machine.toml") -> Machine:
    """Validate the parsed TOML tables of a machine.toml and build the Machine.

    data : dict as returned by tomllib; source : str, file name used in error messages.
    """
    head = _table(data, "head", source)
    dims = {}
    for key in HEAD_KEYS:
        value = _number(head, key, "head", source)
        if value <= 0:
            raise MachineError(f"{source}: [head] {key} = {value} must be positive")
        if key != "max_tilt_deg" and value < MIN_HEAD_MM:
            raise MachineError(f"{source}: [head] {key} = {value:g} mm is below {MIN_HEAD_MM:g} mm: no 3-RPS "
                               "head is that small (its kinematics degenerate); check the value and its unit")
        dims[key] = value
    if dims["max_tilt_deg"] >= 90:
        raise MachineError(f"{source}: [head] max_tilt_deg = {dims['max_tilt_deg']} must be below 90")
    geometry = {}
    for key, default in HEAD_GEOMETRY.items():
        geometry[key] = _number(head, key, "head", source) if key in head else default
        if geometry[key] <= 0:
            raise MachineError(f"{source}: [head] {key} = {geometry[key]} must be positive")
    if geometry["platform_plate_radius_mm"] < dims["platform_radius_mm"]:
        raise MachineError(f"{source}: [head] platform_plate_radius_mm = {geometry['platform_plate_radius_mm']:g} "
                           f"is smaller than the joint circle platform_radius_mm = {dims['platform_radius_mm']:g}: "
                           f"the plate carries the joints")
    clamp = _table(data, "clamp", source) if "clamp" in data else {}
    half_width = _number(clamp, "half_width_mm", "clamp", source) if "half_width_mm" in clamp else \
        CLAMP_GEOMETRY["half_width_mm"]
    if half_width <= 0:
        raise MachineError(f"{source}: [clamp] half_width_mm = {half_width} must be positive")
    sides = {name: _side(data, name, source) for name in SIDES}
    limits_table = _table(data, "limits", source)
    limits = {axis: _limit(limits_table, axis, source) for axis in AXES}
    return Machine(
        base_radius=dims["base_radius_mm"],
        platform_radius=dims["platform_radius_mm"],
        home_height=dims["home_height_mm"],
        gauge_length=dims["gauge_length_mm"],
        max_tilt_deg=dims["max_tilt_deg"],
        left=sides["left"],
        right=sides["right"],
        limits=Limits(**limits),
        spindle_radius=geometry["spindle_radius_mm"],
        platform_plate_radius=geometry["platform_plate_radius_mm"],
        platform_thickness=geometry["platform_thickness_mm"],
        clamp_half_width=half_width,
    )


def machine_to_toml(machine: Machine) -> str:
    """The machine as machine.toml text; ``parse_machine(tomllib.loads(text))`` gives the same values."""
    f = _fmt
    lines = [
        "# bladecam machine model (SPEC.md section 9): two XYZ-3RPS machines facing each other across",
        "# the blade. Per side: p_W = origin_mm + rotation @ p_M. Lengths in mm, angles in degrees.",
        "",
        "[head]",
        f"base_radius_mm = {f(machine.base_radius)}",
        f"platform_radius_mm = {f(machine.platform_radius)}",
        f"home_height_mm = {f(machine.home_height)}",
        f"gauge_length_mm = {f(machine.gauge_length)}",
        f"max_tilt_deg = {f(machine.max_tilt_deg)}",
        f"spindle_radius_mm = {f(machine.spindle_radius)}",
        f"platform_plate_radius_mm = {f(machine.platform_plate_radius)}",
        f"platform_thickness_mm = {f(machine.platform_thickness)}",
        "",
        "[clamp]",
        f"half_width_mm = {f(machine.clamp_half_width)}",
    ]
    for name in SIDES:
        t = machine.side(name)
        rows = ", ".join("[" + ", ".join(f(v) for v in row) + "]" for row in t.rotation)
        lines += ["", f"[{name}]", f"origin_mm = [{', '.join(f(v) for v in t.origin)}]",
                  f"rotation = [{rows}]"]
    for axis in AXES:
        lim = machine.limits.axis(axis)
        lines += ["", f"[limits.{axis}]"] + [f"{k} = {f(getattr(lim, k))}" for k in LIMIT_KEYS]
    return "\n".join(lines) + "\n"


def _fmt(value: float) -> str:
    """A float as a TOML float that reads back to the same double."""
    v = float(value)
    if not math.isfinite(v):
        raise MachineError(f"cannot write a non-finite machine value ({v}) to machine.toml")
    return repr(v)


def _table(parent: dict, key: str, source: str, where: str = "") -> dict:
    name = f"{where}.{key}" if where else key
    if key not in parent:
        raise MachineError(f"{source}: missing table [{name}]")
    value = parent[key]
    if not isinstance(value, dict):
        raise MachineError(f"{source}: [{name}] must be a table, got {type(value).__name__}")
    return value


def _is_number(value: object) -> bool:
    """A TOML int or float that a float holds (an integer of 400 digits is not one)."""
    if not isinstance(value, int | float) or isinstance(value, bool):
        return False
    try:
        float(value)
    except OverflowError:
        return False
    return True


def _number(table: dict, key: str, where: str, source: str) -> float:
    if key not in table:
        raise MachineError(f"{source}: missing key [{where}] {key}")
    value = table[key]
    if not _is_number(value):
        shown = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
        raise MachineError(f"{source}: [{where}] {key} must be a number a float can hold, got {shown}")
    if not math.isfinite(value):
        raise MachineError(f"{source}: [{where}] {key} must be finite, got {value!r}")
    if abs(value) > MAX_MAGNITUDE:
        raise MachineError(f"{source}: [{where}] {key} = {value!r} is beyond any bench machine (at most "
                           f"{MAX_MAGNITUDE:g} in magnitude); check the value and its unit")
    return float(value)


def _side(data: dict, name: str, source: str) -> SideTransform:
    table = _table(data, name, source)
    if "origin_mm" not in table:
        raise MachineError(f"{source}: missing key [{name}] origin_mm")
    origin = table["origin_mm"]
    if not (isinstance(origin, list) and len(origin) == 3 and all(_is_number(v) for v in origin)):
        raise MachineError(f"{source}: [{name}] origin_mm must be a list of 3 numbers, got {origin!r}")
    if "rotation" not in table:
        raise MachineError(f"{source}: missing key [{name}] rotation")
    rot = table["rotation"]
    if not (isinstance(rot, list) and len(rot) == 3 and all(
            isinstance(r, list) and len(r) == 3 and all(_is_number(v) for v in r) for r in rot)):
        raise MachineError(f"{source}: [{name}] rotation must be 3 rows of 3 numbers, got {rot!r}")
    o = np.array(origin, dtype=float)
    r = np.array(rot, dtype=float)
    if not (np.isfinite(o).all() and np.isfinite(r).all()):
        raise MachineError(f"{source}: [{name}] origin_mm and rotation must be finite numbers")
    if np.abs(o).max() > MAX_MAGNITUDE:
        raise MachineError(f"{source}: [{name}] origin_mm = {origin!r} is beyond any bench machine (at most "
                           f"{MAX_MAGNITUDE:g} mm from the workpiece origin)")
    off = float(np.abs(r.T @ r - np.eye(3)).max())
    if off > ROTATION_TOLERANCE:
        raise MachineError(f"{source}: [{name}] rotation is not orthonormal (R^T R differs from the "
                           f"identity by {off:.2e}); give a rotation matrix, rows to >= 7 digits")
    det = float(np.linalg.det(r))
    if det < 0:
        raise MachineError(f"{source}: [{name}] rotation has determinant {det:.6f}: a mirror, not a "
                           f"proper rotation; the right side is the left one turned (e.g. 180 deg about X_W)")
    if off > _SNAP_ABOVE:
        u, _, vt = np.linalg.svd(r)
        r = u @ vt
    o.setflags(write=False)
    r.setflags(write=False)
    return SideTransform(origin=o, rotation=r)


def _limit(limits: dict, axis: str, source: str) -> AxisLimit:
    table = _table(limits, axis, source, where="limits")
    where = f"limits.{axis}"
    vals = {k: _number(table, k, where, source) for k in LIMIT_KEYS}
    if vals["min_mm"] >= vals["max_mm"]:
        raise MachineError(f"{source}: [{where}] min_mm = {vals['min_mm']} must be below "
                           f"max_mm = {vals['max_mm']}")
    for k in ("max_speed_mm_s", "max_accel_mm_s2"):
        if vals[k] <= 0:
            raise MachineError(f"{source}: [{where}] {k} = {vals[k]} must be positive")
    if vals["max_accel_mm_s2"] < MIN_ACCEL_MM_S2:
        raise MachineError(f"{source}: [{where}] max_accel_mm_s2 = {vals['max_accel_mm_s2']:g} is below "
                           f"{MIN_ACCEL_MM_S2:g} mm/s^2: no machine axis is that slow; check the value and its unit")
    return AxisLimit(**vals)

"""Where a mesh or CAD blade sits in its file: the length unit of its numbers and its propeller axis.

AXIS strings (the CLI's --axis, the project file's and plan.json's axis):
- ``x``, ``y`` or ``z``: that file axis, through the origin;
- ``DX,DY,DZ``: the axis along that direction, through the origin;
- either followed by ``@PX,PY,PZ``: through that point (file units) instead, e.g. ``z@200,0,0``.

Units (``--units``): mm, cm, m or in, what a mesh's numbers mean (an STL states none; a STEP or IGES
file states its own unit, which OpenCASCADE converts to mm). ``unit_hint`` names the unit that makes a
blade's size a propeller's when the one given makes it implausible.
"""

from __future__ import annotations

import math

import numpy as np

from core.errors import BladeInputError

UNITS = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4}
#: named file axes -> blade frame (rows: new X, Y, Z), cyclic permutations (right-handed)
AXIS_ROTATIONS = {
    "x": np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]),
    "y": np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
    "z": np.eye(3),
}
#: a propeller blade's tip radius, mm: the diameters of core.blade.bounds.DIAMETER_MM's usual range
TIP_RADIUS_MM = (10.0, 6000.0)


def unit_factor(units: str) -> float:
    """mm per unit of ``units`` (mm, cm, m, in); BladeInputError for another."""
    key = str(units).strip().lower()
    if key not in UNITS:
        raise BladeInputError(f"units {units!r} are not one of {', '.join(UNITS)}")
    return UNITS[key]


def _vector(text: str, what: str, spec: str) -> np.ndarray:
    try:
        v = np.array([float(x) for x in text.split(",")])
    except ValueError:
        v = np.array([])
    if v.shape != (3,) or not np.isfinite(v).all():
        raise BladeInputError(f"axis {spec!r}: the {what} {text!r} is not three numbers X,Y,Z; give x, y, z or "
                              "DX,DY,DZ, optionally followed by @PX,PY,PZ (a point of the axis)")
    return v


def parse_axis(spec: str) -> tuple[str | None, np.ndarray, np.ndarray]:
    """(the axis's name or None, rotation (3, 3) file -> blade frame turning it onto +Z, a point of it
    (3,), file units) of an AXIS string (see the module)."""
    text = str(spec).strip().lower()
    direction, _, at = text.partition("@")
    point = _vector(at, "point", spec) if at else np.zeros(3)
    direction = direction.strip()
    if direction in AXIS_ROTATIONS:
        return direction, AXIS_ROTATIONS[direction], point
    d = _vector(direction, "direction", spec)
    size = float(np.linalg.norm(d))
    if size == 0.0:
        raise BladeInputError(f"axis {spec!r}: the direction is zero; give the propeller axis's direction")
    d = d / size
    # the named axis nearest the direction keeps its frame's orientation: its rotation, turned onto d
    name = "xyz"[int(np.argmax(np.abs(d)))]
    base = AXIS_ROTATIONS[name]
    e1 = base[0] - np.dot(base[0], d) * d
    if np.linalg.norm(e1) < 1e-9:
        e1 = base[1] - np.dot(base[1], d) * d
    e1 /= np.linalg.norm(e1)
    return None, np.array([e1, np.cross(d, e1), d]), point


def unit_hint(tip_radius_mm: float, units: str) -> str | None:
    """None when a tip radius of ``tip_radius_mm`` (read in ``units``) is a propeller's; otherwise why
    not, and the unit that makes it one (the one nearest the middle of TIP_RADIUS_MM on a log scale)."""
    lo, hi = TIP_RADIUS_MM
    if lo <= tip_radius_mm <= hi or not math.isfinite(tip_radius_mm) or tip_radius_mm <= 0:
        return None
    raw = tip_radius_mm / unit_factor(units)
    mid = math.sqrt(lo * hi)
    fits = [(abs(math.log(raw * f / mid)), u) for u, f in UNITS.items() if lo <= raw * f <= hi and u != units]
    what = "small" if tip_radius_mm < lo else "large"
    if not fits:
        return (f"a tip radius of {tip_radius_mm:.4g} mm is too {what} for a propeller blade "
                f"({lo:g} to {hi:g} mm); check the file's units")
    u = min(fits)[1]
    return (f"a tip radius of {tip_radius_mm:.4g} mm (numbers read in {units}) is too {what} for a propeller "
            f"blade ({lo:g} to {hi:g} mm); in {u} it is {raw * UNITS[u]:.4g} mm: give --units {u}")

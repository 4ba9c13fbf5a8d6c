"""``bladecam verify``: one side's axis table (``axes_checks``): forward kinematics of every row
reproduces the CL tip and axis, every stroke, speed and acceleration limit of machine.toml holds, and
the velocity columns are the derivative of the positions (``derivative_slack``)."""

from __future__ import annotations

import numpy as np

from core.errors import MachineError
from core.machine.kinematics import forward_kinematics
from core.machine.model import AXES, Machine
from core.verify.report import Report


def derivative_slack(t: np.ndarray, x: np.ndarray, v: np.ndarray, a_lim: float) -> np.ndarray:
    """(n - 1,) mm/ms: how far the chord velocity (x[i+1] - x[i]) / (t[i+1] - t[i]) lies outside what
    velocities v (n,) mm/ms at the two rows allow (0 inside): between the rows the axis moves at v(tau)
    with |dv/dtau| <= a_lim (mm/ms^2), so its mean velocity lies within [min, max] of v[i], v[i+1]
    widened by a_lim dt, allowing for the rounding of the written positions (1e-6 mm), times (1e-6 ms)
    and velocities (1e-9 mm/ms). Any time column, uniform or not."""
    dt = np.diff(t)
    c = np.diff(x) / dt
    lo, hi = np.minimum(v[:-1], v[1:]), np.maximum(v[:-1], v[1:])
    room = a_lim * dt + (1e-6 + 1e-6 * np.abs(c)) / dt + 2e-9
    return np.maximum(np.maximum(lo - c, c - hi) - room, 0.0)


def axes_checks(side: str, a: np.ndarray, cl: dict, machine: Machine, rep: Report, name: str) -> dict:
    """One side's axis table ``a`` (n, 13) (the file ``name``) against its CL table and machine.toml:
    forward kinematics (core.machine.kinematics, the mechanism solved by Newton's method, not the
    planner's closed-form inverse) reproduces the CL tip and axis (1e-3 mm, 1e-4 rad); every stroke,
    speed and acceleration limit holds (acceleration: the change of the velocity column between two
    rows over their time step); the velocities are the derivative of the positions. Returns figures."""
    t = cl["t"]
    figures: dict = {}
    if len(a) != len(t) or np.abs(a[:, 0] - t).max(initial=0) > 1e-9:
        rep.bad("time column", f"{name}: its time column differs from the CL tables' ({len(a)} rows, "
                               f"the CL tables {len(t)})")
        return figures
    try:
        tips, axes = forward_kinematics(machine, side, a[:, 1:7])
    except MachineError as exc:
        rep.bad("forward kinematics", f"{name}: {exc}")
        return figures
    ep = np.linalg.norm(tips - cl["p"], axis=1)
    w = cl["w"] / np.linalg.norm(cl["w"], axis=1)[:, None]
    ew = np.arccos(np.clip((axes * w).sum(axis=1), -1.0, 1.0))
    for arr, tol, what, unit in ((ep, 1e-3, "tip", "mm"), (ew, 1e-4, "axis", "rad")):
        rep.many("forward kinematics", np.flatnonzero(arr > tol),
                 lambda i, arr=arr, what=what, unit=unit: (f"t = {t[i]:.1f} ms: {side} forward kinematics "
                                                           f"misses the CL {what} by {arr[i]:.2e} {unit}"))
    figures[f"{side}_fk_error_mm"] = float(f"{ep.max(initial=0):.3g}")
    for k, axis in enumerate(AXES):
        peak = _axis_column(side, axis, t, a[:, 1 + k], a[:, 7 + k], machine.limits.axis(axis), rep)
        figures[f"{side}_{axis}_peak_accel_mm_s2"] = round(peak, 2)
    return figures


def _axis_column(side: str, axis: str, t: np.ndarray, x: np.ndarray, v: np.ndarray, lim,
                 rep: Report) -> float:
    """One axis's positions x (n,) mm and velocities v (n,) mm/ms at times t (n,) ms against its limits
    ``lim`` (stroke, speed, acceleration) and as a derivative; returns its peak acceleration, mm/s^2."""
    dt = np.diff(t)
    rep.many("axis range", np.flatnonzero((x < lim.min_mm - 1e-6) | (x > lim.max_mm + 1e-6)),
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} = {x[i]:.4f} mm outside its stroke "
                       f"[{lim.min_mm:g}, {lim.max_mm:g}]")
    speed = np.abs(v) * 1000.0
    rep.many("axis speed", np.flatnonzero(speed > lim.max_speed_mm_s * (1 + 1e-6) + 1e-6),
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} moves at {speed[i]:.3f} mm/s > "
                       f"{lim.max_speed_mm_s:g} mm/s")
    # the mean acceleration between two rows' velocities (as the planner bounds it), allowing for the
    # rounding of the written velocities (1e-9 mm/ms) and times
    dv = np.diff(v)
    acc = np.abs(dv) / dt * 1e6
    slack = (2e-9 / dt + np.abs(dv) * 2e-6 / dt**2) * 1e6
    hard = np.flatnonzero(acc > lim.max_accel_mm_s2 * (1 + 1e-6) + slack)
    rep.many("axis acceleration", hard[np.argsort(-acc[hard])],
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} accelerates at {acc[i]:.1f} mm/s^2 > "
                       f"{lim.max_accel_mm_s2:g} mm/s^2 (to the next row)")
    out = derivative_slack(t, x, v, lim.max_accel_mm_s2 / 1e6)
    bad = np.flatnonzero(out > 0)
    rep.many("axis velocities", bad[np.argsort(-out[bad])],
             lambda i: f"t = {t[i]:.1f} ms: {side} v{axis.lstrip('d')} is not the derivative of {axis}: from "
                       f"this row to the next {axis} moves at {(x[i + 1] - x[i]) / dt[i] * 1000:.3f} mm/s, "
                       f"the rows say {v[i] * 1000:.3f} and {v[i + 1] * 1000:.3f} mm/s")
    return float(acc.max(initial=0))

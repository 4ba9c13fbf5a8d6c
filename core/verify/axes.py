"""``bladecam verify``: one side's axis table (``axes_checks``): forward kinematics of every row
reproduces the CL tip and axis, every stroke, speed and acceleration limit of machine.toml holds, and
the velocity columns are the derivative of the positions (``derivative_slack``). The forward
kinematics are verify's own (core.verify._axes: the mechanism solved by Newton's method, compiled),
not the planner's (core.machine.kinematics)."""

from __future__ import annotations

import numpy as np

from core.machine.model import AXES, Machine
from core.verify._axes import axis_column, derivative_slacks, forward_errors
from core.verify.report import Report

#: what a row's status from core.verify._axes.forward_errors means (0: a pose)
FK_FAILURES = {1: "axis values are not finite numbers at samples {}",
               2: "no platform pose for the leg values at samples {} (forward kinematics did not converge); "
                  "check d1..d3",
               3: "the leg values at samples {} put the platform upside down"}


def derivative_slack(t: np.ndarray, x: np.ndarray, v: np.ndarray, a_lim: float) -> np.ndarray:
    """(n - 1,) mm/ms: how far the chord velocity (x[i+1] - x[i]) / (t[i+1] - t[i]) lies outside what
    velocities v (n,) mm/ms at the two rows allow (0 inside): between the rows the axis moves at v(tau)
    with |dv/dtau| <= a_lim (mm/ms^2), so its mean velocity lies within [min, max] of v[i], v[i+1]
    widened by a_lim dt, allowing for the rounding of the written positions (1e-6 mm), times (1e-6 ms)
    and velocities (1e-9 mm/ms). Any time column, uniform or not (compiled: core.verify._axes)."""
    out = np.empty(max(len(t) - 1, 0))
    derivative_slacks(np.ascontiguousarray(t, float), np.asarray(x, float), np.asarray(v, float), float(a_lim), out)
    return out


def axes_checks(side: str, a: np.ndarray, cl: dict, machine: Machine, rep: Report, name: str) -> dict:
    """One side's axis table ``a`` (n, 13) (the file ``name``) against its CL table and machine.toml:
    forward kinematics (core.verify._axes: the mechanism solved by Newton's method, not the planner's
    closed-form inverse) reproduces the CL tip and axis (1e-3 mm, 1e-4 rad); every stroke,
    speed and acceleration limit holds (acceleration: the change of the velocity column between two
    rows over their time step); the velocities are the derivative of the positions. Returns figures."""
    t = cl["t"]
    figures: dict = {}
    if len(a) != len(t) or np.abs(a[:, 0] - t).max(initial=0) > 1e-9:
        rep.bad("time column", f"{name}: its time column differs from the CL tables' ({len(a)} rows, "
                               f"the CL tables {len(t)})")
        return figures
    ep, ew = forward_kinematics(side, a, cl, machine, rep, name)
    if ep is None:
        return figures
    for arr, tol, what, unit in ((ep, 1e-3, "tip", "mm"), (ew, 1e-4, "axis", "rad")):
        rep.many("forward kinematics", np.flatnonzero(arr > tol),
                 lambda i, arr=arr, what=what, unit=unit: (f"t = {t[i]:.1f} ms: {side} forward kinematics "
                                                           f"misses the CL {what} by {arr[i]:.2e} {unit}"))
    figures[f"{side}_fk_error_mm"] = float(f"{ep.max(initial=0):.3g}")
    for k, axis in enumerate(AXES):
        peak = _axis_column(side, axis, t, a[:, 1 + k], a[:, 7 + k], machine.limits.axis(axis), rep)
        figures[f"{side}_{axis}_peak_accel_mm_s2"] = round(peak, 2)
    return figures


def forward_kinematics(side: str, a: np.ndarray, cl: dict, machine: Machine, rep: Report, name: str
                       ) -> tuple[np.ndarray | None, np.ndarray]:
    """The distance (n,) mm of each row's forward-kinematics tip from the CL tip, and the angle (n,) rad
    of its axis from the CL axis (core.verify._axes); (None, ...) with a finding naming the rows
    where the axis values have no pose."""
    n = len(a)
    ep, ew, status = np.empty(n), np.empty(n), np.zeros(n, np.uint8)
    t = machine.side(side)
    forward_errors(a[:, 1:7], cl["p"], cl["w"], (machine.base_radius, machine.platform_radius, machine.home_height,
                   machine.gauge_length), np.ascontiguousarray(t.rotation, float),
                   np.ascontiguousarray(t.origin, float), ep, ew, status)
    if not status.any():
        return ep, ew
    for code, what in FK_FAILURES.items():  # (one finding per kind, naming its first samples)
        bad = np.flatnonzero(status == code)
        if bad.size:
            shown = ", ".join(str(int(i)) for i in bad[:8]) + (f" (and {bad.size - 8} more)" if bad.size > 8 else "")
            rep.bad("forward kinematics", f"{name}: {side}: {what.format(shown)}")
    return None, ew


def _axis_column(side: str, axis: str, t: np.ndarray, x: np.ndarray, v: np.ndarray, lim,
                 rep: Report) -> float:
    """One axis's positions x (n,) mm and velocities v (n,) mm/ms at times t (n,) ms against its limits
    ``lim`` (stroke, speed, acceleration) and as a derivative (``derivative_slack``), in one compiled
    pass (core.verify._axes.axis_column); returns its peak acceleration, mm/s^2 (the mean acceleration
    between two rows' velocities, as the planner bounds it)."""
    n = len(t)
    acc, out, flags = np.empty(max(n - 1, 0)), np.empty(max(n - 1, 0)), np.empty(n, np.uint8)
    axis_column(np.ascontiguousarray(t, float), x, v, (lim.min_mm, lim.max_mm, lim.max_speed_mm_s, lim.max_accel_mm_s2),
                acc, out, flags)
    if flags.any():
        _axis_findings(side, axis, t, x, v, lim, (acc, out, flags), rep)
    return float(acc.max(initial=0))


def _axis_findings(side: str, axis: str, t: np.ndarray, x: np.ndarray, v: np.ndarray, lim,
                   measured: tuple[np.ndarray, np.ndarray, np.ndarray], rep: Report) -> None:
    """The findings of one axis column: ``measured`` = (acceleration (n - 1,) mm/s^2, derivative slack
    (n - 1,) mm/ms, flags (n,)) from core.verify._axes.axis_column."""
    acc, out, flags = measured
    dt = np.diff(t)
    rep.many("axis range", np.flatnonzero(flags & 1),
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} = {x[i]:.4f} mm outside its stroke "
                       f"[{lim.min_mm:g}, {lim.max_mm:g}]")
    rep.many("axis speed", np.flatnonzero(flags & 2),
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} moves at {abs(v[i]) * 1000.0:.3f} mm/s > "
                       f"{lim.max_speed_mm_s:g} mm/s")
    hard = np.flatnonzero(flags & 4)
    rep.many("axis acceleration", hard[np.argsort(-acc[hard])],
             lambda i: f"t = {t[i]:.1f} ms: {side} {axis} accelerates at {acc[i]:.1f} mm/s^2 > "
                       f"{lim.max_accel_mm_s2:g} mm/s^2 (to the next row)")
    bad = np.flatnonzero(flags & 8)
    rep.many("axis velocities", bad[np.argsort(-out[bad])],
             lambda i: f"t = {t[i]:.1f} ms: {side} v{axis.lstrip('d')} is not the derivative of {axis}: from "
                       f"this row to the next {axis} moves at {(x[i + 1] - x[i]) / dt[i] * 1000:.3f} mm/s, "
                       f"the rows say {v[i] * 1000:.3f} and {v[i + 1] * 1000:.3f} mm/s")

"""The machines' drive tables (paper section 7, Tables 2-3; SPEC.md sections 9-10), after the schedule:
1. ``axis_motion``: inverse kinematics (core.machine.kinematics) of both cutters on the common time
   column, and the velocities as the derivative of the planned motion (the Jacobian of the inverse
   kinematics times the pose's own rates), not a difference of the table's rows. The machine clock
   that keeps the axes' speeds and accelerations is core.machine.timing; ``axis_excess`` is its
   check of the rows as written.
2. ``check_limits``: stroke, speed and acceleration of every axis against machine.toml.
The tool axes within the heads' reach, before the schedule, are core.machine.reach.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core.machine.kinematics import inverse_kinematics_rates
from core.machine.model import AXES, Machine
from core.util.parallel import ROW_BLOCK


@dataclass(frozen=True)
class AxisTable:
    """One side's drive table: t (n,) ms; values (n, 6) mm (x, y, z, d1, d2, d3); velocities (n, 6)
    mm/ms. The accelerations between consecutive rows' velocities are derived on demand
    (``acceleration``): a plan's table holds two (n, 6) columns, not three."""

    side: str
    t: np.ndarray
    values: np.ndarray
    velocities: np.ndarray

    #: per axis (6,): the lowest and highest value (mm), the largest |velocity| (mm/ms) and
    #: |acceleration| (mm/ms^2; zeros for one row): ``peaks`` and ``check_limits`` read them (the limit
    #: check searches the rows only for an axis and kind beyond its limit)
    extremes: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        lo, hi = column_range(self.values)
        v_lo, v_hi = column_range(self.velocities)
        a_lo, a_hi = (np.full(6, np.inf), np.full(6, -np.inf)) if len(self.t) > 1 else (np.zeros(6), np.zeros(6))
        for start in range(0, len(self.t) - 1, ROW_BLOCK):  # (a block's accelerations at a time)
            b_lo, b_hi = column_range(self.accelerations(start, start + ROW_BLOCK))
            a_lo, a_hi = np.minimum(a_lo, b_lo), np.maximum(a_hi, b_hi)  # (NaN propagates, as in min())
        object.__setattr__(self, "extremes", {"min": lo, "max": hi, "speed": np.maximum(v_hi, -v_lo),
                                              "accel": np.maximum(a_hi, -a_lo)})

    def accelerations(self, start: int = 0, stop: int | None = None) -> np.ndarray:
        """(m, 6) mm/ms^2 between the velocities of rows i and i + 1, for i in start..stop - 1 (all
        n - 1 by default)."""
        stop = len(self.t) - 1 if stop is None else min(stop, len(self.t) - 1)
        vel, t = self.velocities[start:stop + 1], self.t[start:stop + 1]
        return np.diff(vel, axis=0) / np.diff(t)[:, None]


def column_range(a: np.ndarray, group: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) of each column of an (n, m) array, as a.min(axis=0) and a.max(axis=0) (NaN
    propagates the same way) but ~10x faster on a plan's (n, 6) tables: the rows are reduced ``group``
    at a time laid side by side, so that the reduction runs along contiguous memory; a block of rows at
    a time (a table's columns are often a slice of a wider array: each block is copied contiguous)."""
    m = a.shape[1]
    lo, hi = np.full(m, np.inf), np.full(m, -np.inf)  # (what an empty column's extremes mean here)
    for start in range(0, len(a), ROW_BLOCK):
        b = np.ascontiguousarray(a[start:start + ROW_BLOCK])
        whole = len(b) - len(b) % group
        parts_lo, parts_hi = [lo[None], b[whole:]], [hi[None], b[whole:]]
        if whole:
            wide = b[:whole].reshape(-1, group * m)
            parts_lo.append(wide.min(axis=0).reshape(group, m))
            parts_hi.append(wide.max(axis=0).reshape(group, m))
        lo, hi = np.vstack(parts_lo).min(axis=0), np.vstack(parts_hi).max(axis=0)
    return lo, hi


def axis_motion(machine: Machine, side: str, tips: np.ndarray, axes: np.ndarray, tip_rate: np.ndarray,
                axis_rate: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axis values (n, 6) by inverse kinematics of the tips and unit axes (n, 3), and their velocities
    (n, 6) per unit of the rates' time: the exact derivative of the inverse kinematics along the tips'
    and axes' rates (n, 3) (core.machine.kinematics.inverse_kinematics_rates; the rates from
    core.schedule.movetable.MoveTable.sample_with_rates), computed in blocks of rows."""
    n = len(tips)
    values, vel = np.empty((n, 6)), np.empty((n, 6))
    for lo in range(0, n, ROW_BLOCK):  # (errors name the rows of the whole column: first_sample)
        hi = min(lo + ROW_BLOCK, n)
        values[lo:hi], vel[lo:hi] = inverse_kinematics_rates(machine, side, tips[lo:hi], axes[lo:hi],
                                                             tip_rate[lo:hi], axis_rate[lo:hi], first_sample=lo)
    return values, vel


def axis_excess(velocities: list[np.ndarray], rate: np.ndarray, period: float, v_lim: np.ndarray,
                a_lim: np.ndarray) -> np.ndarray:
    """(n - 1,) per interval between consecutive rows ``period`` ms apart, the largest share of an axis
    limit over the tables: each table's velocities (n, 6) are ``velocities`` times the clock's ``rate``
    (n,) (a derivative in the schedule's time made one in the machines'); an acceleration's share is
    |v[i+1] - v[i]| / (period a_lim), a speed's (|v| / v_lim)^2 at either end of the interval (squared:
    a share like an acceleration's, for one factor to lower the rate by). In blocks of rows: no
    temporary holds a whole column."""
    n = len(rate)
    over = np.zeros(max(n - 1, 0))
    for lo in range(0, n - 1, ROW_BLOCK):
        hi = min(lo + ROW_BLOCK, n - 1)  # (intervals lo..hi-1: rows lo..hi)
        part = over[lo:hi]
        for vel in velocities:
            v = vel[lo:hi + 1] * rate[lo:hi + 1, None]
            np.maximum(part, (np.abs(np.diff(v, axis=0)) / (period * a_lim)).max(axis=1), out=part)
            speed = (np.abs(v) / v_lim).max(axis=1)
            np.maximum(part, np.maximum(speed[:-1], speed[1:]) ** 2, out=part)
    return over


@dataclass(frozen=True)
class LimitFinding:
    side: str
    axis: str
    kind: str      # stroke, speed or acceleration
    t_ms: float
    value: float
    limit: float
    unit: str

    def __str__(self) -> str:
        return (f"{self.side} {self.axis}: {self.kind} {self.value:.4f} {self.unit} beyond the limit "
                f"{self.limit:g} {self.unit} at t = {self.t_ms:.3f} ms")


def peaks(table: AxisTable) -> dict:
    """Peak |speed| (mm/s) and |acceleration| (mm/s^2) and the stroke used (mm) per axis."""
    ex = table.extremes
    out = {}
    for k, name in enumerate(AXES):
        out[name] = {"min_mm": round(float(ex["min"][k]), 4),
                     "max_mm": round(float(ex["max"][k]), 4),
                     "peak_speed_mm_s": round(float(ex["speed"][k] * 1000.0), 4),
                     "peak_accel_mm_s2": round(float(ex["accel"][k] * 1e6), 2)}
    return out


def machine_figures(machine: Machine, warp, tables: dict, findings: list, tilt_limited: dict,
                    time_at_feed_s: float, enforced: tuple) -> dict:
    """plan.json's machine figures: tilt limit and points turned per side, the machine clock (share
    of the job slowed, lowest rate of the schedule's clock), stroke, peak speed and acceleration per axis and side,
    the limit findings and which kinds of them refuse an export."""
    slowed = (np.diff(warp.t) * (warp.scale[1:] < 1 - 1e-9)).sum() / max(float(warp.t[-1]), 1e-12)
    return {"max_tilt_deg": machine.max_tilt_deg,
            "enforced": list(enforced),
            "time_at_feed_s": round(time_at_feed_s, 3),
            "machine_clock": {"slowed_share_of_time": round(float(slowed), 6),
                              "min_speed_scale": round(float(warp.scale.min(initial=1.0)), 6)},
            "tilt_limited_points": tilt_limited,
            "axes": {side: peaks(tables[side]) for side in tables},
            "limit_findings": [str(f) for f in findings]}


def check_limits(machine: Machine, table: AxisTable, max_per_kind: int = 3) -> list[LimitFinding]:
    """Every axis's stroke, speed and acceleration against machine.toml; at most ``max_per_kind``
    findings per axis and kind (the worst ones). The rows are searched only for an axis and kind whose
    extreme (AxisTable.extremes) is beyond its limit (the same test on the extreme: each excess is
    monotone in the value)."""

    def rows(kind: str, k: int, lim) -> tuple[np.ndarray, np.ndarray]:
        """(excess, value) at every row (every interval for the acceleration)."""
        if kind == "stroke":
            v = table.values[:, k]
            return np.maximum(lim.min_mm - v, v - lim.max_mm), v
        if kind == "speed":
            v = table.velocities[:, k] * 1000.0
            return np.abs(v) - lim.max_speed_mm_s, v
        a = table.accelerations()[:, k] * 1e6
        return np.abs(a) - lim.max_accel_mm_s2, a

    found = []
    ex = table.extremes
    for k, name in enumerate(AXES):
        lim = machine.limits.axis(name)
        checks = [("stroke", max(lim.min_mm - ex["min"][k], ex["max"][k] - lim.max_mm), None, "mm"),
                  ("speed", ex["speed"][k] * 1000.0 - lim.max_speed_mm_s, lim.max_speed_mm_s, "mm/s"),
                  ("acceleration", ex["accel"][k] * 1e6 - lim.max_accel_mm_s2 if len(table.t) > 1 else 0.0,
                   lim.max_accel_mm_s2, "mm/s^2")]
        for kind, worst, limit, unit in checks:
            if worst <= 1e-9:  # (a NaN extreme falls through to the rows)
                continue
            excess, value = rows(kind, k, lim)
            bad = np.flatnonzero(excess > 1e-9)
            for i in bad[np.argsort(-excess[bad])][:max_per_kind]:
                lim_v = limit if limit is not None else (lim.min_mm if value[i] < lim.min_mm else lim.max_mm)
                found.append(LimitFinding(table.side, name, kind, float(table.t[i]), float(value[i]),
                                          float(lim_v), unit))
    return found


#: what the machine clock slows the job for at a row (TimeWarp.slowed_for: indices into this); a row
#: counts as slowed where the clock runs below SLOWED_BELOW of the schedule's speed
SLOWED_FOR = ("nothing", "axes", "chord")
SLOWED_BELOW = 0.99


@dataclass(frozen=True)
class TimeWarp:
    """The machine clock shared by both machines (core.machine.timing) at the rows: row i is the
    schedule's motion at ``schedule_t[i]``, where the schedule's clock runs at ``scale[i]`` (<= 1) of
    the machines'. Both machines slow down by the same factor at every instant, so the collaborative
    schedule's instants, and with them every tip spacing and clearance, are kept."""

    t: np.ndarray           # (n,) ms, new time of each row
    schedule_t: np.ndarray  # (n,) ms, the schedule's time of each row
    scale: np.ndarray       # (n,) d(schedule time) / d(new time) at each row
    #: (n,) int8 per row, what the clock slows the job for there (SLOWED_FOR: nothing, an axis's
    #: speed or acceleration, the chord tolerance); None where not known
    slowed_for: np.ndarray | None = None
    #: per side, (n,) the rate that machine's own limits would allow at the rows, were it timed alone
    #: (>= scale: where it is higher, the other machine's limits slow this one); None where not known
    own_scale: dict | None = None

    def to_schedule_time(self, t_new: np.ndarray) -> np.ndarray:
        """(m,) ms of the new time column -> (m,) ms of the schedule (moves) time."""
        return np.interp(t_new, self.t, self.schedule_t)

    def rate(self, t_new: np.ndarray) -> np.ndarray:
        """(m,) d(schedule time)/d(new time) at times t_new."""
        return np.interp(t_new, self.t, self.scale)

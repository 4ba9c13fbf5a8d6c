"""XYZ-3RPS post-processor (paper section 7, Tables 2-3; SPEC.md sections 9-10).

Three steps between the schedule and the machines' drive tables:
1. ``limit_tilt``: the paper's tool axes (surface normals in the tip region, the line through both
   ball centres elsewhere) tilt up to ~100 degrees from the spindle axis round the rounded edges,
   and a 3-RPS head reaches ``max_tilt_deg`` (40 on the default machine). Where an axis tilts more,
   it is turned towards the spindle axis, in the plane of the two, until it tilts by the limit less
   ``TILT_MARGIN_DEG``, about the ball centre: the ball, and so the surface it cuts, stays the same;
   only the tip and the shank move. Applied to the plan before scheduling (``machine_plan``), so the
   schedule, its safety check, the CL tables and ``bladecam verify`` all see the executed axes;
   pairs.csv keeps the paper's orientation.
2. ``axis_motion``: inverse kinematics (core.machine.kinematics) of both cutters on the common time
   column, and the velocities as the derivative of the planned motion (the inverse kinematics of
   the pose moved along its own rates by +- ``DERIVATIVE_STEP_MS``), not a difference of the table's
   rows. The machine clock that keeps the axes' speeds and accelerations is core.machine.timing.
3. ``check_limits``: stroke, speed and acceleration of every axis against machine.toml.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from core.machine.kinematics import inverse_kinematics
from core.machine.model import AXES, Machine
from core.machine.tool_axes import single_sided_axes
from core.util.parallel import ROW_BLOCK, per_side
from core.util.rowwise import row_norm

TILT_MARGIN_DEG = 0.5
DERIVATIVE_STEP_MS = 1e-3


def spindle_direction(machine: Machine, side: str) -> np.ndarray:
    """(3,) unit vector, W: the side's spindle axis at zero tilt (+z_M), tip -> spindle."""
    return machine.side(side).vectors_to_workpiece(np.array([[0.0, 0.0, 1.0]]))[0]


def limit_tilt(tips: np.ndarray, axes: np.ndarray, tool_radius: float, spindle: np.ndarray,
               max_tilt_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tool tips (n, 3) mm and unit axes (n, 3) with every axis within ``max_tilt_deg`` of ``spindle``.

    An axis beyond it is turned towards ``spindle`` in the plane of the two, about the ball centre
    c = tip + r w, to exactly the limit; the tip follows: tip' = c - r w'. Returns the new tips, the new
    axes and a (n,) bool mask of the rows changed. Inputs are not modified.
    """
    tips = np.asarray(tips, float)
    axes = np.asarray(axes, float)
    limit = np.radians(max_tilt_deg)
    cos_t = axes @ spindle
    over = cos_t < np.cos(limit)
    if not over.any():
        return tips.copy(), axes.copy(), over
    w = axes[over]
    perp = w - cos_t[over, None] * spindle
    norm = row_norm(perp)
    # an axis exactly opposite the spindle has no plane: tilt it towards any perpendicular direction
    fallback = np.cross(spindle, [1.0, 0.0, 0.0] if abs(spindle[0]) < 0.9 else [0.0, 1.0, 0.0])
    perp = np.where(norm[:, None] > 1e-12, perp / np.where(norm > 1e-12, norm, 1.0)[:, None],
                    fallback / np.linalg.norm(fallback))
    new_w = np.cos(limit) * spindle + np.sin(limit) * perp
    out_axes = axes.copy()
    out_tips = tips.copy()
    out_axes[over] = new_w
    out_tips[over] = tips[over] + tool_radius * (w - new_w)
    return out_tips, out_axes, over


def machine_plan(plan, machine: Machine, kept: dict | None = None):
    """The PathPlan with every pair's axes within the machine's reach (the limit less
    TILT_MARGIN_DEG): single-sided (tip region) pairs' axes chosen per path so that the head does not
    swing while it cuts (core.machine.tool_axes), the others turned to the limit where beyond it
    (``limit_tilt``); the ball centres stay. Also returns the number of points changed per side. ``kept``: a dict the caller
    keeps for one machine and one tool (core.planner.Planner), of the pairs done already by identity
    (each path's axes depend on that path alone): an h_safe or K_max change redoes only the pairs
    that changed."""
    r = plan.params.tool_radius
    limit = machine.max_tilt_deg - TILT_MARGIN_DEG
    dirs = {s: spindle_direction(machine, s) for s in ("left", "right")}
    kept = {} if kept is None else kept
    todo = [k for k, pair in enumerate(plan.pairs) if kept.get(id(pair), (None,))[0] is not pair]
    single = [k for k in todo if plan.pairs[k].kind == "single"]

    def chosen_side(side: str) -> dict:
        normals = [getattr(plan.pairs[k], f"{side}_axis") for k in single]  # the paper's: the normals
        centres = [getattr(plan.pairs[k], f"{side}_tip") + r * w
                   for k, w in zip(single, normals, strict=True)]
        axes = single_sided_axes(centres, normals, dirs[side], limit).axes
        return {k: (c - r * w, w) for k, c, w in zip(single, centres, axes, strict=True)}

    chosen = per_side(chosen_side, parallel=len(single) > 0)
    for k in todo:
        pair = plan.pairs[k]
        new, count = {}, {}
        for side in ("left", "right"):
            old_tip, old_axis = getattr(pair, f"{side}_tip"), getattr(pair, f"{side}_axis")
            if k in chosen[side]:
                tips, axes = chosen[side][k]
                mask = np.einsum("ij,ij->i", axes, old_axis) < 1.0 - 1e-12
            else:
                tips, axes, mask = limit_tilt(old_tip, old_axis, r, dirs[side], limit)
            new[f"{side}_tip"], new[f"{side}_axis"] = tips, axes
            count[side] = int(mask.sum())
        kept[id(pair)] = (pair, replace(pair, **new), count)  # (the pair itself: its id stays its own)
    pairs, changed = [], {"left": 0, "right": 0}
    for pair in plan.pairs:
        _, done, count = kept[id(pair)]
        pairs.append(done)
        for side in changed:
            changed[side] += count[side]
    return replace(plan, pairs=pairs, pairs_rows=None), changed


@dataclass(frozen=True)
class AxisTable:
    """One side's drive table: t (n,) ms; values (n, 6) mm (x, y, z, d1, d2, d3); velocities (n, 6)
    mm/ms; accelerations (n - 1,) rows of (6,) mm/ms^2 between consecutive rows' velocities."""

    side: str
    t: np.ndarray
    values: np.ndarray
    velocities: np.ndarray

    #: (n - 1, 6) mm/ms^2 between consecutive rows' velocities (derived when the table is made)
    accelerations: np.ndarray = field(init=False, repr=False, compare=False)
    #: per axis (6,): the lowest and highest value (mm), the largest |velocity| (mm/ms) and
    #: |acceleration| (mm/ms^2; zeros for one row): ``peaks`` and ``check_limits`` read them (the limit
    #: check searches the rows only for an axis and kind beyond its limit)
    extremes: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        acc = np.diff(self.velocities, axis=0) / np.diff(self.t)[:, None]
        lo, hi = column_range(self.values)
        v_lo, v_hi = column_range(self.velocities)
        a_lo, a_hi = column_range(acc) if len(acc) else (np.zeros(6), np.zeros(6))
        object.__setattr__(self, "accelerations", acc)
        object.__setattr__(self, "extremes", {"min": lo, "max": hi, "speed": np.maximum(v_hi, -v_lo),
                                              "accel": np.maximum(a_hi, -a_lo)})


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
                axis_rate: np.ndarray, h: float = DERIVATIVE_STEP_MS) -> tuple[np.ndarray, np.ndarray]:
    """Axis values (n, 6) by inverse kinematics of the tips and unit axes (n, 3), and their velocities
    (n, 6) per unit of the rates' time: the central difference of the inverse kinematics of the pose
    moved by -+ h along the tips' and axes' rates (n, 3) (core.schedule.movetable.MoveTable.
    sample_with_rates), computed in blocks of rows."""
    n = len(tips)
    values, vel = np.empty((n, 6)), np.empty((n, 6))

    def unit(w):
        return w / row_norm(w)[:, None]

    for lo in range(0, n, ROW_BLOCK):  # (errors name the rows of the whole column: first_sample)
        hi = min(lo + ROW_BLOCK, n)
        p, w, dp, dw = tips[lo:hi], axes[lo:hi], h * tip_rate[lo:hi], h * axis_rate[lo:hi]
        values[lo:hi] = inverse_kinematics(machine, side, p, w, first_sample=lo)
        step = (inverse_kinematics(machine, side, p + dp, unit(w + dw), first_sample=lo)
                - inverse_kinematics(machine, side, p - dp, unit(w - dw), first_sample=lo))
        vel[lo:hi] = step / (2.0 * h)
    return values, vel


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
        a = table.accelerations[:, k] * 1e6
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


@dataclass(frozen=True)
class TimeWarp:
    """The machine clock shared by both machines (core.machine.timing) at the rows: row i is the
    schedule's motion at ``schedule_t[i]``, where the schedule's clock runs at ``scale[i]`` (<= 1) of
    the machines'. Both machines slow down by the same factor at every instant, so the collaborative
    schedule's instants, and with them every tip spacing and clearance, are kept."""

    t: np.ndarray           # (n,) ms, new time of each row
    schedule_t: np.ndarray  # (n,) ms, the schedule's time of each row
    scale: np.ndarray       # (n,) d(schedule time) / d(new time) at each row

    def to_schedule_time(self, t_new: np.ndarray) -> np.ndarray:
        """(m,) ms of the new time column -> (m,) ms of the schedule (moves) time."""
        return np.interp(t_new, self.t, self.schedule_t)

    def rate(self, t_new: np.ndarray) -> np.ndarray:
        """(m,) d(schedule time)/d(new time) at times t_new."""
        return np.interp(t_new, self.t, self.scale)

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
2. ``axis_table``: inverse kinematics (core.kinematics) of both cutters on the common time column,
   and the velocities as the derivative of the planned motion: the inverse kinematics of the
   motion itself at t +- ``DERIVATIVE_STEP_MS``, not a difference of the table's rows.
3. ``check_limits``: stroke, speed and acceleration of every axis against machine.toml.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .csvio import csv_bytes
from .errors import Cancelled
from .kinematics import inverse_kinematics
from .machine import AXES, Machine
from .motion import Move, sample_moves

TILT_MARGIN_DEG = 0.5
DERIVATIVE_STEP_MS = 1e-3
AXES_COLUMNS = "t_ms,x_mm,y_mm,z_mm,d1_mm,d2_mm,d3_mm,vx,vy,vz,v1,v2,v3".split(",")


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
    norm = np.linalg.norm(perp, axis=1)
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


def machine_plan(plan, machine: Machine):
    """The PathPlan with every pair's axes within the machine's reach (the limit less
    TILT_MARGIN_DEG): single-sided (tip region) pairs' axes smoothed along their paths
    (core.tool_axes), the others turned to the limit where beyond it (``limit_tilt``); the ball
    centres stay. Also returns the number of points changed per side."""
    from .tool_axes import smooth_axes

    r = plan.params.tool_radius
    limit = machine.max_tilt_deg - TILT_MARGIN_DEG
    dirs = {s: spindle_direction(machine, s) for s in ("left", "right")}
    single = [k for k, pair in enumerate(plan.pairs) if pair.kind == "single"]
    smoothed = {}
    for side in ("left", "right"):
        normals = [getattr(plan.pairs[k], f"{side}_axis") for k in single]  # the paper's: the normals
        centres = [getattr(plan.pairs[k], f"{side}_tip") + r * w for k, w in zip(single, normals, strict=True)]
        axes, _ = smooth_axes(centres, normals, dirs[side], limit)
        smoothed[side] = {k: (c - r * w, w) for k, c, w in zip(single, centres, axes, strict=True)}
    pairs, changed = [], {"left": 0, "right": 0}
    for k, pair in enumerate(plan.pairs):
        new = {}
        for side in ("left", "right"):
            old_tip, old_axis = getattr(pair, f"{side}_tip"), getattr(pair, f"{side}_axis")
            if k in smoothed[side]:
                tips, axes = smoothed[side][k]
                mask = np.einsum("ij,ij->i", axes, old_axis) < 1.0 - 1e-12
            else:
                tips, axes, mask = limit_tilt(old_tip, old_axis, r, dirs[side], limit)
            new[f"{side}_tip"], new[f"{side}_axis"] = tips, axes
            changed[side] += int(mask.sum())
        pairs.append(replace(pair, **new))
    return replace(plan, pairs=pairs, pairs_rows=None), changed


@dataclass(frozen=True)
class AxisTable:
    """One side's drive table: t (n,) ms; values (n, 6) mm (x, y, z, d1, d2, d3); velocities (n, 6)
    mm/ms; accelerations (n - 1,) rows of (6,) mm/ms^2 between consecutive rows' velocities."""

    side: str
    t: np.ndarray
    values: np.ndarray
    velocities: np.ndarray

    @property
    def accelerations(self) -> np.ndarray:
        return np.diff(self.velocities, axis=0) / np.diff(self.t)[:, None]


def axis_table(machine: Machine, side: str, moves: list[Move], t: np.ndarray, tips: np.ndarray,
               axes: np.ndarray, h: float = DERIVATIVE_STEP_MS, end: float | None = None) -> AxisTable:
    """Axis values by inverse kinematics of the sampled tips/axes (n, 3) at t (n,) ms, and velocities
    as the central difference of the inverse kinematics of the motion at t +- h (one-sided at the
    start and at the end of the job, ``end`` ms, by default t[-1])."""
    values = inverse_kinematics(machine, side, tips, axes)
    end = t[-1] if end is None else end
    lo = np.maximum(t - h, 0.0)
    hi = np.minimum(t + h, end)
    a = sample_moves(moves, lo)
    b = sample_moves(moves, hi)
    va = inverse_kinematics(machine, side, a.tips, a.axes)
    vb = inverse_kinematics(machine, side, b.tips, b.axes)
    vel = (vb - va) / (hi - lo)[:, None]
    return AxisTable(side, t, values, vel)


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
    acc = np.abs(table.accelerations) * 1e6 if len(table.t) > 1 else np.zeros((1, 6))
    out = {}
    for k, name in enumerate(AXES):
        out[name] = {"min_mm": round(float(table.values[:, k].min()), 4),
                     "max_mm": round(float(table.values[:, k].max()), 4),
                     "peak_speed_mm_s": round(float(np.abs(table.velocities[:, k]).max() * 1000.0), 4),
                     "peak_accel_mm_s2": round(float(acc[:, k].max()), 2)}
    return out


def machine_figures(machine: Machine, warp, tables: dict, findings: list, tilt_limited: dict,
                    time_at_feed_s: float, enforced: tuple) -> dict:
    """plan.json's machine figures: tilt limit and points turned per side, the feed override (share
    of the job slowed, lowest speed scale), stroke, peak speed and acceleration per axis and side,
    the limit findings and which kinds of them refuse an export."""
    slowed = (np.diff(warp.t) * (warp.scale[1:] < 1 - 1e-9)).sum() / max(float(warp.t[-1]), 1e-12)
    return {"max_tilt_deg": machine.max_tilt_deg,
            "enforced": list(enforced),
            "time_at_feed_s": round(time_at_feed_s, 3),
            "feed_override": {"slowed_share_of_time": round(float(slowed), 6),
                              "min_speed_scale": round(float(warp.scale.min(initial=1.0)), 6)},
            "tilt_limited_points": tilt_limited,
            "axes": {side: peaks(tab) for side, tab in tables.items()},
            "limit_findings": [str(f) for f in findings]}


def check_limits(machine: Machine, table: AxisTable, max_per_kind: int = 3) -> list[LimitFinding]:
    """Every axis's stroke, speed and acceleration against machine.toml; at most ``max_per_kind``
    findings per axis and kind (the worst ones)."""
    found = []
    acc = table.accelerations * 1e6 if len(table.t) > 1 else np.zeros((0, 6))
    for k, name in enumerate(AXES):
        lim = machine.limits.axis(name)
        v = table.values[:, k]
        checks = [
            ("stroke", np.maximum(lim.min_mm - v, v - lim.max_mm), v, None, "mm"),
            ("speed", np.abs(table.velocities[:, k]) * 1000.0 - lim.max_speed_mm_s,
             table.velocities[:, k] * 1000.0, lim.max_speed_mm_s, "mm/s"),
            ("acceleration", np.abs(acc[:, k]) - lim.max_accel_mm_s2 if len(acc) else np.zeros(0),
             acc[:, k] if len(acc) else np.zeros(0), lim.max_accel_mm_s2, "mm/s^2"),
        ]
        for kind, excess, value, limit, unit in checks:
            bad = np.flatnonzero(excess > 1e-9)
            for i in bad[np.argsort(-excess[bad])][:max_per_kind]:
                lim_v = limit if limit is not None else (lim.min_mm if value[i] < lim.min_mm else lim.max_mm)
                found.append(LimitFinding(table.side, name, kind, float(table.t[i]), float(value[i]),
                                          float(lim_v), unit))
    return found


def axes_csv(table: AxisTable) -> bytes:
    """left_axes.csv / right_axes.csv: t in ms, axis values in mm to 1e-6, velocities in mm/ms to 1e-9."""
    cols = [("f", table.t, 6)]
    cols += [("f", table.values[:, k], 6) for k in range(6)]
    cols += [("f", table.velocities[:, k], 9) for k in range(6)]
    return csv_bytes(AXES_COLUMNS, cols)



#: the feed override changes the speed scale s (new speed / planned speed) at most this fast:
#: |ds/dtau| <= RETIME_ACCEL_SHARE * a_max / v_max, so that slowing down or speeding up again adds at
#: most this share of a_max to the tip's acceleration along the path
RETIME_ACCEL_SHARE = 0.2
#: the override aims this far inside the axes' speed limits
RETIME_MARGIN = 0.97
#: rows are added (halving, VELOCITY_ROUNDS times at most) where an axis velocity changes by more
#: than this share of its speed limit between two rows
VELOCITY_STEP = 0.02
VELOCITY_ROUNDS = 6


@dataclass(frozen=True)
class TimeWarp:
    """A feed override shared by both machines: row i of the retimed timeline is the schedule's motion
    at ``schedule_t[i]``, where the schedule's clock runs at ``scale[i]`` (<= 1) of the new one; the
    scale is continuous (linear in schedule time between the schedule's own rows). Both machines slow
    down by the same factor at every instant, so the collaborative schedule's instants, and with them
    every tip spacing and clearance, are kept."""

    t: np.ndarray           # (n,) ms, new time of each row
    schedule_t: np.ndarray  # (n,) ms, the schedule's time of each row
    scale: np.ndarray       # (n,) d(schedule time) / d(new time) at each row

    def to_schedule_time(self, t_new: np.ndarray) -> np.ndarray:
        """(m,) ms of the new time column -> (m,) ms of the schedule (moves) time."""
        return np.interp(t_new, self.t, self.schedule_t)

    def rate(self, t_new: np.ndarray) -> np.ndarray:
        """(m,) d(schedule time)/d(new time) at times t_new."""
        return np.interp(t_new, self.t, self.scale)

    @property
    def row_rate(self) -> np.ndarray:
        return self.scale


def _need(machine: Machine, schedule, t: np.ndarray) -> np.ndarray:
    """(n,) by how much both machines must slow down at schedule times t (n,) to keep every axis
    within RETIME_MARGIN of its speed limit (>= 1)."""
    vmax = np.array([machine.limits.axis(a).max_speed_mm_s for a in AXES]) / 1000.0 * RETIME_MARGIN
    need = np.ones(len(t))
    for side in ("left", "right"):
        moves = getattr(schedule, side)
        s = sample_moves(moves, t)
        tab = axis_table(machine, side, moves, t, s.tips, s.axes)
        need = np.maximum(need, (np.abs(tab.velocities) / vmax).max(axis=1))
    return need


def _cone(q: np.ndarray, t: np.ndarray, c2: float) -> np.ndarray:
    """The largest q' <= q (at increasing times t) with |dq'/dt| <= c2, clipped to [1e-12, 1]."""
    fwd = np.minimum.accumulate(q - c2 * t) + c2 * t
    bwd = (np.minimum.accumulate((q + c2 * t)[::-1]) - c2 * t[::-1])[::-1]
    return np.clip(np.minimum(fwd, bwd), 1e-12, 1.0)


def speed_scale(machine: Machine, schedule, t: np.ndarray, v_max: float, a_max: float,
                extra: np.ndarray | None = None) -> np.ndarray:
    """(n,) speed scale s <= 1 at the rows t (n,) (schedule time, ms; linear in between): the largest
    that keeps every axis of both machines within RETIME_MARGIN of its speed limit at the rows and
    at the intervals' quarter points, with s^2 changing by at most 2 c per ms of schedule time,
    c = RETIME_ACCEL_SHARE a_max / v_max (a bounded rate of change of s in the new time, since
    s ds/dt = ds/dtau). v_max mm/ms, a_max mm/ms^2. ``extra`` : more schedule times to probe."""
    dt = np.diff(t)
    more = np.empty(0) if extra is None else np.asarray(extra, float)
    probe = np.concatenate([t, t[:-1] + 0.25 * dt, t[:-1] + 0.5 * dt, t[:-1] + 0.75 * dt, more])
    order = np.argsort(probe, kind="stable")
    tp = probe[order]
    need = _need(machine, schedule, tp)
    c2 = 2.0 * RETIME_ACCEL_SHARE * a_max / v_max
    s_probe = np.empty(len(tp))
    s_probe[order] = np.sqrt(_cone(1.0 / need**2, tp, c2))
    n = len(t)
    inner = s_probe[n:4 * n - 3].reshape(3, n - 1).min(axis=0)  # per interval
    if more.size:
        k = np.clip(np.searchsorted(t, more, side="right") - 1, 0, n - 2)
        np.minimum.at(inner, k, s_probe[4 * n - 3:])
    # s at a row: no more than what the probes inside either neighbouring interval allow, so that
    # the linear scale between two rows stays below every probe in between
    rows = s_probe[:n].copy()
    rows[:-1] = np.minimum(rows[:-1], inner)
    rows[1:] = np.minimum(rows[1:], inner)
    return np.sqrt(_cone(rows**2, t, c2))  # lowering rows must not steepen the scale: envelope again


def _rows_beside(new_tau: np.ndarray, sched_t: np.ndarray, verts: np.ndarray, schedule, to_tau) -> np.ndarray:
    """Indices of the rows (not the first or last) closer than the row gap to one of the vertex
    instants ``verts`` (new time, ms) without being at a vertex themselves (a move start or a
    polyline vertex of either cutter, within 1e-6 ms)."""
    from .timeline import MIN_ROW_GAP, vertices_in

    if verts.size == 0 or len(new_tau) < 3:
        return np.empty(0, int)
    k = np.clip(np.searchsorted(new_tau, verts), 1, len(new_tau) - 1)
    j = np.where(np.abs(new_tau[k - 1] - verts) <= np.abs(new_tau[k] - verts), k - 1, k)
    d = np.abs(new_tau[j] - verts)
    j = np.unique(j[(d < MIN_ROW_GAP) & (d > 5e-7)])
    j = j[(j > 0) & (j < len(new_tau) - 1)]
    if j.size == 0:
        return j
    near = np.sort(to_tau(vertices_in(schedule, sched_t[j] - 2e-6, sched_t[j] + 2e-6)))
    if near.size == 0:
        return j
    m = np.clip(np.searchsorted(near, new_tau[j]), 1, max(len(near) - 1, 1))
    gap = np.minimum(np.abs(near[m - 1] - new_tau[j]), np.abs(near[np.minimum(m, len(near) - 1)] - new_tau[j]))
    return j[gap > 1.5e-6]


def retime(machine: Machine, schedule, timeline, period: float, v_max: float, a_max: float, cancel=None):
    """Apply the feed override of ``speed_scale``: returns (Timeline, TimeWarp) with every row kept
    (shifted by < 1e-6 ms of schedule time so that its new time lies on the tables' 1e-6 ms grid) and
    rows added wherever a new interval would exceed ``period``. Unchanged when no slowing is needed."""
    from .timeline import Insertion, Timeline, new_rows, vertices_in

    t = timeline.t
    dt = np.diff(t)
    vmax = np.array([machine.limits.axis(a).max_speed_mm_s for a in AXES]) / 1000.0
    extra = np.empty(0)
    for _attempt in range(8):
        if cancel is not None and cancel():
            raise Cancelled()
        scale = speed_scale(machine, schedule, t, v_max, a_max, extra)
        if scale.min(initial=1.0) >= 1.0:
            return timeline, TimeWarp(t.copy(), t.copy(), np.ones(len(t)))
        s0, s1 = scale[:-1], scale[1:]
        slope = (s1 - s0) / dt                     # ds/dt in each interval
        flat = np.abs(s1 - s0) <= 1e-9 * s0
        # new time of an interval: integral of dt / s(t), s linear
        with np.errstate(divide="ignore", invalid="ignore"):
            dtau = np.where(flat, dt / s0, np.log(s1 / s0) / np.where(flat, 1.0, slope))
        tau = np.concatenate([[0.0], np.cumsum(dtau)])
        pieces = np.maximum(np.ceil(dtau / period - 1e-9), 1).astype(int)
        idx = np.repeat(np.arange(len(dt)), pieces)
        j = np.arange(len(idx)) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        new_tau = np.append(tau[idx] + j / pieces[idx] * (tau[idx + 1] - tau[idx]), tau[-1])

        def at(new: np.ndarray, tau=tau, s0=s0, slope=slope, flat=flat) -> np.ndarray:
            seg = np.clip(np.searchsorted(tau, new, side="right") - 1, 0, len(dt) - 1)
            x = new - tau[seg]
            k = slope[seg]
            with np.errstate(over="ignore", invalid="ignore"):
                step = np.where(flat[seg], s0[seg] * x, s0[seg] * np.expm1(k * x) / np.where(flat[seg], 1.0, k))
            return np.clip(t[seg] + step, t[seg], t[seg + 1])

        def to_tau(ts: np.ndarray, tau=tau, s0=s0, slope=slope, flat=flat) -> np.ndarray:
            seg = np.clip(np.searchsorted(t, ts, side="right") - 1, 0, len(dt) - 1)
            y = ts - t[seg]
            k = slope[seg]
            with np.errstate(divide="ignore", invalid="ignore"):
                x = np.where(flat[seg], y / s0[seg], np.log1p(k * y / s0[seg]) / np.where(flat[seg], 1.0, k))
            return tau[seg] + x

        def scale_at(ts: np.ndarray, s=scale) -> np.ndarray:
            return np.interp(ts, t, s)

        # the kept rows (shifted onto the 1e-6 ms grid), then the polyline vertices inside split
        # intervals (see timeline.vertex_times), then the even splits, each apart from the ones before
        kept = np.unique(np.round(tau, 6))
        split = np.flatnonzero((pieces > 1) | (np.minimum(s0, s1) < 1.0))
        verts = to_tau(vertices_in(schedule, t[split], t[split + 1])) if split.size else np.empty(0)
        new_tau = np.union1d(kept, new_rows(kept, np.round(verts, 6), np.round(new_tau, 6)))

        # rows where the slowed motion's axis velocities change by more than VELOCITY_STEP of their
        # limit from one row to the next (the axes swing round an edge): the table resolves the motion.
        # Rows keep their values when others are added, so only the new rows are evaluated.
        def evaluate(taus, last=False, at=at, scale_at=scale_at):
            sched_t = at(taus)
            if last:
                sched_t[-1] = t[-1]
            rate = scale_at(sched_t)
            samples, vel = {}, {}
            for side in ("left", "right"):
                moves = getattr(schedule, side)
                smp = samples[side] = sample_moves(moves, sched_t)
                tab = axis_table(machine, side, moves, sched_t, smp.tips, smp.axes, end=t[-1])
                vel[side] = tab.velocities * rate[:, None]
            return sched_t, samples, vel

        def measures(vel):
            n = len(vel["left"])
            jump, ratio = np.zeros(n - 1), np.zeros(n)
            for v in vel.values():
                jump = np.maximum(jump, (np.abs(np.diff(v, axis=0)) / vmax).max(axis=1))
                ratio = np.maximum(ratio, (np.abs(v) / vmax).max(axis=1))
            return jump, ratio

        sched_t, samples, vel = evaluate(new_tau, last=True)
        jump, ratio = measures(vel)
        for _ in range(VELOCITY_ROUNDS):
            if cancel is not None and cancel():
                raise Cancelled()
            bad = np.flatnonzero(jump > VELOCITY_STEP)
            if bad.size == 0:
                break
            # halving, and a row at every polyline vertex inside the halved intervals: the axis
            # velocities jump at a vertex, so halving closes in on it, and a chord across the corner
            # reads as a speed dip (3315 mm/s^2 at the default dR). A row closer than the row gap to
            # such a vertex, not itself at a vertex, gives its place to the vertex.
            verts = np.unique(np.round(to_tau(vertices_in(schedule, sched_t[bad], sched_t[bad + 1])), 6))
            drop = _rows_beside(new_tau, sched_t, verts, schedule, to_tau)
            if drop.size:
                keep = np.ones(len(new_tau), bool)
                keep[drop] = False
                new_tau, sched_t = new_tau[keep], sched_t[keep]
                for side in ("left", "right"):
                    samples[side] = samples[side].take(keep)
                    vel[side] = vel[side][keep]
                jump, _ = measures(vel)
                bad = np.flatnonzero(jump > VELOCITY_STEP)
            halves = np.round(0.5 * (new_tau[bad] + new_tau[bad + 1]), 6)
            add = new_rows(new_tau, verts, halves)
            if add.size == 0:
                break
            st_add, smp_add, vel_add = evaluate(add)
            ins = Insertion.of(new_tau, add)
            new_tau = ins.merge(new_tau, add)
            sched_t = ins.merge(sched_t, st_add)
            for side in ("left", "right"):
                samples[side] = ins.merge_samples(samples[side], smp_add[side])
                vel[side] = ins.merge(vel[side], vel_add[side])
            jump, ratio = measures(vel)
        over = ratio > 1.0
        if not over.any():
            break
        extra = np.union1d(extra, sched_t[over])  # probe there too, and plan the override again
    # the last check was made on the final rows (every change of new_tau above is checked again)
    return Timeline(new_tau, samples["left"], samples["right"]), TimeWarp(new_tau, sched_t, scale_at(sched_t))


def drive_table(machine: Machine, side: str, moves: list[Move], timeline, warp: TimeWarp) -> AxisTable:
    """One side's axis table on the (retimed) time column: values by inverse kinematics of the rows,
    velocities d/dt of the motion: the schedule's derivative at the row times the override's rate."""
    s = getattr(timeline, side)
    tab = axis_table(machine, side, moves, warp.schedule_t, s.tips, s.axes)
    return AxisTable(side, timeline.t, tab.values, tab.velocities * warp.row_rate[:, None])

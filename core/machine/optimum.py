"""The time-optimal traversal of a cutter's path under the machine's limits: the reference the job the
machines run (core.machine.timing) is measured against. It times nothing that is written.

The path is a polyline of tips and unit tool axes (the executed axes: a MoveTable's, after the reach
step), taken as the smooth C1 cubic Hermite curve through its vertices in the polyline's arc length s
(tangents: the three-point difference of the vertices, ``tangents``), tips and axes alike; the tip
speed is v = ds/dt and u = v^2. With q(s) the six axis values by inverse kinematics, each axis moves at
q' v and accelerates at q' a + q'' u (a = dv/dt = u' / 2). The limits, each aimed as the machine clock
aims it (core.machine.caps.AIM, CHORD_AIM; core.machine.timing.TIP_AIM):
- **cruise**: v <= the move's cruise speed (the feed while cutting, the rapid speed in the air);
- **axis speed**: |q'_j| v <= AIM v_lim_j;
- **axis acceleration**: |q'_j a + q''_j u| <= AIM a_lim_j: the path's curvature alone may take
  CURVE_SHARE of it (a bound on u), and the rest bounds the tangential acceleration a at that u;
- **tip acceleration**: |a| <= TIP_AIM a_max along the path;
- **chord tolerance**: the controller moves straight between two rows ``period`` ms apart; across a
  chord v period of a curve of curvature kappa it strays (v period)^2 kappa / 8, kept within
  CHORD_AIM of the tolerance for the tips and for the ball centres (tip + r axis).
q' is the analytic Jacobian of the inverse kinematics (core.machine.kinematics) times the curve's
derivatives at knots PIECES per polyline segment; q'' and the curvatures are the three-point
differences of those derivatives along s. Not modelled, as in the machine clock: jerk, and a
controller's own look-ahead.

The profile is the largest u(s) under these bounds (``fastest``): a forward and a backward pass along s
(``cone``, CNC look-ahead) with the acceleration each interval allows at the speeds it runs, iterated.
Where the curvature takes from the allowance the bound falls as u rises; where it would add to it,
none is counted (so the allowance never rises with u, slightly below the exact optimum there). A pass
with the allowances of a profile at or above the optimum therefore lies at or below it and keeps its
own bounds; the iterates close in from both sides and the last, feasible, one is returned. Between
two knots u is linear in s (constant acceleration): a segment of length h takes 2 h / (v0 + v1).

Units: mm, ms, mm/ms, mm/ms^2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.machine.caps import AIM, CHORD_AIM, axis_limits
from core.machine.kinematics import inverse_kinematics_rates
from core.machine.model import Machine
from core.machine.timing import TIP_AIM
from core.util.polyline import cumulative_length
from core.util.rowwise import row_norm, row_sum_of_products

#: the share of an axis's acceleration the path's curvature alone may take at the bound on u
CURVE_SHARE = 0.9
#: knots per polyline segment the bounds are found at (round a tip path's ends the heads' swing per mm
#: of tip changes by half within a segment)
PIECES = 4
#: forward-backward passes of ``fastest`` after the first (odd: the last is feasible)
PASSES = 7
#: mm: segments shorter than this count as zero length (a junction's two vertices)
MIN_SEGMENT = 1e-12
#: what bounds the speed at a knot (``Caps.why``)
WHY = ("cruise", "axis speed", "axis acceleration", "chord")


@dataclass(frozen=True)
class Limits:
    """What a cutter's speed is bounded by: its machine (inverse kinematics and machine.toml's axis
    limits), the controller's period (ms) and chord tolerance (mm), the ball radius (mm), the feed
    (mm/ms) and a_max (mm/ms^2)."""

    machine: Machine
    period: float
    chord_tol: float
    tool_radius: float
    feed: float
    a_max: float

    @property
    def axes(self) -> tuple[np.ndarray, np.ndarray]:
        """(6,) axis speed limits mm/ms and (6,) acceleration limits mm/ms^2."""
        return axis_limits(self.machine)


@dataclass(frozen=True)
class Knots:
    """Runs of knots laid end to end (``size``: knots per run): arc length s (each run from 0), tips and
    unit axes (n, 3) and their derivatives in s (n, 3), and the run of each knot's path segment."""

    s: np.ndarray
    tips: np.ndarray
    axes: np.ndarray
    d_tips: np.ndarray
    d_axes: np.ndarray
    size: np.ndarray


@dataclass(frozen=True)
class Caps:
    """A path's bounds at its knots: s (n,) mm; u_cap (n,) the bound on v^2 and why (n,) int8 which limit
    sets it (WHY); dq (n, 6) |dq/ds| and ddq (n, 6) d2q/ds2 times the sign of dq/ds; a_lim (6,) the aimed
    axis accelerations, a_tip the aimed tip acceleration; joined (n - 1,) whether an interval lies
    within one run (False between two runs: no bound crosses it)."""

    s: np.ndarray
    u_cap: np.ndarray
    why: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    a_lim: np.ndarray
    a_tip: float
    joined: np.ndarray


def tangents(points: np.ndarray, s: np.ndarray, size: np.ndarray) -> np.ndarray:
    """(n, k) d(points)/ds at each vertex of runs laid end to end (``size`` (m,) vertices per run, s each
    run's own increasing arc length): the three-point (non-uniform) difference inside a run, the end
    segment's slope at its ends; a run of one vertex has 0."""
    n = len(points)
    out = np.zeros((n,) + points.shape[1:])
    if n < 2:
        return out
    run = np.repeat(np.arange(len(size)), size)
    inner = run[:-1] == run[1:]
    h = np.where(inner, np.diff(s), 1.0)
    slope = np.where(inner[:, None], np.diff(points, axis=0) / h[:, None], 0.0)
    has_prev = np.zeros(n, bool)
    has_prev[1:] = inner
    has_next = np.zeros(n, bool)
    has_next[:-1] = inner
    m0 = np.zeros_like(out)
    m0[1:] = slope
    m1 = np.zeros_like(out)
    m1[:-1] = slope
    h0 = np.zeros(n)
    h0[1:] = h
    h1 = np.zeros(n)
    h1[:-1] = h
    both = has_prev & has_next
    w = np.where(both, h1 / np.where(both, h0 + h1, 1.0), 0.0)[:, None]
    out = np.where(both[:, None], w * m0 + (1.0 - w) * m1, np.where(has_next[:, None], m1, m0))
    return out


def knots(tips: np.ndarray, axes: np.ndarray, s: np.ndarray, size: np.ndarray, pieces: int = PIECES) -> Knots:
    """The Knots of runs of polyline vertices (tips, unit axes (n, 3), each run's arc length s (n,),
    ``size`` vertices per run): ``pieces`` knots per segment on the cubic Hermite curve through the
    vertices, and each run's last vertex; segments shorter than MIN_SEGMENT are dropped (a run keeps
    at least its first vertex)."""
    size = np.asarray(size, np.int64)
    run = np.repeat(np.arange(len(size)), size)
    start = np.zeros(len(s), bool)
    start[np.concatenate([[0], np.cumsum(size)[:-1]])[size > 0]] = True
    keep = start.copy()
    keep[1:] |= ~start[1:] & (np.diff(s) > MIN_SEGMENT)
    tips, axes, s, run = tips[keep], axes[keep], s[keep], run[keep]
    size = np.bincount(run, minlength=len(size))
    t_tan, a_tan = tangents(tips, s, size), tangents(axes, s, size)
    seg = np.flatnonzero(run[:-1] == run[1:])  # the segments inside a run
    h = (s[seg + 1] - s[seg])[:, None]
    f = np.tile(np.arange(pieces) / pieces, len(seg))[:, None]
    i = np.repeat(seg, pieces)
    hh = np.repeat(h, pieces, axis=0)
    f2 = f * f
    # the cubic Hermite basis and its derivative in f (divided by h: d/ds)
    b_p1, b_m0, b_m1 = f2 * (3.0 - 2.0 * f), f * (f2 - 2.0 * f + 1.0), f2 * (f - 1.0)
    d_p1, d_m0, d_m1 = 6.0 * f * (1.0 - f), (3.0 * f - 4.0) * f + 1.0, (3.0 * f - 2.0) * f
    out = []
    for p, m in ((tips, t_tan), (axes, a_tan)):
        d = p[i + 1] - p[i]
        value = p[i] + d * b_p1 + hh * (m[i] * b_m0 + m[i + 1] * b_m1)
        deriv = d / hh * d_p1 + m[i] * d_m0 + m[i + 1] * d_m1
        out.append((value, deriv))
    ends = np.flatnonzero(np.diff(np.append(run, -1)) != 0)  # each run's last vertex
    order = np.argsort(np.concatenate([i + f[:, 0], ends + 0.5]), kind="stable")
    k_s = np.concatenate([s[i] + f[:, 0] * hh[:, 0], s[ends]])[order]
    k_tips = np.vstack([out[0][0], tips[ends]])[order]
    k_dt = np.vstack([out[0][1], t_tan[ends]])[order]
    w = np.vstack([out[1][0], axes[ends]])[order]
    dw = np.vstack([out[1][1], a_tan[ends]])[order]
    norm = row_norm(w)
    unit = w / norm[:, None]
    d_unit = (dw - unit * row_sum_of_products(unit, dw)[:, None]) / norm[:, None]
    return Knots(k_s, k_tips, unit, k_dt, d_unit, np.bincount(run[np.concatenate([i, ends])], minlength=len(size)))


def _chord_bound(d1: np.ndarray, d2: np.ndarray, tol: float) -> np.ndarray:
    """(n,) bound on (v period)^2 from the sagitta of a curve with derivatives d1, d2 (n, 3) in the tips'
    arc length: (v period |d1|)^2 kappa / 8 <= tol, kappa |d1|^2 = |d1 x d2| / |d1|."""
    cross = row_norm(np.cross(d1, d2))
    speed = row_norm(d1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cross > 0, 8.0 * tol * speed / cross, np.inf)


def path_caps(limits: Limits, side: str, k: Knots, cruise: np.ndarray | float) -> Caps:
    """The Caps at knots ``k`` of one cutter's path (or of runs of paths), ``cruise`` (mm/ms, one or one
    per knot) the fastest tip speed allowed."""
    v_lim, a_lim = limits.axes
    _, dq = inverse_kinematics_rates(limits.machine, side, k.tips, k.axes, k.d_tips, k.d_axes)
    ddq = tangents(dq, k.s, k.size) * np.sign(dq)
    dq = np.abs(dq)
    aim_tol = CHORD_AIM * limits.chord_tol
    d_centres = k.d_tips + limits.tool_radius * k.d_axes
    chord = np.minimum(_chord_bound(k.d_tips, tangents(k.d_tips, k.s, k.size), aim_tol),
                       _chord_bound(d_centres, tangents(d_centres, k.s, k.size), aim_tol)) / limits.period ** 2
    with np.errstate(divide="ignore"):
        speed = ((AIM * v_lim) ** 2 / np.maximum(dq * dq, 1e-300)).min(axis=1)
        accel = (CURVE_SHARE * AIM * a_lim / np.maximum(np.abs(ddq), 1e-300)).min(axis=1)
    table = np.column_stack([np.broadcast_to(np.asarray(cruise, float) ** 2, k.s.shape), speed, accel, chord])
    why = np.argmin(table, axis=1).astype(np.int8)
    run = np.repeat(np.arange(len(k.size)), k.size)
    return Caps(k.s, table[np.arange(len(k.s)), why], why, dq, ddq, AIM * a_lim, TIP_AIM * limits.a_max,
                run[:-1] == run[1:])


def cone(cap: np.ndarray, step_up: np.ndarray, step_down: np.ndarray) -> np.ndarray:
    """The largest u <= cap (n,) with u[i + 1] - u[i] <= step_up[i] and u[i] - u[i + 1] <= step_down[i]
    (n - 1,; inf: no bound): a forward and a backward pass (cumulative minima of cap -+ the sums of the
    steps). A step above the cap's range bounds nothing and is clipped there (the sums keep their
    digits and an infinite step separates what lies either side of it)."""
    top = 2.0 * float(cap.max(initial=0.0)) + 1.0
    g = np.concatenate([[0.0], np.cumsum(np.minimum(step_up, top))])
    fwd = np.minimum.accumulate(cap - g) + g
    g = np.concatenate([[0.0], np.cumsum(np.minimum(step_down, top))])
    bwd = np.minimum.accumulate((cap + g)[::-1])[::-1] - g
    return np.minimum(fwd, bwd)


def _steps(caps: Caps, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n - 1,) each, the largest rise and fall of u over each interval (2 a h) at the speeds of u: every
    axis's |q'| a + q'' sgn(q') u within its aimed acceleration at both ends, u taken at the larger of
    the two ends where the curvature takes from the allowance (none counted where it adds), and the
    tip's |a| within a_tip; inf across runs."""
    top = np.maximum(u[:-1], u[1:])[:, None]
    up, down = np.full(len(u) - 1, caps.a_tip), np.full(len(u) - 1, caps.a_tip)
    with np.errstate(divide="ignore", invalid="ignore"):
        for end in (slice(None, -1), slice(1, None)):
            dq, c = caps.dq[end], caps.ddq[end]
            for sign, out in ((1.0, up), (-1.0, down)):
                take = np.maximum(sign * c, 0.0) * top
                allow = np.where(dq > 0, (caps.a_lim - take) / dq, np.inf).min(axis=1)
                np.minimum(out, allow, out=out)
    h = np.diff(caps.s)
    step = 2.0 * h
    return (np.where(caps.joined, step * np.clip(up, 0.0, None), np.inf),
            np.where(caps.joined, step * np.clip(down, 0.0, None), np.inf))


def fastest(caps: Caps, v_start: np.ndarray | float = 0.0, v_end: np.ndarray | float = 0.0) -> np.ndarray:
    """(n,) mm/ms: the time-optimal tip speed at the knots (module docstring), each run from v_start to
    v_end (one or one per run; each lowered to what the caps allow there)."""
    cap = caps.u_cap.copy()
    n = len(cap)
    if n < 2:
        return np.sqrt(np.minimum(cap, np.minimum(v_start, v_end) ** 2))
    first = np.concatenate([[0], np.flatnonzero(~caps.joined) + 1])
    last = np.append(first[1:] - 1, n - 1)
    cap[first] = np.minimum(cap[first], np.asarray(v_start, float) ** 2)
    cap[last] = np.minimum(cap[last], np.asarray(v_end, float) ** 2)
    u = cone(cap, *_steps(caps, np.zeros(n)))
    for _ in range(PASSES):
        u = cone(cap, *_steps(caps, u))
    return np.sqrt(np.clip(u, 0.0, None))


def durations(s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(n - 1,) ms over each interval with u = v^2 linear in s (constant acceleration): 2 h / (v0 + v1);
    an interval of no length (or between two runs) takes none."""
    h = np.diff(s)
    w = v[:-1] + v[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(h > 0, 2.0 * h / w, 0.0)


def run_times(caps: Caps, v: np.ndarray) -> np.ndarray:
    """(m,) ms: each run's time on the profile v (``fastest``)."""
    run = np.concatenate([[0], np.cumsum(~caps.joined)])
    dur = np.where(caps.joined, durations(caps.s, v), 0.0)
    return np.bincount(run[:-1], weights=dur, minlength=int(run[-1]) + 1)


def traverse_time(limits: Limits, side: str, tips: np.ndarray, axes: np.ndarray, v_start: float = 0.0,
                  v_end: float = 0.0) -> float:
    """ms: the time-optimal traversal of one path (tips, unit axes (n, 3)) at the feed, from v_start to
    v_end."""
    k = knots(tips, axes, cumulative_length(tips), np.array([len(tips)]))
    caps = path_caps(limits, side, k, limits.feed)
    return float(run_times(caps, fastest(caps, v_start, v_end))[0])

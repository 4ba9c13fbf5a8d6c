"""The time-optimal traversal of a cutter's path under the machine's limits: the reference the job the
machines run (core.machine.timing) is measured against. It times nothing that is written.

The path is a polyline of tips and unit tool axes (the executed axes: a MoveTable's, after the reach
step), taken as the smooth (C2) not-a-knot cubic spline through its vertices in the polyline's arc
length s, tips and axes alike: the curve the vertices sample, without the turn at every vertex that
sampling the polyline itself adds. The tip speed is v = ds/dt and u = v^2. With q(s) the six axis
values by inverse kinematics, each axis moves at q' v and accelerates at q' a + q'' u (a = dv/dt =
u' / 2). The limits, each aimed as the machine clock
aims it (core.machine.caps.AIM, CHORD_AIM; core.machine.timing.TIP_AIM):
- **cruise**: v <= the move's cruise speed (the feed while cutting, the rapid speed in the air);
- **axis speed**: |q'_j| v <= AIM v_lim_j;
- **axis acceleration**: -AIM a_lim_j <= q'_j a + q''_j u <= AIM a_lim_j: at each u a range of the
  tangential acceleration a, empty above a largest u (the maximum velocity curve); a speed change may
  offset the path's curvature (where the heads' swing per mm of tip changes, the tip slows or speeds
  up so that the axes do not);
- **tip acceleration**: |a| <= TIP_AIM a_max along the path;
- **chord tolerance**: the controller moves straight between two rows ``period`` ms apart; across a
  chord v period of a curve of curvature kappa it strays (v period)^2 kappa / 8, kept within
  CHORD_AIM of the tolerance for the tips and for the ball centres (tip + r axis), with the largest
  curvature within the longest chord's reach (the curvature changes along a chord).
q' is the analytic Jacobian of the inverse kinematics (core.machine.kinematics) times the curve's
derivatives at knots PIECES per polyline segment; q'' and the curvatures are the three-point
differences of those derivatives along s. Not modelled, as in the machine clock: jerk, and a
controller's own look-ahead.

The profile is the largest u(s) under these bounds (``fastest``), by numerical integration over the
knots with a constant a between two knots (u linear in s), the bounds kept at both knots of each
interval: a backward pass gives at each knot the largest u from which the end can still be reached
braking as hard as the knot allows, and a forward pass speeds up as hard as each knot allows within
it (the time-optimal bang-bang profile). A segment of length h then takes 2 h / (v0 + v1).

Units: mm, ms, mm/ms, mm/ms^2.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from core.machine.caps import AIM, CHORD_AIM, axis_limits
from core.machine.kinematics import inverse_kinematics_rates
from core.machine.model import Machine
from core.machine.timing import TIP_AIM
from core.util.polyline import cumulative_length
from core.util.rowwise import row_norm, row_sum_of_products
from core.util.spline import Cubic

#: mm per mm: an axis moving less than this per mm of tip counts as not moving with it
MOVING = 1e-9
#: knots per polyline segment the bounds are found at: round the edges and a tip path's ends the heads'
#: swing per mm of tip changes by half within a segment; at 8 the profile's rows keep the aimed limits
#: (at 4 they pass them by up to 12 % on the sample's staggered stretches)
PIECES = 8
#: mm: segments shorter than this count as zero length (a junction's two vertices)
MIN_SEGMENT = 1e-12
#: knots either side over which a chord's bound is taken (``_over_chords``)
CHORD_REACH = 64
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
    unit axes (n, 3) and their derivatives in s (n, 3)."""

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
    ``size`` vertices per run): ``pieces`` knots per segment on each run's not-a-knot cubic spline
    through its vertices (core.util.spline.Cubic), and its last vertex; segments shorter than
    MIN_SEGMENT are dropped (a run keeps at least its first vertex)."""
    size = np.asarray(size, np.int64)
    run = np.repeat(np.arange(len(size)), size)
    start = np.zeros(len(s), bool)
    start[np.concatenate([[0], np.cumsum(size)[:-1]])[size > 0]] = True
    keep = start.copy()
    keep[1:] |= ~start[1:] & (np.diff(s) > MIN_SEGMENT)
    pts, s, run = np.hstack([tips, axes])[keep], s[keep], run[keep]
    size = np.bincount(run, minlength=len(size))
    frac = np.arange(pieces) / pieces
    values, derivs, at = [], [], []
    lo = 0
    for n in size[size > 0]:
        x = s[lo:lo + n]
        if n == 1:
            values.append(pts[lo:lo + 1])
            derivs.append(np.zeros((1, 6)))
            at.append(x)
        else:
            curve = Cubic(x, pts[lo:lo + n])
            i = np.append(np.repeat(np.arange(n - 1), pieces), n - 2)
            xk = np.append((x[:-1, None] + np.diff(x)[:, None] * frac).ravel(), x[-1])
            values.append(curve.eval_in(i, xk))
            derivs.append(curve.eval_in(i, xk, 1))
            at.append(xk)
        lo += n
    value, deriv = np.vstack(values), np.vstack(derivs)
    w, dw = value[:, 3:], deriv[:, 3:]
    norm = row_norm(w)
    unit = w / norm[:, None]
    d_unit = (dw - unit * row_sum_of_products(unit, dw)[:, None]) / norm[:, None]
    k_size = np.where(size > 1, (size - 1) * pieces + 1, size)
    return Knots(np.concatenate(at), value[:, :3], unit, deriv[:, :3], d_unit, k_size)


def _chord_bound(d1: np.ndarray, d2: np.ndarray, tol: float) -> np.ndarray:
    """(n,) bound on (v period)^2 from the sagitta of a curve with derivatives d1, d2 (n, 3) in the tips'
    arc length: (v period |d1|)^2 kappa / 8 <= tol, kappa |d1|^2 = |d1 x d2| / |d1|."""
    cross = row_norm(np.cross(d1, d2))
    speed = row_norm(d1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cross > 0, 8.0 * tol * speed / cross, np.inf)


def _over_chords(cap: np.ndarray, s: np.ndarray, run: np.ndarray, chord: np.ndarray) -> np.ndarray:
    """(n,) the chord bound at each knot lowered to the least of it over the knots of its run within
    half of ``chord`` (n,) mm (the longest chord there) either side: a chord spans them, and the
    curvature may change along it (at most CHORD_REACH knots either side)."""
    out = cap.copy()
    n = len(cap)
    for step in range(1, CHORD_REACH + 1):
        if step >= n:
            break
        near = (run[step:] == run[:-step]) & (s[step:] - s[:-step] <= 0.5 * chord[step:])
        if not near.any():
            break
        out[step:] = np.where(near, np.minimum(out[step:], cap[:-step]), out[step:])
        out[:-step] = np.where(near, np.minimum(out[:-step], cap[step:]), out[:-step])
    return out


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
    run = np.repeat(np.arange(len(k.size)), k.size)
    cruise_u = np.broadcast_to(np.asarray(cruise, float) ** 2, k.s.shape)
    chord = _over_chords(chord, k.s, run, np.sqrt(cruise_u) * limits.period)
    with np.errstate(divide="ignore"):
        speed = ((AIM * v_lim) ** 2 / np.maximum(dq * dq, 1e-300)).min(axis=1)
    caps = Caps(k.s, np.empty(0), np.empty(0, np.int8), dq, ddq, AIM * a_lim, TIP_AIM * limits.a_max,
                run[:-1] == run[1:])
    table = np.column_stack([cruise_u, speed, _accel_bound(caps, np.minimum(np.minimum(cruise_u, speed), chord)),
                             chord])
    why = np.argmin(table, axis=1).astype(np.int8)
    return replace(caps, u_cap=table[np.arange(len(k.s)), why], why=why)


def _pseudo_axes(caps: Caps, i: np.ndarray | slice = slice(None)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """At knots i, each axis's and the tip's bound on the tangential acceleration a as w - r u (the
    tip as a seventh axis moving 1 mm per mm with no curvature): (r, w, moving) (k, 7) each, r = c / |q'|
    and w = A / |q'| where the axis moves with the tip (``moving``), else 0 and inf."""
    dq = np.column_stack([caps.dq[i], np.ones(len(caps.dq[i]))])
    c = np.column_stack([caps.ddq[i], np.zeros(len(dq))])
    lim = np.append(caps.a_lim, caps.a_tip)
    moving = dq > MOVING
    safe = np.where(moving, dq, 1.0)
    return np.where(moving, c / safe, 0.0), np.where(moving, lim / safe, np.inf), moving


def _accel_bound(caps: Caps, other: np.ndarray) -> np.ndarray:
    """(n,) the largest u at each knot at which some tangential acceleration a keeps every axis within
    its aimed acceleration, -A <= q' a + q'' u <= A, and the tip within a_tip: each pair of bounds
    on a (w_k - r_k u from above, -w_j - r_j u from below) meets below that u. At a = 0 every
    |q''| u <= A holds up to a lower bound of it: where that bound is at least the knot's ``other``
    caps already, it is returned (the pairs are found only where the curvature may bind)."""
    with np.errstate(divide="ignore"):
        u = (caps.a_lim / np.maximum(np.abs(caps.ddq), 1e-300)).min(axis=1)
    need = np.flatnonzero(u < other)
    if need.size == 0:
        return u
    r, w, moving = _pseudo_axes(caps, need)
    lim = np.append(caps.a_lim, caps.a_tip)
    c = np.column_stack([caps.ddq[need], np.zeros(len(need))])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        got = np.where(~moving & (c != 0), lim / np.abs(c), np.inf).min(axis=1)
        for j in range(r.shape[1]):
            coef = r - r[:, j:j + 1]
            bound = np.where(moving & moving[:, j:j + 1] & (coef > 0), (w + w[:, j:j + 1]) / coef, np.inf)
            np.minimum(got, bound.min(axis=1), out=got)
    u[need] = got
    return u


def fastest(caps: Caps, v_start: np.ndarray | float = 0.0, v_end: np.ndarray | float = 0.0) -> np.ndarray:
    """(n,) mm/ms: the time-optimal tip speed at the knots (module docstring), each run from v_start to
    v_end (one or one per run; each lowered to what the caps allow there). The runs are passed in
    lockstep, one knot of each a step: backward, the largest u_i from which the most negative a the
    interval allows (at both its knots) still reaches the next knot's bound; then forward, the
    largest a the interval allows, within the next knot's bound."""
    n = len(caps.u_cap)
    first = np.concatenate([[0], np.flatnonzero(~caps.joined) + 1])
    size = np.diff(np.append(first, n))
    bound = caps.u_cap.copy()
    bound[first + size - 1] = np.minimum(bound[first + size - 1], np.asarray(v_end, float) ** 2)
    h = np.append(np.diff(caps.s), 0.0)
    r, w, _ = _pseudo_axes(caps)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for step in range(1, int(size.max(initial=0))):  # backward: knot first + size - 1 - step
            lanes = size > step
            i = first[lanes] + size[lanes] - 1 - step
            two_h = 2.0 * h[i][:, None]
            # the most negative a is the largest of the lower bounds, w and r at knot i as they stand and
            # at knot i + 1 through u_i + 2 h a: a >= (-w' - r' u_i) / (1 + 2 h r')
            nxt = 1.0 + two_h * r[i + 1]
            keep = nxt > 0
            alpha = np.hstack([-w[i], np.where(keep, -w[i + 1] / np.where(keep, nxt, 1.0), -np.inf)])
            beta = np.hstack([-r[i], np.where(keep, -r[i + 1] / np.where(keep, nxt, 1.0), 0.0)])
            coef = 1.0 + two_h * beta
            rhs = bound[i + 1][:, None] - two_h * alpha
            reach = np.where((coef > 0) & np.isfinite(alpha), rhs / coef, np.inf).min(axis=1)
            bound[i] = np.minimum(bound[i], reach)
        u = bound.copy()
        u[first] = np.minimum(u[first], np.asarray(v_start, float) ** 2)
        for step in range(int(size.max(initial=0)) - 1):  # forward: knot first + step
            lanes = size > step + 1
            i = first[lanes] + step
            two_h = 2.0 * h[i][:, None]
            here = (w[i] - r[i] * u[i][:, None]).min(axis=1)
            nxt = 1.0 + two_h * r[i + 1]
            there = np.where(nxt > 0, (w[i + 1] - r[i + 1] * u[i][:, None]) / np.where(nxt > 0, nxt, 1.0),
                             np.inf).min(axis=1)
            u[i + 1] = np.clip(u[i] + 2.0 * h[i] * np.minimum(here, there), 0.0, bound[i + 1])
    return np.sqrt(u)


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

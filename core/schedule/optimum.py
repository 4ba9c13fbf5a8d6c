"""The time-optimal traversal of one cutter's path under the machine's limits: the speed profile the
schedule's cutting stretches, turns and moves home run on, and the reference the job is measured
against.

The path is the smooth curve through the move's polyline (core.schedule.curve), parameterised by its
arc length s; the tip speed is v = ds/dt and u = v^2. With q(s) the six axis values by inverse
kinematics, each axis moves at q' v and accelerates at q' a + q'' u (a = dv/dt = u' / 2). The limits:
- **feed**: v <= feed (the tip's speed along the path);
- **axis speed**: |q'_j| v <= v_lim_j;
- **axis acceleration**: |q'_j| |a| + |q''_j| u <= a_lim_j, which bounds u (at a = 0) and, below that
  bound, the tangential acceleration a;
- **tip acceleration**: |a| <= a_max (the schedule's a_max along the path);
- **chord tolerance**: the controller moves straight between two rows ``period`` ms apart; across a
  chord v period of a curve of curvature kappa it strays (v period)^2 kappa / 8 from it, for the
  tips and for the ball centres (tip + r axis, whose speed is |c'| v).
Speeds and accelerations are aimed AIM inside the limits, the chord CHORD_AIM inside the tolerance,
and a curvature bound takes at most CURVE_SHARE of an axis's acceleration (the rest is left to speed
changes; at 1 no speed could change where that bound holds). q', q'' and the curvatures are the
three-point differences of the curve at its vertices, the smooth path's own derivatives.

The profile is the largest u(s) under these bounds (``fastest``): a forward and a backward pass
along s (``cone``, CNC look-ahead) with the acceleration each interval allows at the speeds it
runs, iterated: the bound on a falls as u rises, so a pass with the allowances of a profile above the
optimum lies below it and is feasible, and one with a feasible profile's allowances lies above it;
the iterates close in from both sides and the last feasible one is returned. Between two vertices
u is linear in s (constant acceleration), so the time over a segment of length h is 2 h / (v0 + v1).

Units: mm, ms, mm/ms, mm/ms^2.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from core.schedule.curve import evaluate, segment_rows, tangents
from core.util.rowwise import row_norm

#: speeds and accelerations are aimed this far inside the machine's limits
AIM = 0.97
#: speed changes (the tip's acceleration along the path, and the axes' share of it) are aimed this far
#: inside the limits: a time-optimal profile switches between accelerating and cruising at once, and
#: the axes' velocity columns must still agree with the central differences of their positions over
#: two periods (a switch of acceleration a reads as a * period / 4 there)
SPEED_CHANGE_AIM = 0.6
#: the chord deviation is aimed this far inside the tolerance
CHORD_AIM = 0.8
#: the share of an axis's acceleration the path's curvature alone may take at the bound on u
CURVE_SHARE = 0.9
#: knots per segment of the polyline the caps are found at (the curve's derivatives vary within a
#: segment: round a path's end the axes' swing changes by half within 0.2 mm)
PIECES = 4
#: forward-backward passes of ``fastest`` (odd: the last is feasible)
PASSES = 7
#: what bounds the speed at a vertex (``Caps.why``), as plan.json names it
WHY = ("feed", "axis speed", "axis acceleration", "chord")
FEED, AXIS_SPEED, AXIS_ACCEL, CHORD = range(4)


@dataclass(frozen=True)
class Limits:
    """What a cutter's speed is bounded by: its machine's inverse kinematics ``ik(side, tips, axes)``
    -> (n, 6) axis values and its axes' speed (mm/ms) and acceleration (mm/ms^2) limits (6,) each
    (core.machine.caps.machine_limits makes them from a machine.toml), the controller's period (ms)
    and chord tolerance (mm), the ball radius (mm), the feed (mm/ms) and a_max (mm/ms^2)."""

    ik: Callable[[str, np.ndarray, np.ndarray], np.ndarray]
    v_lim: np.ndarray
    a_lim: np.ndarray
    period: float
    chord_tol: float
    tool_radius: float
    feed: float
    a_max: float


@dataclass(frozen=True)
class Caps:
    """One path's bounds at its vertices: s (n,) arc length mm; u_cap (n,) the bound on v^2 and why
    (n,) int8 which limit sets it (WHY); dq (n, 6) |dq/ds| of the six axes and ddq (n, 6) d2q/ds2
    times the sign of dq/ds (positive where the curvature adds to the acceleration of a speed-up);
    a_tip the bound on the tip's acceleration along the path."""

    s: np.ndarray
    u_cap: np.ndarray
    why: np.ndarray
    dq: np.ndarray
    ddq: np.ndarray
    a_lim: np.ndarray
    a_tip: float

    def part(self, i: int, j: int) -> Caps:
        """The caps of vertices i..j (inclusive), s from 0."""
        k = slice(i, j + 1)
        return Caps(self.s[k] - self.s[i], self.u_cap[k], self.why[k], self.dq[k], self.ddq[k], self.a_lim,
                    self.a_tip)


def _curve_bound(d1: np.ndarray, d2: np.ndarray, tol: float) -> np.ndarray:
    """(n,) bound on (v period)^2 from the chord's sagitta on a curve with derivatives d1, d2 (n, 3) in
    the tip's arc length: (v period |d1|)^2 kappa / 8 <= tol, kappa |d1|^2 = |d1 x d2| / |d1|."""
    cross = row_norm(np.cross(d1, d2))
    speed = row_norm(d1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(cross > 0, 8.0 * tol * speed / cross, np.inf)


def knots(tips: np.ndarray, axes: np.ndarray, s: np.ndarray, pieces: int = PIECES
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(s, tips, unit axes) at ``pieces`` knots per segment of a polyline (n,), on its smooth curve
    (core.schedule.curve); segments of zero length are dropped."""
    keep = np.concatenate([[True], np.diff(s) > 0])
    s, tips, axes = s[keep], tips[keep], axes[keep]
    size = np.array([len(s)])
    if len(s) < 2:
        return s, tips, axes
    f = np.arange(pieces) / pieces
    seg = np.repeat(np.arange(len(s) - 1), pieces)
    frac = np.tile(f, len(s) - 1)
    h = np.diff(s)
    out_s = np.append(s[seg] + frac * h[seg], s[-1])
    out = []
    for pts in (tips, axes):
        rows = segment_rows(pts, tangents(pts, s, size), s)
        out.append(np.vstack([evaluate(rows[seg], frac), pts[-1:]]))
    w = out[1] / row_norm(out[1])[:, None]
    return out_s, out[0], w


def path_caps(limits: Limits, side: str, tips: np.ndarray, axes: np.ndarray, s: np.ndarray,
              size: np.ndarray | None = None) -> Caps:
    """The Caps at the vertices of one cutter's path (tips, unit axes (n, 3) mm, arc length s (n,);
    ``knots`` gives them on its curve), or of several laid end to end (``size``: vertices per run;
    derivatives are taken within each run)."""
    size = np.array([len(s)]) if size is None else size
    v_lim, a_lim = limits.v_lim, limits.a_lim
    q = limits.ik(side, tips, axes)
    dq = tangents(q, s, size)
    ddq = tangents(dq, s, size) * np.sign(dq)
    dq = np.abs(dq)
    dt = tangents(tips, s, size)
    dw = tangents(axes, s, size)
    aim_tol = CHORD_AIM * limits.chord_tol
    chord = np.minimum(_curve_bound(dt, tangents(dt, s, size), aim_tol),
                       _curve_bound(dt + limits.tool_radius * dw,
                                    tangents(dt + limits.tool_radius * dw, s, size), aim_tol))
    chord = chord / limits.period ** 2
    with np.errstate(divide="ignore"):
        speed = ((AIM * v_lim) ** 2 / np.maximum(dq * dq, 1e-300)).min(axis=1)
        accel = (CURVE_SHARE * AIM * a_lim / np.maximum(np.abs(ddq), 1e-300)).min(axis=1)
    table = np.column_stack([np.full(len(s), limits.feed ** 2), speed, accel, chord])
    why = np.argmin(table, axis=1).astype(np.int8)
    return Caps(np.asarray(s, float), table[np.arange(len(s)), why], why, dq, ddq, a_lim,
                SPEED_CHANGE_AIM * limits.a_max)


def cone(cap: np.ndarray, ds: np.ndarray, up: np.ndarray, down: np.ndarray | None = None) -> np.ndarray:
    """The largest u <= cap (n,) with u[i + 1] - u[i] <= up[i] ds[i] and u[i] - u[i + 1] <= down[i] ds[i]
    (n - 1,; down = up when not given): a forward and a backward pass (cumulative minima of cap -+
    the integrals of the rates)."""
    g = np.concatenate([[0.0], np.cumsum(up * ds)])
    fwd = np.minimum.accumulate(cap - g) + g
    if down is not None:
        g = np.concatenate([[0.0], np.cumsum(down * ds)])
    bwd = np.minimum.accumulate((cap + g)[::-1])[::-1] - g
    return np.minimum(fwd, bwd)


def _rates(caps: Caps, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n - 1,) each, the bounds on du/ds = 2 a when speeding up and when slowing down over each
    interval, at the speeds of u: each axis's |q'| |a| +- q'' sgn(q') u <= AIM a_lim at both ends,
    u taken where it binds most (the larger u of the two ends where the curvature takes from the
    allowance, the smaller where it adds)."""
    top = np.maximum(u[:-1], u[1:])[:, None]
    low = np.minimum(u[:-1], u[1:])[:, None]
    aim = SPEED_CHANGE_AIM * caps.a_lim
    up, down = np.full(len(u) - 1, caps.a_tip), np.full(len(u) - 1, caps.a_tip)
    with np.errstate(divide="ignore", invalid="ignore"):
        for end in (slice(None, -1), slice(1, None)):
            dq, c = caps.dq[end], caps.ddq[end]
            for sign, out in ((1.0, up), (-1.0, down)):
                k = sign * c
                allow = np.where(dq > 0, (aim - k * np.where(k > 0, top, low)) / dq, np.inf).min(axis=1)
                np.minimum(out, allow, out=out)
    return 2.0 * np.clip(up, 0.0, None), 2.0 * np.clip(down, 0.0, None)


def fastest(caps: Caps, v_start: float = 0.0, v_end: float = 0.0) -> np.ndarray:
    """(n,) mm/ms: the time-optimal tip speed at the vertices of a path (module docstring), from
    v_start to v_end (each lowered to what the caps allow there)."""
    cap = caps.u_cap.copy()
    cap[0] = min(cap[0], v_start * v_start)
    cap[-1] = min(cap[-1], v_end * v_end)
    if len(cap) < 2:
        return np.sqrt(cap)
    ds = np.diff(caps.s)
    u = cone(cap, ds, *_rates(caps, np.zeros_like(cap)))
    for _ in range(PASSES):
        u = cone(cap, ds, *_rates(caps, u))
    return np.sqrt(np.clip(u, 0.0, None))


def durations(s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(n - 1,) ms over each segment with u = v^2 linear in s (constant acceleration): 2 h / (v0 + v1);
    a segment of zero length takes none."""
    h = np.diff(s)
    w = v[:-1] + v[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(h > 0, 2.0 * h / w, 0.0)


def _swap(k: tuple) -> tuple:
    """knots' (s, tips, axes) as path_caps' (tips, axes, s)."""
    return k[1], k[2], k[0]


def traverse_time(limits: Limits, side: str, tips: np.ndarray, axes: np.ndarray, s: np.ndarray,
                  v_start: float = 0.0, v_end: float = 0.0) -> float:
    """ms: the time-optimal traversal of one path (``fastest`` at its ``knots``)."""
    caps = path_caps(limits, side, *_swap(knots(tips, axes, s)))
    return float(durations(caps.s, fastest(caps, v_start, v_end)).sum())


def held(caps: Caps, v_in: float, v_out: float, duration: float) -> tuple[np.ndarray, float]:
    """(v (n,) mm/ms, V): a speed stage on the machine: the path from v_in to v_out (as far as the
    caps allow at its ends) in ``duration`` ms: the time-optimal profile, lowered to a plateau V
    between a descent from the start and a climb to the end at the acceleration the profile's
    speeds allow (so that the stage leaves at the speed it entered with), V found by bisection so
    that the duration is met to 1e-9 of it. A duration shorter than the time-optimal profile's gives
    that profile (V = the larger end speed)."""
    v0 = max(v_in, v_out)
    u_fast = fastest(caps, v_in, v_out) ** 2
    if durations(caps.s, np.sqrt(u_fast)).sum() >= duration or len(u_fast) < 3:
        return np.sqrt(u_fast), v0
    up, down = _rates(caps, u_fast)
    ds = np.diff(caps.s)
    descent = u_fast[0] - np.concatenate([[0.0], np.cumsum(down * ds)])
    climb = u_fast[-1] - np.concatenate([[0.0], np.cumsum((up * ds)[::-1])])[::-1]
    valley = np.maximum(descent, climb)

    def profile(top: float) -> np.ndarray:
        return np.sqrt(np.clip(np.minimum(u_fast, np.maximum(top * top, valley)), 0.0, None))

    lo, hi = 0.0, v0  # the plateau: too slow at lo, fast enough at hi
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        v = profile(mid)
        t = durations(caps.s, v).sum() if mid > 0 else np.inf
        if abs(t - duration) <= 1e-9 * duration:
            return v, mid
        lo, hi = (mid, hi) if t > duration else (lo, mid)
    return profile(hi), hi

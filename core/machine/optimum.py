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

Each limit is a constraint object (toppra's model): ``Cruise``, ``AxisSpeed``, ``AxisAcceleration``,
``TipAcceleration``, ``Chord``. A constraint gives, at the knots of a ``Segment`` (the path's knots with
its machine's dq/ds and d2q/ds2), caps on u and rows bounding the tangential acceleration as
-w - r u <= a <= w - r u. ``profile(segment, constraints)`` is the largest u(s) under them all (the
compiled passes of core.machine._optimum): a constant a between two knots (u linear in s), the
bounds kept at both knots of each interval; a backward pass gives at each knot the largest u from
which the end can still be reached braking as hard as the knot allows, and a forward pass speeds up
as hard as each knot allows within it (the time-optimal bang-bang profile). A segment of length h
then takes 2 h / (v0 + v1). The Profile names, per knot, the constraint that binds there
(``Profile.why``): the cap that sets it, the acceleration row that brakes or speeds it up, or the
speed it enters or leaves with.

Units: mm, ms, mm/ms, mm/ms^2.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from core.machine._optimum import row_caps, solve
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
#: the reason a knot's speed is set by the speed a run enters or leaves with (``Profile.why``)
ENDS = "entry or exit speed"


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


@dataclass(frozen=True)
class Segment:
    """A cutter's path as the constraints see it: its Knots, run by run, with the machine's axis rates
    there: dq (n, 6) |dq/ds| and ddq (n, 6) d2q/ds2 times the sign of dq/ds (the three-point
    difference of dq/ds along s)."""

    knots: Knots
    dq: np.ndarray
    ddq: np.ndarray

    @property
    def run(self) -> np.ndarray:
        """(n,) the run of each knot."""
        return np.repeat(np.arange(len(self.knots.size)), self.knots.size)


def segment(machine: Machine, side: str, k: Knots) -> Segment:
    """The Segment of knots ``k`` on one side's machine (inverse kinematics and its analytic Jacobian)."""
    _, dq = inverse_kinematics_rates(machine, side, k.tips, k.axes, k.d_tips, k.d_axes)
    return Segment(k, np.abs(dq), tangents(dq, k.s, k.size) * np.sign(dq))


class Constraint(Protocol):
    """A limit on the motion along a Segment (toppra's constraint objects): ``caps`` (n,) bounds on
    u = v^2 at the knots, or None; ``rows`` (r, w) each (n, k): the tangential acceleration a bounded by
    -w - r u <= a <= w - r u (w = inf: no bound), or None; ``name``: what the read-out calls it."""

    @property
    def name(self) -> str: ...

    def caps(self, seg: Segment) -> np.ndarray | None: ...

    def rows(self, seg: Segment) -> tuple[np.ndarray, np.ndarray] | None: ...


@dataclass(frozen=True)
class Cruise:
    """The fastest tip speed (mm/ms; one, or one per knot): the feed cutting, the rapid speed in the air."""

    speed: np.ndarray | float
    name: str = "cruise"

    def caps(self, seg: Segment) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.speed, float) ** 2, seg.knots.s.shape)

    def rows(self, seg: Segment) -> None:
        return None


@dataclass(frozen=True)
class AxisSpeed:
    """Each axis's speed: |q'_j| v <= limit_j (mm/ms, (6,), already aimed)."""

    limit: np.ndarray
    name: str = "axis speed"

    def caps(self, seg: Segment) -> np.ndarray:
        with np.errstate(divide="ignore"):
            return (self.limit ** 2 / np.maximum(seg.dq * seg.dq, 1e-300)).min(axis=1)

    def rows(self, seg: Segment) -> None:
        return None


@dataclass(frozen=True)
class AxisAcceleration:
    """Each axis's acceleration: -A_j <= q'_j a + q''_j u <= A_j (mm/ms^2, (6,), already aimed). An axis
    moving with the tip bounds a (a row); one that does not (|q'| <= MOVING) bounds u alone."""

    limit: np.ndarray
    name: str = "axis acceleration"

    def caps(self, seg: Segment) -> np.ndarray:
        still = seg.dq <= MOVING
        with np.errstate(divide="ignore"):
            return np.where(still & (seg.ddq != 0), self.limit / np.maximum(np.abs(seg.ddq), 1e-300),
                            np.inf).min(axis=1)

    def rows(self, seg: Segment) -> tuple[np.ndarray, np.ndarray]:
        moving = seg.dq > MOVING
        safe = np.where(moving, seg.dq, 1.0)
        return np.where(moving, seg.ddq / safe, 0.0), np.where(moving, self.limit / safe, np.inf)


@dataclass(frozen=True)
class TipAcceleration:
    """The tip's acceleration along its path: |a| <= limit (mm/ms^2, already aimed)."""

    limit: float
    name: str = "tip acceleration"

    def caps(self, seg: Segment) -> None:
        return None

    def rows(self, seg: Segment) -> tuple[np.ndarray, np.ndarray]:
        n = len(seg.knots.s)
        return np.zeros((n, 1)), np.full((n, 1), float(self.limit))


@dataclass(frozen=True)
class Chord:
    """The chord tolerance: the controller moves straight between two rows ``period`` ms apart, which
    strays (v period)^2 kappa / 8 from a curve of curvature kappa; kept within ``tolerance`` (mm,
    already aimed) for the tips and the ball centres (tip + radius axis), with the largest curvature
    within the longest chord's reach (at ``cruise`` mm/ms, one or one per knot)."""

    tolerance: float
    period: float
    radius: float
    cruise: np.ndarray | float
    name: str = "chord"

    def caps(self, seg: Segment) -> np.ndarray:
        k = seg.knots
        d_centres = k.d_tips + self.radius * k.d_axes
        bound = np.minimum(_chord_bound(k.d_tips, tangents(k.d_tips, k.s, k.size), self.tolerance),
                           _chord_bound(d_centres, tangents(d_centres, k.s, k.size), self.tolerance))
        longest = np.broadcast_to(np.asarray(self.cruise, float), k.s.shape) * self.period
        return _over_chords(bound / self.period ** 2, k.s, seg.run, longest)

    def rows(self, seg: Segment) -> None:
        return None


def limits_of(limits: Limits, cruise: np.ndarray | float) -> list[Constraint]:
    """The constraints of a cutter's motion under ``limits``, each aimed inside its limit (AIM,
    CHORD_AIM, TIP_AIM), at the cruise speed ``cruise`` (mm/ms; one, or one per knot)."""
    v_lim, a_lim = limits.axes
    return [Cruise(cruise), AxisSpeed(AIM * v_lim), AxisAcceleration(AIM * a_lim),
            TipAcceleration(TIP_AIM * limits.a_max),
            Chord(CHORD_AIM * limits.chord_tol, limits.period, limits.tool_radius, cruise)]


@dataclass(frozen=True)
class Profile:
    """The time-optimal motion along a Segment: s (n,) mm and v (n,) mm/ms at its knots (u = v^2 linear
    in s between two), ``why`` (n,) int8 the reason that binds at each knot, an index into ``reasons``
    (the constraints' names, then ENDS), and ``joined`` (n - 1,) whether an interval lies within one
    run (no time is spent between two runs)."""

    s: np.ndarray
    v: np.ndarray
    why: np.ndarray
    reasons: tuple[str, ...]
    joined: np.ndarray

    def durations(self) -> np.ndarray:
        """(n - 1,) ms each interval takes (none between two runs)."""
        return np.where(self.joined, durations(self.s, self.v), 0.0)

    def run_times(self) -> np.ndarray:
        """(m,) ms each run takes."""
        run = np.concatenate([[0], np.cumsum(~self.joined)])
        return np.bincount(run[:-1], weights=self.durations(), minlength=int(run[-1]) + 1)

    def slowed_for(self) -> np.ndarray:
        """(n,) the name of the reason at each knot."""
        return np.asarray(self.reasons, dtype=object)[self.why]


def _stacked(seg: Segment, constraints: Sequence[Constraint]) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                                          np.ndarray, np.ndarray]:
    """The constraints at the segment's knots, stacked: (u_cap (n,), cap_owner (n,) the constraint
    index of the lowest cap, r (n, m), w (n, m), row_owner (m,) each row's constraint)."""
    n = len(seg.knots.s)
    caps, owners, rs, ws, row_owner = [], [], [], [], []
    for j, c in enumerate(constraints):
        cap = c.caps(seg)
        if cap is not None:
            caps.append(np.broadcast_to(cap, (n,)))
            owners.append(j)
        rows = c.rows(seg)
        if rows is not None:
            rs.append(rows[0])
            ws.append(rows[1])
            row_owner += [j] * rows[0].shape[1]
    r = np.ascontiguousarray(np.hstack(rs) if rs else np.zeros((n, 0)), float)
    w = np.ascontiguousarray(np.hstack(ws) if ws else np.zeros((n, 0)), float)
    mvc, which = np.empty(n), np.empty(n, np.int32)
    row_caps(r, w, mvc, which)
    table = np.column_stack([*caps, mvc]) if caps else mvc[:, None]
    lowest = np.argmin(table, axis=1)
    owner_of = np.append(np.asarray(owners, int), -1)[lowest]
    from_rows = lowest == len(caps)
    owner_of[from_rows] = np.append(row_owner, len(constraints))[which[from_rows]]
    return table[np.arange(n), lowest], owner_of, r, w, np.append(row_owner, len(constraints)).astype(int)


def profile(seg: Segment, constraints: Sequence[Constraint], v_start: np.ndarray | float = 0.0,
            v_end: np.ndarray | float = 0.0) -> Profile:
    """The time-optimal Profile along ``seg`` under ``constraints`` (module docstring), each run from
    v_start to v_end (mm/ms; one or one per run; each lowered to what the constraints allow there)."""
    k = seg.knots
    n, runs = len(k.s), len(k.size)
    u_cap, cap_owner, r, w, row_owner = _stacked(seg, constraints)
    first = np.concatenate([[0], np.cumsum(k.size)[:-1]]).astype(np.int64)
    ends = [np.ascontiguousarray(np.broadcast_to(np.asarray(v, float) ** 2, (runs,))) for v in (v_start, v_end)]
    u, row, phase = np.empty(n), np.empty(n, np.int32), np.empty(n, np.int8)
    solve(np.ascontiguousarray(k.s, float), np.ascontiguousarray(u_cap, float), r, w, first,
          np.ascontiguousarray(k.size, np.int64), ends[0], ends[1], u, row, phase)
    why = np.where(phase == 0, np.where(u < u_cap, len(constraints), cap_owner), row_owner[row])
    joined = np.repeat(np.arange(runs), k.size)
    reasons = tuple(c.name for c in constraints) + (ENDS,)
    return Profile(k.s, np.sqrt(np.maximum(u, 0.0)), why.astype(np.int8), reasons, joined[:-1] == joined[1:])


def durations(s: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(n - 1,) ms over each interval with u = v^2 linear in s (constant acceleration): 2 h / (v0 + v1);
    an interval of no length (or between two runs) takes none."""
    h = np.diff(s)
    w = v[:-1] + v[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(h > 0, 2.0 * h / w, 0.0)


def traverse_time(limits: Limits, side: str, tips: np.ndarray, axes: np.ndarray, v_start: float = 0.0,
                  v_end: float = 0.0) -> float:
    """ms: the time-optimal traversal of one path (tips, unit axes (n, 3)) at the feed, from v_start to
    v_end."""
    k = knots(tips, axes, cumulative_length(tips), np.array([len(tips)]))
    seg = segment(limits.machine, side, k)
    return float(profile(seg, limits_of(limits, limits.feed), v_start, v_end).run_times()[0])

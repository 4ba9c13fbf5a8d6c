"""What the machines and the controller allow a cutter's tip speed to be, per segment of its polyline.

A cutter's motion is a polyline (tips and unit tool axes at its vertices, core.schedule.movetable)
passed under a speed law. Three things bound the tip speed v (mm/ms) along it, each from the geometry
alone, so that they are computed once per schedule and hold whatever the laws:
- **axis speed**: an axis moves at dq/ds * v (q the six axis values by inverse kinematics, s the
  distance along the polyline): v <= v_lim / |dq/ds| on each segment;
- **axis acceleration**: where dq/ds turns by J from one segment to the next, the axis velocity (the
  derivative of the motion, as the tables hold it) jumps by v J within one row interval, ``period``
  ms; over a run of vertices h apart it turns at v^2 J / h: v <= min(a_lim period / J,
  sqrt(a_lim h / J)) at each vertex;
- **chord tolerance**: the controller moves in a straight line between two rows ``period`` ms apart,
  across a chord c = v * period of the path. At a vertex where the path turns by theta the chord
  strays (c / 2) sin(theta / 2) from it, and over a run of vertices turning theta every h (a curve of
  curvature theta / h) c^2 theta / (8 h): both within ``chord_tol`` gives c, so v <= c / period. Both
  the tips and the ball centres (tip + r axis) are bounded.
Each bound is aimed a margin inside its limit (``AIM``); the machine clock (core.machine.timing)
checks the table as written and lowers the speed further where an estimate fell short.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from core.machine.kinematics import inverse_kinematics
from core.machine.model import AXES, Machine
from core.schedule.curve import evaluate
from core.schedule.movetable import MoveTable
from core.schedule.optimum import CHORD, PIECES, Limits, path_caps
from core.util.polyline import ball_centres
from core.util.rowwise import row_norm

#: speeds and accelerations are aimed this far inside the machine's limits
AIM = 0.97
#: the chord deviation is aimed this far inside the tolerance
CHORD_AIM = 0.8
#: share of each axis's acceleration left to the speed changes of the machine clock (the rest bounds
#: the acceleration of the path's own curvature at the scheduled speed)
SCALE_SHARE = 0.2


def axis_limits(machine: Machine) -> tuple[np.ndarray, np.ndarray]:
    """(6,) speed limits mm/ms and (6,) acceleration limits mm/ms^2 of one machine's axes."""
    v = np.array([machine.limits.axis(a).max_speed_mm_s for a in AXES]) / 1000.0
    a = np.array([machine.limits.axis(a).max_accel_mm_s2 for a in AXES]) / 1e6
    return v, a


def machine_limits(machine: Machine, period: float, chord_tol: float, tool_radius: float, feed: float,
                   a_max: float) -> Limits:
    """The Limits (core.schedule.optimum) of a machine.toml's machines: their inverse kinematics and
    axis limits; period ms, chord_tol mm, tool_radius mm, feed mm/ms, a_max mm/ms^2."""
    v_lim, a_lim = axis_limits(machine)
    return Limits(partial(inverse_kinematics, machine), v_lim, a_lim, period, chord_tol, tool_radius, feed, a_max)


@dataclass(frozen=True)
class SegmentCaps:
    """One cutter's caps on the tip speed (mm/ms) along its MoveTable polyline: ``segment`` (n - 1,) on
    each segment (vertex i to i + 1; none on a segment between two moves) from the axis speeds;
    ``vertex`` (n,) at each vertex from the axis accelerations and the chord tolerance, and ``chord``
    (n,) the part of it the chord tolerance sets (to report where the feed was cut for it);
    ``junction`` (n,) the vertices where one move ends and the next begins (a cutter usually passes
    them at rest, and a row's chord reaches across them from where it moves fast again); ``slope``
    (n - 1,) per segment the largest |dq/ds| / a_lim over the axes (ms^2: the axis acceleration a
    change of the tip speed costs, per mm/ms^2)."""

    segment: np.ndarray
    vertex: np.ndarray
    chord: np.ndarray
    junction: np.ndarray
    slope: np.ndarray


def _turn(d0: np.ndarray, d1: np.ndarray) -> np.ndarray:
    """(k,) angle between the directions of consecutive segments d0, d1 (k, 3)."""
    n0, n1 = row_norm(d0), row_norm(d1)
    c = np.einsum("ij,ij->i", d0, d1) / np.maximum(n0 * n1, 1e-300)
    return np.arccos(np.clip(c, -1.0, 1.0))


def chord_length(theta: np.ndarray, h: np.ndarray, tol: float) -> np.ndarray:
    """The longest chord (mm) across a vertex turning by theta (rad) between segments of mean length h
    (mm) that keeps within ``tol`` mm of the path (module docstring)."""
    with np.errstate(divide="ignore"):
        corner = 2.0 * tol / np.sin(np.minimum(theta, np.pi) / 2.0)
        curve = np.sqrt(8.0 * tol * h / theta)
    return np.minimum(corner, curve)


def _chords(theta: np.ndarray, before: np.ndarray, after: np.ndarray, tol: float) -> np.ndarray:
    """chord_length at consecutive vertices turning by theta between segments of lengths before and
    after; where a chord that long would reach the next or the previous vertex too (a zig-zag of a
    mesh's facets), with the two turns added."""
    h = 0.5 * (before + after)
    c = chord_length(theta, h, tol)
    both = theta.copy()
    reach_next = np.zeros(len(theta), bool)
    reach_next[:-1] = after[:-1] < 0.5 * c[:-1]
    reach_prev = np.zeros(len(theta), bool)
    reach_prev[1:] = before[1:] < 0.5 * c[1:]
    both[:-1] = np.where(reach_next[:-1], np.maximum(both[:-1], theta[:-1] + theta[1:]), both[:-1])
    both[1:] = np.where(reach_prev[1:], np.maximum(both[1:], theta[1:] + theta[:-1]), both[1:])
    return np.minimum(c, chord_length(both, h, tol))


def segment_caps(machine: Machine, side: str, table: MoveTable, tool_radius: float, period: float,
                 chord_tol: float, feed: float) -> SegmentCaps:
    """The SegmentCaps of one cutter's moves on the smooth curve its rows are sampled from
    (core.schedule.curve): each segment's cap is the least of the time-optimal profile's bounds
    (core.machine.optimum.path_caps: axis speed, the axes' acceleration on the curve's own curvature,
    the chord tolerance) at PIECES knots along it and its ends; ``vertex`` keeps the junctions' caps
    (module docstring: a cutter passes a junction of two moves at rest or at a hand-over speed, and a
    row's chord reaches across it); ``feed`` mm/ms, the fastest tip speed of the cutting moves."""
    pts, axes = table.points, table.axes
    n = len(pts)
    vertex, chord, junction = np.full(n, np.inf), np.full(n, np.inf), np.zeros(n, bool)
    if n < 2:
        return SegmentCaps(np.full(0, np.inf), vertex, chord, junction, np.zeros(0))
    v_lim, a_lim = axis_limits(machine)
    owner = np.repeat(np.arange(len(table.poly.size)), table.poly.size)
    seg = np.diff(table.poly.x)
    on = (owner[:-1] == owner[1:]) & (seg > 1e-12)
    segment = np.full(n - 1, np.inf)
    slope = np.zeros(n - 1)
    k_on = np.flatnonzero(on)
    if k_on.size:
        # the knots: PIECES per segment of every move, each move's run ending at its last vertex
        frac = np.arange(PIECES) / PIECES
        idx = np.repeat(k_on, PIECES)
        f = np.tile(frac, k_on.size)
        rows = table.segment_coefficients(idx)
        kt, kw = evaluate(rows[:, :12], f), evaluate(rows[:, 12:], f)
        kw /= row_norm(kw)[:, None]
        ks = table.poly.x[idx] + f * seg[idx]
        # runs of knots: each run of consecutive segments of one move, closed by the end vertex
        brk = np.flatnonzero(np.diff(k_on) != 1)
        run_last = np.append(k_on[brk], k_on[-1])          # the last segment of each run
        ends_at = np.append(brk, len(k_on) - 1)             # its position in k_on
        insert = (ends_at + 1) * PIECES                     # where each run's end vertex goes
        kt = np.insert(kt, insert, pts[run_last + 1], axis=0)
        kw = np.insert(kw, insert, axes[run_last + 1], axis=0)
        ks = np.insert(ks, insert, table.poly.x[run_last + 1])
        size = np.diff(np.concatenate([[0], insert + np.arange(1, len(insert) + 1)]))
        lim = machine_limits(machine, period, chord_tol, tool_radius, np.inf, np.inf)  # (no feed: rapid moves)
        caps = path_caps(lim, side, kt, kw, ks, size)
        # each segment: the least bound over its knots and its end vertex (the next segment's first
        # knot, or its run's end vertex)
        knot_seg = np.insert(idx, insert, run_last)
        u = caps.u_cap
        u_next = np.append(u[1:], u[-1])
        u_pair = np.minimum(u, np.where(np.diff(np.append(knot_seg, -1)) == 0, u_next, u))
        least = np.full(n - 1, np.inf)
        np.minimum.at(least, knot_seg, u_pair)
        segment = np.sqrt(least)
        np.maximum.at(slope, knot_seg, (caps.dq / a_lim).max(axis=1))
        c_bound = np.where(caps.why == CHORD, np.sqrt(u), np.inf)
        np.minimum.at(chord, np.minimum(knot_seg + 1, n - 1), c_bound)
    # the junctions of two moves that meet at a vertex where the motion carries on
    k = np.flatnonzero(on)
    if len(k) >= 2:
        a, b = k[:-1], k[1:]
        meet = (row_norm(pts[b] - pts[a + 1]) <= 1e-9) & (owner[b] != owner[a])
        a, b = a[meet], b[meet]
        q0 = inverse_kinematics(machine, side, pts[np.r_[a, a + 1, b, b + 1]], axes[np.r_[a, a + 1, b, b + 1]])
        m = len(a)
        dqa = (q0[m:2 * m] - q0[:m]) / seg[a][:, None]
        dqb = (q0[3 * m:] - q0[2 * m:3 * m]) / seg[b][:, None]
        jump = np.abs(dqb - dqa)
        a_aim = (1.0 - SCALE_SHARE) * AIM * a_lim
        hh = 0.5 * (seg[a] + seg[b])
        with np.errstate(divide="ignore", invalid="ignore"):
            acc = np.minimum(a_aim * period / jump, np.sqrt(a_aim * hh[:, None] / jump)).min(axis=1)
        centres = ball_centres(pts, axes, tool_radius)
        aim = CHORD_AIM * chord_tol
        turn_tips = _turn(pts[a + 1] - pts[a], pts[b + 1] - pts[b])
        turn_centres = _turn(centres[a + 1] - centres[a], centres[b + 1] - centres[b])
        c_len = np.minimum(_chords(turn_tips, seg[a], seg[b], aim), _chords(turn_centres, seg[a], seg[b], aim))
        chord[b] = np.minimum(chord[b], c_len / period)
        vertex[b] = np.minimum(acc, c_len / period)
        junction[b] = True
    segment[~on] = np.inf
    return SegmentCaps(segment, vertex, chord, junction, slope)

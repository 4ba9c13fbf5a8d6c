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
  the tips and the ball centres (tip + r axis) are bounded. Corners between two moves that do not
  cut (in the air) are held to AIR_CHORD_TOL instead.
Each bound is aimed a margin inside its limit (``AIM``); the machine clock (core.machine.timing)
checks the table as written and lowers the speed further where an estimate fell short.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.machine.kinematics import inverse_kinematics
from core.machine.model import AXES, Machine
from core.schedule.movetable import MoveTable
from core.util.polyline import ball_centres
from core.util.rowwise import row_norm

#: speeds and accelerations are aimed this far inside the machine's limits
AIM = 0.97
#: the chord deviation is aimed this far inside the tolerance
CHORD_AIM = 0.8
#: the chord tolerance (mm) at the corners between two moves that do not cut: a turn's lift, traverse
#: and descent and the way home, in the air, where the straight line between two rows may cut a corner
#: by this much (the plan's own tolerance where that is larger); every corner on or next to a cutting
#: move keeps the plan's tolerance
AIR_CHORD_TOL = 0.01

#: share of each axis's acceleration left to the speed changes of the machine clock (the rest bounds
#: the acceleration of the path's own curvature at the scheduled speed)
SCALE_SHARE = 0.2


def axis_limits(machine: Machine) -> tuple[np.ndarray, np.ndarray]:
    """(6,) speed limits mm/ms and (6,) acceleration limits mm/ms^2 of one machine's axes."""
    v = np.array([machine.limits.axis(a).max_speed_mm_s for a in AXES]) / 1000.0
    a = np.array([machine.limits.axis(a).max_accel_mm_s2 for a in AXES]) / 1e6
    return v, a


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


def chord_length(theta: np.ndarray, h: np.ndarray, tol: float | np.ndarray) -> np.ndarray:
    """The longest chord (mm) across a vertex turning by theta (rad) between segments of mean length h
    (mm) that keeps within ``tol`` mm of the path (module docstring)."""
    with np.errstate(divide="ignore"):
        corner = 2.0 * tol / np.sin(np.minimum(theta, np.pi) / 2.0)
        curve = np.sqrt(8.0 * tol * h / theta)
    return np.minimum(corner, curve)


def _chords(theta: np.ndarray, before: np.ndarray, after: np.ndarray, tol: float | np.ndarray) -> np.ndarray:
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
    """The SegmentCaps of one cutter's moves (module docstring); ``feed`` mm/ms, the fastest tip speed
    of the cutting moves."""
    pts, axes = table.points, table.axes
    n = len(pts)
    vertex, chord, junction = np.full(n, np.inf), np.full(n, np.inf), np.zeros(n, bool)
    if n < 2:
        return SegmentCaps(np.full(0, np.inf), vertex, chord, junction, np.zeros(0))
    v_lim, a_lim = axis_limits(machine)
    q = inverse_kinematics(machine, side, pts, axes)
    owner = np.repeat(np.arange(len(table.poly.size)), table.poly.size)
    seg = np.diff(table.poly.x)
    on = (owner[:-1] == owner[1:]) & (seg > 1e-12)
    h = np.where(on, seg, 1.0)
    dqds = np.where(on[:, None], np.diff(q, axis=0) / h[:, None], 0.0)
    with np.errstate(divide="ignore"):
        segment = 1.0 / (np.abs(dqds) / (AIM * v_lim)).max(axis=1)
    slope = (np.abs(dqds) / a_lim).max(axis=1)
    # the vertices between consecutive segments that carry motion (within a move, or across the
    # junction of two moves that meet there): vertex b is where segment a ends and segment b starts
    k = np.flatnonzero(on)
    if len(k) >= 2:
        a, b = k[:-1], k[1:]
        meet = row_norm(pts[b] - pts[a + 1]) <= 1e-9
        a, b = a[meet], b[meet]
        hh = 0.5 * (seg[a] + seg[b])
        jump = np.abs(dqds[b] - dqds[a])
        # a row interval may take in a vertex's neighbour too where the segment between them is shorter
        # than the longest row chord (the jumps add)
        near = (np.minimum(seg[a], seg[b]) < feed * period)[:, None]
        both = jump.copy()
        both[1:] = np.maximum(both[1:], jump[1:] + jump[:-1] * near[1:])
        both[:-1] = np.maximum(both[:-1], jump[:-1] + jump[1:] * near[:-1])
        a_aim = (1.0 - SCALE_SHARE) * AIM * a_lim
        with np.errstate(divide="ignore", invalid="ignore"):
            acc = np.minimum(a_aim * period / both, np.sqrt(a_aim * hh[:, None] / jump)).min(axis=1)
        centres = ball_centres(pts, axes, tool_radius)
        in_air = ~table.cutting[owner[a]] & ~table.cutting[owner[b]]
        aim = CHORD_AIM * np.where(in_air, max(chord_tol, AIR_CHORD_TOL), chord_tol)
        turn_tips = _turn(pts[a + 1] - pts[a], pts[b + 1] - pts[b])
        turn_centres = _turn(centres[a + 1] - centres[a], centres[b + 1] - centres[b])
        c_len = np.minimum(_chords(turn_tips, seg[a], seg[b], aim),
                           _chords(turn_centres, seg[a], seg[b], aim))
        chord[b] = c_len / period
        vertex[b] = np.minimum(acc, chord[b])
        junction[b] = owner[b] != owner[a]
    segment[~on] = np.inf
    return SegmentCaps(segment, vertex, chord, junction, slope)

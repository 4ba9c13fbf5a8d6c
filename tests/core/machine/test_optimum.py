"""core.machine.optimum: the time-optimal traversal of a path under the machine clock's limits, checked on
cases computed by hand (a straight line: a trapezoid or a triangle; a circle under the chord tolerance:
a known speed), against toppra (TOPP-RA, a second implementation of the same problem) on paths of each
kind of the sample blade, and on its own rows sampled at the period (the project's limit check)."""

from __future__ import annotations

import numpy as np
import pytest

from core.machine.caps import AIM, CHORD_AIM, axis_limits
from core.machine.kinematics import inverse_kinematics
from core.machine.model import load_machine
from core.machine.optimum import (
    ENDS,
    Cruise,
    Limits,
    TipAcceleration,
    durations,
    knots,
    limits_of,
    profile,
    segment,
    traverse_time,
)
from core.machine.reach import spindle_direction
from core.machine.tables import AxisTable, axis_motion, check_limits
from core.machine.timing import TIP_AIM
from core.paths.regions import REGION_CODE
from core.schedule.movetable import MAPPED, RAMP
from core.util.polyline import cumulative_length

FEED = 1000.0 / 60000.0
A_MAX = 500.0 / 1e6


@pytest.fixture(scope="module")
def machine():
    return load_machine()


def _limits(machine, chord_tol=0.001, period=12.0):
    return Limits(machine, period, chord_tol, 1.5, FEED, A_MAX)


def _line(machine, side, direction, length, h):
    s = np.linspace(0.0, length, int(round(length / h)) + 1)
    base = np.array([0.0, 0.0, -60.0 if side == "left" else 60.0])
    tips = base + s[:, None] * np.asarray(direction, float)
    return tips, np.tile(spindle_direction(machine, side), (len(s), 1))


def test_a_straight_line_is_a_trapezoid_or_a_triangle(machine):
    """Constant axes, straight tips: q' is constant and q'' zero, so the optimum is the trapezoid at the
    lowest of the feed and each axis's aimed speed over |q'_j|, its ramps at the lowest of the aimed
    a_max and each axis's aimed acceleration over |q'_j|; a line too short to reach it, a triangle."""
    lim = _limits(machine)
    v_lim, a_lim = axis_limits(machine)
    for side, direction, length in (("left", (1, 0, 0), 30.0), ("right", (0.6, 0.8, 0), 20.0),
                                    ("left", (0, 0, 1), 0.05)):
        tips, axes = _line(machine, side, direction, length, 0.2 if length > 1 else 0.001)
        q = inverse_kinematics(machine, side, tips, axes)
        dq = np.abs(q[-1] - q[0]) / length
        v = min(FEED, *(AIM * v_lim[dq > 0] / dq[dq > 0]))
        a = min(TIP_AIM * A_MAX, *(AIM * a_lim[dq > 0] / dq[dq > 0]))
        expected = length / v + v / a if length >= v * v / a else 2.0 * np.sqrt(length / a)
        assert traverse_time(lim, side, tips, axes) == pytest.approx(expected, rel=1e-4), (side, direction)
    # entered and left at the feed: the line at the feed throughout
    tips, axes = _line(machine, "left", (1, 0, 0), 30.0, 0.2)
    assert traverse_time(lim, "left", tips, axes, FEED, FEED) == pytest.approx(30.0 / FEED, rel=1e-9)


def test_a_circle_runs_at_the_chord_tolerance_speed(machine):
    """A circle of radius R at constant axes: the chord across v period strays (v period)^2 / (8 R), so
    within CHORD_AIM of the tolerance v = sqrt(8 CHORD_AIM tol R) / period (below the feed and the axes'
    limits here), reached and left at the aimed a_max."""
    period, tol = 12.0, 0.001
    lim = _limits(machine, tol, period)
    phi = np.linspace(0.0, 2 * np.pi, 2001)
    for radius in (0.5, 1.0, 2.0):
        tips = np.c_[radius * np.cos(phi), radius * np.sin(phi), np.full_like(phi, -60.0)]
        axes = np.tile(spindle_direction(machine, "left"), (len(phi), 1))
        k = knots(tips, axes, cumulative_length(tips), np.array([len(tips)]))
        v = profile(segment(machine, "left", k), limits_of(lim, FEED)).v
        expected = np.sqrt(8 * CHORD_AIM * tol * radius) / period
        assert expected < FEED
        middle = slice(len(v) // 4, 3 * len(v) // 4)
        np.testing.assert_allclose(v[middle], expected, rtol=1e-3)
        a = TIP_AIM * A_MAX
        assert durations(k.s, v).sum() == pytest.approx(2 * np.pi * radius / expected + expected / a, rel=1e-3)


def test_runs_laid_end_to_end_time_as_each_alone(machine):
    lim = _limits(machine)
    parts = [_line(machine, "left", (1, 0, 0), 10.0, 0.2), _line(machine, "left", (0, 1, 0), 4.0, 0.1)]
    phi = np.linspace(0.0, np.pi, 300)
    parts.append((np.c_[np.cos(phi), np.sin(phi), np.full_like(phi, -60.0)],
                  np.tile(spindle_direction(machine, "left"), (300, 1))))
    alone = [traverse_time(lim, "left", t, a, 0.0, FEED / 2) for t, a in parts]
    k = knots(np.vstack([t for t, _ in parts]), np.vstack([a for _, a in parts]),
              np.concatenate([cumulative_length(t) for t, _ in parts]), np.array([len(t) for t, _ in parts]))
    got = profile(segment(machine, "left", k), limits_of(lim, FEED), 0.0, FEED / 2).run_times()
    np.testing.assert_allclose(got, alone, rtol=1e-9)


def test_a_line_under_two_constraints_is_the_trapezoid_and_says_why(machine):
    """A straight line under a cruise speed and a tip acceleration alone: the speed is exactly
    min(sqrt(2 a s), v, sqrt(2 a (L - s))) at every knot, and each knot names what binds it: the
    ends the entry and exit speeds, the ramps the tip's acceleration, the middle the cruise."""
    v, a, length = FEED, A_MAX / 50, 30.0  # (ramps of 13.9 mm)
    tips, axes = _line(machine, "left", (1, 0, 0), length, 0.2)
    k = knots(tips, axes, cumulative_length(tips), np.array([len(tips)]))
    prof = profile(segment(machine, "left", k), [Cruise(v), TipAcceleration(a)])
    expected = np.minimum(np.minimum(np.sqrt(2 * a * k.s), v), np.sqrt(np.maximum(2 * a * (length - k.s), 0)))
    np.testing.assert_allclose(prof.v, expected, rtol=1e-9, atol=1e-12)
    why = prof.slowed_for()
    assert why[0] == why[-1] == ENDS
    ramp = v * v / (2 * a)
    inside = (k.s > 1e-9) & (k.s < length - 1e-9)
    assert set(why[inside & (np.abs(k.s - ramp) > 0.3) & (np.abs(length - k.s - ramp) > 0.3)
                   & ((k.s < ramp) | (k.s > length - ramp))]) == {"tip acceleration"}
    assert set(why[(k.s > ramp + 0.3) & (k.s < length - ramp - 0.3)]) == {"cruise"}
    # (the interval where a ramp meets the cruise speed has u linear across the kink: 1e-7 slower)
    assert prof.run_times()[0] == pytest.approx(length / v + v / a, rel=1e-6)


def test_every_knot_is_held_by_the_constraint_it_names(machine, stretches):
    """On the sample's paths under every limit, no constraint is broken at any knot (each interval's
    constant acceleration keeps every row at both its knots: exact on the knots), and each knot's
    reason binds there: a speed cap (cruise, axis speed, chord) names the constraint whose cap the
    speed equals; an acceleration names one whose row an interval next to the knot meets (or whose
    own cap the speed equals)."""
    from core.machine.optimum import _stacked

    lim = _limits(machine)
    for kind, side, tips, axes in stretches:
        seg = segment(machine, side, knots(tips, axes, cumulative_length(tips), np.array([len(tips)])))
        cons = limits_of(lim, FEED)
        prof = profile(seg, cons)
        u, why = prof.v ** 2, prof.slowed_for()
        u_cap = _stacked(seg, cons)[0]
        assert (u <= u_cap * (1 + 1e-9) + 1e-15).all(), kind
        a = np.diff(u) / (2 * np.diff(prof.s))  # (each interval's constant acceleration)
        tight = np.zeros(len(u), bool)
        for c in cons:
            cap, rows = c.caps(seg), c.rows(seg)
            at = why == c.name
            if cap is not None:
                tight[at] |= np.isclose(u[at], np.minimum(np.broadcast_to(cap, u.shape), u_cap)[at], rtol=1e-9)
            if rows is None:
                continue
            r, w = rows
            for end in (slice(None, -1), slice(1, None)):  # (both knots of each interval keep the rows)
                load = np.abs(a[:, None] + r[end] * u[end, None]) / w[end]
                assert (load <= 1 + 1e-9).all(), (kind, c.name, load.max())
                full = (load >= 1 - 1e-6).any(axis=1)
                tight[:-1] |= at[:-1] & full
                tight[1:] |= at[1:] & full
            tight[at] |= np.isclose(u[at], u_cap[at], rtol=1e-9)
        assert tight[(why != ENDS)].all(), (kind, np.unique(why[~tight]))


@pytest.fixture(scope="module")
def stretches(coarse_result):
    """(kind, side, tips, axes) of the sample's cutting moves of each kind, at the executed tool axes (a
    coarse machine-timed plan's move tables): a single-sided tip path (step 1), a symmetric internal
    stretch (both cutters on one master law) and a staggered edge stretch (steps 5-6)."""
    res = coarse_result  # (the sample's coarse plan in memory, once per session)
    out = []
    for side in ("left", "right"):
        tab = res.schedule.table(side)
        long = np.array([m.cum[-1] for m in tab.moves]) > 2.0
        first = tab.regions[tab.poly.off]
        for kind, sel in (("tip", tab.cutting & (tab.step <= 2) & (first == REGION_CODE["tip"])),
                          ("symmetric", tab.cutting & (tab.kind == MAPPED)),
                          ("staggered", tab.cutting & (tab.kind == RAMP) & np.isin(tab.step, (5, 6))
                           & (first == REGION_CODE["edge"]))):
            idx = np.flatnonzero(sel & long)
            assert idx.size, (side, kind)
            for j in idx[[0, len(idx) // 2]]:
                m = tab.moves[j]
                out.append((kind, side, m.points, m.axes))
    return out


def _toppra_time(machine, side, tips, axes):
    """The same problem for toppra: the six axes and the arc length as seven joints of a cubic spline
    path through the vertices, with the aimed speed and acceleration limits as its constraints."""
    toppra = pytest.importorskip("toppra")
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    v_lim, a_lim = axis_limits(machine)
    s = cumulative_length(tips)
    keep = np.concatenate([[True], np.diff(s) > 1e-9])
    q = inverse_kinematics(machine, side, tips, axes)
    path = toppra.SplineInterpolator(s[keep], np.column_stack([q, s])[keep])
    vmax = np.append(AIM * v_lim, FEED)
    amax = np.append(AIM * a_lim, TIP_AIM * A_MAX)
    grid = np.linspace(0.0, s[-1], min(4000, 8 * len(s)))
    inst = algo.TOPPRA([constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
                        constraint.JointAccelerationConstraint(np.c_[-amax, amax])], path, gridpoints=grid,
                       parametrizer="ParametrizeConstAccel")
    traj = inst.compute_trajectory(0.0, 0.0)
    assert traj is not None
    return float(traj.duration)


#: how far the optimum may lie from toppra's on the sample's paths (see the test)
TOPPRA_AGREEMENT = 0.03


def test_agrees_with_toppra_on_each_kind_of_path(machine, stretches):
    """With a loose chord tolerance (toppra has no chord bound), the same limits give toppra's time
    within TOPPRA_AGREEMENT (0.1-0.4 % on these paths). The two differ by construction: toppra
    interpolates a cubic spline of q through the vertices, ours the inverse kinematics of the tips'
    and axes' spline, and each bounds the accelerations on its own grid."""
    lim = _limits(machine, chord_tol=10.0)
    for kind, side, tips, axes in stretches:
        ours = traverse_time(lim, side, tips, axes)
        theirs = _toppra_time(machine, side, tips, axes)
        assert abs(ours / theirs - 1.0) <= TOPPRA_AGREEMENT, (kind, side, ours, theirs)


def _on_profile(k, v, t):
    """(s, v) at times t (ms) of the profile v at knots k (u linear in s between knots)."""
    tk = np.concatenate([[0.0], np.cumsum(durations(k.s, v))])
    j = np.clip(np.searchsorted(tk, t, side="right") - 1, 0, len(tk) - 2)
    tau = t - tk[j]
    acc = (v[j + 1] ** 2 - v[j] ** 2) / (2.0 * (k.s[j + 1] - k.s[j]))
    return np.minimum(k.s[j] + v[j] * tau + 0.5 * acc * tau * tau, k.s[-1]), v[j] + acc * tau


def _rows(lim, side, tips, axes):
    """The optimum profile as a controller runs it: rows every period (t, s, v on the profile), the
    tips and axes there on the spline (knots 16 to a segment, linear between them), the axes' values
    and velocities (the tables' own axis_motion), and each row interval's largest distance of the
    spline's tips and ball centres (at 8 instants inside it) from the straight line between its rows."""
    size = np.array([len(tips)])
    cum = cumulative_length(tips)
    k = knots(tips, axes, cum, size)
    v = profile(segment(lim.machine, side, k), limits_of(lim, lim.feed)).v
    t = np.arange(0.0, durations(k.s, v).sum(), lim.period)
    fine = knots(tips, axes, cum, size, pieces=16)

    def pose(s):
        at = [np.column_stack([np.interp(s, fine.s, c) for c in a.T])
              for a in (fine.tips, fine.axes, fine.d_tips, fine.d_axes)]
        at[1] /= np.linalg.norm(at[1], axis=1)[:, None]
        return at

    s, speed = _on_profile(k, v, t)
    at = pose(s)
    values, vel = axis_motion(lim.machine, side, at[0], at[1], at[2] * speed[:, None], at[3] * speed[:, None])
    stray = np.zeros(len(t) - 1)
    for pts in (at[0], at[0] + lim.tool_radius * at[1]):
        a, b = pts[:-1], pts[1:]
        e = b - a
        for f in np.arange(1, 9) / 9:
            mid = pose(_on_profile(k, v, t[:-1] + f * lim.period)[0])
            p = mid[0] + (lim.tool_radius * mid[1] if pts is not at[0] else 0.0)
            x = np.clip(np.einsum("ij,ij->i", p - a, e) / np.maximum(np.einsum("ij,ij->i", e, e), 1e-300), 0, 1)
            stray = np.maximum(stray, np.linalg.norm(a + x[:, None] * e - p, axis=1))
    return t, speed, AxisTable(side, t, values, vel), stray


def test_its_rows_keep_the_limits(machine, stretches):
    """The profile sampled every period keeps every axis's speed and acceleration limit as the plan's
    own check finds them (core.machine.tables.check_limits on the rows), the tips keep the feed and
    a_max along the path, and the straight lines between rows keep the chord tolerance."""
    lim = _limits(machine)
    for kind, side, tips, axes in stretches:
        t, speed, table, stray = _rows(lim, side, tips, axes)
        found = [f for f in check_limits(machine, table) if f.kind != "stroke"]
        assert not found, (kind, side, [str(f) for f in found])
        assert speed.max() <= FEED * (1 + 1e-9)
        assert (np.abs(np.diff(speed)) / lim.period).max() <= A_MAX
        assert stray.max() <= lim.chord_tol, (kind, side, stray.max())

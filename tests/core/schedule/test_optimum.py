"""core.schedule.optimum: the time-optimal traversal of a path under the machine's limits, checked on
cases computed by hand (a straight line: a trapezoid; a circle under the chord tolerance: a known
speed), against toppra (TOPP-RA, a second implementation of the same problem) on paths of each kind
of the sample blade, and on its own rows (axis speed and acceleration as a controller runs them)."""

from __future__ import annotations

import numpy as np
import pytest

from core.blade.source import load_blade
from core.machine.caps import axis_limits, machine_limits
from core.machine.kinematics import inverse_kinematics
from core.machine.model import load_machine
from core.machine.reach import machine_plan, spindle_direction
from core.paths.planning import plan_paths
from core.records import PlanParameters
from core.schedule.motion import MoveTag, ProfileLaw, make_move
from core.schedule.movetable import MoveTable
from core.schedule.optimum import (
    AIM,
    CHORD_AIM,
    SPEED_CHANGE_AIM,
    durations,
    fastest,
    knots,
    path_caps,
    traverse_time,
)
from core.util.polyline import cumulative_length as polyline_cum

FEED = 1000.0 / 60000.0
A_MAX = 500.0 / 1e6


@pytest.fixture(scope="module")
def machine():
    return load_machine()


def _limits(machine, chord_tol=0.001, period=12.0):
    return machine_limits(machine, period, chord_tol, 1.5, FEED, A_MAX)


def _line(machine, side, direction, length, h=0.2):
    n = int(round(length / h)) + 1
    s = np.linspace(0.0, length, n)
    spindle = spindle_direction(machine, side)
    base = np.array([0.0, 0.0, -60.0 if side == "left" else 60.0])
    tips = base + s[:, None] * np.asarray(direction, float)
    return tips, np.tile(spindle, (n, 1)), s


def test_a_straight_line_is_a_trapezoid(machine):
    """Constant axes, straight tips: q' is constant and q'' zero, so the optimum is the trapezoid at
    the lowest of the feed and each axis's speed over |q'_j|, ramps at the lowest of a_max and each
    axis's acceleration over |q'_j| (all aimed AIM inside)."""
    lim = _limits(machine)
    v_lim, a_lim = axis_limits(machine)
    for side, direction, length in (("left", (1, 0, 0), 30.0), ("right", (0.6, 0.8, 0), 20.0),
                                    ("left", (0, 0, 1), 0.05)):
        tips, axes, s = _line(machine, side, direction, length, h=0.2 if length > 1 else 0.001)
        q = inverse_kinematics(machine, side, tips, axes)
        dq = np.abs(q[-1] - q[0]) / length
        v = min(FEED, *(AIM * v_lim[dq > 0] / dq[dq > 0]))
        a = min(SPEED_CHANGE_AIM * A_MAX, *(SPEED_CHANGE_AIM * a_lim[dq > 0] / dq[dq > 0]))
        if length >= v * v / a:
            expected = length / v + v / a
        else:  # a triangle
            expected = 2.0 * np.sqrt(length / a)
        got = traverse_time(lim, side, tips, axes, s)
        assert got == pytest.approx(expected, rel=2e-3), (side, direction)


def test_a_circle_runs_at_the_chord_tolerance_speed(machine):
    """A circle of radius R at constant axes: the chord across v period strays (v period)^2 / (8 R), so
    within CHORD_AIM of the tolerance v = sqrt(8 CHORD_AIM tol R) / period (here below the feed and far
    below the axes' limits), reached and left at a_max."""
    period, tol = 12.0, 0.001
    lim = _limits(machine, tol, period)
    for radius in (0.5, 1.0, 2.0):
        phi = np.linspace(0.0, 2 * np.pi, 2001)
        side = "left"
        tips = np.c_[radius * np.cos(phi), radius * np.sin(phi), np.full_like(phi, -60.0)]
        axes = np.tile(spindle_direction(machine, side), (len(phi), 1))
        s = polyline_cum(tips)
        caps = path_caps(lim, side, tips, axes, s)
        v = fastest(caps)
        expected = np.sqrt(8 * CHORD_AIM * tol * radius) / period
        assert expected < FEED
        middle = slice(len(v) // 4, 3 * len(v) // 4)
        np.testing.assert_allclose(v[middle], expected, rtol=2e-3)
        a = SPEED_CHANGE_AIM * A_MAX
        t = durations(s, v).sum()
        assert t == pytest.approx(s[-1] / expected + expected / a, rel=3e-3)


@pytest.fixture(scope="module")
def sample_paths(machine):
    plan = plan_paths(load_blade("sample"), PlanParameters(dr=4.0, h_safe=1.5))
    return machine_plan(plan, machine)[0]


def _stretches(plan):
    """(name, side, tips, axes) of a single-sided tip path, a symmetric (internal) stretch and a
    staggered (edge and variable) stretch of the sample."""
    tip = next(p for p, r in zip(plan.pairs, plan.regions, strict=True) if r.is_tip)
    k, (pair, reg) = next((k, pr) for k, pr in enumerate(zip(plan.pairs, plan.regions, strict=True))
                          if not pr[1].is_tip)
    bd = reg.boundaries
    e_vl, s_vs = bd["E_vl"], bd["S_vs"]
    mid = (e_vl + s_vs) // 2
    return [("tip", "left", tip.left_tip, tip.left_axis),
            ("symmetric", "right", pair.right_tip[mid - 150:mid + 150], pair.right_axis[mid - 150:mid + 150]),
            ("staggered", "left", pair.left_tip[:e_vl + 1], pair.left_axis[:e_vl + 1])]


def _toppra_time(machine, side, tips, axes, s):
    """The same problem for toppra: the six axes and the arc length as seven joints of a spline path
    through the vertices, with the speed and acceleration limits (aimed AIM inside) as its constraints."""
    toppra = pytest.importorskip("toppra")
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    v_lim, a_lim = axis_limits(machine)
    q = inverse_kinematics(machine, side, tips, axes)
    keep = np.concatenate([[True], np.diff(s) > 1e-9])
    path = toppra.SplineInterpolator(s[keep], np.column_stack([q, s])[keep])
    vmax = np.append(AIM * v_lim, FEED)
    amax = np.append(SPEED_CHANGE_AIM * a_lim, SPEED_CHANGE_AIM * A_MAX)
    grid = np.linspace(0.0, s[-1], min(4000, 4 * len(s)))
    inst = algo.TOPPRA([constraint.JointVelocityConstraint(np.c_[-vmax, vmax]),
                        constraint.JointAccelerationConstraint(np.c_[-amax, amax])], path, gridpoints=grid)
    traj = inst.compute_trajectory(0.0, 0.0)
    assert traj is not None
    return float(traj.duration)


def test_agrees_with_toppra_on_each_kind_of_path(machine, sample_paths):
    """Without the chord tolerance (a loose one), the same limits give toppra's time within several per
    cent: ours keeps CURVE_SHARE of each axis's acceleration from the curvature bound (slower where
    it binds), and toppra interpolates a different curve: a cubic spline of q through the vertices
    rather than the inverse kinematics of the tips' and axes' curve. Round a tip path's ends, where
    |dq/ds| halves within 0.05 mm, the two curves' derivatives differ most (ours 6 % faster there)."""
    lim = _limits(machine, chord_tol=10.0)
    for name, side, tips, axes in _stretches(sample_paths):
        s = polyline_cum(tips)
        ours = traverse_time(lim, side, tips, axes, s)
        theirs = _toppra_time(machine, side, tips, axes, s)
        assert 0.92 * theirs <= ours <= 1.08 * theirs, (name, ours, theirs)


def test_its_rows_keep_the_limits(machine, sample_paths):
    """The profile as a move, sampled every period from the smooth curve as the tables are: the axes'
    speed and their mean acceleration between rows within the limits (and the tips' speed within the
    feed, their acceleration along the path within a_max)."""
    lim = _limits(machine)
    v_lim, a_lim = axis_limits(machine)
    for _, side, tips, axes in _stretches(sample_paths):
        s, kt, ka = knots(tips, axes, polyline_cum(tips))
        v = fastest(path_caps(lim, side, kt, ka, s))
        law = ProfileLaw(s, v)
        s = polyline_cum(tips)
        tab = MoveTable([make_move(0.0, law, tips, axes, MoveTag(1, 0, True, "tip"))])
        t = np.arange(0.0, law.duration, lim.period)
        h = 1e-3
        q = [inverse_kinematics(machine, side, smp.tips, smp.axes) for smp in (tab.sample(t - h),
                                                                               tab.sample(t + h))]
        vel = (q[1] - q[0]) / (2 * h)
        # (within the first and last 0.3 mm of a tip path the heads swing by up to 150 mm per mm of
        # tip, and |dq/ds| changes by half between knots 0.05 mm apart: there the rows exceed the
        # limits by up to 30 %, and the machine clock's check of the rows as written lowers the
        # speed over them, core.machine.timing)
        at = law.distance(t)
        inner = (at > 0.3) & (at < s[-1] - 0.3)
        assert (np.abs(vel[inner]) <= v_lim * 1.001).all()
        acc = np.abs(np.diff(vel, axis=0)) / lim.period
        assert (acc[inner[1:] & inner[:-1]] <= a_lim * 1.001).all(), (acc / a_lim).max()
        speed = tab.speeds(t)
        assert speed.max() <= FEED * (1 + 1e-9)
        assert (np.abs(np.diff(speed)) / lim.period).max() <= A_MAX * (1 + 1e-9)

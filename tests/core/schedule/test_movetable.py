"""core.schedule.movetable evaluates every move of a cutter at once. Its closed forms are checked here against
the laws' own methods (the reference definitions, themselves checked against numerical integration in
test_sigmoid / test_speed_profiles), its positions against a plain loop over the moves, and its
vertex instants against the laws and the polylines; a schedule carries its two tables, built with it."""

from __future__ import annotations

import numpy as np
import pytest

from core.paths.regions import REGION_NAMES_ARRAY
from core.schedule.motion import MoveTag, make_move, ramp_law
from core.schedule.movetable import (
    MAPPED,
    OTHER,
    PLATEAU_LOGISTIC,
    PLATEAU_SEPTIC,
    RAMP,
    SIGMOID,
    WAIT,
    MoveTable,
    build_tables,
)
from core.schedule.sigmoid import SigmoidStage
from core.schedule.steps import build_schedule


@pytest.fixture(scope="module")
def paths(sample_paths):
    return sample_paths(dr=4.0, h_safe=1.5)


@pytest.fixture(scope="module", params=[("collaborative", "sigmoid"), ("collaborative", "smooth"),
                                        ("symmetric", "sigmoid"), ("single", "sigmoid")])
def schedule(request, paths):
    mode, profile = request.param
    return build_schedule(paths, mode, profile=profile)


def _reference_sample(moves, t):
    """Positions by a plain loop over the samples' moves, with each law's own distance method."""
    starts = np.array([m.t0 for m in moves])
    owner = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(moves) - 1)
    tips, axes = np.empty((len(t), 3)), np.empty((len(t), 3))
    region = np.empty(len(t), np.int64)
    for j in np.unique(owner):
        m, idx = moves[j], np.flatnonzero(owner == j)
        if len(m.points) == 1:
            tips[idx], axes[idx], region[idx] = m.points[0], m.axes[0], m.regions[0]
            continue
        s = np.clip(m.law.distance(np.clip(t[idx] - m.t0, 0, m.law.duration)), 0.0, m.cum[-1])
        for i, si in zip(idx, s, strict=True):
            k = min(max(int(np.searchsorted(m.cum, si, side="right")) - 1, 0), len(m.cum) - 2)
            seg = m.cum[k + 1] - m.cum[k]
            f = (si - m.cum[k]) / seg if seg > 0 else 0.0
            tips[i] = m.points[k] + f * (m.points[k + 1] - m.points[k])
            w = m.axes[k] + f * (m.axes[k + 1] - m.axes[k])
            axes[i] = w / np.linalg.norm(w)
            region[i] = m.regions[k + 1 if f > 0.5 else k]
    return tips, axes, REGION_NAMES_ARRAY[region]


def test_laws_match_their_own_methods(schedule):
    rng = np.random.default_rng(1)
    kinds = set()
    for moves in (schedule.left, schedule.right):
        tab = MoveTable(moves)
        kinds |= set(tab.kind.tolist())
        assert OTHER not in tab.kind
        j = np.repeat(np.arange(len(moves)), 12)
        frac = np.tile(np.r_[0.0, 1.0, rng.uniform(0, 1, 10)], len(moves))
        tau = frac * tab.dur[j]
        d_ref = np.array([moves[jj].law.distance(np.array([x]))[0] for jj, x in zip(j, tau, strict=True)])
        v_ref = np.array([moves[jj].law.speed(np.array([x]))[0] for jj, x in zip(j, tau, strict=True)])
        np.testing.assert_allclose(tab.distance(j, tau), d_ref, rtol=0, atol=1e-11)
        np.testing.assert_allclose(tab.speed(j, tau), v_ref, rtol=0, atol=1e-14)
    assert {WAIT, RAMP} <= kinds
    if schedule.mode != "single":  # single-sided machining is ramps and waits only
        assert kinds & {PLATEAU_LOGISTIC, PLATEAU_SEPTIC, MAPPED}


def test_sigmoid_and_foreign_laws():
    """The paper's own stage (rare in real plans: the plateau variant usually wins) and a law of a type
    the table does not know (evaluated through its own methods)."""

    class Cubic:  # s = L (tau/T)^2 (3 - 2 tau/T)
        duration, length = 40.0, 2.0

        def distance(self, tau):
            x = np.clip(np.asarray(tau) / self.duration, 0, 1)
            return self.length * x * x * (3 - 2 * x)

        def speed(self, tau):
            x = np.clip(np.asarray(tau) / self.duration, 0, 1)
            return self.length * 6 * x * (1 - x) / self.duration

    pts = np.c_[np.linspace(0, 3, 7), np.zeros(7), np.zeros(7)]
    ax = np.tile([0.0, 0.0, 1.0], (7, 1))
    st = SigmoidStage.from_length(3.0, 0.02, 200.0)
    moves = [make_move(0.0, st, pts, ax, MoveTag(5, 1, True, "variable"))]
    cub = Cubic()
    pts2 = np.c_[3 + np.linspace(0, 2, 5), np.zeros(5), np.zeros(5)]
    moves.append(make_move(moves[0].t1, cub, pts2, ax[:5], MoveTag(5, 1, True, "edge")))
    tab = MoveTable(moves)
    assert tab.kind.tolist() == [SIGMOID, OTHER]
    for j, m in enumerate(moves):
        tau = np.linspace(0, m.law.duration, 101)
        np.testing.assert_allclose(tab.distance(np.full(101, j), tau), m.law.distance(tau), atol=1e-13)
        np.testing.assert_allclose(tab.speed(np.full(101, j), tau), m.law.speed(tau), atol=1e-15)
    t = np.linspace(0, moves[-1].t1, 777)
    tips, axes, region = _reference_sample(moves, t)
    got = tab.sample(t)
    np.testing.assert_allclose(got.tips, tips, atol=1e-12)
    np.testing.assert_array_equal(got.region, region)


def test_positions_match_a_loop_over_moves(schedule):
    rng = np.random.default_rng(2)
    for side in ("left", "right"):
        moves = getattr(schedule, side)
        t = np.sort(np.concatenate([rng.uniform(0, schedule.duration, 4000), [m.t0 for m in moves[::7]],
                                    [0.0, schedule.duration]]))
        tips, axes, region = _reference_sample(moves, t)
        got = schedule.table(side).sample(t)
        np.testing.assert_allclose(got.tips, tips, rtol=0, atol=1e-11)
        np.testing.assert_allclose(got.axes, axes, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(got.region, region)
        starts = np.array([m.t0 for m in moves])
        own = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(moves) - 1)
        np.testing.assert_array_equal(got.step, [moves[k].step for k in own])
        np.testing.assert_array_equal(got.path, [moves[k].path for k in own])
        np.testing.assert_array_equal(got.cutting, [moves[k].cutting for k in own])


def test_segment_at_is_the_segment_each_instant_lies_on(schedule):
    """segment_at(t): the polyline segment (global vertex index) of the move each instant belongs to
    whose two vertices' distances bracket the move's distance law at that instant; nondecreasing in
    t; a move standing at one point gives its vertex."""
    rng = np.random.default_rng(5)
    t = np.sort(np.concatenate([rng.uniform(0, schedule.duration, 5000), [0.0, schedule.duration]]))
    for side in ("left", "right"):
        moves, tab = getattr(schedule, side), schedule.table(side)
        seg = tab.segment_at(t)
        assert (np.diff(seg) >= 0).all()
        starts = np.array([m.t0 for m in moves])
        own = np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(moves) - 1)
        offsets = np.concatenate([[0], np.cumsum([len(m.points) for m in moves])])
        for x, i, j in zip(t, seg, own, strict=True):
            m = moves[j]
            if len(m.points) == 1:
                assert i == min(offsets[j], len(tab.points) - 2)
                continue
            k = i - offsets[j]
            assert 0 <= k < len(m.points) - 1
            d = float(np.clip(m.law.distance(np.array([x - m.t0]))[0], 0.0, m.cum[-1]))
            assert m.cum[k] - 1e-9 <= d <= m.cum[k + 1] + 1e-9


def test_schedule_carries_its_tables_built_with_it(schedule):
    """The schedule's MoveTables are built once, with it: schedule.table(side) is the same object on
    every call (its left_table / right_table), and samples (positions and speeds) exactly what a
    MoveTable built afresh on that side's moves samples, as build_tables' do."""
    rng = np.random.default_rng(3)
    t = np.sort(np.concatenate([rng.uniform(0, schedule.duration, 3000), [0.0, schedule.duration]]))
    fresh = build_tables(schedule.left, schedule.right)
    for k, side in enumerate(("left", "right")):
        tab = schedule.table(side)
        assert schedule.table(side) is tab and tab is getattr(schedule, f"{side}_table")
        moves = getattr(schedule, side)
        assert len(tab.t0) == len(moves)
        for own in (MoveTable(moves), fresh[k]):
            got, want = tab.sample(t), own.sample(t)
            for name in ("tips", "axes", "step", "path", "cutting", "code"):
                np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=(side, name))
            np.testing.assert_array_equal(tab.speeds(t), own.speeds(t))
    assert schedule.table("left") is not schedule.table("right")
    # the schedule's own sampling reads its tables
    left, right = schedule.sample(t)
    np.testing.assert_array_equal(left.tips, schedule.table("left").sample(t).tips)
    np.testing.assert_array_equal(right.axes, schedule.table("right").sample(t).axes)
    np.testing.assert_array_equal(schedule.speeds("right", t), schedule.table("right").speeds(t))


def test_a_table_is_of_the_moves_it_was_built_on():
    """A MoveTable is a snapshot of the list it was built on: a table built after the list grew has
    the new move too (the one built before keeps the arrays of the moves it saw)."""
    pts = np.array([[0.0, 0, 0], [1.0, 0, 0]])
    ax = np.array([[0.0, 0, 1], [0.0, 0, 1]])
    moves = [make_move(0.0, ramp_law(1.0, 0.01, 1e-4), pts, ax, MoveTag(1, 0, True, "internal"))]
    a = MoveTable(moves)
    moves.append(make_move(moves[0].t1, ramp_law(1.0, 0.01, 1e-4), pts[::-1], ax, MoveTag(1, 0, True, "internal")))
    b = MoveTable(moves)
    assert len(a.t0) == 1 and len(b.t0) == 2
    np.testing.assert_allclose(b.sample(np.array([moves[1].t1])).tips, [[0.0, 0, 0]], atol=1e-12)

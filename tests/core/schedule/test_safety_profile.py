"""A time column's safety figures (core.schedule.timeline.SafetyProfile, computed once by the planner and
shared by core's figures and the workbench's views) are core.schedule.safety's own: the same spacing and
clearance arrays, and the rows breaking the one safety rule; a Timeline itself keeps no figures."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from core.schedule.motion import Samples
from core.schedule.safety import capsule_clearance, tip_spacing, unsafe_samples, violations
from core.schedule.timeline import SafetyProfile, Timeline
from core.util.parallel import MIN_PARALLEL_ROWS


def _samples(rng, n):
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    return Samples(rng.normal(size=(n, 3)) * 10, axes, np.ones(n, np.int64), np.zeros(n, np.int64),
                   np.ones(n, bool), np.zeros(n, np.int8))


@pytest.mark.parametrize("n", [5000, MIN_PARALLEL_ROWS + 1])  # (the two figures in one thread, and in two)
def test_profile_is_core_safety(n):
    rng = np.random.default_rng(3)
    tl = Timeline(np.arange(n, dtype=float), _samples(rng, n), _samples(rng, n))
    h_safe = 12.0  # (about the median tip spacing of the random tips: some rows break the rule, some not)
    prof = SafetyProfile.of(tl, 1.5, 40.0, h_safe)
    at, between = tip_spacing(tl.left.tips, tl.right.tips)
    clear = capsule_clearance(tl.left.tips, tl.left.axes, tl.right.tips, tl.right.axes, 1.5, 40.0)
    np.testing.assert_array_equal(prof.at, at)
    np.testing.assert_array_equal(prof.between, between)
    np.testing.assert_array_equal(prof.clearance, clear)
    np.testing.assert_array_equal(prof.unsafe, unsafe_samples(at, between, clear, h_safe))
    assert 0 < prof.unsafe.sum() < n
    # the rule row by row: a row is unsafe where its spacing or clearance breaks it, or an interval next
    # to it does
    bad_at, bad_between, bad_clear = violations(at, between, clear, h_safe)
    for i in np.random.default_rng(5).choice(n, 300, replace=False):
        near = bool(i > 0 and bad_between[i - 1]) or bool(i < n - 1 and bad_between[i])
        assert prof.unsafe[i] == (bool(bad_at[i] or bad_clear[i]) or near)
    # another tool: its own clearance; another h_safe: its own rows
    other = SafetyProfile.of(tl, 2.0, 40.0, h_safe)
    assert not np.array_equal(other.clearance, prof.clearance)
    np.testing.assert_array_equal(other.at, prof.at)
    looser = SafetyProfile.of(tl, 1.5, 40.0, 0.5 * h_safe)
    assert looser.unsafe.sum() < prof.unsafe.sum() and not (looser.unsafe & ~prof.unsafe).any()


def test_timeline_keeps_no_figures():
    """The column is its times and both cutters' samples, nothing computed on the side."""
    assert [f.name for f in dataclasses.fields(Timeline)] == ["t", "left", "right"]
    rng = np.random.default_rng(4)
    tl = Timeline(np.arange(10, dtype=float), _samples(rng, 10), _samples(rng, 10))
    with pytest.raises(dataclasses.FrozenInstanceError):
        tl.t = np.zeros(10)
    assert vars(tl).keys() == {"t", "left", "right"}

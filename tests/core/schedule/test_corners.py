"""Tight corners of a contact path (core.schedule.motion.tight_corners) and the stops the schedule makes there."""

import numpy as np

from core.schedule.motion import CORNER_SEGMENT, CORNER_TURN_DEG, tight_corners


def _path(turns_deg, lengths):
    """A planar polyline from the origin: segment k has length lengths[k] and turns by turns_deg[k-1]
    (degrees, left) from segment k - 1."""
    heading, pts = 0.0, [np.zeros(3)]
    for k, length in enumerate(lengths):
        if k:
            heading += np.radians(turns_deg[k - 1])
        pts.append(pts[-1] + length * np.array([np.cos(heading), np.sin(heading), 0.0]))
    return np.array(pts)


def test_only_sharp_turns_next_to_short_segments_are_tight():
    long, short = 0.2, 0.5 * CORNER_SEGMENT
    big, small = 3 * CORNER_TURN_DEG, 0.5 * CORNER_TURN_DEG
    #   vertex:       1      2      3      4      5      6
    turns = [big, small, big, big, 170.0, big]
    lengths = [long, long, short, long, short, short, long]
    # 1: sharp but both segments long; 2: short segment after but a small turn; 3: sharp, short after;
    # 4: sharp, short before; 5: a reversal between two short segments; 6: sharp, short before
    np.testing.assert_array_equal(tight_corners(_path(turns, lengths)), [3, 4, 5, 6])


def test_zero_length_segments_are_skipped():
    p = _path([90.0, 90.0], [0.2, 1e-4, 0.2])
    dup = np.insert(p, 2, p[2], axis=0)  # a repeated vertex inside the short segment
    c = tight_corners(dup)
    assert len(c) == 2 and np.allclose(dup[c], p[[1, 2]])


def test_single_sided_paths_stop_at_tight_corners(sample_paths):
    """A single-sided path with a tight zig-zag is machined as several moves from rest to rest, split
    at exactly its tight corners; every move's law starts and ends at rest."""
    from core.schedule.steps import build_schedule

    plan = sample_paths(dr=4.0)
    sch = build_schedule(plan, "single")
    tips = {p.index: p.left_tip for p in plan.pairs}
    stops = 0
    for m in sch.left:
        if m.cutting and m.step == 1:
            assert abs(float(m.law.speed(0.0))) < 1e-12 and abs(float(m.law.speed(m.law.duration))) < 1e-12
            inner = tight_corners(m.points)
            assert inner.size == 0  # no tight corner inside a move
            stops += int(np.any(np.all(np.isclose(tips[m.path][1:-1], m.points[0]), axis=1)))
    corners = sum(len(tight_corners(t)) for t in tips.values())
    assert corners > 0 and stops == corners

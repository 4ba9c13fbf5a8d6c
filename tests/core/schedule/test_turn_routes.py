"""Moves in the air keep clear of the blade: a turn whose move across would pass within AIR_CLEARANCE
of it is lifted higher (MoveBuilder.turn_path), measured here against a fin of known geometry."""

from __future__ import annotations

import numpy as np

from core.paths.contours import TURN_LIFT
from core.paths.tessellation import SurfaceMesh, TriangleIndex, closest_point_distance
from core.schedule.air import AIR_CLEARANCE, MAX_TURN_LIFT
from core.schedule.builder import MoveBuilder

UP = np.array([0.0, 0.0, 1.0])
# two path ends far from the sample blade (no contact there: the back-off is the axis), 20 mm apart
END, START = np.array([1000.0, 0.0, 0.0]), np.array([1000.0, 20.0, 0.0])


def _fin(top: float) -> SurfaceMesh:
    """A wall across the move, in the plane y = 10, from z = -10 up to ``top``."""
    v = np.array([[990.0, 10.0, -10.0], [1010.0, 10.0, -10.0], [1010.0, 10.0, top], [990.0, 10.0, top]])
    return SurfaceMesh(vertices=v, triangles=np.array([[0, 1, 2], [0, 2, 3]]))


def _builder(sample_paths, fin: SurfaceMesh) -> MoveBuilder:
    return MoveBuilder(sample_paths(dr=3.0), 1000.0, 500.0, "sigmoid", {}, TriangleIndex(fin))


def _least_distance(fin: SurfaceMesh, a: np.ndarray, c: np.ndarray) -> float:
    """The least distance from the fin of a ball centre moving straight from a to c (dense samples)."""
    p = a + np.linspace(0.0, 1.0, 2001)[:, None] * (c - a)
    v, t = fin.vertices, fin.triangles
    return min(float(closest_point_distance(p, *(np.repeat(v[tri][None, k], len(p), 0) for k in range(3))).min())
               for tri in t)


def test_a_turn_clear_of_the_blade_keeps_its_lift(sample_paths):
    fin = _fin(-5.0)
    b = _builder(sample_paths, fin)
    pts, axes = b.turn_path("left", END, UP, START, UP)
    r = b.plan.params.tool_radius
    assert np.allclose(pts, [END, END + TURN_LIFT * UP, START + TURN_LIFT * UP, START])
    assert _least_distance(fin, pts[1] + r * UP, pts[2] + r * UP) >= r + AIR_CLEARANCE


def test_a_turn_across_a_fin_is_lifted_over_it(sample_paths):
    fin = _fin(3.0)  # 2 mm lift: the ball centres pass 0.5 mm over the fin's top, less than r + 0.5
    b = _builder(sample_paths, fin)
    r = b.plan.params.tool_radius
    low = _least_distance(fin, END + (TURN_LIFT + r) * UP, START + (TURN_LIFT + r) * UP)
    assert low < r + AIR_CLEARANCE
    pts, axes = b.turn_path("left", END, UP, START, UP)
    lift = pts[1][2] - END[2]
    assert lift == 2 * TURN_LIFT  # the least doubling that clears: 4 mm
    assert np.allclose(pts[2], START + lift * UP) and np.allclose(pts[[0, 3]], [END, START])
    assert _least_distance(fin, pts[1] + r * axes[1], pts[2] + r * axes[2]) >= r + AIR_CLEARANCE


def test_a_turn_no_lift_clears_goes_over_the_top(sample_paths):
    fin = _fin(40.0)  # higher than the largest lift: the way round, at the zero position's height
    b = _builder(sample_paths, fin)
    r = b.plan.params.tool_radius
    assert _least_distance(fin, END + (MAX_TURN_LIFT + r) * UP, START + (MAX_TURN_LIFT + r) * UP) < r
    pts, axes = b.turn_path("left", END, UP, START, UP)
    safe = b.home["left"][0][2]
    assert len(pts) == 6 and safe < -10.0  # (the left cutter's side: below the blade and the fin)
    assert np.allclose(pts[[0, 1, 4, 5]], [END, END + TURN_LIFT * UP, START + TURN_LIFT * UP, START])
    assert pts[2][2] == safe and pts[3][2] == safe
    for k in range(1, 4):  # (the lift and the descent go along the normal, away from the blade)
        assert _least_distance(fin, pts[k] + r * axes[k], pts[k + 1] + r * axes[k + 1]) >= r + AIR_CLEARANCE


def test_a_way_to_the_other_side_goes_round_the_blades_tip(sample_paths):
    """A contact on the far side of the blade from the cutter's zero position (round the blade's tip,
    where the contact's normal points to the other cutter's side): the way down to it from the zero
    position's height goes out along X_W beyond the blade's tip, not through the blade."""
    plate = SurfaceMesh(vertices=np.array([[990.0, -10.0, 0.0], [1010.0, -10.0, 0.0], [1010.0, 30.0, 0.0],
                                           [990.0, 30.0, 0.0]]), triangles=np.array([[0, 1, 2], [0, 2, 3]]))
    b = _builder(sample_paths, plate)
    b.tip_x = 1010.0  # (the plate's tip along X_W)
    r = b.plan.params.tool_radius
    safe = b.home["left"][0][2]
    assert safe < -10.0  # (the left cutter's side: below the plate)
    start = np.array([1000.0, 10.0, 0.0])  # on the plate's top, backing off upwards
    up = start + TURN_LIFT * UP
    assert _least_distance(plate, up + r * UP, np.array([up[0], up[1], safe]) + r * UP) < r  # (straight down)
    way = b._riser(start, UP, UP, safe)
    assert way is not None and len(way) == 3
    assert np.allclose(way[0], up)
    assert way[1][0] >= 1010.0 + r + AIR_CLEARANCE and way[1][2] == up[2]
    assert np.allclose(way[2], [way[1][0], way[1][1], safe])
    for a, c in zip(way[:-1], way[1:], strict=True):
        assert _least_distance(plate, a + r * UP, c + r * UP) >= r + AIR_CLEARANCE

"""Each single-sided contact goes to the cutter it faces (core.paths.single_sided.facing_sides)."""

import numpy as np
import pytest

from core.paths.contours import ContourPath
from core.paths.single_sided import FACING_DEG, facing_sides

LIMIT = np.sin(np.radians(FACING_DEG))


def _ellipse(theta: np.ndarray, a: float = 20.0, b: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Points and outward unit normals of the ellipse y = a cos t, z = b sin t in the plane x = 100."""
    pts = np.column_stack([np.full_like(theta, 100.0), a * np.cos(theta), b * np.sin(theta)])
    n = np.column_stack([np.zeros_like(theta), b * np.cos(theta), a * np.sin(theta)])
    return pts, n / np.linalg.norm(n, axis=1, keepdims=True)


def _seam_past_the_edges(overshoot: float, direction: int = 1) -> ContourPath:
    """A thin section whose lower side (the left cutter's, facing -Z_W) runs ``overshoot`` radians past
    both edges onto the upper side, as a mesh whose seam lies beyond the edges gives it. Both sides run
    from the edge at y < 0 (LE) to the edge at y > 0; ``direction`` -1 reverses both."""
    left, nl = _ellipse(np.linspace(np.pi - overshoot, 2 * np.pi + overshoot, 801))
    right, nr = _ellipse(np.linspace(np.pi - overshoot, overshoot, 601))
    right[[0, -1]], nr[[0, -1]] = left[[0, -1]], nl[[0, -1]]  # the seam's two points, shared
    if direction < 0:
        left, nl, right, nr = left[::-1], nl[::-1], right[::-1], nr[::-1]
    return ContourPath(index=0, r=100.0, direction=direction, left_cc=left, left_normals=nl,
                       right_cc=right, right_normals=nr)


def _ordered(pts: np.ndarray, most: float) -> bool:
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    return bool((steps > 0).all() and steps.max() <= most)


@pytest.mark.parametrize("direction", [1, -1])
def test_contacts_past_the_edge_go_to_the_cutter_they_face(direction):
    path = _seam_past_the_edges(0.5, direction)  # the seam 0.5 rad past each edge: normals n_z ~0.999
    got = facing_sides(path)
    assert got is not path
    # no contact faces the other cutter more than FACING_DEG past the silhouette
    assert got.left_normals[:, 2].max() <= LIMIT
    assert got.right_normals[:, 2].min() >= -LIMIT
    # every contact is still machined, by one cutter (the shared edge points once)
    before = np.unique(np.concatenate([path.left_cc, path.right_cc]), axis=0)
    after = np.concatenate([got.left_cc, got.right_cc])
    assert len(after) == len(before) == len(np.unique(after, axis=0))
    assert np.array_equal(np.unique(after, axis=0), before)
    # each side is still one continuous run in machining order, and the sides still meet at the edges
    spacing = max(np.linalg.norm(np.diff(p, axis=0), axis=1).max() for p in (path.left_cc, path.right_cc))
    assert _ordered(got.left_cc, spacing) and _ordered(got.right_cc, spacing)
    for end in (0, -1):
        assert np.linalg.norm(got.left_cc[end] - got.right_cc[end]) <= spacing
    # what moved is the left's overshoot, up to its last contact past the limit: the right now starts
    # and ends on it, the left on its first contact within the limit
    for end, inner in ((0, 1), (-1, -2)):
        k = np.flatnonzero((path.left_cc == got.right_cc[end]).all(axis=1))
        assert k.size == 1 and path.left_normals[k[0], 2] > LIMIT
        k = np.flatnonzero((path.left_cc == got.left_cc[end]).all(axis=1))[0]
        assert path.left_normals[k, 2] <= LIMIT < path.left_normals[k - inner, 2]


def test_a_section_whose_sides_stay_on_their_side_is_unchanged():
    # the seam where the lower side's normal has turned FACING_DEG - 1 degrees past the silhouette
    path = _seam_past_the_edges(np.arctan(2.0 / 20.0 * np.tan(np.radians(FACING_DEG - 1.0))))
    assert path.left_normals[:, 2].max() == pytest.approx(np.sin(np.radians(FACING_DEG - 1.0)))
    assert facing_sides(path) is path


def test_the_sample_blades_single_sided_paths_are_unchanged(sample_paths):
    """The sample's sides turn less than FACING_DEG past their silhouettes wherever it is machined
    single-sided (round its hub, where its sections are pitched most, they turn further: those paths are
    collaborative)."""
    plan = sample_paths(dr=2.0)
    tip = [path for path, reg in zip(plan.paths, plan.regions, strict=True) if reg.is_tip]
    assert len(tip) > 20
    for path in tip:
        assert facing_sides(path) is path, path.index


@pytest.mark.parametrize("left_above", [True, False])
def test_crossed_sides(left_above):
    """A fold at the start (a mesh whose pieces cross at a thin tip): each side's first ten contacts lie
    on a sheet that faces the other cutter, side by side with the other's. With the left's sheet above
    the right's (facing +Z_W, away from the material) the runs change sides; with it below, the sheets
    face each other across no material and neither cutter machines them."""
    y = np.arange(40) * 0.1
    fold = y < 0.95
    z_left = np.where(fold, 0.01 if left_above else -0.01, -0.5)
    left = np.column_stack([np.full(40, 100.0), y, z_left])
    right = np.column_stack([np.full(40, 100.0), y, -z_left])
    up = np.column_stack([np.zeros(40), np.zeros(40), np.ones(40)])
    nl = np.where(fold[:, None], up, -up)
    path = ContourPath(index=0, r=100.0, direction=1, left_cc=left, left_normals=nl, right_cc=right,
                       right_normals=-nl)
    got = facing_sides(path)
    if left_above:
        assert np.array_equal(got.left_cc[:10], right[:10]) and np.array_equal(got.right_cc[:10], left[:10])
        assert np.array_equal(got.left_cc[10:], left[10:]) and np.array_equal(got.right_cc[10:], right[10:])
    else:
        assert np.array_equal(got.left_cc, left[10:]) and np.array_equal(got.right_cc, right[10:])
    assert (got.left_normals[:, 2] < 0).all() and (got.right_normals[:, 2] > 0).all()

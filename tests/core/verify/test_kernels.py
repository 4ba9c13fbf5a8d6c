"""verify's compiled kernels against references formulated afresh here: the index's build
(core.verify._index: extents, the order of the triangles, the cells' boxes, the coarse field against
scipy's Euclidean distance transform, the area), verify's own forward kinematics (core.verify._axes)
against the planner's inverse and forward kinematics, and one axis column's limits and derivative
rule against numpy."""

from __future__ import annotations

import numpy as np
import pytest
from core.verify._axes import axis_column
from core.verify._index import cell_boxes, cell_order, distance_field, extents, total_area
from scipy.ndimage import distance_transform_edt

from core.machine.kinematics import forward_kinematics as planner_forward
from core.machine.kinematics import inverse_kinematics
from core.machine.model import load_machine
from core.paths.tessellation import SurfaceMesh
from core.verify.assembly import clamp_box
from core.verify.axes import axes_checks, derivative_slack
from core.verify.distance import DistanceIndex
from core.verify.report import Report

MACHINE = load_machine()


def soup(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """n random triangles (vertices (V, 3) mm, some shared, and triangles (n, 3))."""
    rng = np.random.default_rng(seed)
    v = rng.uniform(-20, 20, (n + 20, 3))
    tris = np.column_stack([rng.integers(0, len(v), n) for _ in range(3)])
    return v, tris


def test_extents_order_and_cell_boxes_against_numpy():
    v, tris = soup(3000, 1)
    corners = v[tris]
    extent, lo, hi = np.empty(len(tris)), np.empty(3), np.empty(3)
    extents(v, tris.astype(np.int64), extent, lo, hi)
    np.testing.assert_array_equal(extent, (corners.max(axis=1) - corners.min(axis=1)).max(axis=1))
    np.testing.assert_array_equal(lo, corners.reshape(-1, 3).min(axis=0))
    np.testing.assert_array_equal(hi, corners.reshape(-1, 3).max(axis=0))
    h = 3.0
    origin, dims = lo - h, (np.floor((hi - lo) / h).astype(np.int64) + 3)
    order, key = np.empty(len(tris), np.int64), np.empty(len(tris), np.int64)
    cell_order(v, tris.astype(np.int64), origin, h, dims, order, key)
    q = np.clip(np.floor((corners.mean(axis=1) - origin) * (4.0 / h)).astype(np.int64), 0, 4 * dims - 1)
    cell, sub = np.divmod(q, 4)
    want = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    full = want * 64 + sub[:, 0] * 16 + sub[:, 1] * 4 + sub[:, 2]
    np.testing.assert_array_equal(np.sort(order), np.arange(len(tris)))  # (a permutation)
    np.testing.assert_array_equal(full[order], np.sort(full))  # (by cell, then quarter-cell)
    np.testing.assert_array_equal(key, want[order])
    first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    ordered = corners[order]
    tri = np.ascontiguousarray(np.hstack([ordered[:, 0], ordered[:, 1] - ordered[:, 0], ordered[:, 2] - ordered[:, 0]]))
    cbox = np.empty((len(first), 6))
    cell_boxes(tri, np.append(first, len(key)), cbox)
    for s in range(len(first)):
        t = tri[first[s]:(first[s + 1] if s + 1 < len(first) else len(key))]
        pts = np.vstack([t[:, :3], t[:, :3] + t[:, 3:6], t[:, :3] + t[:, 6:]])
        np.testing.assert_array_equal(cbox[s], np.r_[pts.min(axis=0), pts.max(axis=0)])


def test_a_triangle_naming_a_missing_vertex_is_refused():
    v, tris = soup(10, 2)
    tris[4, 1] = len(v)
    with pytest.raises(IndexError, match="triangle 4"):
        extents(v, tris.astype(np.int64), np.empty(10), np.empty(3), np.empty(3))


@pytest.mark.parametrize("seed", [3, 4])
def test_the_field_is_scipys_distance_transform(seed):
    rng = np.random.default_rng(seed)
    occupied = (rng.uniform(size=(23, 17, 11)) < 0.02).astype(np.uint8)
    occupied[0, 0, 0] = 1
    h = 0.7
    field = np.empty(occupied.shape, np.float32)
    distance_field(occupied, h, field)
    edt = distance_transform_edt(occupied == 0, sampling=h) - h * np.sqrt(3.0)
    want = np.maximum(edt * (1.0 - 1e-6) - 1e-6, 0.0).astype(np.float32)
    np.testing.assert_allclose(field, want, rtol=1e-6, atol=1e-6)
    # (a lower bound of each cell's centre's distance to the nearest occupied centre, less a diagonal)
    centres = np.argwhere(occupied) * h
    cells = np.argwhere(np.ones_like(occupied)) * h
    nearest = np.min(np.linalg.norm(cells[:, None] - centres[None], axis=2), axis=1)
    assert (field.ravel() <= np.maximum(nearest - h * np.sqrt(3.0), 0.0) + 1e-9).all()


def test_an_empty_grid_has_an_infinite_field():
    field = np.empty((3, 4, 5), np.float32)
    distance_field(np.zeros((3, 4, 5), np.uint8), 1.0, field)
    assert np.isinf(field).all()


def test_the_index_area_and_the_clamp_box_against_numpy():
    v, tris = soup(500, 5)
    index = DistanceIndex(SurfaceMesh(vertices=v, triangles=tris))
    c = v[tris]
    area = 0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum()
    assert index.area == pytest.approx(area, rel=1e-12)
    assert total_area(np.zeros((0, 9))) == 0.0
    lo, hi = clamp_box(index, 0.0, 3.0)
    xy = c.reshape(-1, 3)[:, :2]
    root = xy[xy[:, 0] <= 0.0, 1]
    np.testing.assert_array_equal(lo, [-np.inf, root.min(), -3.0])
    np.testing.assert_array_equal(hi, [0.0, root.max(), 3.0])


def poses(side: str, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """n tips (n, 3) mm and unit axes (n, 3) within the machine's reach and tilt."""
    rng = np.random.default_rng(seed)
    tips = np.column_stack([rng.uniform(40, 235, n), rng.uniform(-90, 90, n), rng.uniform(-60, 60, n)])
    tilt = np.radians(MACHINE.max_tilt_deg) * np.sqrt(rng.uniform(0, 1, n))
    az = rng.uniform(-np.pi, np.pi, n)
    sign = -1.0 if side == "left" else 1.0
    return tips, np.column_stack([np.sin(tilt) * np.cos(az), np.sin(tilt) * np.sin(az), sign * np.cos(tilt)])


def cl_of(tips: np.ndarray, axes: np.ndarray) -> dict:
    return {"t": np.arange(len(tips)) * 10.0, "p": tips, "w": axes}


@pytest.mark.parametrize("side", ["left", "right"])
def test_verifys_forward_kinematics_reproduce_the_poses(side):
    tips, axes = poses(side, 2000, 6)
    values = inverse_kinematics(MACHINE, side, tips, axes)
    table = np.column_stack([np.arange(len(tips)) * 10.0, values, np.zeros((len(tips), 6))])
    rep = Report()
    figures = axes_checks(side, table, cl_of(tips, axes * 3.0), MACHINE, rep, "x.csv")
    assert not any("forward kinematics" in k for k in rep.kinds), rep.findings
    assert figures[f"{side}_fk_error_mm"] < 1e-6
    # the planner's forward kinematics agree
    tips2, _ = planner_forward(MACHINE, side, values)
    assert np.linalg.norm(tips2 - tips, axis=1).max() < 1e-6


@pytest.mark.parametrize("side", ["left", "right"])
def test_verifys_forward_kinematics_find_a_moved_tip_and_rows_without_a_pose(side):
    tips, axes = poses(side, 50, 7)
    values = inverse_kinematics(MACHINE, side, tips, axes)
    table = np.column_stack([np.arange(len(tips)) * 10.0, values, np.zeros((len(tips), 6))])
    moved = tips.copy()
    moved[9, 1] += 0.01
    rep = Report()
    axes_checks(side, table, cl_of(moved, axes), MACHINE, rep, "x.csv")
    assert any("misses the CL tip by 1.00e-02 mm" in f for f in rep.findings), rep.findings
    table[3, 5] = np.nan
    table[7, 4] = 1e4  # (a leg no platform can take)
    rep = Report()
    axes_checks(side, table, cl_of(tips, axes), MACHINE, rep, "x.csv")
    assert rep.findings == [f"x.csv: {side}: axis values are not finite numbers at samples 3",
                            f"x.csv: {side}: no platform pose for the leg values at samples 7 (forward "
                            "kinematics did not converge); check d1..d3"]


def reference_column(t, x, v, lim):
    """The rows an axis column's limits flag (stroke, speed, acceleration, derivative) and its
    accelerations (mm/s^2), in numpy."""
    dt = np.diff(t)
    dv = np.diff(v)
    acc = np.abs(dv) / dt * 1e6
    slack = (2e-9 / dt + np.abs(dv) * 2e-6 / dt**2) * 1e6
    c = np.diff(x) / dt
    lo, hi = np.minimum(v[:-1], v[1:]), np.maximum(v[:-1], v[1:])
    room = lim[3] / 1e6 * dt + (1e-6 + 1e-6 * np.abs(c)) / dt + 2e-9
    out = np.maximum(np.maximum(lo - c, c - hi) - room, 0.0)
    return ((x < lim[0] - 1e-6) | (x > lim[1] + 1e-6), np.abs(v) * 1000.0 > lim[2] * (1 + 1e-6) + 1e-6,
            acc > lim[3] * (1 + 1e-6) + slack, out > 0, acc, out)


def test_an_axis_column_against_numpy():
    rng = np.random.default_rng(8)
    n = 5000
    t = np.cumsum(rng.uniform(0.5, 12.0, n))
    x = np.cumsum(rng.normal(0, 0.3, n))
    v = np.r_[np.diff(x) / np.diff(t), 0.0] + rng.normal(0, 2e-3, n)
    lim = (-5.0, 5.0, 40.0, 300.0)
    acc, slack, flags = np.empty(n - 1), np.empty(n - 1), np.empty(n, np.uint8)
    axis_column(t, x, v, lim, acc, slack, flags)
    stroke, speed, accel, deriv, want_acc, want_slack = reference_column(t, x, v, lim)
    for bit, want in ((1, stroke), (2, speed), (4, np.r_[accel, False]), (8, np.r_[deriv, False])):
        assert want.any() and not want.all()
        np.testing.assert_array_equal((flags & bit) > 0, want)
    np.testing.assert_allclose(acc, want_acc, rtol=1e-12)
    np.testing.assert_allclose(slack, want_slack, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(derivative_slack(t, x, v, lim[3] / 1e6), want_slack, rtol=1e-9, atol=1e-15)


def test_the_nearest_chords_of_a_points_own_path():
    """core.verify.coverage.near_segments (the completeness check's search for the few ambiguous pair
    points): exact between tol/10 and tol, on the right side of both, against brute force."""
    from core.verify.coverage import near_segments

    rng = np.random.default_rng(9)
    verts = np.cumsum(rng.normal(0, 0.05, (3000, 3)), axis=0)
    a = np.arange(len(verts) - 1)
    seg_label = a // 500
    x = verts[rng.integers(0, len(verts), 200)] + rng.normal(0, 0.004, (200, 3))
    x_label = rng.integers(0, 7, 200)  # (label 6 has no segments)
    d = near_segments(x, x_label, verts, a, a + 1, seg_label, 0.01, 1e-3)[0]
    e = verts[a + 1] - verts[a]
    want = np.full(len(x), np.inf)
    for i in range(len(x)):
        own = seg_label == x_label[i]
        s = np.clip(((x[i] - verts[a[own]]) * e[own]).sum(axis=1) / (e[own] ** 2).sum(axis=1), 0, 1)
        want[i] = np.linalg.norm(verts[a[own]] + s[:, None] * e[own] - x[i], axis=1).min(initial=np.inf)
    assert np.isinf(d[x_label == 6]).all()
    exact = (want >= 1e-3) & (want <= 0.01)
    np.testing.assert_allclose(d[exact], want[exact], rtol=1e-12)
    assert ((d < 1e-3) == (want < 1e-3)).all() and ((d > 0.01) == (want > 0.01)).all()

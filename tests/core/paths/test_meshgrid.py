"""The blade index's exact search (core.paths.meshgrid.MeshGrid): its fields against scipy's distance
transform, its bounds and its exact distances against brute force over every triangle, on meshes of
small triangles, of mixed sizes, and along a row of nearby queries (each one's search bounded by the
last one's distance)."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from core.paths.meshgrid import MeshGrid
from core.paths.tessellation import SurfaceMesh, TriangleIndex, closest_point_distance


def wavy_mesh(n: int = 15) -> SurfaceMesh:
    """A wavy sheet 20 x 15 mm, z = 2 sin(x / 3) cos(y / 4), as n x n vertices."""
    x, y = np.meshgrid(np.linspace(0, 20, n), np.linspace(0, 15, n))
    v = np.column_stack([x.ravel(), y.ravel(), (2 * np.sin(x / 3) * np.cos(y / 4)).ravel()])
    a = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    tri = np.concatenate([np.column_stack([a, a + 1, a + n + 1]), np.column_stack([a, a + n + 1, a + n])])
    return SurfaceMesh(v, tri)


def mixed_mesh() -> SurfaceMesh:
    """The wavy sheet with two large triangles across it (a grid's cells far smaller than they)."""
    mesh = wavy_mesh()
    k = len(mesh.vertices)
    big = np.array([[-5.0, -5.0, 3.0], [30.0, 0.0, -3.0], [10.0, 25.0, 1.0], [0.0, 20.0, -4.0]])
    tri = np.vstack([mesh.triangles, [[k, k + 1, k + 2], [k, k + 2, k + 3]]])
    return SurfaceMesh(np.vstack([mesh.vertices, big]), tri)


def point_distances(mesh: SurfaceMesh, points: np.ndarray) -> np.ndarray:
    """(n,) exact distances of points (n, 3) from the mesh: the least over every triangle."""
    v, t = mesh.vertices, mesh.triangles
    out = np.empty(len(points))
    for lo in range(0, len(points), 256):
        p = points[lo:lo + 256]
        k = np.tile(np.arange(len(t)), len(p))
        d = closest_point_distance(np.repeat(p, len(t), axis=0), v[t[k, 0]], v[t[k, 1]], v[t[k, 2]])
        out[lo:lo + 256] = d.reshape(len(p), len(t)).min(axis=1)
    return out


def segment_brute(mesh: SurfaceMesh, p0: np.ndarray, p1: np.ndarray, m: int = 101) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) brackets of the segments' distances from the mesh: the least distance of m points
    along each (an upper bound), less half their spacing (the distance is 1-Lipschitz along it)."""
    f = np.linspace(0.0, 1.0, m)
    pts = (p0[:, None, :] + f[None, :, None] * (p1 - p0)[:, None, :]).reshape(-1, 3)
    upper = point_distances(mesh, pts).reshape(len(p0), m).min(axis=1)
    return upper - 0.5 * np.linalg.norm(p1 - p0, axis=1) / (m - 1), upper


def test_fields_are_the_distance_transforms_of_the_cells():
    """floor: h times the distance of each cell's centre from the nearest cell a triangle's bounding
    box overlaps, less half a diagonal, rounded down to a float; ceiling: from the nearest cell
    holding a centroid, plus half a diagonal, rounded up (scipy's transform, the cells found here)."""
    mesh = wavy_mesh()
    grid = MeshGrid(TriangleIndex(mesh, k=8))
    v, t = mesh.vertices, mesh.triangles
    lo = np.floor((v[t].min(axis=1) - grid.origin) / grid.h).astype(int)
    hi = np.floor((v[t].max(axis=1) - grid.origin) / grid.h).astype(int)
    occupied = np.zeros(grid.dims, bool)
    for a, b in zip(lo, hi, strict=True):
        occupied[a[0]:b[0] + 1, a[1]:b[1] + 1, a[2]:b[2] + 1] = True
    held = np.zeros(grid.dims, bool)
    held[tuple(np.floor((v[t].mean(axis=1) - grid.origin) / grid.h).astype(int).T)] = True
    half = 0.5 * grid.h * np.sqrt(3.0)
    floor = grid.h * distance_transform_edt(~occupied).ravel() - half
    ceiling = grid.h * distance_transform_edt(~held).ravel() + half
    assert (grid.floor <= floor).all() and (grid.ceiling >= ceiling).all()
    np.testing.assert_allclose(grid.floor, floor, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(grid.ceiling, ceiling, rtol=1e-6, atol=1e-6)


def test_bounds_against_brute_force():
    """point_bound <= the distance <= point_upper for points in and around the mesh (and far outside
    the grid), and the segments' bounds bracket their distances, on a mesh of small triangles and one
    with large ones."""
    rng = np.random.default_rng(7)
    for mesh in (wavy_mesh(), mixed_mesh()):
        grid = MeshGrid(TriangleIndex(mesh, k=8))
        pts = np.vstack([rng.uniform([-3, -3, -5], [23, 18, 5], (300, 3)), rng.uniform(-60, 80, (40, 3))])
        exact = point_distances(mesh, pts)
        assert (grid.point_bound(pts) <= exact + 1e-9).all()
        assert (grid.point_upper(pts) >= exact - 1e-9).all()
        p0 = pts[:60]
        p1 = p0 + rng.normal(size=(60, 3)) * 3.0
        p1 = p0 + (p1 - p0) * (3.0 / np.linalg.norm(p1 - p0, axis=1))[:, None]  # (one length)
        low, high = segment_brute(mesh, p0, p1)
        assert (grid.bound(p0, p1, grid.h) <= high + 1e-9).all()
        assert (grid.bound(p0, p1, 0.5 * grid.h, upper=True) >= low - 1e-9).all()


def test_distances_against_brute_force():
    """Exact segment distances (points among them) within the brute force's brackets, on a mesh of
    small triangles and one whose large triangles reach far beyond their cells; cut off where asked."""
    rng = np.random.default_rng(3)
    for mesh in (wavy_mesh(), mixed_mesh()):
        grid = MeshGrid(TriangleIndex(mesh, k=8))
        p0 = rng.uniform([-3, -3, -5], [23, 18, 5], (40, 3))
        p1 = p0 + rng.normal(size=(40, 3)) * 4
        p1[:8] = p0[:8]
        got = grid.distance(p0, p1, 100.0)
        low, high = segment_brute(mesh, p0, p1)
        assert (low - 1e-9 <= got).all() and (got <= high + 1e-9).all()
        np.testing.assert_array_equal(grid.distance(p0, p1, 0.5), np.minimum(got, 0.5))


def test_a_row_of_nearby_queries_is_exact():
    """Along a path of segments a small step apart (each search bounded by the last one's distance
    plus the step), every distance equals the one found alone, also where the path crosses the sheet,
    with a cutoff the path passes in and out of, and from a first reach far short of the distance."""
    mesh = wavy_mesh()
    grid = MeshGrid(TriangleIndex(mesh, k=8))
    s = np.linspace(0.0, 1.0, 400)[:, None]
    p0 = np.array([-2.0, 1.0, 4.0]) + s * np.array([24.0, 12.0, -8.0])
    p1 = p0 + np.array([0.5, -1.0, 2.5])
    for cutoff in (100.0, 2.5):
        row = grid.distance(p0, p1, cutoff, reach=0.0)
        alone = np.array([grid.distance(p0[i:i + 1], p1[i:i + 1], cutoff, reach=0.0)[0] for i in range(len(p0))])
        np.testing.assert_array_equal(row, alone)
        assert (row == 0.0).any() and (row < cutoff).any()
    low, high = segment_brute(mesh, p0[::20], p1[::20])
    got = grid.distance(p0, p1, 100.0)[::20]
    assert (low - 1e-9 <= got).all() and (got <= high + 1e-9).all()

"""core.paths.tessellation.TriangleIndex.closest is exact: the nearest triangle of the whole mesh, also
where the triangles with the nearest centroids are not the nearest triangles (a large facet beside a
cluster of small ones, as a mesh blade's facets are), checked against brute force."""

from __future__ import annotations

import numpy as np

from core.paths.tessellation import SurfaceMesh, TriangleIndex, closest_point_on_triangle


def _brute(points: np.ndarray, mesh: SurfaceMesh) -> np.ndarray:
    tri = mesh.vertices[mesh.triangles]
    out = np.empty(len(points))
    for i, p in enumerate(points):
        q = closest_point_on_triangle(np.broadcast_to(p, tri[:, 0].shape), tri[:, 0], tri[:, 1], tri[:, 2])
        out[i] = np.linalg.norm(q - p, axis=1).min()
    return out


def _big_beside_small() -> SurfaceMesh:
    """One 20 mm triangle in z = 0 and a cluster of 200 tiny triangles 1 mm above its middle: a point
    0.3 mm above the big one has the tiny ones' centroids nearest, but the big one is nearer."""
    rng = np.random.default_rng(3)
    verts = [np.array([[-10.0, -10.0, 0.0], [10.0, -10.0, 0.0], [0.0, 10.0, 0.0]])]
    for _ in range(200):
        c = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), 1.0])
        verts.append(c + rng.normal(scale=0.02, size=(3, 3)))
    v = np.vstack(verts)
    return SurfaceMesh(v, np.arange(len(v)).reshape(-1, 3))


def test_the_nearest_triangle_is_found_beyond_the_nearest_centroids():
    mesh = _big_beside_small()
    index = TriangleIndex(mesh, k=8)
    points = np.array([[0.0, 0.0, 0.3], [0.2, -0.1, 0.35], [3.0, 2.0, 0.3], [0.0, 0.0, 1.2]])
    d, q = index.closest(points)
    np.testing.assert_allclose(d, _brute(points, mesh), rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(q - points, axis=1), d, rtol=0, atol=1e-12)
    assert d[0] == 0.3  # (the big facet below, not the cluster's 0.7 mm above)


def test_random_points_near_a_random_mesh_match_brute_force():
    rng = np.random.default_rng(11)
    big = _big_beside_small()
    pts = rng.uniform([-8, -8, -1], [8, 8, 2], size=(400, 3))
    d, q = TriangleIndex(big, k=4).closest(pts)
    np.testing.assert_allclose(d, _brute(pts, big), rtol=0, atol=1e-12)

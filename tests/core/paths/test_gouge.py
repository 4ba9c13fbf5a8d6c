"""The gouge check's geometry, against brute force."""

import numpy as np

from core.paths.tessellation import SurfaceMesh, closest_point_distance, distance_to_surface


def brute_triangle_distance(p, a, b, c, n=400):
    # dense barycentric sampling of the triangle: an upper bound converging to the true distance
    u, v = np.meshgrid(np.linspace(0, 1, n), np.linspace(0, 1, n))
    m = (u + v) <= 1
    u, v = u[m], v[m]
    pts = a + np.outer(u, b - a) + np.outer(v, c - a)
    return np.linalg.norm(pts - p, axis=1).min()


def test_point_triangle_distance_against_brute_force():
    rng = np.random.default_rng(3)
    for _ in range(40):
        a, b, c = rng.normal(size=(3, 3))
        p = rng.normal(size=3) * 2
        d = closest_point_distance(p[None], a[None], b[None], c[None])[0]
        brute = brute_triangle_distance(p, a, b, c)
        assert d <= brute + 1e-12
        assert brute - d < 5e-3  # sampling step of the brute force


def test_index_closest_points_agree_with_the_reference_in_every_region():
    """TriangleIndex's closest points (barycentric form, blocks of candidates) against
    closest_point_on_triangle, on points round a triangle that fall into each of its seven Voronoi
    regions (three corners, three edges, the face), and brute force on the nearest distance."""
    from core.paths.tessellation import TriangleIndex, closest_point_on_triangle

    rng = np.random.default_rng(11)
    tri = np.array([[0.0, 0.0, 0.0], [3.0, 0.2, 0.1], [0.7, 2.5, -0.3]])
    mesh = SurfaceMesh(np.vstack([tri, tri + [10.0, 0.0, 0.0]]), np.array([[0, 1, 2], [3, 4, 5]]))
    index = TriangleIndex(mesh, k=2)
    index.BLOCK = 37  # several blocks, the last one short
    pts = rng.uniform([-3, -3, -2], [6, 5, 2], size=(400, 3))
    d, q = index.closest(pts)
    want = np.minimum(*(np.linalg.norm(pts - closest_point_on_triangle(pts, *np.repeat(mesh.vertices[t][:, None], 400, 1)),
                                       axis=1) for t in mesh.triangles))
    np.testing.assert_allclose(d, want, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(pts - q, axis=1), d, atol=1e-12)
    # every region is exercised: barycentric (v, w) of the reference closest points on the first triangle
    ref = closest_point_on_triangle(pts, *np.repeat(tri[:, None], 400, 1))
    vw = np.linalg.lstsq(np.column_stack([tri[1] - tri[0], tri[2] - tri[0]]), (ref - tri[0]).T, rcond=None)[0].T
    v, w = vw[:, 0], vw[:, 1]
    eps = 1e-9
    kinds = {"a": (v < eps) & (w < eps), "b": v > 1 - eps, "c": w > 1 - eps,
             "ab": (w < eps) & (v > eps) & (v < 1 - eps), "ac": (v < eps) & (w > eps) & (w < 1 - eps),
             "bc": (np.abs(v + w - 1) < eps) & (v > eps) & (w > eps),
             "face": (v > eps) & (w > eps) & (v + w < 1 - eps)}
    assert all(m.sum() >= 5 for m in kinds.values()), {k: int(m.sum()) for k, m in kinds.items()}
    for i in range(0, 400, 40):
        assert d[i] <= min(brute_triangle_distance(pts[i], *mesh.vertices[t]) for t in mesh.triangles) + 1e-12


def test_distance_to_a_plane_mesh():
    x, y = np.meshgrid(np.linspace(0, 10, 21), np.linspace(0, 10, 21))
    v = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    idx = np.arange(441).reshape(21, 21)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    tris = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    mesh = SurfaceMesh(v, tris)
    rng = np.random.default_rng(0)
    pts = np.column_stack([rng.uniform(1, 9, 200), rng.uniform(1, 9, 200), rng.uniform(-3, 3, 200)])
    assert np.allclose(distance_to_surface(pts, mesh), np.abs(pts[:, 2]), atol=1e-12)


def test_straight_moves_between_ball_centres_stay_on_the_offset_surface():
    """At the closing tip the ball rolls round a leading edge of a few hundredths of a millimetre: the
    chords between consecutive ball centres of the outermost paths (default dR) dip into the offset
    surface by no more than the chord tolerance (plus the check mesh's own error), by brute-force
    distance at points along every chord. (Only the outermost radii are planned: each path is planned
    on its own, so these are the pairs a whole plan at the defaults has there.)"""
    from core.blade.source import load_blade
    from core.paths.interpolation import CHORD_TOLERANCE
    from core.paths.planning import PathsJob
    from core.paths.tessellation import TriangleIndex, surface_mesh
    from core.records import PlanParameters

    blade = load_blade("sample")
    job = PathsJob(blade, PlanParameters())  # (one process: its radii are planned in result())
    job.radii = job.radii[:16]  # tip first: room for a path or two skipped near the tip
    plan = job.result()
    assert len(plan.pairs) >= 10 and plan.params.dr == 0.375
    mesh = TriangleIndex(surface_mesh(blade, plan.frame))  # (built once for every chord below)
    r = plan.params.tool_radius
    worst = 0.0
    for pair in plan.pairs[:10]:
        for tip, axis in ((pair.left_tip, pair.left_axis), (pair.right_tip, pair.right_axis)):
            c = tip + r * axis
            along = np.concatenate([c[:-1] + f * (c[1:] - c[:-1]) for f in (0.25, 0.5, 0.75)])
            worst = min(worst, float((distance_to_surface(along, mesh) - r).min()))
    assert worst > -(CHORD_TOLERANCE + 2e-4)

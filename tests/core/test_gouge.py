"""The gouge check's geometry, against brute force."""

import numpy as np

from core.gouge import SurfaceMesh, closest_point_distance, distance_to_surface


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
    distance at points along every chord."""
    from core.blade_source import load_blade
    from core.gouge import surface_mesh
    from core.interpolation import CHORD_TOLERANCE
    from core.pipeline import PlanParameters, plan_paths

    blade = load_blade("sample")
    plan = plan_paths(blade, PlanParameters(), workers=2)
    mesh = surface_mesh(blade, plan.frame)
    r = plan.params.tool_radius
    worst = 0.0
    for pair in plan.pairs[:10]:
        for tip, axis in ((pair.left_tip, pair.left_axis), (pair.right_tip, pair.right_axis)):
            c = tip + r * axis
            along = np.concatenate([c[:-1] + f * (c[1:] - c[:-1]) for f in (0.25, 0.5, 0.75)])
            worst = min(worst, float((distance_to_surface(along, mesh) - r).min()))
    assert worst > -(CHORD_TOLERANCE + 2e-4)

"""verify's own distance engine (core.verify.distance, core.verify.sweep) against brute force: small
meshes (a wavy sheet, a closed tessellated ellipsoid, a soup of random triangles), every triangle
measured by a formulation of its own here (the closest point by projection and the three edges; a
segment by the two ends, the three edges and a crossing solved as a 3 x 3 system). The engine must
be exact within a query's cutoff and never above the true distance beyond it; its sweeps must never
bound a row above its clearance, must measure every colliding row, and must find a collision that
only a pose between two rows shows."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.paths.tessellation import SurfaceMesh
from core.verify.cutters import BALL_EXACT, _track
from core.verify.distance import DistanceIndex, box_gaps, box_sweeps, pair_sweeps, segment_gaps, turns
from core.verify.sweep import TOLERANCE, between_rows, bounded, motion, poses_between, reach, stretches

EXACT = 1e-9


# -- brute force, formulated afresh -----------------------------------------------------------------

def point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) distances of points p (n, 3) from the segments a-b (n, 3)."""
    ab = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300), 0.0, 1.0)
    return np.linalg.norm(p - a - t[:, None] * ab, axis=1)


def point_triangles(p: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(m,) distances of one point p (3,) from triangles tri (m, 3, 3): the plane's distance where the
    point projects inside, else the nearest edge's."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    n = np.cross(b - a, c - a)
    area2 = np.einsum("ij,ij->i", n, n)
    ok = area2 > 1e-24
    nu = n / np.sqrt(np.where(ok, area2, 1.0))[:, None]
    h = np.einsum("ij,ij->i", p - a, nu)
    q = p - h[:, None] * nu
    # barycentric signs: q inside when it lies on the inner side of all three edges
    inside = ok.copy()
    for u, v in ((a, b), (b, c), (c, a)):
        inside &= np.einsum("ij,ij->i", np.cross(v - u, q - u), n) >= 0
    pp = np.broadcast_to(p, a.shape)
    edges = np.min([point_segment(pp, u, v) for u, v in ((a, b), (b, c), (c, a))], axis=0)
    return np.where(inside, np.abs(h), edges)


def segment_segment(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n,) distances between segments p-q and a-b (each (n, 3)): the least over the square of
    parameters, at its interior critical point or on one of its four sides (each a clamped line)."""
    d1, d2, r = q - p, b - a, p - a
    aa, ee, bb = (np.einsum("ij,ij->i", x, y) for x, y in ((d1, d1), (d2, d2), (d1, d2)))
    cc, ff = np.einsum("ij,ij->i", d1, r), np.einsum("ij,ij->i", d2, r)
    den = aa * ee - bb * bb
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (bb * ff - cc * ee) / den
        t = (aa * ff - bb * cc) / den
    inner = (den > 1e-12 * np.maximum(aa * ee, 1e-300)) & (s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)
    s, t = np.where(inner, s, 0.0), np.where(inner, t, 0.0)
    best = np.where(inner, np.linalg.norm(r + s[:, None] * d1 - t[:, None] * d2, axis=1), np.inf)
    for x, y, u in ((p, q, a), (p, q, b), (a, b, p), (a, b, q)):  # (an end of one to the other)
        best = np.minimum(best, point_segment(u, x, y))
    return best


def segment_triangles(p: np.ndarray, q: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(m,) distances of one segment p-q (3,) from triangles tri (m, 3, 3)."""
    if np.allclose(p, q, rtol=0, atol=0):
        return point_triangles(p, tri)
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    m = len(tri)
    pp, qq = np.broadcast_to(p, (m, 3)), np.broadcast_to(q, (m, 3))
    best = np.minimum(point_triangles(p, tri), point_triangles(q, tri))
    for u, v in ((a, b), (b, c), (c, a)):
        best = np.minimum(best, segment_segment(pp, qq, u, v))
    # crossing: p + s (q - p) = a + u (b - a) + v (c - a), s, u, v >= 0, u + v <= 1, s <= 1
    mat = np.stack([q - p + 0 * a, a - b, a - c], axis=2)
    det = np.linalg.det(mat)
    ok = np.abs(det) > 1e-12
    sol = np.zeros((m, 3))
    sol[ok] = np.linalg.solve(mat[ok], (a - p)[ok][..., None])[..., 0]
    s, u, v = sol.T
    hit = ok & (s >= 0) & (s <= 1) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(hit, 0.0, best)


def brute(tri: np.ndarray, p0: np.ndarray, p1: np.ndarray) -> np.ndarray:
    return np.array([segment_triangles(a, b, tri).min() for a, b in zip(p0, p1, strict=True)])


# -- small meshes ------------------------------------------------------------------------------------

def sheet(nx: int = 24, ny: int = 16) -> SurfaceMesh:
    """A wavy sheet 12 x 8 mm (a grid of quads, each two triangles)."""
    x, y = np.meshgrid(np.linspace(0, 12, nx), np.linspace(0, 8, ny), indexing="ij")
    v = np.stack([x, y, 0.6 * np.sin(x) * np.cos(0.7 * y)], -1).reshape(-1, 3)
    i = (np.arange(nx - 1)[:, None] * ny + np.arange(ny - 1)[None, :]).ravel()
    return SurfaceMesh(v, np.concatenate([np.stack([i, i + ny, i + ny + 1], 1), np.stack([i, i + ny + 1, i + 1], 1)]))


def ellipsoid(n: int = 18) -> SurfaceMesh:
    """A closed ellipsoid 8 x 4 x 1.5 mm (a thin 'blade' with two sides and rounded edges)."""
    th, ph = np.meshgrid(np.linspace(0, np.pi, n), np.linspace(0, 2 * np.pi, 2 * n, endpoint=False), indexing="ij")
    v = np.stack([4 * np.cos(th), 2 * np.sin(th) * np.cos(ph), 0.75 * np.sin(th) * np.sin(ph)], -1).reshape(-1, 3)
    m = 2 * n
    tris = []
    for i in range(n - 1):
        for j in range(m):
            a, b, c, d = i * m + j, i * m + (j + 1) % m, (i + 1) * m + j, (i + 1) * m + (j + 1) % m
            tris += [(a, b, d), (a, d, c)]
    return SurfaceMesh(v, np.array(tris))


def soup(seed: int = 0, count: int = 120) -> SurfaceMesh:
    """Random triangles (some long and thin, some tiny) in a 10 mm box."""
    rng = np.random.default_rng(seed)
    centre = rng.uniform(0, 10, (count, 1, 3))
    size = rng.choice([0.05, 0.5, 2.0], (count, 1, 1))
    v = (centre + size * rng.normal(size=(count, 3, 3))).reshape(-1, 3)
    return SurfaceMesh(v, np.arange(3 * count).reshape(count, 3))


MESHES = {"sheet": sheet, "ellipsoid": ellipsoid, "soup": soup}


@pytest.fixture(scope="module", params=sorted(MESHES))
def case(request):
    mesh = MESHES[request.param]()
    return mesh, DistanceIndex(mesh), np.asarray(mesh.vertices)[np.asarray(mesh.triangles)]


def _queries(rng: np.random.Generator, tri: np.ndarray, n: int, length: float) -> tuple[np.ndarray, np.ndarray]:
    """n random points near and far from the mesh (in order: neighbours near each other, as paths
    are), and segments of up to ``length`` from them."""
    lo, hi = tri.reshape(-1, 3).min(axis=0) - 3.0, tri.reshape(-1, 3).max(axis=0) + 3.0
    walk = np.cumsum(rng.normal(0, 0.2, (n, 3)), axis=0) + rng.uniform(lo, hi)
    jump = rng.uniform(lo, hi, (n, 3))
    p0 = np.where((rng.random(n) < 0.3)[:, None], jump, walk)
    p1 = p0 + rng.normal(0, length, (n, 3)) * (rng.random(n) < 0.8)[:, None]
    return p0, p1


@pytest.mark.parametrize("length", [0.0, 0.3, 3.0])
def test_exact_within_the_cutoff_and_a_lower_bound_beyond(case, length):
    mesh, index, tri = case
    rng = np.random.default_rng(int(length * 10) + len(tri))
    p0, p1 = _queries(rng, tri, 300, length)
    truth = brute(tri, p0, p1)
    for cutoff in (0.2, 1.0, 4.0, 1e9):
        got = index.distances(p0, p1, cutoff)
        near = truth <= cutoff
        np.testing.assert_allclose(got[near], truth[near], rtol=0, atol=EXACT)
        assert (got[~near] <= truth[~near] + EXACT).all(), "a lower bound above the true distance"
        assert (got[~near] >= cutoff).all(), "beyond the cutoff, but reported within it"
    # (the same queries one by one, and in reverse order: the start from the last nearest is no part
    # of the answer)
    back = index.distances(p0[::-1], p1[::-1], 4.0)[::-1]
    np.testing.assert_allclose(np.minimum(back, 4.0), np.minimum(index.distances(p0, p1, 4.0), 4.0), rtol=0,
                               atol=EXACT)


def test_points_close_together_each_from_the_last_ones_nearest(case):
    """Points a ball's row and the middle of its move apart: each search starts from the triangle
    nearest the point before (the hint), which must not change the answer."""
    _, index, tri = case
    rng = np.random.default_rng(7)
    p, _ = _queries(rng, tri, 200, 0.0)
    # (and along a line, as a ball's rows go: each pair starts from the last one's nearest triangle)
    lo, hi = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    line = lo - 0.5 + np.linspace(0.0, 1.0, 200)[:, None] * (hi - lo + 1.0)
    p = np.concatenate([p, line + [0.0, 0.0, 0.9]])
    both = np.repeat(p, 2, axis=0) + np.tile([[0.0, 0, 0], [0.1, -0.05, 0.2]], (len(p), 1))
    truth = brute(tri, both, both)
    for cutoff in (0.5, 3.0):
        got = index.distances(both, cutoff=cutoff)
        near = truth <= cutoff
        np.testing.assert_allclose(got[near], truth[near], rtol=0, atol=EXACT)
        assert (got[~near] <= truth[~near] + EXACT).all() and (got[~near] >= cutoff).all()


def test_the_coarse_field_is_never_above_the_distance(case):
    _, index, tri = case
    p0, p1 = _queries(np.random.default_rng(5), tri, 300, 2.0)
    assert (index.field_bounds(p0, p1) <= brute(tri, p0, p1) + EXACT).all()
    far = tri.reshape(-1, 3).max(axis=0) + np.array([[40.0, 0, 0], [0, 60.0, 0], [0, 0, -80.0]])
    assert (index.field_bounds(far) > 30).all()  # (far off: the field alone says so)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-6.0, 16.0), min_size=6, max_size=6), st.floats(0.05, 5.0))
def test_any_segment_near_the_sheet(ends, cutoff):
    p0, p1 = np.array([ends[:3]]), np.array([ends[3:]])
    truth = brute(SHEET_TRI, p0, p1)[0]
    got = SHEET.distances(p0, p1, cutoff)[0]
    assert (abs(got - truth) <= EXACT) if truth <= cutoff else (cutoff <= got <= truth + EXACT)


SHEET_MESH = sheet()
SHEET = DistanceIndex(SHEET_MESH)
SHEET_TRI = np.asarray(SHEET_MESH.vertices)[np.asarray(SHEET_MESH.triangles)]


def test_a_point_on_a_triangle_and_a_segment_through_one_are_at_zero():
    corner = SHEET_TRI[37, 1]
    centre = SHEET_TRI[40].mean(axis=0)
    normal = np.cross(SHEET_TRI[40, 1] - SHEET_TRI[40, 0], SHEET_TRI[40, 2] - SHEET_TRI[40, 0])
    normal /= np.linalg.norm(normal)
    got = SHEET.distances(np.array([corner, centre - normal]), np.array([corner, centre + normal]), 1.0)
    np.testing.assert_allclose(got, 0.0, atol=EXACT)


def test_segment_gaps_in_closed_form():
    rng = np.random.default_rng(2)
    a0, a1, b0, b1 = rng.normal(0, 3, (4, 500, 3))
    # parallel, collinear, crossing and degenerate (point) segments among them
    b0[:50], b1[:50] = a0[:50] + [0, 0, 1], a1[:50] + [0, 0, 1]
    b0[50:80], b1[50:80] = a0[50:80] + 0.5 * (a1[50:80] - a0[50:80]), a1[50:80] + 2 * (a1[50:80] - a0[50:80])
    b1[80:100] = b0[80:100]
    a1[100:110] = a0[100:110]
    np.testing.assert_allclose(segment_gaps(a0, a1, b0, b1), segment_segment(a0, a1, b0, b1), rtol=0, atol=1e-9)


def _box_truth(p0: np.ndarray, p1: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The least box distance along each segment by ternary search (the distance is convex on it)."""
    def f(s):
        x = p0 + s[:, None] * (p1 - p0)
        return np.linalg.norm(np.maximum(np.maximum(lo - x, x - hi), 0.0), axis=1)

    a, b = np.zeros(len(p0)), np.ones(len(p0))
    for _ in range(200):
        m1, m2 = a + (b - a) / 3, b - (b - a) / 3
        left = f(m1) <= f(m2)
        a, b = np.where(left, a, m1), np.where(left, m2, b)
    return np.minimum(f(0.5 * (a + b)), np.minimum(f(np.zeros(len(p0))), f(np.ones(len(p0)))))


def test_box_gaps_in_closed_form():
    rng = np.random.default_rng(3)
    p0, p1 = rng.normal(0, 20, (2, 400, 3))
    lo, hi = np.array([-np.inf, -5.0, -2.0]), np.array([3.0, 8.0, 2.0])
    np.testing.assert_allclose(box_gaps(p0, p1, lo, hi), _box_truth(p0, p1, np.maximum(lo, -1e9), hi), atol=1e-7)


# -- sweeps along rows ------------------------------------------------------------------------------

def _rows(n: int = 400, seed: int = 0):
    """A tool above the sheet: ball centres wandering 0.5 to 2.5 mm over it, axes tilting."""
    rng = np.random.default_rng(seed)
    s = np.linspace(0, 1, n)
    c = np.column_stack([1 + 10 * s, 4 + 3 * np.sin(7 * s), 0.6 + 1.4 * (1 + np.sin(23 * s)) / 2 - 0.3])
    c += rng.normal(0, 0.01, c.shape)
    w = np.column_stack([0.4 * np.sin(5 * s), 0.3 * np.cos(3 * s), np.ones(n)])
    return c, w / np.linalg.norm(w, axis=1, keepdims=True)


@pytest.mark.parametrize("rows", [400, 60])
@pytest.mark.parametrize("part", [(0.5, 3.0, 0.8), (2.0, 12.0, 1.5), (-1.0, 1.0, 0.3)])
def test_a_sweep_bounds_every_row_and_measures_every_collision(part, rows):
    c, w = _rows(rows)
    s0, s1, r = part
    truth = brute(SHEET_TRI, c + s0 * w, c + s1 * w) - r
    moved = reach(motion(c, w), max(abs(s0), abs(s1)))
    for exact, cap in ((0.5, 0.25), (2.0, 2.0)):
        values, measured = SHEET.sweep(c, w, part, moved, exact, cap, TOLERANCE)
        values = bounded(values, measured, moved)
        assert (values <= truth + EXACT).all(), "a row bounded above its clearance"
        hit = truth < -TOLERANCE
        assert measured[hit].all() and np.allclose(values[hit], truth[hit], atol=EXACT)
        if truth.min() < cap:
            assert abs(values.min() - truth.min()) <= EXACT, "the least clearance below the cap is exact"
        floor = max(min(values[measured].min(), cap), -TOLERANCE)
        assert (values[~measured] >= floor - EXACT).all(), "a row left unmeasured whose bound is below the floor"
        assert rows < 400 or measured.sum() < len(c)  # (rows close together: it does skip some)


def test_the_motion_bound_holds_between_rows():
    c, w = _rows(60)
    for s in (0.0, 3.0, 40.0):
        bound = np.diff(reach(motion(c, w), s))
        rows = np.repeat(np.arange(59), 7)
        frac = np.tile(np.linspace(0, 1, 7), 59)
        cb, wb = poses_between(c, w, rows, frac)
        moved = np.linalg.norm(cb + s * wb - (c[rows] + s * w[rows]), axis=1)
        assert (moved <= bound[rows] + 1e-12).all()
    np.testing.assert_allclose(turns(np.array([[0, 0, 1.0], [0, 1.0, 0], [0, 1.0, 0]])), [np.pi / 2, 0.0])


def test_a_collision_only_between_two_rows_is_found():
    """A thin spike of the mesh between two rows of a capsule that clears it at both rows."""
    spike = SurfaceMesh(np.array([[0.0, -0.05, 0], [0.0, 0.05, 0], [0.0, 0.0, 5.0]]), np.array([[0, 1, 2]]))
    index = DistanceIndex(spike)
    c = np.array([[-1.2, 0, 1.0], [1.2, 0, 1.0], [3.6, 0, 1.0]])
    w = np.tile([0.0, 0.0, 1.0], (3, 1))
    part = (0.0, 2.0, 0.5)
    moved = reach(motion(c, w), 2.0)
    values, measured = index.sweep(c, w, part, moved, 1.0, 0.5, TOLERANCE)
    assert (values > 0).all()

    def at(rows, frac):
        cb, wb = poses_between(c, w, rows, frac)
        return index.distances(cb, cb + 2.0 * wb, 1.5) - 0.5

    hidden = between_rows(bounded(values, measured, moved), moved, at)
    runs = stretches(values, hidden)
    assert len(runs) == 1 and runs[0].between and runs[0].row == 0 and runs[0].depth == pytest.approx(0.5, abs=1e-6)


def test_pair_and_box_sweeps_against_their_closed_forms():
    cl, wl = _rows(300, 1)
    cr, wr = cl + np.array([0.0, 0.0, 9.0]) + np.random.default_rng(4).normal(0, 0.5, cl.shape), -wl
    a, b = (0.5, 6.0, 1.5), (0.5, 6.0, 2.0)
    truth = segment_segment(cl + a[0] * wl, cl + a[1] * wl, cr + b[0] * wr, cr + b[1] * wr) - a[2] - b[2]
    moved = reach(motion(cl, wl), 6.0) + reach(motion(cr, wr), 6.0)
    got = pair_sweeps((cl, cr), (wl, wr), (a, b), moved, 50.0, TOLERANCE)
    assert (got <= truth + EXACT).all() and abs(got.min() - truth.min()) <= EXACT
    box = (np.array([-np.inf, -1.0, -0.5]), np.array([4.0, 9.0, 0.5]))
    t2 = _box_truth(cl + a[0] * wl, cl + a[1] * wl, np.array([-1e9, -1.0, -0.5]), box[1]) - a[2]
    got = box_sweeps(cl, wl, a, box, reach(motion(cl, wl), 6.0), 50.0, TOLERANCE)
    assert (got <= t2 + 1e-7).all() and abs(got.min() - t2.min()) <= 1e-7


def test_the_moves_between_rows_measured_only_where_they_could_matter():
    """core.verify.cutters._track measures a point of a move only where its bound from the two rows
    allows a dip or a new least: its findings and least clearance are those of measuring every one."""
    rng = np.random.default_rng(11)
    n, r, dip = 400, 0.5, 0.004
    s = np.linspace(0, 1, n)
    tips = np.column_stack([1 + 10 * s, 4 + 3 * np.sin(9 * s), np.zeros(n)])
    tips[:, 2] = 0.6 * np.sin(tips[:, 0]) * np.cos(0.7 * tips[:, 1]) + rng.normal(0.05, 0.03, n)  # (about on it)
    axes = np.tile([0.0, 0.0, 1.0], (n, 1))
    cl = {"p": tips, "w": axes, "cutting": rng.random(n) < 0.8}
    got = _track(cl, r, SHEET, 1, dip)
    c = tips + r * axes
    mid = c[got["seg"]] + 0.5 * (c[got["seg"] + 1] - c[got["seg"]])  # (one point per move: all short here)
    truth = brute(SHEET_TRI, mid, mid) - r
    assert (got["moves"] - r <= truth + EXACT).all()
    deep = truth < -dip
    np.testing.assert_allclose(got["moves"][deep] - r, truth[deep], atol=EXACT)
    assert ((got["moves"] - r < -dip) == deep).all()
    assert abs((got["moves"] - r).min() - truth.min()) <= EXACT
    rows = brute(SHEET_TRI, c, c)
    near = rows <= r + BALL_EXACT  # (exact up to there, a lower bound beyond)
    np.testing.assert_allclose(got["rows"][near], rows[near], atol=EXACT)
    assert (got["rows"][~near] <= rows[~near] + EXACT).all() and (got["rows"][~near] >= r + BALL_EXACT).all()


def test_distinct_corners_keep_every_point_once_in_first_order():
    """blade.stl's corners are measured once each (core.verify.assembly._distinct): every distinct point
    is kept, in the order of its first appearance, repeats dropped (-0.0 and 0.0 may both stay)."""
    from core.verify.assembly import _distinct

    rng = np.random.default_rng(7)
    base = rng.normal(size=(500, 3)).round(2)
    points = base[rng.integers(0, len(base), 4000)]
    got = _distinct(points)
    _, first = np.unique(points, axis=0, return_index=True)
    assert np.array_equal(got, points[np.sort(first)])

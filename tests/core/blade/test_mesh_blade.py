"""MeshBlade: a blade from one closed mesh or from two open surfaces (core.blade.mesh)."""

from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.interpolate import CubicSpline

from core.blade.mesh import RESAMPLE_STEP, fix_winding, load_mesh_blade, read_mesh
from core.blade.model import chord_frame, section_chord, section_max_thickness, section_pitch_angle
from core.errors import BladeInputError
from core.paths.tessellation import closest_point_distance

REPO = Path(__file__).resolve().parents[3]
BLADEX = REPO.parent / "shared" / "data" / "bladex-test-blade"

# synthetic blade: elliptic sections, linear chord and thickness, constant pitch (twisted), r 20..100
R0, R1, PITCH = 20.0, 100.0, 150.0


def chord_of(r):
    return 60.0 - 0.25 * (r - R0)


def thick_of(r):
    return 8.0 - 0.06 * (r - R0)


def blade_grid(n_r=81, n_s=160, theta0_deg=0.0):
    """(n_r, n_s, 3) points of the synthetic blade, blade frame; column 0 is the LE, n_s/2 the TE,
    columns 1..n_s/2-1 the face (right of the chord LE -> TE: larger z), the others the back."""
    r = np.linspace(R0, R1, n_r)[:, None]
    s = np.linspace(0.0, 2 * np.pi, n_s, endpoint=False)[None, :]
    phi = np.arctan(PITCH / (2 * np.pi * r))
    u, v = 0.5 * chord_of(r) * np.cos(s), 0.5 * thick_of(r) * np.sin(s)
    a = u * np.cos(phi) - v * np.sin(phi)  # e_c = (cos, sin) to the LE, e_face = (-sin, cos)
    z = u * np.sin(phi) + v * np.cos(phi)
    th = a / r + np.radians(theta0_deg)
    return np.stack([r * np.cos(th) + 0 * s, r * np.sin(th) + 0 * s, z + 0 * r], axis=-1)


def grid_faces(n_r, n_cols, wrap):
    i, j = np.meshgrid(np.arange(n_r - 1), np.arange(n_cols if wrap else n_cols - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    j1 = (j + 1) % n_cols
    a, b, c, d = i * n_cols + j, i * n_cols + j1, (i + 1) * n_cols + j, (i + 1) * n_cols + j1
    return np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])


def closed_blade_mesh(theta0_deg=0.0, n_r=81, n_s=160):
    g = blade_grid(n_r, n_s, theta0_deg)
    verts = g.reshape(-1, 3)
    faces = grid_faces(n_r, n_s, wrap=True)
    caps = []
    for row, flip in ((0, True), (n_r - 1, False)):  # fan from the section centre on the cylinder
        centre = len(verts) + len(caps)
        caps.append(g[row].mean(axis=0))
        ring = row * n_s + np.arange(n_s)
        tri = np.column_stack([np.full(n_s, centre), ring, np.roll(ring, -1)])
        faces = np.concatenate([faces, tri[:, ::-1] if flip else tri])
    caps = np.array(caps)
    caps[:, :2] *= (np.array([R0, R1]) / np.hypot(caps[:, 0], caps[:, 1]))[:, None]
    return trimesh.Trimesh(np.concatenate([verts, caps]), faces, process=True)


def export(mesh, path):
    mesh.export(path)
    return path


@pytest.fixture(scope="module")
def bladex():
    if not (BLADEX / "upper.stl").is_file():
        pytest.skip("shared BladeX data not present")
    return load_mesh_blade([BLADEX / "upper.stl", BLADEX / "lower.stl"], axis="x")


@pytest.fixture(scope="module")
def closed_stl(tmp_path_factory):
    return export(closed_blade_mesh(theta0_deg=40.0), tmp_path_factory.mktemp("mesh") / "blade.stl")


def check_section(s, r, step=RESAMPLE_STEP):
    for pts in (s.face, s.back):
        assert len(pts) >= 3
        assert np.max(np.abs(np.hypot(pts[:, 0], pts[:, 1]) - r)) < 1e-9
        assert np.linalg.norm(np.diff(pts, axis=0), axis=1).max() <= step  # resampled along the facets
    np.testing.assert_array_equal(s.face[0], s.back[0])
    np.testing.assert_array_equal(s.face[-1], s.back[-1])
    for n in (s.face_normals, s.back_normals):
        np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    assert s.face_normals.shape == s.face.shape and s.back_normals.shape == s.back.shape
    # LE: the end with the larger r * theta; the face lies right of the back (smaller v in the chord
    # frame; a strongly cambered section may have both sides right of the chord line)
    th = np.arctan2(s.face[[0, -1], 1], s.face[[0, -1], 0])
    assert th[0] > th[1]
    fuv, buv, chord = chord_frame(s)
    assert np.mean(fuv[1:-1, 1]) < np.mean(buv[1:-1, 1])


def outward_share(s):
    """Share of the inner points (10..90 % chord) whose normal points away from the nearest point of
    the other side: (face, back)."""
    fuv, buv, chord = chord_frame(s)
    out = []
    for pts, nrm, uv, other in ((s.face, s.face_normals, fuv, s.back), (s.back, s.back_normals, buv, s.face)):
        inner = (uv[:, 0] > 0.1 * chord) & (uv[:, 0] < 0.9 * chord)
        d = np.linalg.norm(pts[inner, None, :] - other[None, :, :], axis=2)
        away = pts[inner] - other[np.argmin(d, axis=1)]
        out.append(float(np.mean(np.einsum("ij,ij->i", nrm[inner], away) > 0)))
    return out


# ---------------------------------------------------------------- BladeX, two open surfaces


def test_bladex_hub_and_tip(bladex):
    assert bladex.tip_radius == pytest.approx(125.0, rel=1e-3)
    assert bladex.hub_radius == pytest.approx(34.375, rel=1e-3)
    assert not bladex.closed and bladex.warnings == []  # upper.stl lies on the face side


@pytest.mark.parametrize("frac", [0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 0.99, 1.0])
def test_bladex_sections(bladex, frac):
    r = bladex.hub_radius + frac * (bladex.tip_radius - bladex.hub_radius)
    s = bladex.section(r)
    check_section(s, r)
    if 0.05 < frac < 0.95:
        assert outward_share(s) == [1.0, 1.0]


def test_bladex_chord_and_thickness(bladex):
    s = bladex.section(0.5 * bladex.tip_radius)
    assert 60.0 < section_chord(s) < 100.0  # 81 mm measured
    assert 4.0 < section_max_thickness(s) < 12.0  # 8.1 mm measured
    info = bladex.info()
    assert info["chord_mm"]["0.2"] is None  # 0.2 R = 25 mm lies inside the hub
    assert info["chord_mm"]["0.95"] > 0 and info["max_thickness_mm"]["0.95"] > 0


def test_bladex_reversed_pair_is_kept_and_noted():
    if not (BLADEX / "upper.stl").is_file():
        pytest.skip("shared BladeX data not present")
    b = load_mesh_blade([BLADEX / "lower.stl", BLADEX / "upper.stl"], axis="x")
    assert len(b.warnings) == 1 and "lower.stl" in b.warnings[0]
    s = b.section(80.0)
    fuv, buv, _ = chord_frame(s)
    assert np.mean(fuv[1:-1, 1]) > np.mean(buv[1:-1, 1])  # the first file stays the face, left side
    assert outward_share(s) == [1.0, 1.0]  # normals still outward


def test_bladex_same_blade_with_origin_and_axis_y(tmp_path, bladex):
    origin = np.array([5.0, -7.0, 3.0])
    paths = []
    for name in ("upper.stl", "lower.stl"):
        m = trimesh.load(BLADEX / name)
        m.vertices = m.vertices[:, [1, 0, 2]] * [1, 1, -1] + origin  # axis x -> y (a proper rotation)
        paths.append(export(m, tmp_path / name))
    b = load_mesh_blade(paths, axis="y", origin=origin)
    for r in (50.0, 90.0):
        assert section_chord(b.section(r)) == pytest.approx(section_chord(bladex.section(r)), rel=1e-6)


# ---------------------------------------------------------------- synthetic closed blade


def test_closed_blade_chord_thickness_pitch(closed_stl):
    b = load_mesh_blade(closed_stl)
    assert b.closed and b.hub_radius == pytest.approx(R0, abs=1e-6) and b.tip_radius == pytest.approx(R1)
    for r in (R0, 25.3, 45.0, 61.7, 80.0, 95.5, R1):
        s = b.section(r)
        check_section(s, r)
        rr = min(max(r, R0 + 0.08), R1 - 0.08)  # the hub and tip are cut 1e-3 span inside
        assert section_chord(s) == pytest.approx(chord_of(rr), rel=0.01)
        assert section_max_thickness(s) == pytest.approx(thick_of(rr), rel=0.01)
        phi = np.degrees(np.arctan(PITCH / (2 * np.pi * rr)))
        assert section_pitch_angle(s) == pytest.approx(phi, abs=0.2)
        assert outward_share(s) == [1.0, 1.0]


def test_closed_blade_frame_puts_centroid_on_x(closed_stl):
    s = load_mesh_blade(closed_stl).section(60.0)
    theta = np.degrees(np.arctan2(s.face[:, 1], s.face[:, 0]))
    assert abs(0.5 * (theta.max() + theta.min())) < 2.0  # built at 40 degrees, turned back to 0


def test_closed_blade_normals_point_out_of_the_section():
    b = load_mesh_blade_from(closed_blade_mesh(), "z")
    s = b.section(50.0)
    centre = 0.5 * (s.leading_edge + s.trailing_edge)
    for pts, nrm in ((s.face, s.face_normals), (s.back, s.back_normals)):
        assert np.all(np.einsum("ij,ij->i", nrm, pts - centre) > 0)


def load_mesh_blade_from(mesh, axis, origin=(0, 0, 0), tmp=None):
    import tempfile

    d = Path(tmp or tempfile.mkdtemp())
    return load_mesh_blade(export(mesh, d / "m.stl"), axis=axis, origin=origin)


def test_closed_blade_axis_y_and_origin(tmp_path):
    m = closed_blade_mesh()
    origin = np.array([10.0, 20.0, -30.0])
    m2 = m.copy()
    m2.vertices = m.vertices[:, [1, 2, 0]] + origin  # blade (X, Y, Z) -> file (z, x, y): axis y
    bz = load_mesh_blade(export(m, tmp_path / "z.ply"))
    by = load_mesh_blade(export(m2, tmp_path / "y.obj"), axis="y", origin=origin)
    for r in (30.0, 70.0):
        assert section_chord(by.section(r)) == pytest.approx(section_chord(bz.section(r)), rel=1e-6)
        assert section_chord(by.section(r)) == pytest.approx(chord_of(r), rel=0.01)


def test_closed_blade_with_inconsistent_winding(tmp_path):
    m = closed_blade_mesh()
    faces = m.faces.copy()
    faces[::3] = faces[::3, ::-1]
    bad = trimesh.Trimesh(m.vertices, faces, process=False)
    assert not bad.is_winding_consistent
    fixed = bad.copy()
    fix_winding(fixed)
    assert fixed.is_winding_consistent
    s = load_mesh_blade(export(bad, tmp_path / "bad.stl")).section(60.0)
    assert outward_share(s) == [1.0, 1.0]


def test_two_surfaces_of_the_synthetic_blade(tmp_path):
    n_r, n_s = 81, 160
    g = blade_grid(n_r, n_s)
    half = n_s // 2
    face = g[:, : half + 1].reshape(-1, 3)  # LE .. TE through the face
    back = np.concatenate([g[:, half:], g[:, :1]], axis=1).reshape(-1, 3)  # TE .. LE through the back
    fp = export(trimesh.Trimesh(face, grid_faces(n_r, half + 1, wrap=False)), tmp_path / "face.stl")
    bp = export(trimesh.Trimesh(back, grid_faces(n_r, n_s - half + 1, wrap=False)), tmp_path / "back.stl")
    b = load_mesh_blade([fp, bp])
    assert b.warnings == []
    for r in (30.0, 60.0, 90.0):
        s = b.section(r)
        check_section(s, r)
        assert section_chord(s) == pytest.approx(chord_of(r), rel=0.01)
        assert section_max_thickness(s) == pytest.approx(thick_of(r), rel=0.01)
        assert outward_share(s) == [1.0, 1.0]


# ---------------------------------------------------------------- resampling along the facets


def blade_frame_facets(blade, paths):
    """Triangles (T, 3, 3) mm and unit normals (T, 3) of the blade's mesh files in the blade frame,
    the normals of each file turned to agree with the blade's section normals (its outward side)."""
    tris, normals = [], []
    s = blade.section(0.5 * (blade.hub_radius + blade.tip_radius))
    probe = np.concatenate([s.face, s.back])[::20]
    probe_n = np.concatenate([s.face_normals, s.back_normals])[::20]
    for p in paths:
        m = read_mesh(p)
        t = (m.vertices @ blade.transform[:3, :3].T + blade.transform[:3, 3])[m.faces]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        d = point_triangle_distances(probe, t)
        mine = d.min(axis=1) < 1e-6
        if np.einsum("ij,ij->", probe_n[mine], n[d[mine].argmin(axis=1)]) < 0:
            n = -n
        tris.append(t)
        normals.append(n)
    return np.concatenate(tris), np.concatenate(normals)


def point_triangle_distances(points, tris):
    """(n, T) exact distances (mm) from points (n, 3) to triangles (T, 3, 3), in blocks of points."""
    out = []
    for start in range(0, len(points), 64):
        p = points[start:start + 64]
        n, t = len(p), len(tris)
        corners = [np.tile(tris[:, k], (n, 1)) for k in range(3)]
        out.append(closest_point_distance(np.repeat(p, t, axis=0), *corners).reshape(n, t))
    return np.concatenate(out)


@pytest.fixture(scope="module")
def coarse_blade(tmp_path_factory):
    """A coarse closed blade (rows 10 mm apart, 32 points round a section): long facets, corners of
    several degrees, and long row edges that dip inside a cylinder just below their row."""
    p = export(closed_blade_mesh(n_r=9, n_s=32), tmp_path_factory.mktemp("coarse") / "coarse.stl")
    b = load_mesh_blade(p)
    return b, *blade_frame_facets(b, [p])


def on_facets(pts, tris, tol=1e-8):
    """(n, T) bool: the triangles each point lies on."""
    return point_triangle_distances(pts, tris) <= tol


@pytest.mark.parametrize("r", [25.3, 29.99, 45.7, 77.7])
def test_points_lie_on_the_facets_densely(coarse_blade, r):
    b, tris, _ = coarse_blade
    s = b.section(r)
    check_section(s, r)
    for pts in (s.face, s.back):
        assert on_facets(pts, tris).any(axis=1).all()  # 29.99: also across the dipping row edges


@pytest.mark.parametrize("r", [25.3, 29.99, 45.7, 77.7])
def test_a_cubic_spline_through_a_section_stays_on_the_facets(coarse_blade, r):
    b, tris, _ = coarse_blade
    s = b.section(r)
    for pts in (s.face, s.back):
        t = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        mid = CubicSpline(t, pts)(0.5 * (t[1:] + t[:-1]))  # not-a-knot, as the planner fits
        assert point_triangle_distances(mid, tris).min(axis=1).max() < 1e-3


def check_facet_normals(s, step, tris, normals, edges_min=10):
    """Inside a facet, farther than `step` from its edges (beyond any ramp), a point has the facet's
    normal; on an edge the normalised mean of its two facets' normals, except at a side's ends (LE and
    TE), which keep their own side's facet (the one their neighbour lies on); on the ramp between, a
    normal no farther from the facet's than the edge's. Returns the number of points checked inside
    facets."""
    checked = 0
    for pts, nrm in ((s.face, s.face_normals), (s.back, s.back_normals)):
        on = on_facets(pts, tris)
        count = on.sum(axis=1)
        edge, inner = np.flatnonzero(count == 2), np.flatnonzero(count == 1)
        assert edge.size >= edges_min
        for i in edge:
            if i in (0, len(pts) - 1):
                own = np.flatnonzero(on[i] & on[1 if i == 0 else len(pts) - 2])
                assert any(np.allclose(nrm[i], normals[k], atol=1e-9) for k in own)
                continue
            mean = normals[on[i]].sum(axis=0)
            np.testing.assert_allclose(nrm[i], mean / np.linalg.norm(mean), atol=1e-9)
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
        gap = np.abs(arc[inner, None] - arc[None, edge])
        facet = normals[np.argmax(on[inner], axis=1)]
        far = gap.min(axis=1) > step
        np.testing.assert_allclose(nrm[inner[far]], facet[far], atol=1e-9)
        nearest = edge[gap.argmin(axis=1)]
        off = np.arccos(np.clip(np.einsum("ij,ij->i", nrm[inner], facet), -1.0, 1.0))
        ramp = np.arccos(np.clip(np.einsum("ij,ij->i", nrm[nearest], facet), -1.0, 1.0))
        assert np.all(off <= ramp + 1e-9)
        checked += int(far.sum())
    return checked


@pytest.mark.parametrize("r", [25.3, 45.7, 77.7])
def test_normals_are_the_facet_normals(coarse_blade, r):
    b, tris, normals = coarse_blade
    s = b.section(r)
    assert check_facet_normals(s, b.step, tris, normals) > 0.5 * (len(s.face) + len(s.back))


def test_bladex_normals_are_the_facet_normals(bladex):
    tris, normals = blade_frame_facets(bladex, [BLADEX / "upper.stl", BLADEX / "lower.stl"])
    for r in (40.0, 80.0, 115.0):
        s = bladex.section(r)
        # points of the LE and TE pieces lie off the facets (the sides' ends are averaged): not counted
        assert check_facet_normals(s, bladex.step, tris, normals) > 0.5 * (len(s.face) + len(s.back))


# ---------------------------------------------------------------- bad input


def raises_naming(name, fn, match=None):
    with pytest.raises(BladeInputError, match=match) as exc:
        fn()
    assert name in str(exc.value)
    return str(exc.value)


def test_missing_empty_garbage_unsupported(tmp_path):
    raises_naming("nope.stl", lambda: load_mesh_blade(tmp_path / "nope.stl"), "not found")
    (tmp_path / "empty.stl").write_bytes(b"")
    raises_naming("empty.stl", lambda: load_mesh_blade(tmp_path / "empty.stl"), "empty")
    (tmp_path / "garbage.stl").write_text("hello, I am not a mesh\n")
    raises_naming("garbage.stl", lambda: load_mesh_blade(tmp_path / "garbage.stl"), "not a readable")
    (tmp_path / "noise.ply").write_bytes(np.random.default_rng(1).bytes(500))
    raises_naming("noise.ply", lambda: load_mesh_blade(tmp_path / "noise.ply"), "not a readable")
    (tmp_path / "blade.step").write_text("ISO-10303-21;")
    raises_naming("blade.step", lambda: load_mesh_blade(tmp_path / "blade.step"), "unsupported")
    (tmp_path / "points.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n")
    raises_naming("points.obj", lambda: load_mesh_blade(tmp_path / "points.obj"), "no triangles")


def test_too_many_files(tmp_path, closed_stl):
    raises_naming("blade.stl", lambda: load_mesh_blade([closed_stl] * 3), "got 3 files")


def test_open_surface_as_one_closed_blade(tmp_path):
    g = blade_grid(41, 160)[:, :81].reshape(-1, 3)
    p = export(trimesh.Trimesh(g, grid_faces(41, 81, wrap=False)), tmp_path / "half.stl")
    raises_naming("half.stl", lambda: load_mesh_blade(p), "not a closed")


def test_axis_through_the_mesh(tmp_path):
    m = closed_blade_mesh()
    m.apply_translation([-60.0, 0.0, 0.0])  # the z axis now pierces the section at r = 60
    p = export(m, tmp_path / "pierced.stl")
    raises_naming("pierced.stl", lambda: load_mesh_blade(p), "axis 'z'")
    rod = trimesh.creation.box(extents=(1e-3, 1e-3, 50.0))  # all radii the same, near zero
    p = export(rod, tmp_path / "rod.stl")
    raises_naming("rod.stl", lambda: load_mesh_blade(p), "spans no radius")


def test_mesh_far_from_axis(tmp_path):
    m = closed_blade_mesh()
    m.apply_translation([1000.0, 0.0, 0.0])
    b = load_mesh_blade(export(m, tmp_path / "far.stl"))
    assert b.hub_radius > 900
    raises_naming("far.stl", lambda: b.section(60.0), "outside the blade")


def test_no_surface_at_radius(tmp_path):
    cube = trimesh.creation.box(extents=(5.0, 5.0, 5.0))
    cube.apply_translation([300.0, 0.0, 0.0])
    m = trimesh.util.concatenate([closed_blade_mesh(), cube])
    p = export(m, tmp_path / "gap.stl")
    raises_naming("gap.stl", lambda: load_mesh_blade(p).section(200.0), "no blade surface at r = ")


def test_two_surfaces_that_do_not_meet(tmp_path):
    g = blade_grid(41, 160)[:, :81]
    faces = grid_faces(41, 81, wrap=False)
    a = export(trimesh.Trimesh(g.reshape(-1, 3), faces), tmp_path / "a.stl")
    b = export(trimesh.Trimesh((g + [0.0, 0.0, -40.0]).reshape(-1, 3), faces), tmp_path / "b.stl")
    raises_naming("a.stl + b.stl", lambda: load_mesh_blade([a, b]), "do not meet")

"""The whole-tool collision check (core.machine.clearance, core.machine.tool): the distance
computation against hand-computed cases, the sweep along rows against evaluating every row, and the
tool file's loading and errors."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from core.errors import ToolError
from core.machine.clearance import (
    EXACT_MM,
    Clamp,
    MeshGrid,
    clearance,
    part_blade,
    part_clamp,
    part_pair,
    sweep,
)
from core.machine.collisions import check_rows
from core.machine.model import load_machine
from core.machine.tool import Part, assembly, load_tool, parse_tool, tool_to_toml
from core.paths.tessellation import SurfaceMesh, TriangleIndex, closest_point_distance


def plane_index(size: float = 50.0) -> TriangleIndex:
    """The plane z = 0 as two triangles of a square (-size..size)^2."""
    v = np.array([[-size, -size, 0.0], [size, -size, 0.0], [size, size, 0.0], [-size, size, 0.0]])
    return TriangleIndex(SurfaceMesh(v, np.array([[0, 1, 2], [0, 2, 3]])), k=8)


def axis(deg: float) -> np.ndarray:
    """A unit axis at ``deg`` degrees from +z towards +x."""
    a = math.radians(deg)
    return np.array([[math.sin(a), 0.0, math.cos(a)]])


NECK = Part("neck", 1.5, 0.75, 12.0)


def test_golden_capsule_over_a_plane():
    """Hand-computed: the neck's capsule over the plane z = 0 from a ball centre at z = 2. Tilted 60
    degrees, its lowest axis point is its lower end, 2 + 0.75 cos 60 = 2.375 above the plane: clearance
    0.875. Tilted past horizontal so that its upper end is 1.52 above the plane (cos t = -0.04): 0.02.
    Tilted 100 degrees it crosses the plane: -1.5. From 30 mm up, straight up: 30.75 - 1.5, a lower
    bound above EXACT_MM, exact when asked to be."""
    index, c = plane_index(), np.array([[0.0, 0.0, 2.0]])
    assert part_blade(NECK, index, c, axis(60.0))[0] == pytest.approx(0.875, abs=1e-9)
    w = np.array([[math.sqrt(1 - 0.04 ** 2), 0.0, -0.04]])
    assert part_blade(NECK, index, c, w)[0] == pytest.approx(0.02, abs=1e-9)
    assert part_blade(NECK, index, c, axis(100.0))[0] == pytest.approx(-1.5, abs=1e-9)
    assert clearance([NECK], index, c, axis(100.0))["neck"][0] == pytest.approx(-1.5, abs=1e-9)
    high = np.array([[0.0, 0.0, 30.0]])
    low = part_blade(NECK, index, high, axis(0.0))[0]
    assert EXACT_MM <= low <= 29.25 + 1e-9
    assert part_blade(NECK, index, high, axis(0.0), exact_below=40.0)[0] == pytest.approx(29.25, abs=1e-9)


def wavy_mesh(n: int = 15) -> SurfaceMesh:
    """A wavy sheet 20 x 15 mm, z = 2 sin(x / 3) cos(y / 4), as n x n vertices."""
    x, y = np.meshgrid(np.linspace(0, 20, n), np.linspace(0, 15, n))
    v = np.column_stack([x.ravel(), y.ravel(), (2 * np.sin(x / 3) * np.cos(y / 4)).ravel()])
    a = (np.arange(n - 1)[:, None] * n + np.arange(n - 1)[None, :]).ravel()
    tri = np.concatenate([np.column_stack([a, a + 1, a + n + 1]), np.column_stack([a, a + n + 1, a + n])])
    return SurfaceMesh(v, tri)


def test_segment_distances_against_brute_force():
    """MeshGrid's exact segment distances against the least point-to-triangle distance over every
    triangle at 401 points along each segment (the distance is 1-Lipschitz along it: that least lies
    within half a spacing above the segment's), and its grid bound below them, for random segments
    (points among them) in and around a wavy sheet, cut off where asked."""
    mesh = wavy_mesh()
    grid = MeshGrid(TriangleIndex(mesh, k=8))
    v, t = mesh.vertices, mesh.triangles
    rng = np.random.default_rng(1)
    p0 = rng.uniform([-3, -3, -4], [23, 18, 5], (40, 3))
    p1 = p0 + rng.normal(size=(40, 3)) * 4
    p1[:5] = p0[:5]
    got = grid.distance(p0, p1, 100.0)
    f = np.linspace(0, 1, 401)
    for i in range(len(p0)):
        pts = np.repeat(p0[i] + f[:, None] * (p1[i] - p0[i]), len(t), axis=0)
        k = np.tile(np.arange(len(t)), len(f))
        brute = closest_point_distance(pts, v[t[k, 0]], v[t[k, 1]], v[t[k, 2]]).min()
        half = 0.5 * np.linalg.norm(p1[i] - p0[i]) / 400
        assert brute - half - 1e-9 <= got[i] <= brute + 1e-9
    assert (grid.bound(p0, p1, grid.h) <= got + 1e-9).all()
    cut = grid.distance(p0, p1, 0.5)
    np.testing.assert_allclose(cut, np.minimum(got, 0.5), atol=1e-12)


def test_golden_capsule_pair_and_clamp():
    """Two parallel vertical capsules 10 mm apart, radii 1.5 and 3: 5.5. The clamp block X <= 40,
    |Z| <= 30, a horizontal capsule of radius 5 at X = 50, Z = 40 from x 50 to 100: its nearest point
    is (50, 40): hypot(10, 10) - 5."""
    a, b = Part("a", 1.5, 0.0, 10.0), Part("b", 3.0, 2.0, 20.0)
    up = np.array([[0.0, 0.0, 1.0]])
    assert part_pair(a, b, np.zeros((1, 3)), up, np.array([[10.0, 0, 0]]), up)[0] == pytest.approx(5.5)
    clamp = Clamp(40.0, 30.0)
    p = Part("housing", 5.0, 0.0, 50.0)
    got = part_clamp(p, clamp, np.array([[50.0, 0.0, 40.0]]), np.array([[1.0, 0.0, 0.0]]))[0]
    assert got == pytest.approx(math.hypot(10, 10) - 5, abs=1e-9)
    got = part_clamp(p, clamp, np.array([[60.0, 0.0, 100.0]]), np.array([[-0.6, 0.0, -0.8]]))[0]
    # the axis from (60, 0, 100) towards (30, 0, 60): it enters the block's corner region; brute force
    s = np.linspace(0, 50, 200001)
    pts = np.array([60.0, 0, 100]) + s[:, None] * np.array([-0.6, 0, -0.8])
    assert got == pytest.approx(clamp.distance(pts).min() - 5, abs=1e-6)


def test_sweep_bounds_every_row():
    """Along a random motion over the plane the sweep's value at every row is a lower bound of the
    row's own clearance and equals it where it is below REFINE (exact there); a motion through the plane between two
    rows that both clear it is found."""
    index = plane_index(500.0)
    rng = np.random.default_rng(5)
    n = 3000
    s = np.linspace(0, 60, n)
    centres = np.column_stack([s, np.zeros(n), 2.0 + 0.4 * np.sin(s / 3)])
    tilt = np.radians(50 + 45 * np.sin(s / 7)) + rng.normal(0, 1e-3, n)
    axes = np.column_stack([np.sin(tilt), np.zeros(n), np.cos(tilt)])
    every = part_blade(NECK, index, centres, axes)

    def ev(rows, frac):
        assert not frac.any() or len(rows)
        c = centres[rows] + frac[:, None] * (centres[np.minimum(rows + 1, n - 1)] - centres[rows])
        w = axes[rows] + frac[:, None] * (axes[np.minimum(rows + 1, n - 1)] - axes[rows])
        return part_blade(NECK, index, c, w / np.linalg.norm(w, axis=1, keepdims=True))

    from core.machine.clearance import motion

    got, hidden = sweep(ev, motion(centres, axes, NECK.s1), n)
    assert (got <= every + 1e-9).all()
    near = every < 0.05
    assert near.any() and (every < -1e-3).any()
    np.testing.assert_allclose(got[near], every[near], atol=1e-9)
    # two rows that clear, the motion between them through the plane
    w2 = np.array([[0.0, 0, 1.0], [0.0, 0, 1.0]])
    dip = Part("dip", 1.0, 0.0, 1.0)

    def ev2(rows, frac):
        # the centre dips to z = 0.5 halfway: a V-shaped motion the rows do not show
        z = 3.0 - 5.0 * (0.5 - np.abs(frac - 0.5))
        return part_blade(dip, index, np.column_stack([40 * frac, 0 * frac, z]), w2[rows])

    val, hidden = sweep(ev2, np.array([np.hypot(40, 0) + 5]), 2)
    assert (val >= -1e-3).all() and hidden and min(v for _, _, v in hidden) < -1e-3


def test_default_tool_file_and_round_trip():
    tool = load_tool()
    assert (tool.ball_radius, tool.stick_out) == (1.5, 40.0)
    back = parse_tool(tomllib.loads(tool_to_toml(tool)), source=tool.source)
    assert back == tool
    parts = {p.name: p for p in assembly(tool, load_machine())}
    assert parts["neck"].radius == 1.5 and parts["shank"].s1 == pytest.approx(38.5)
    assert list(parts)[-2:] == ["spindle housing", "platform"]
    # the parts follow each other along the axis without gaps
    ordered = list(parts.values())
    for a, b in zip(ordered[:-1], ordered[1:], strict=True):
        assert a.s1 == pytest.approx(b.s0)


@pytest.mark.parametrize("edit, words", [
    (lambda d: d["cutter"].pop("neck_radius_mm"), "missing key [cutter] neck_radius_mm"),
    (lambda d: d["cutter"].update(neck_radius_mm=4.0), "neck_radius_mm = 4 does not fit"),
    (lambda d: d["cutter"].update(stick_out_mm=-3), "must be a positive"),
    (lambda d: d["cutter"].update(holder=[[10.0]]), "holder stage 1 must be [length_mm, radius_mm]"),
    (lambda d: d["cutter"].update(holder=[[10.0, "a"]]), "radius_mm must be a number"),
    (lambda d: d.pop("spindle_nose"), "missing table [spindle_nose]"),
])
def test_bad_tool_files_name_the_key(tmp_path, edit, words):
    from core.machine.tool import default_tool_path

    data = tomllib.loads(default_tool_path().read_text())
    edit(data)
    with pytest.raises(ToolError) as err:
        parse_tool(data, source="t.toml")
    assert words in str(err.value) and "t.toml" in str(err.value)
    bad = tmp_path / "tool.toml"
    bad.write_text("[cutter\n")
    with pytest.raises(ToolError, match="not valid TOML"):
        load_tool(bad)
    with pytest.raises(ToolError, match="cannot read tool file"):
        load_tool(tmp_path / "none.toml")


def test_a_tool_longer_than_the_gauge_length_is_refused():
    tool = load_tool()
    from dataclasses import replace

    with pytest.raises(ToolError, match="gauge length"):
        assembly(replace(tool, nose_length=300.0), load_machine())


def test_check_rows_finds_a_holder_on_the_blade_and_heads_apart():
    """Two tools over the plane z = 0 from both sides would need a blade between them; here both
    sides work from above at 200 mm apart: the left tool dips its holder into the plane on rows
    10-19, which the check reports as one stretch of the left holder against the blade."""
    index = plane_index(500.0)
    parts = assembly(load_tool(), load_machine())
    n = 40
    cl = np.column_stack([np.linspace(0, 20, n), np.zeros(n), np.full(n, 1.5)])
    wl = np.tile([0.0, 0.0, 1.0], (n, 1))
    tilt = np.where((np.arange(n) >= 10) & (np.arange(n) < 20), np.radians(89.0), 0.0)
    wl = np.column_stack([np.sin(tilt), np.zeros(n), np.cos(tilt)])
    cr = cl + [0.0, 400.0, 0.0]
    wr = np.tile([0.0, 0.0, 1.0], (n, 1))
    prof = check_rows(parts, index, Clamp(-1000.0, 1.0), {"left": (cl, wl), "right": (cr, wr)})
    hits = [c for c in prof.collisions if c.side == "left" and c.part.startswith("holder")]
    assert hits and all(10 <= c.first <= c.last <= 19 for c in hits if not c.between)
    assert not [c for c in prof.collisions if c.side == "right"]
    assert prof.heads.min() > 0 and prof.figures()["collisions"] == len(prof.collisions)


def test_project_file_keeps_the_tool_file(tmp_path):
    """A project's optional [tool] file: saved relative to the project, read back absolute; a bad
    value named with its key."""
    from core.errors import ProjectError
    from core.machine.tool import resolve_tool
    from core.output.project import Project, load_project, save_project

    tool = tmp_path / "tools" / "t.toml"
    tool.parent.mkdir()
    tool.write_text(default_tool_text())
    path = save_project(Project(tool=str(tool)), tmp_path / "p.toml")
    assert 'file = "tools/t.toml"' in path.read_text()
    back = load_project(path)
    assert back.tool == str(tool.resolve())
    assert resolve_tool(back.tool, back.params.tool_radius, back.params.tool_length).stick_out == 40.0
    path.write_text(path.read_text().replace('file = "tools/t.toml"', "file = 3"))
    with pytest.raises(ProjectError, match=r"\[tool\] file must be"):
        load_project(path)
    with pytest.raises(ToolError, match="differs from"):
        resolve_tool(str(tool), 2.0)


def default_tool_text() -> str:
    from core.machine.tool import default_tool_path

    return default_tool_path().read_text()


def test_check_rows_finds_the_heads_against_each_other():
    """Two upright tools 100 mm apart over the plane z = 0: their platforms (75 mm in radius, from
    271 to 286 mm above the ball centre) overlap by 50 mm, their spindle housings (40 mm) clear each
    other by 20 mm; the check names the left platform against the right platform, 50 mm deep."""
    index = plane_index(500.0)
    parts = assembly(load_tool(), load_machine())
    n = 12
    cl = np.column_stack([np.linspace(0, 5, n), np.zeros(n), np.full(n, 1.5)])
    up = np.tile([0.0, 0.0, 1.0], (n, 1))
    prof = check_rows(parts, index, Clamp(-1000.0, 1.0), {"left": (cl, up), "right": (cl + [100.0, 0, 0], up)})
    heads = [c for c in prof.collisions if c.side == "both"]
    assert heads and {(c.part, c.against) for c in heads} == {("platform", "right platform")}
    assert heads[0].depth == pytest.approx(50.0, abs=1e-9) and (heads[0].first, heads[0].last) == (0, n - 1)
    assert prof.figures()["heads_mm"] == pytest.approx(-50.0)
    row, value, which = prof.closest("heads")
    assert value == pytest.approx(-50.0) and which == "left platform and right platform"


def test_a_tool_file_beyond_the_toml_reader_is_a_tool_error(tmp_path):
    """A tool.toml nested too deeply, or with an integer of more digits than Python reads, is refused
    as any malformed TOML is (the machine file's reader, core.util.files.read_toml), not a crash."""
    deep = tmp_path / "deep.toml"
    deep.write_text("x = " + "[" * 5000 + "]" * 5000 + "\n")
    long = tmp_path / "long.toml"
    long.write_text("[cutter]\nball_radius_mm = " + "1" * 5000 + "\n")
    for path in (deep, long):
        with pytest.raises(ToolError, match="not valid TOML"):
            load_tool(path)

"""The whole-tool collision check in the planner, one test per part: a tool or machine file made to
collide, and the plan turns the single-sided paths' axes clear (core.machine.tool_axes's clearance)
or is refused naming the path, the time, the part and the depth (and written with --force, saying
so). The whole plans take minutes on a loaded machine and are marked slow; each part has a fast test
here or in test_clearance.py (the neck in a groove, the shank off a round edge, the holder on a plane,
the heads' platforms)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.errors import PlanningError
from core.machine.clearance import Clamp, least_clearance
from core.machine.collisions import check_rows, refusal
from core.machine.tool import Part, default_tool_path
from core.output.writer import write_result
from core.paths.tessellation import SurfaceMesh, TriangleIndex
from tests.conftest import COARSE, cli, plan_on


def _tool_file(tmp_path, **edits) -> str:
    """The default tool file with keys of [cutter] (or 'holder', 'spindle_nose') replaced."""
    text = default_tool_path().read_text()
    lines = []
    skip = False
    for line in text.splitlines():
        key = line.split("=")[0].strip()
        if skip:
            skip = not line.strip().startswith("]")
            continue
        if key in edits:
            value = edits[key]
            lines.append(f"{key} = {value}")
            skip = key == "holder" and line.strip().endswith("[")
            continue
        lines.append(line)
    path = tmp_path / "tool.toml"
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def groove_index(angle_deg: float = 60.0) -> TriangleIndex:
    """A V groove along x: the planes through the x axis at +-angle/2 from +z's normal... two walls
    z = |y| tan(a), a = 90 - angle/2, meeting at the x axis (an inside corner of ``angle_deg``)."""
    a = math.radians(90.0 - angle_deg / 2)
    ys = np.linspace(-40.0, 40.0, 161)
    xs = np.linspace(-20.0, 60.0, 161)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    v = np.column_stack([gx.ravel(), gy.ravel(), np.abs(gy.ravel()) * math.tan(a)])
    n_y = len(ys)
    i, j = np.meshgrid(np.arange(len(xs) - 1), np.arange(n_y - 1), indexing="ij")
    p = (i * n_y + j).ravel()
    tris = np.concatenate([np.column_stack([p, p + n_y, p + n_y + 1]), np.column_stack([p, p + n_y + 1, p + 1])])
    return TriangleIndex(SurfaceMesh(v, tris), k=8)


def test_neck_in_a_groove_is_turned_clear_or_reported():
    """The ball in a 90-degree groove touching both walls, its axis leaning 47.4 degrees towards one
    wall: the neck (r 1.5 from 0.75 mm above the ball centre) runs 0.5 mm into that wall at its upper
    end (hand-computed below). The check reports
    the neck against the blade with its depth, the refusal names the part, and turning the axis about
    the ball centre clears it."""
    index = groove_index(90.0)
    neck = Part("neck", 1.5, 0.75, 12.0)
    n = 30
    # ball of r 1.5 touching both walls of a 90-degree groove: centre 1.5 * sqrt(2) above the corner
    centres = np.column_stack([np.linspace(0, 20, n), np.zeros(n), np.full(n, 1.5 * math.sqrt(2))])
    # the wall z = y: the axis point at s, (y, z) = (s sin t, c + s cos t) with c = 1.5 sqrt 2, lies
    # (z - y) / sqrt 2 from it, least at s = 12 where t leans more than 45 degrees; 1.0 mm there for
    # cos t - sin t = (sqrt 2 - c) / 12, i.e. t = arccos((sqrt 2 - c) / (12 sqrt 2)) - 45 degrees
    c0 = 1.5 * math.sqrt(2)
    lean = math.acos((math.sqrt(2) - c0) / (12 * math.sqrt(2))) - math.pi / 4
    axes = np.tile([0.0, math.sin(lean), math.cos(lean)], (n, 1))
    far = Part("far", 0.1, 0.0, 0.0)
    prof = check_rows((neck, far), index, Clamp(-1e3, 1.0),
                      {"left": (centres, axes), "right": (centres + [0, 0, 50], axes)})
    hits = [c for c in prof.collisions if c.side == "left" and c.part == "neck" and c.against == "blade"]
    assert hits
    assert hits[0].depth == pytest.approx(0.5, abs=1e-3)
    text = refusal(prof, np.arange(n) * 10.0, np.full(n, 7), np.full(n, 7))
    assert "left neck hits the blade" in text and "path 7" in text and "mm deep" in text


def test_single_sided_axes_turn_a_shank_off_a_round_edge():
    """A single-sided path wrapping round a cylinder of radius 5 (an edge) from -80 to 80 degrees: its
    one axis, the mean normal (straight up), leaves a shank 20 mm across, from 12 mm above the ball
    centre, 0.4 mm deep in the cylinder at the path's ends (its lowest axis point (6.5 sin 80, 6.5 cos 80
    + 12) is 9.6 mm off the surface, its radius 10). Given the shank's least clearance
    (core.machine.clearance.least_clearance), core.machine.tool_axes.single_sided_axes stands the axes up
    towards the normals until it clears."""
    from core.machine.tool_axes import single_sided_axes

    phi = np.radians(np.linspace(-150.0, 150.0, 121))
    xs = np.linspace(-20.0, 40.0, 61)
    v = np.array([[x, 5.0 * math.sin(p), 5.0 * math.cos(p)] for x in xs for p in phi])
    m = len(phi)
    i, j = np.meshgrid(np.arange(len(xs) - 1), np.arange(m - 1), indexing="ij")
    p0 = (i * m + j).ravel()
    tris = np.concatenate([np.column_stack([p0, p0 + m, p0 + m + 1]), np.column_stack([p0, p0 + m + 1, p0 + 1])])
    index = TriangleIndex(SurfaceMesh(v, tris), k=8)
    n = 41
    a = np.radians(np.linspace(-80.0, 80.0, n))
    normals = np.column_stack([np.zeros(n), np.sin(a), np.cos(a)])
    centres = np.column_stack([np.linspace(0.0, 20.0, n), np.zeros(n), np.zeros(n)]) + 6.5 * normals
    least = least_clearance((Part("shank", 10.0, 12.0, 38.5),), index)
    free = single_sided_axes([centres], [normals], np.array([0.0, 0.0, 1.0]), 89.0)
    low = math.hypot(6.5 * math.sin(a[-1]), 6.5 * math.cos(a[-1]) + 12.0)  # (the shank's lowest axis point)
    # (a shank is thicker than THIN_MM: its collision is reported once certain, at least as deep as
    # the value; the chords lie within 1.2e-3 of the cylinder)
    assert low - 5.0 - 10.0 - 2e-3 <= least(centres, free.axes[0]).min() < -1e-3
    got = single_sided_axes([centres], [normals], np.array([0.0, 0.0, 1.0]), 89.0, clearance=least)
    assert got.clear.all() and (least(centres, got.axes[0]) >= 0).all()


@pytest.fixture(scope="module")
def coarse(sample_paths):
    return sample_paths(**COARSE)


@pytest.mark.slow
def test_fat_neck_is_refused_and_force_writes_it(coarse, tmp_path):
    """A neck 3 mm in radius (a ball of 1.5; the default neck clears the blade by 1.25 mm on these paths):
    next to the blade on collaborative paths, whose axes are the paper's and are not turned, it runs
    into the blade; the plan is refused naming the neck, the path, the time and the depth, and written
    with --force (tool.toml and blade.stl in the folder), where verify finds the same collisions from
    the folder alone. (A holder's collision is found the same way: test_clearance's holder on a plane;
    a whole plan with a holder that grazes the blade over long stretches takes minutes: README.)"""
    tool = _tool_file(tmp_path, neck_radius_mm=3.0)
    res = plan_on(coarse, tool=tool)
    necks = [c for c in res.collisions if c.part == "neck" and c.against == "blade"]
    assert necks and res.figures["collisions"]["collisions"] == len(res.collisions)
    assert res.figures["collisions"]["blade_mm"]["left"]["neck"] < 0 or \
        res.figures["collisions"]["blade_mm"]["right"]["neck"] < 0
    with pytest.raises(PlanningError) as err:
        write_result(res, tmp_path / "plan")
    text = str(err.value)
    assert "neck hits the blade" in text and "path " in text and "t = " in text and "mm deep" in text
    out = write_result(res, tmp_path / "forced", force=True)
    assert "neck_radius_mm = 3.0" in (out / "tool.toml").read_text() and (out / "blade.stl").stat().st_size > 84
    from core.verify.check import verify

    rep = verify(out, workers=1)
    lines = [f for f, k in zip(rep.findings, rep.kinds, strict=True) if k == "collision"]
    assert lines and any("neck" in f and "hits the blade" in f for f in lines)
    assert abs(rep.counts["collision"] - len(res.collisions)) <= 1  # (the files hold the rows to 1e-6)


@pytest.mark.slow
def test_shank_collision_is_turned_or_refused(coarse, tmp_path):
    """A shank 20 mm across from 6 mm above the tip: the single-sided paths' axes are turned where that
    clears, and whatever still collides refuses the plan naming the shank."""
    tool = _tool_file(tmp_path, flute_length_mm=4.5, neck_length_mm=6.0, shank_radius_mm=10.0)
    res = plan_on(coarse, tool=tool)
    assert [c for c in res.collisions if c.part == "shank" and c.against == "blade"]
    # (the two shanks, 20 mm across, also hit each other across the blade, deepest: named first)
    with pytest.raises(PlanningError, match="shank hits the"):
        write_result(res, tmp_path / "plan")
    assert not [c for c in res.collisions if c.part not in ("shank", "holder 1", "holder 2", "spindle nose")]


@pytest.mark.slow
def test_head_collision_refuses_the_plan(coarse, tmp_path):
    """Machines whose platforms are 1.2 m across: the two heads, some 560 mm apart across the blade,
    hit each other; refused as the left platform against the right one."""
    from core.machine.model import default_machine_path

    text = default_machine_path().read_text().replace("platform_plate_radius_mm = 75.0",
                                                      "platform_plate_radius_mm = 600.0")
    machine = tmp_path / "machine.toml"
    machine.write_text(text)
    res = plan_on(coarse, machine=str(machine))
    heads = [c for c in res.collisions if c.side == "both" and c.part == "platform" and c.against == "right platform"]
    assert heads and res.figures["collisions"]["heads_mm"] < 0
    with pytest.raises(PlanningError, match="left platform hits the right platform"):
        write_result(res, tmp_path / "plan")


@pytest.mark.slow
def test_default_plan_is_clear(coarse):
    """The shipped tool on the shipped machines: no collision, every figure positive."""
    res = plan_on(coarse)
    fig = res.figures["collisions"]
    assert fig["collisions"] == 0 and not res.collisions
    assert min(min(v.values()) for v in fig["blade_mm"].values()) > 0
    assert fig["clamp_mm"] > 0 and fig["tools_mm"] > 0 and fig["heads_mm"] > 0


def test_cli_tool_file_and_radius_must_agree(tmp_path, capsys):
    tool = _tool_file(tmp_path, ball_radius_mm=2.0, neck_radius_mm=2.0)
    got = cli(capsys, "plan", "--tool", tool, "--tool-radius", "1.5", "--out", tmp_path / "p")
    assert got.returncode == 2 and "ball_radius_mm = 2" in got.stderr and "Traceback" not in got.stderr
    got = cli(capsys, "plan", "--tool", tmp_path / "none.toml", "--out", tmp_path / "p")
    assert got.returncode == 2 and "cannot read tool file" in got.stderr

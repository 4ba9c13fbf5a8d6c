"""Units and the propeller axis's placement of a mesh blade (core.blade.placement), at blade info."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.blade.model import section_chord, section_max_thickness
from core.blade.placement import parse_axis, unit_hint
from core.blade.source import load_blade
from core.errors import BladeInputError
from tests.conftest import cli
from tests.core.blade.test_mesh_blade import R1, closed_blade_mesh


@pytest.fixture(scope="module")
def reference():
    return closed_blade_mesh(theta0_deg=40.0, n_r=41, n_s=96)


def sizes(blade, r=60.0):
    s = blade.section(r)
    return blade.tip_radius, section_chord(s), section_max_thickness(s)


def test_parse_axis():
    name, rot, point = parse_axis("y@1,2,3")
    assert name == "y" and np.allclose(point, [1, 2, 3]) and np.allclose(rot @ [0, 1, 0], [0, 0, 1])
    name, rot, point = parse_axis(" 0, 0, -2 ")
    assert name is None and np.allclose(rot @ [0, 0, -1], [0, 0, 1]) and np.isclose(np.linalg.det(rot), 1.0)
    for bad, words in (("w", "three numbers"), ("1,2", "three numbers"), ("0,0,0", "zero"), ("z@1,2", "point")):
        with pytest.raises(BladeInputError, match=words):
            parse_axis(bad)


def test_an_axis_off_the_origin_given_as_a_point(tmp_path, reference):
    ref = load_blade(str(_export(reference, tmp_path / "ref.stl")))
    moved = reference.copy()
    moved.apply_translation([200.0, -50.0, 30.0])
    path = str(_export(moved, tmp_path / "moved.stl"))
    assert load_blade(path, axis="z").tip_radius > ref.tip_radius + 100.0  # (about the wrong line)
    blade = load_blade(path, axis="z@200,-50,30")
    assert sizes(blade) == pytest.approx(sizes(ref), abs=1e-4)  # (the STL file's single precision)


def test_an_axis_along_any_direction(tmp_path, reference):
    ref = load_blade(str(_export(reference, tmp_path / "ref.stl")))
    tilted = reference.copy()
    d = np.array([1.0, 2.0, 2.0]) / 3.0  # the propeller axis turned onto d: z -> d, about the axis z x d
    axis = np.cross([0.0, 0.0, 1.0], d)
    angle = np.arccos(d[2])
    k = axis / np.linalg.norm(axis)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    turn = np.eye(4)
    turn[:3, :3] = np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx
    tilted.apply_transform(turn)
    blade = load_blade(str(_export(tilted, tmp_path / "tilted.stl")), axis="1,2,2")
    assert sizes(blade) == pytest.approx(sizes(ref), abs=1e-4)


def test_units_hint_and_units(tmp_path, reference):
    metres = reference.copy()
    metres.apply_scale(1e-3)
    path = str(_export(metres, tmp_path / "m.stl"))
    blade = load_blade(path)
    assert any("give --units m" in w for w in blade.warnings)
    scaled = load_blade(path, units="m")
    assert scaled.tip_radius == pytest.approx(R1, rel=1e-6) and not scaled.warnings
    assert unit_hint(R1 / 25.4, "mm").endswith("--units in")  # (an inch blade read in mm)
    assert unit_hint(R1, "mm") is None
    with pytest.raises(BladeInputError, match="applies to meshes"):
        load_blade("sample", units="m")


def test_blade_info_with_units_and_a_point_on_the_axis(tmp_path, reference, capsys):
    m = reference.copy()
    m.apply_translation([10.0, 0.0, 0.0])
    m.apply_scale(0.1)  # cm
    path = str(_export(m, tmp_path / "cm.stl"))
    out = cli(capsys, "blade", "info", "--blade", path, "--units", "cm", "--axis", "z@1,0,0", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["tip_radius_mm"] == pytest.approx(R1, abs=1e-3)
    bad = cli(capsys, "blade", "info", "--blade", path, "--axis", "z@1,0")
    assert bad.returncode == 2 and "point" in bad.stderr and "Traceback" not in bad.stderr


def _export(mesh, path):
    mesh.export(path)
    return path


def test_plan_reads_a_mesh_in_metres_with_units(tmp_path, reference, capsys):
    """``plan --units m`` on a blade written in metres plans the same blade as the file in mm: as many
    paths, pairs within 0.1 % in number (the STL's single precision moves the interpolation steps), the
    paths' ends within 0.01 mm; plan.json records the unit in the SOURCE string, and verify reloads the
    blade in it. Without --units the warning names the unit."""
    mm = str(_export(reference, tmp_path / "mm.stl"))
    metres = reference.copy()
    metres.apply_scale(0.001)
    m = str(_export(metres, tmp_path / "m.stl"))
    args = ("--dr", "8", "--paths-only", "--workers", "2")
    runs = {}
    for name, blade, extra in (("mm", mm, ()), ("m", m, ("--units", "m"))):
        out = tmp_path / name
        res = cli(capsys, "plan", "--blade", blade, *extra, *args, "--out", out)
        assert res.returncode == 0, res.stderr
        assert "--units" not in res.stderr
        runs[name] = np.loadtxt(out / "pairs.csv", delimiter=",", skiprows=1, usecols=(0, 3, 4, 5, 9, 10, 11))
    assert json.loads((tmp_path / "m" / "plan.json").read_text())["inputs"]["blade_source"] == f"{m}?units=m"
    assert len(runs["m"]) == pytest.approx(len(runs["mm"]), rel=1e-3)
    paths = np.unique(runs["mm"][:, 0])
    assert np.array_equal(np.unique(runs["m"][:, 0]), paths)
    for p in paths:
        a, b = runs["m"][runs["m"][:, 0] == p, 1:], runs["mm"][runs["mm"][:, 0] == p, 1:]
        assert np.abs(a[[0, -1]] - b[[0, -1]]).max() < 1e-2
    ver = cli(capsys, "verify", tmp_path / "m")
    assert ver.returncode == 0, ver.stdout
    plain = cli(capsys, "plan", "--blade", m, *args, "--out", tmp_path / "plain")
    assert "give --units m" in plain.stderr and "Traceback" not in plain.stderr


def test_project_file_units_reach_the_blade(tmp_path, reference):
    from core.output.project import Project, load_project, save_project

    metres = reference.copy()
    metres.apply_scale(0.001)
    m = _export(metres, tmp_path / "m.stl")
    path = save_project(Project(source=f"{m}?units=m"), tmp_path / "p.toml")
    assert 'units = "m"' in path.read_text()
    blade = load_blade(load_project(path).source)
    assert blade.tip_radius == pytest.approx(R1, abs=1e-3) and blade.warnings == []

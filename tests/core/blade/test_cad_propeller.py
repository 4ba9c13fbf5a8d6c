"""One blade of a whole propeller given as exact CAD surfaces (core.blade.cad_propeller).

The propellers are made here with OpenCASCADE (tests/core/blade/cad_blades.py): the sample table's blade
as B-spline surfaces through the table's own points, in N_BLADES copies about Z on a hub cylinder, in one
STEP or IGES file. A picked blade's exact sections, turned back by its copy's angle, are checked against
the table's own sections."""

from __future__ import annotations

import json

import numpy as np
import pytest

from core.blade.propeller import BANDS, HUB_MARGIN
from core.blade.source import load_blade
from core.errors import BladeInputError

from ...conftest import cli

pytest.importorskip("OCP")
from tests.core.blade.cad_blades import bspline_surface, grid, propeller, write  # noqa: E402
from tests.core.blade.test_cad_blade import in_file_frame, polyline_distance, table_section  # noqa: E402

N_BLADES = 4
#: the hub cylinder's radius above the table's hub radius (mm)
HUB_OVER = 3.0
#: the CAD blades' grid (rows of radii from the hub to 0.995 R, chordwise stations)
ROWS, STATIONS = 40, 241


def turn_z(deg: float) -> np.ndarray:
    a = np.radians(deg)
    return np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])


def row_radii(table, fractions=(0.35, 0.55, 0.8)):
    """Radii of the grid's rows nearest the fractions of the tip radius (there the surfaces pass through
    the table's own points)."""
    radii = np.linspace(table.hub_radius, 0.995 * table.tip_radius, ROWS)
    return [float(radii[np.argmin(np.abs(radii - f * table.tip_radius))]) for f in fractions]


@pytest.fixture(scope="module")
def table():
    return load_blade("sample")


@pytest.fixture(scope="module")
def cad_propellers(tmp_path_factory, table):
    folder = tmp_path_factory.mktemp("cadprop")
    hub = table.hub_radius + HUB_OVER
    return {"step": write(propeller(table, N_BLADES, hub, ROWS, STATIONS), folder / "propeller.step"),
            "igs": write(propeller(table, N_BLADES, hub, ROWS, STATIONS), folder / "propeller.igs"),
            "solids": write(propeller(table, N_BLADES, hub, ROWS, STATIONS, solids=True), folder / "solids.step")}


def copy_turn(blade, table, r: float) -> np.ndarray:
    """The rotation that turns blade's section at r (file frame) back onto the table's blade: of the
    N_BLADES copies' turns, the one that brings its points nearest the table's section."""
    s = blade.section(r)
    pts = in_file_frame(blade, np.vstack([s.face, s.back]))
    ref = np.vstack(table_section(table, r, 2001))
    turns = [turn_z(-360.0 * j / N_BLADES) for j in range(N_BLADES)]
    return min(turns, key=lambda t: polyline_distance(pts @ t.T, ref).max())


# (make test: each kind of file once, blades 1, 2 and 4; a second blade of the STEP file in make test-all)
@pytest.mark.parametrize("kind,k", [("step", 1), pytest.param("step", 3, marks=pytest.mark.slow), ("igs", 2),
                                    ("solids", 4)])
def test_blade_k_sections_are_exactly_the_tables(table, cad_propellers, kind, k):
    blade = load_blade(f"{cad_propellers[kind]}?blade={k}")
    assert blade.blade_index == k and blade.warnings == [] and not blade.closed
    assert blade.name == f"{cad_propellers[kind].name} blade {k} of {N_BLADES}"
    prop = blade.propeller
    assert blade.hub_radius == pytest.approx(prop.r_min, abs=1e-6)
    # copy j of the table's blade is blade j + 1 (the table's blade lies at a small positive angle)
    turn = copy_turn(blade, table, row_radii(table)[1])
    assert np.allclose(turn, turn_z(-360.0 * (k - 1) / N_BLADES))
    for r in row_radii(table):
        s = blade.section(r)
        ref_face, ref_back = table_section(table, r)
        for pts, ref in ((s.face, ref_face), (s.back, ref_back)):
            p = in_file_frame(blade, pts) @ turn.T
            assert np.abs(np.hypot(p[:, 0], p[:, 1]) - r).max() < 1e-9
            assert polyline_distance(p, ref).max() <= 1e-3  # mm: exact, on the table's surface
        mid = len(s.face) // 2
        other = s.back[np.argmin(np.linalg.norm(s.back - s.face[mid], axis=1))]
        assert np.dot(s.face_normals[mid], s.face[mid] - other) > 0  # (outward)
    # the check tessellation is the picked blade's sides, cut at the hub (no hub, no other blade, no cap)
    v, _ = blade.facets()
    rv = np.hypot(v[:, 0], v[:, 1])
    assert rv.min() >= prop.r_min - 1e-6 and rv.max() <= blade.tip_radius + 0.05
    assert np.ptp(np.degrees(np.arctan2(v[:, 1], v[:, 0]))) < 360.0 / N_BLADES


def test_the_blades_and_the_hub_are_found(table, cad_propellers):
    blade = load_blade(str(cad_propellers["step"]))
    prop = blade.propeller
    assert blade.blade_index == 1 and any(f"whole propeller: {N_BLADES} blades" in w for w in blade.warnings)
    angles = np.array([b.angle_deg for b in prop.blades])
    assert len(angles) == N_BLADES and np.diff(angles) == pytest.approx(360.0 / N_BLADES, abs=1e-3)
    hub = table.hub_radius + HUB_OVER
    tip = prop.blades[0].r_to
    assert hub <= prop.hub_end <= hub + tip / BANDS + 1e-9
    assert prop.r_min == pytest.approx(prop.hub_end + HUB_MARGIN * (tip - prop.hub_end))
    assert tip == pytest.approx(0.995 * table.tip_radius, abs=1e-3)
    given = load_blade(f"{cad_propellers['step']}?blade=2&r_min=60")
    assert given.hub_radius == pytest.approx(60.0, abs=1e-6) and given.propeller.r_min_given
    with pytest.raises(BladeInputError, match="beyond the mesh's tip radius"):
        load_blade(f"{cad_propellers['step']}?r_min=400")


def test_blade_info_lists_the_blades_and_a_bad_index_exits_2(cad_propellers, capsys):
    path = str(cad_propellers["step"])
    out = cli(capsys, "blade", "info", "--blade", path, "--blade-index", "3", "--json")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["propeller"]["blades"] == N_BLADES and info["propeller"]["picked"] == 3
    assert info["source"] == f"{path}?blade=3"
    text = cli(capsys, "blade", "info", "--blade", path, "--blade-index", "3")
    rows = [line.split() for line in text.stdout.splitlines() if line.strip()[:1].isdigit()
            and len(line.split()) >= 5]
    assert [int(r[0]) for r in rows] == list(range(1, N_BLADES + 1))
    assert [float(r[1]) for r in rows] == pytest.approx([b["angle_deg"] for b in info["propeller"]["found"]],
                                                        abs=1e-3)
    assert "<- these sizes" in next(line for line in text.stdout.splitlines() if line.split()[:1] == ["3"])
    bad = cli(capsys, "blade", "info", "--blade", path, "--blade-index", "7")
    assert bad.returncode == 2 and f"has {N_BLADES} blades" in bad.stderr and "Traceback" not in bad.stderr


def test_a_face_wrapped_round_the_edges_is_refused(table, tmp_path):
    """One surface round the LE (the back from TE to LE, then the face to TE): face and back cannot be
    split along CAD faces."""
    from OCP.BRep import BRep_Builder
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace, BRepBuilderAPI_Transform
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    from OCP.gp import gp, gp_Ax2, gp_Pnt, gp_Trsf
    from OCP.TopoDS import TopoDS_Compound

    face_g, back_g = grid(table, 30, 121)
    wrapped = BRepBuilderAPI_MakeFace(bspline_surface(np.concatenate([back_g[:, ::-1], face_g[:, 1:]], axis=1)),
                                      1e-7).Face()
    out, builder = TopoDS_Compound(), BRep_Builder()
    builder.MakeCompound(out)
    for k in range(3):
        turn = gp_Trsf()
        turn.SetRotation(gp.OZ_s(), 2.0 * np.pi * k / 3)
        builder.Add(out, BRepBuilderAPI_Transform(wrapped, turn, True).Shape())
    z = np.concatenate([face_g[0, :, 2], back_g[0, :, 2]])
    builder.Add(out, BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, z.min() - 5), gp.DZ_s()), table.hub_radius + 3,
                                              np.ptp(z) + 10).Shape())
    path = write(out, tmp_path / "wrapped.step")
    with pytest.raises(BladeInputError, match="lies on both its face and its back") as err:
        load_blade(f"{path}?blade=2")
    assert "wrapped.step" in str(err.value)


def test_a_cad_propeller_blade_plans_and_verifies(cad_propellers, tmp_path):
    from core.records import PlanParameters
    from tests.core.blade.test_closed_mesh_plan import plan_and_verify

    res = plan_and_verify(f"{cad_propellers['step']}?blade=2", PlanParameters(dr=8.0), tmp_path)
    assert res.plan.region_counts()["paths"] > 15

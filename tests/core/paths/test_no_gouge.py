"""No planned ball cuts into the blade, or the plan is refused (core.paths.guard, core.paths.stations):
a sharp-edged table, a table of extreme camber, and a mesh read with the wrong propeller axis. Each
plan is measured as bladecam verify measures it: against the gouge check's own tessellation (or the
mesh's facets), at every pair point and along every straight move between two."""

from __future__ import annotations

import numpy as np
import pytest

from core.blade.frame import workpiece_frame
from core.blade.source import load_blade
from core.cli import main
from core.errors import PlanningError
from core.paths.alignment import align_single, align_symmetric, sides
from core.paths.guard import blade_guard
from core.paths.planning import plan_paths
from core.paths.stations import contour_stations
from core.paths.tessellation import FACET_CANDIDATES, TriangleIndex, facet_mesh, surface_mesh
from core.records import PlanParameters

from ...conftest import REPO

#: bladecam verify's tolerance on a cutting ball's distance from the blade (mm)
VERIFY_TOLERANCE = 2e-3
SAMPLE = REPO / "resources" / "sample_blade.csv"


def _table(tmp_path, name: str, thickness: str | None = None, camber: float | None = None,
           t0: float | None = None):
    """The sample table with another thickness form, or every row's f0/c and t0/c set (mm)."""
    lines = SAMPLE.read_text().splitlines()
    out = []
    for line in lines:
        if thickness and line.startswith("# thickness:"):
            line = f"# thickness: {thickness}"
        elif line[:1].isdigit() and camber is not None:
            cells = line.split(",")
            cells[3], cells[4] = f"{t0}", f"{camber}"
            line = ",".join(cells)
        out.append(line)
    path = tmp_path / f"{name}.csv"
    path.write_text("\n".join(out) + "\n")
    return path


def _clearance(pairs, index: TriangleIndex, r: float) -> float:
    """Least distance from the mesh, less r (mm), of every ball centre of the pairs and of 7 points
    along every straight move between two."""
    f = np.linspace(0.0, 1.0, 9)[1:-1, None, None]
    worst = np.inf
    for pair in pairs:
        for tip, axis in ((pair.left_tip, pair.left_axis), (pair.right_tip, pair.right_axis)):
            c = tip + r * axis
            along = ((1 - f) * c[None, :-1] + f * c[None, 1:]).reshape(-1, 3)
            worst = min(worst, float(index.closest(np.vstack([c, along]))[0].min()) - r)
    return worst


def _unguarded(plan) -> list:
    """The plan's pairs as aligned before the guard (symmetrical, or single-sided in the tip region)."""
    p = plan.params
    out = []
    for path, reg in zip(plan.paths, plan.regions, strict=True):
        fitted = sides(path)
        sym = align_symmetric(path, p.dd, p.tool_radius, fitted)
        out.append(align_single(path, p.dd, p.tool_radius, p.tool_length, fitted, symmetric=sym) if reg.is_tip
                   else sym)
    return out


def test_the_sample_blade_needs_no_guard():
    """The default plan's paths are the guard's to leave alone: the sample's stations suffice and it
    is nowhere more concave than the tool (nothing is pushed, nothing inserted)."""
    blade = load_blade("sample")
    frame = workpiece_frame(blade)
    assert contour_stations(blade, frame, 1.5) is None
    guard = blade_guard(blade, frame, 1.5)
    assert guard is not None and guard.index is None


def test_a_sharp_edged_table_plans_balls_clear_of_its_edges(tmp_path):
    """The sample with the documented parabolic thickness form (t ~ x at the edges): the a=0.8 mean
    line's slope is log-singular at the LE, so the face curls over within 0.05 mm of the sharp LE,
    with radii down to micrometres; balls placed on the LE's normal cut 0.07 mm into it at the
    defaults. The guard pushes them out of the check tessellation: every ball and every move between
    two stays within verify's tolerance."""
    blade = load_blade(str(_table(tmp_path, "parabolic", thickness="parabolic")))
    plan = plan_paths(blade, PlanParameters(dr=3.0), workers=2)
    assert plan.guard is not None and plan.guard.index is not None  # the hook was found
    index = TriangleIndex(surface_mesh(blade, plan.frame), k=8)  # (bladecam verify's)
    r = plan.params.tool_radius
    sample = slice(None, None, 6)  # the unguarded alignment measured on every sixth path (time)
    assert _clearance(_unguarded(plan)[sample], index, r) < -0.03
    assert _clearance(plan.pairs, index, r) > -VERIFY_TOLERANCE / 2


def test_a_table_of_extreme_camber_plans_balls_clear_of_it(tmp_path):
    """f0/c = 0.4 on sections 2 % thick (within the table's bounds, with a warning): near the closing
    tip the face is a bowl narrower than the ball (1.2 mm of gouge unguarded), the a=0.8 mean line
    curls the LE over, and the contact curve through the table's 241 stations sags into the surface.
    Planned, every ball and every move clears the blade to verify's tolerance."""
    blade = load_blade(str(_table(tmp_path, "camber", camber=0.4, t0=0.02)))
    plan = plan_paths(blade, PlanParameters(dr=3.0), workers=2)
    index = plan.guard.index  # the check tessellation, as bladecam verify builds it
    r = plan.params.tool_radius
    assert _clearance(_unguarded(plan)[:1], index, r) < -1.0  # the tip path, unguarded
    assert _clearance(plan.pairs, index, r) > -VERIFY_TOLERANCE / 2


def test_a_mesh_read_with_the_wrong_axis_is_refused(bladex_dir, tmp_path, capsys):
    """BladeX's propeller axis is x; read about y, some sections' normals point into the blade and
    balls sit on its surface, where no push-out can take them (1.5 mm of gouge, which the plan used to
    write with exit 0). The paths stage refuses, naming the path, the depth and the axis."""
    source = f"{bladex_dir / 'upper.stl'},{bladex_dir / 'lower.stl'}"
    refusal = (r"path \d+ \(r = [\d.]+ mm\): the (left|right) cutter's ball would cut [\d.]+ mm into the "
               r"blade .*--axis")
    with pytest.raises(PlanningError, match=refusal):
        plan_paths(load_blade(source, "y"), PlanParameters(dr=3.0), workers=2)
    code = main(["plan", "--blade", source, "--axis", "y", "--dr", "3", "--paths-only", "--out",
                 str(tmp_path / "plan")])
    assert code == 2
    err = capsys.readouterr().err
    assert "cut" in err and "--axis" in err and len(err.strip().splitlines()) <= 2
    # the right axis plans clean against the facets (as verify measures)
    blade = load_blade(source, "x")
    plan = plan_paths(blade, PlanParameters(dr=6.0), workers=2)
    index = TriangleIndex(facet_mesh(blade, plan.frame), k=FACET_CANDIDATES)
    assert _clearance(plan.pairs, index, plan.params.tool_radius) > -VERIFY_TOLERANCE / 2

"""``bladecam plan`` verifies the rows it holds in memory instead of reading its files back: those rows
are bit-identical to what verify's reader makes of the files, and a defect in them is caught as it
would be in a file."""

from __future__ import annotations

import numpy as np
import pytest
from core.verify._tables import parse_rows

from core.output.csvio import CsvChunks
from core.output.writer import PlanWriter
from core.verify.check import verify
from core.verify.read import table_rows

from ...conftest import COARSE


@pytest.fixture(scope="module")
def written(tmp_path_factory, sample_paths):
    """A coarse plan of the sample written through PlanWriter, with the rows its check was given."""
    from ...conftest import plan_on

    result = plan_on(sample_paths(**COARSE), axes=True)
    seen = {}

    def check(folder, given):
        seen.update({name: rows() if callable(rows) else rows for name, rows in given.items()})
        rep = verify(folder, workers=1, given=given)
        seen["report"] = rep

    out = tmp_path_factory.mktemp("in_memory") / "plan"
    PlanWriter(out, check=check).write(result)
    return out, seen


def test_the_rows_given_are_the_files_as_read(written):
    out, seen = written
    names = {"left_cl.csv", "right_cl.csv", "left_axes.csv", "right_axes.csv", "pairs.csv"}
    assert names <= set(seen)
    for name in names:
        np.testing.assert_array_equal(seen[name], table_rows(out, name), err_msg=name)
    assert seen["report"].findings == []


def test_a_defect_in_the_given_rows_is_found_though_the_files_are_clean(written):
    out, seen = written
    left = seen["left_cl.csv"].copy()
    row = int(np.flatnonzero(left[:, 4] > 0.5)[100])
    left[row, 7] += 0.5 if left[row, 10] < 0 else -0.5  # (the tip moved 0.5 mm along Z_W, into the blade)
    rep = verify(out, workers=1, given={"left_cl.csv": left})
    assert any("left ball cuts into" in f for f in rep.findings), rep.findings[:5]
    assert verify(out, workers=1).findings == []


def test_the_tessellation_given_is_the_one_verify_makes(written):
    from core.blade.frame import workpiece_frame
    from core.blade.source import load_blade
    from core.paths.tessellation import SurfaceMesh, surface_mesh

    out, seen = written
    blade = load_blade("sample")
    mesh = surface_mesh(blade, workpiece_frame(blade))
    given = {name: seen[name] for name in ("left_cl.csv", "right_cl.csv")}
    rep = verify(out, workers=1, given=given, mesh=mesh)
    timed = {"collision_check_s"}  # (a time, not a measure)
    assert rep.findings == []
    assert {k: v for k, v in rep.figures.items() if k not in timed} == {
        k: v for k, v in seen["report"].figures.items() if k not in timed}
    # (a tessellation that is not the blade's is measured as given: the balls miss it)
    shifted = SurfaceMesh(vertices=mesh.vertices + [0.0, 0.0, 0.2], triangles=mesh.triangles)
    rep = verify(out, workers=1, given=given, mesh=shifted)
    assert any("misses the blade" in f or "cuts into" in f for f in rep.findings), rep.findings[:5]


def test_as_written_is_the_readers_value_for_every_decimal_count():
    rng = np.random.default_rng(5)
    values = rng.normal(0, 400, 2000) * 10.0 ** rng.integers(-6, 3, 2000)
    cols = [("f", values, d) for d in (0, 3, 6, 9, 10)] + [("i", rng.integers(-5, 500, 2000), None),
                                                           ("c", (rng.integers(0, 2, 2000), ["tip", "edge"]), None)]
    chunks = CsvChunks([f"c{j}" for j in range(len(cols))], cols)
    body = bytes(chunks).partition(b"\n")[2]
    words = {b"tip": 0, b"edge": 3}
    got, bad = parse_rows(body, len(cols), words)
    assert bad == -1
    np.testing.assert_array_equal(chunks.as_written(words), got)


def test_blade_stl_is_the_blade_within_its_tolerance_and_a_foreign_one_is_found(written, tmp_path):
    import shutil

    from core.output.stl import read_stl, stl_bytes
    from core.paths.tessellation import SurfaceMesh

    out, _ = written
    mesh = read_stl(out / "blade.stl")
    assert 20_000 < len(mesh.triangles) < 200_000  # (the check tessellation has 1.15 M)
    for what, edit in (("shifted", lambda v: v + np.array([0.0, 0.0, 0.3])), ("cut", None)):
        d = tmp_path / what
        shutil.copytree(out, d)
        tris = mesh.triangles[: len(mesh.triangles) // 2] if edit is None else mesh.triangles
        verts = mesh.vertices if edit is None else edit(mesh.vertices)
        (d / "blade.stl").write_bytes(stl_bytes(SurfaceMesh(verts, tris)))
        findings = verify(d, workers=1).findings
        found = [f for f in findings if "not this plan's" in f]
        assert len(found) == 1 and ("up to 0.3 mm" if edit else "whole blade") in found[0], findings

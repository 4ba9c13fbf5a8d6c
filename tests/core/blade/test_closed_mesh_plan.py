"""A single closed blade mesh plans, and its plan passes ``bladecam verify``: one made from the sample
table's surface, and one made from the real BladeX blade's two STL sides. Where the section loop of a
closed mesh is split at LE and TE, face and back each keep their own facet's normal there (as two
surfaces do), so the two balls of the LE pair have distinct centres."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from core.blade.model import section_chord, section_max_thickness
from core.blade.source import load_blade
from core.output.writer import write_result
from core.planner import Planner
from core.records import PlanJob, PlanParameters
from core.verify.check import verify


def closed_mesh(face: np.ndarray, back: np.ndarray) -> trimesh.Trimesh:
    """A closed triangle mesh through rows of section points: face and back (n_r, m, 3), each row LE ->
    TE with the same LE and TE points; the hub and tip rows closed by fans from their mean point."""
    n_r = face.shape[0]
    loop = np.concatenate([face, back[:, -2:0:-1]], axis=1)
    n = loop.shape[1]
    i, j = (g.ravel() for g in np.meshgrid(np.arange(n_r - 1), np.arange(n), indexing="ij"))
    a, b = i * n + j, i * n + (j + 1) % n
    tris = [np.column_stack([a, b, b + n]), np.column_stack([a, b + n, a + n])]
    centres = []
    for row, flip in ((0, True), (n_r - 1, False)):
        centre = n_r * n + len(centres)
        centres.append(loop[row].mean(axis=0))
        ring = row * n + np.arange(n)
        fan = np.column_stack([np.full(n, centre), ring, np.roll(ring, -1)])
        tris.append(fan[:, ::-1] if flip else fan)
    centres = np.array(centres)  # on the cylinders of their rows (the cap is no part of the span)
    ring_r = np.hypot(loop[[0, -1], :, 0], loop[[0, -1], :, 1]).mean(axis=1)
    centres[:, :2] *= (ring_r / np.hypot(centres[:, 0], centres[:, 1]))[:, None]
    mesh = trimesh.Trimesh(np.concatenate([loop.reshape(-1, 3), centres]), np.concatenate(tris), process=True)
    assert mesh.is_watertight
    return mesh


def sample_closed_mesh(n_r: int = 60, m: int = 121) -> trimesh.Trimesh:
    """The sample table's surface at n_r radii (hub to 0.995 R) and m cosine-spaced chordwise stations."""
    table = load_blade("sample")
    radii = np.linspace(table.hub_radius, 0.995 * table.tip_radius, n_r)
    xi = 0.5 * (1.0 - np.cos(np.pi * np.linspace(0.0, 1.0, m)))
    face, back = table.surface_points(np.repeat(radii, m), np.tile(xi, n_r))
    return closed_mesh(face.reshape(n_r, m, 3), back.reshape(n_r, m, 3))


def bladex_closed_mesh(bladex_dir, n_r: int = 60, m: int = 161) -> trimesh.Trimesh:
    """The BladeX blade as one closed mesh: its STL pair's sections (points on the facets, in the blade
    frame) at n_r radii, each side resampled to m points by arc length, joined and capped."""
    from core.blade.model import resample_polyline

    pair = load_blade(f"{bladex_dir / 'upper.stl'},{bladex_dir / 'lower.stl'}", axis="x")
    span = pair.tip_radius - pair.hub_radius
    radii = pair.hub_radius + span * np.linspace(0.01, 0.99, n_r)
    rows = [pair.section(float(r)) for r in radii]
    face = np.array([resample_polyline(s.face, m) for s in rows])
    back = np.array([resample_polyline(s.back, m) for s in rows])
    return closed_mesh(face, back)


def plan_and_verify(source: str, params: PlanParameters, folder, axis: str = "z"):
    """Plan a blade (no axis tables), write it and check it with ``bladecam verify``'s own code."""
    res = Planner(workers=2).plan(PlanJob(source, axis, params, axes=False))
    assert res.safe, res.figures["min_tip_spacing_mm"]
    assert not res.blocking_findings, res.blocking_findings[:3]
    out = write_result(res, folder / "plan", workers=2)
    findings = verify(out).findings
    assert not findings, findings[:5]
    return res


def test_closed_mesh_sections_keep_each_sides_normal_at_le_and_te(tmp_path):
    path = tmp_path / "sample.stl"
    sample_closed_mesh().export(path)
    blade, table = load_blade(str(path)), load_blade("sample")
    for frac in (0.3, 0.6, 0.9):
        r = frac * table.tip_radius
        s, t = blade.section(r), table.section(r)
        assert section_chord(s) == pytest.approx(section_chord(t), rel=2e-3)
        assert section_max_thickness(s) == pytest.approx(section_max_thickness(t), rel=2e-2)
        for end in (0, -1):
            assert np.array_equal(s.face[end], s.back[end])
            # each side's own facet: the normal at the end is its neighbour's (the same facet)
            for pts, nrm in ((s.face, s.face_normals), (s.back, s.back_normals)):
                nb = -2 if end == -1 else 1
                assert np.dot(nrm[end], nrm[nb]) > 1 - 1e-9
                assert abs(np.dot(nrm[end], pts[nb] - pts[end])) < 1e-9
            assert np.dot(s.face_normals[end], s.back_normals[end]) < 1 - 1e-6


def test_a_closed_mesh_made_from_the_sample_table_plans_and_verifies(tmp_path):
    path = tmp_path / "sample.stl"
    sample_closed_mesh().export(path)
    res = plan_and_verify(str(path), PlanParameters(dr=8.0), tmp_path)
    counts = res.plan.region_counts()
    assert counts["paths"] > 15 and 0 < counts["tip_paths"] < counts["paths"]


def test_the_bladex_blade_as_one_closed_mesh_plans_and_verifies(bladex_dir, tmp_path):
    path = tmp_path / "bladex.stl"
    bladex_closed_mesh(bladex_dir).export(path)
    res = plan_and_verify(str(path), PlanParameters(dr=6.0), tmp_path)
    assert res.plan.region_counts()["paths"] > 10

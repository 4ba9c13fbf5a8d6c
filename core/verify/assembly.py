"""verify's whole-tool check: the tool assembly of the folder's tool.toml (and, with machine.toml,
the heads) against the blade, the clamp and the other side, on every row of both CL tables and
between them (core.machine.collisions, the planner's own check run again on the written rows).
The folder's blade.stl must be this plan's blade within its stated tolerance (``stl_matches``)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from core.errors import BladecamError
from core.machine.clearance import clamp_of
from core.machine.collisions import check_rows, folder_findings, rows_poses
from core.machine.model import load_machine
from core.machine.tool import assembly, load_tool
from core.output.stl import read_stl
from core.paths.tessellation import EXPORT_TOLERANCE, TriangleIndex, distance_to_surface
from core.verify.cutters import MISS_TOLERANCE
from core.verify.report import Report

ASSEMBLY_FILES = ("tool.toml", "blade.stl")
#: mm: how far blade.stl's corners (points of the blade) may lie from the blade's fresh tessellation:
#: the export's stated tolerance (core.paths.tessellation.EXPORT_TOLERANCE) and the fresh
#: tessellation's own error, which inside a rounded edge is a few hundredths of a millimetre (the
#: sample's: 0.036 mm; core.verify.cutters.MISS_TOLERANCE). A foreign blade lies millimetres off.
STL_TOLERANCE = EXPORT_TOLERANCE + MISS_TOLERANCE
#: how far blade.stl's area may differ from the fresh tessellation's, relative (both approximate one
#: surface within hundredths of a millimetre: a blade cut short or a foreign one differs by far more)
STL_AREA_TOLERANCE = 2e-3


def mesh_area(corners: np.ndarray) -> float:
    """mm^2: the area of triangles given by their corners (n, 3, 3) mm."""
    return 0.5 * float(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]),
                                      axis=1).sum())


def stl_matches(folder: Path, distance, area: float, rep: Report) -> bool:
    """Whether blade.stl is this plan's blade: every corner within STL_TOLERANCE of the blade's fresh
    tessellation (``distance``: corners (n, 3) mm -> (n,) mm to it) and its area within
    STL_AREA_TOLERANCE of that tessellation's ``area`` (mm^2); a finding where it is not."""
    try:
        mesh = read_stl(folder / "blade.stl")
    except BladecamError as exc:
        rep.bad("collision", str(exc))
        return False
    corners = mesh.vertices.reshape(-1, 3, 3)
    off = float(distance(np.unique(mesh.vertices, axis=0)).max())
    if off > STL_TOLERANCE:
        rep.bad("collision", f"blade.stl's corners lie up to {off:.3g} mm from the blade (its fresh tessellation), "
                             f"beyond {STL_TOLERANCE:g} mm: it is not this plan's blade")
        return False
    got = mesh_area(corners)
    if abs(got - area) > STL_AREA_TOLERANCE * area:
        rep.bad("collision", f"blade.stl's area is {got:.1f} mm^2, the blade's {area:.1f} mm^2: it is not this "
                             "plan's whole blade")
        return False
    return True


def assembly_checks(folder: Path, left: dict, right: dict, inp: dict, x_clamp: float, index: TriangleIndex,
                    machine: bool) -> Report:
    """Findings of kind 'collision' and the figures for the folder's tool assembly (module docstring):
    ``left``, ``right`` the CL tables (core.verify.read.read_cl), ``inp`` plan.json's inputs, ``index``
    the blade's check tessellation made afresh, ``machine`` whether the folder has machine.toml (the
    heads are checked with it)."""
    rep = Report()
    try:
        tool = load_tool(folder / "tool.toml")
        model = load_machine(folder / "machine.toml") if machine else None
        parts = assembly(tool, model) if model is not None else tool.parts()
    except BladecamError as exc:
        rep.bad("collision", str(exc))
        return rep
    if abs(tool.ball_radius - inp["tool_radius"]) > 1e-9:
        rep.bad("collision", f"tool.toml's ball_radius_mm = {tool.ball_radius:g} differs from plan.json's tool "
                             f"radius {inp['tool_radius']:g}")
    fresh = np.stack([index.a.T, (index.a + index.ab).T, (index.a + index.ac).T], axis=1)
    if not stl_matches(folder, lambda p: distance_to_surface(p, index), mesh_area(fresh), rep):
        return rep
    clamp = clamp_of(index, x_clamp, model.clamp_half_width if model is not None else 1.0)
    t0 = time.perf_counter()
    profile = check_rows(parts, index, clamp,
                         rows_poses(left["p"], left["w"], right["p"], right["w"], tool.ball_radius))
    lines = folder_findings(profile, left["t"], {"left": left["path"], "right": right["path"]})
    for line in lines:
        rep.bad("collision", line)
    if len(profile.collisions) > len(lines):
        rep.bad("collision", f"and {len(profile.collisions) - len(lines)} more collision stretches",
                count=len(profile.collisions) - len(lines))
    fig = profile.figures()  # (flat, short figures: the report's lines stay short)
    rep.figures["collisions"] = fig["collisions"]
    for side, parts in fig["blade_mm"].items():
        for part, value in parts.items():
            rep.figures[f"{side}_{part.replace(' ', '_')}_blade_mm"] = value
    for key in ("clamp_mm", "tools_mm", "heads_mm"):
        rep.figures[f"collision_{key}"] = fig[key]
    rep.figures["collision_check_s"] = round(time.perf_counter() - t0, 3)
    return rep

"""verify's whole-tool check: the tool assembly of the folder's tool.toml (and, with machine.toml,
the heads) against the blade, the clamp and the other side, on every row of both CL tables and
between them (core.machine.collisions, the planner's own check run again on the written rows).
The blade is the folder's blade.stl, which must match the blade's check tessellation made afresh
(the same triangles, to the file's float32 digits)."""

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
from core.paths.tessellation import TriangleIndex
from core.verify.report import Report

ASSEMBLY_FILES = ("tool.toml", "blade.stl")
#: mm: how far blade.stl's corners may lie from the fresh tessellation's (float32 at 250 mm: 1.5e-5)
STL_TOLERANCE = 1e-4


def stl_matches(folder: Path, index: TriangleIndex, rep: Report) -> bool:
    """Whether blade.stl holds the triangles of ``index`` (the blade's check tessellation made afresh);
    a finding where it does not."""
    try:
        mesh = read_stl(folder / "blade.stl")
    except BladecamError as exc:
        rep.bad("collision", str(exc))
        return False
    corners = mesh.vertices.reshape(-1, 3, 3)
    if len(corners) != index.a.shape[1]:
        rep.bad("collision", f"blade.stl holds {len(corners)} triangles, the blade's check tessellation "
                             f"{index.a.shape[1]}: it is not this plan's blade")
        return False
    a = index.a.T
    off = max(float(np.abs(corners[:, 0] - a).max()), float(np.abs(corners[:, 1] - (a + index.ab.T)).max()),
              float(np.abs(corners[:, 2] - (a + index.ac.T)).max()))
    if off > STL_TOLERANCE:
        rep.bad("collision", f"blade.stl's corners lie up to {off:.3g} mm from the blade's check tessellation: "
                             "it is not this plan's blade")
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
    if not stl_matches(folder, index, rep):
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

"""verify's whole-tool check, with code of its own (core.verify.distance, core.verify.sweep): the tool
assembly of the folder's tool.toml (and, with machine.toml, the heads: spindle housing and platform)
on every row of both CL tables and between rows, against
- the blade: its tessellation made afresh, on verify's own index (the folder's blade.stl must be this
  plan's blade within its stated tolerance: ``stl_matches``);
- the clamp block that grips the root (``clamp_box``; the heads' parts only);
- the other side's parts (both assemblies on one time column).
Each part is a cylinder about the tool axis, from s0 to s1 mm along it from the ball centre, of a
radius (core.machine.tool.Part: the tool file is an input), checked as the capsule round its axis
segment (which holds it). A clearance below -TOLERANCE (core.verify.sweep) is a collision. A part's
clearance from the blade is measured exactly up to EXACT_MM and its least (the figure) is exact
where below FIGURE_MM, a lower bound above; the clamp's and the other side's (closed forms) are
exact where below PAIR_MM.

How the tessellation's error counts: the clearances are to the blade's triangles made afresh, the
ones the planner checks against. Between sections and stations they lie within
core.paths.tessellation.MESH_TOLERANCE (0.25 micrometres) of a table blade, far inside TOLERANCE;
inside a rounded edge their chords cut into the blade by up to a few hundredths of a millimetre
(core.verify.cutters.MISS_TOLERANCE), where a part's clearance from the blade itself may be that
much less than the one measured (a mesh blade's own facets are the blade).
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from core.errors import BladecamError
from core.machine.model import load_machine
from core.machine.tool import Part, assembly, load_tool
from core.output.stl import read_stl
from core.paths.tessellation import EXPORT_TOLERANCE
from core.util.polyline import ball_centres
from core.verify.cutters import MISS_TOLERANCE
from core.verify.distance import DistanceIndex, box_gaps, box_sweeps, pair_sweeps, segment_gaps
from core.verify.report import Report
from core.verify.sweep import (
    TOLERANCE,
    Stretch,
    between_rows,
    bounded,
    motion,
    poses_between,
    reach,
    stretches,
)

ASSEMBLY_FILES = ("tool.toml", "blade.stl")
#: mm: how far blade.stl's corners (points of the blade) may lie from the blade's fresh tessellation:
#: the export's stated tolerance (core.paths.tessellation.EXPORT_TOLERANCE) and the fresh
#: tessellation's own error, which inside a rounded edge is a few hundredths of a millimetre (the
#: sample's: 0.036 mm; core.verify.cutters.MISS_TOLERANCE). A foreign blade lies millimetres off.
STL_TOLERANCE = EXPORT_TOLERANCE + MISS_TOLERANCE
#: how far blade.stl's area may differ from the fresh tessellation's, relative (both approximate one
#: surface within hundredths of a millimetre: a blade cut short or a foreign one differs by far more)
STL_AREA_TOLERANCE = 2e-3
#: mm: blade.stl's corners are the fresh tessellation's themselves where within this of them (float32
#: at 250 mm: 1.5e-5), and their distances from it measured exactly up to STL_MEASURED
STL_SAME = 1e-4
STL_MEASURED = 1.0
#: mm: a part's clearance from the blade is measured exactly up to EXACT_MM, and its least (the
#: figure) is exact where below FIGURE_MM, a lower bound above (parts farther off cost a few lookups
#: of the index's coarse field, and rows whose bound stays above it are not measured)
EXACT_MM = 0.5
FIGURE_MM = 0.25
#: mm: the least clearance between the two sides' parts, and of the heads from the clamp, is exact
#: where below this, a lower bound above
PAIR_MM = 5.0
#: collision lines shown (the rest counted in one line)
SHOWN = 20
SIDES = ("left", "right")


def mesh_area(corners: np.ndarray) -> float:
    """mm^2: the area of triangles given by their corners (n, 3, 3) mm."""
    return 0.5 * float(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]),
                                      axis=1).sum())


def stl_matches(folder: Path, index: DistanceIndex, rep: Report) -> bool:
    """Whether blade.stl (read by core.output.stl.read_stl, the writer's own reader) is this plan's
    blade: the triangles of ``index`` themselves (the blade's tessellation made afresh, to the file's
    float32 digits: an earlier version's blade.stl), or a mesh whose every corner lies within
    STL_TOLERANCE of them (verify's own distances, exact up to STL_MEASURED) and whose area is within
    STL_AREA_TOLERANCE of theirs; a finding where it is not. (How blade.stl is written is the
    writer's: only this function reads it.)"""
    try:
        mesh = read_stl(folder / "blade.stl")
    except BladecamError as exc:
        rep.bad("collision", str(exc))
        return False
    v, tris = np.asarray(mesh.vertices, float), np.asarray(mesh.triangles)
    plain = tris.size == len(v) and np.array_equal(tris.ravel(), np.arange(tris.size))
    corners = v.reshape(-1, 3, 3) if plain else v[tris]  # (read_stl: each triangle its own corners)
    if len(corners) == len(index.mesh.triangles) and _largest_gap(corners, index.corners) <= STL_SAME:
        return True
    points = _distinct(corners.reshape(-1, 3))  # (a corner is shared by about six triangles)
    near = index.distances(points, cutoff=STL_TOLERANCE)  # (exact up to the tolerance: most are 0)
    far = near > STL_TOLERANCE
    off = float(index.distances(points[far], cutoff=STL_MEASURED).max(initial=near.max(initial=0.0)))
    if off > STL_TOLERANCE:
        rep.bad("collision", f"blade.stl's corners lie up to {off:.3g} mm from the blade (its fresh tessellation), "
                             f"beyond {STL_TOLERANCE:g} mm: it is not this plan's blade")
        return False
    got, area = mesh_area(corners), index.area
    if abs(got - area) > STL_AREA_TOLERANCE * area:
        rep.bad("collision", f"blade.stl's area is {got:.1f} mm^2, the blade's {area:.1f} mm^2: it is not this "
                             "plan's whole blade")
        return False
    return True


def _distinct(points: np.ndarray) -> np.ndarray:
    """The points (n, 3) with repeats dropped, in their first order (neighbours stay neighbours for the
    search): sorted by a hash of their bits, a point equal to the one before it in that order is a
    repeat (two points whose hashes collide are both kept: none is ever lost)."""
    bits = np.ascontiguousarray(points, float).view(np.uint64)
    key = bits[:, 0] * np.uint64(0x9E3779B97F4A7C15) ^ bits[:, 1] * np.uint64(0xC2B2AE3D27D4EB4F) ^ bits[:, 2]
    order = np.argsort(key, kind="stable")
    p = points[order]
    repeat = np.zeros(len(p), bool)
    repeat[1:] = (key[order][1:] == key[order][:-1]) & (p[1:] == p[:-1]).all(axis=1)
    return points[np.sort(order[~repeat])]


def _largest_gap(a: np.ndarray, b: np.ndarray) -> float:
    """mm: the largest coordinate difference of two equal arrays (n, ...) (in blocks: no whole-array
    temporaries)."""
    return max((float(np.abs(a[k:k + 65536] - b[k:k + 65536]).max()) for k in range(0, len(a), 65536)),
               default=0.0)


def clamp_box(index: DistanceIndex, x_clamp: float, half_width: float) -> tuple[np.ndarray, np.ndarray]:
    """The clamp block (lo, hi) (3,) mm, W: X_W <= x_clamp, |Z_W| <= half_width, and along Y_W as long
    as the blade's triangle corners inboard of the clamp plane (the root it grips; the whole blade's
    extent where none lie inboard)."""
    v = np.asarray(index.mesh.vertices, float)
    used = np.zeros(len(v), bool)
    used[np.asarray(index.mesh.triangles).ravel()] = True  # (each corner once, not once per triangle)
    xy = v[used, :2]
    root = xy[xy[:, 0] <= x_clamp, 1]
    y = root if root.size else xy[:, 1]
    return (np.array([-np.inf, float(y.min()), -half_width]), np.array([x_clamp, float(y.max()), half_width]))


class Side:
    """One side's rows as the check sees them: ball centres (n, 3) mm and unit axes (n, 3), W, and per
    part its cumulative motion bound along the rows (core.verify.sweep.motion)."""

    def __init__(self, cl: dict, radius: float, parts: tuple[Part, ...]):
        self.w = np.ascontiguousarray(cl["w"], float)
        self.c = np.ascontiguousarray(ball_centres(cl["p"], self.w, radius), float)
        self.path = cl["path"]
        moves = motion(self.c, self.w)
        self.reach = {p.name: reach(moves, _span(p)) for p in parts}

    def segment(self, part: Part, rows: np.ndarray, frac: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The part's axis segment (ends (m, 3) mm each) at the rows, or between them (``frac``)."""
        c, w = (self.c[rows], self.w[rows]) if frac is None else poses_between(self.c, self.w, rows, frac)
        return c + part.s0 * w, c + part.s1 * w


def _blade(side: Side, part: Part, index: DistanceIndex) -> tuple[np.ndarray, list[Stretch]]:
    """One part of one side against the blade: (clearance (n,) mm, lower bounds; collision stretches)."""
    reach = side.reach[part.name]
    values, measured = index.sweep(side.c, side.w, (part.s0, part.s1, part.radius), reach, EXACT_MM, FIGURE_MM,
                                   TOLERANCE)
    values = bounded(values, measured, reach)  # (each row also from the measured row after it)

    def at(rows, frac):
        p0, p1 = side.segment(part, rows, frac)
        return index.distances(p0, p1, part.radius + EXACT_MM) - part.radius

    return values, stretches(values, between_rows(values, reach, at))


def _clamp(side: Side, part: Part, box: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, list[Stretch]]:
    """One head part of one side against the clamp block (exact closed form wherever measured)."""
    def at(rows, frac=None):
        return box_gaps(*side.segment(part, rows, frac), *box) - part.radius

    reach = side.reach[part.name]
    values = box_sweeps(side.c, side.w, (part.s0, part.s1, part.radius), box, reach, PAIR_MM, TOLERANCE)
    return values, stretches(values, between_rows(values, reach, at))


def _pairs(sides: dict[str, Side], group: list[tuple[Part, Part]]) -> tuple[np.ndarray, list[Stretch]]:
    """A group of (left part, right part) pairs: the least clearance between the two capsules of any
    pair at each row (each pair swept on its own, exact in closed form wherever measured: where below
    PAIR_MM, the least is) and the group's collision stretches."""
    left, right = sides["left"], sides["right"]

    def gap(a, b, rows, frac=None):
        return segment_gaps(*left.segment(a, rows, frac), *right.segment(b, rows, frac)) - a.radius - b.radius

    values = np.full(len(left.c), np.inf)
    for a, b in group:
        v = pair_sweeps((left.c, right.c), (left.w, right.w), ((a.s0, a.s1, a.radius), (b.s0, b.s1, b.radius)),
                        left.reach[a.name] + right.reach[b.name], PAIR_MM, TOLERANCE)
        np.minimum(values, v, out=values)
    # (the group's motion: its parts' that reach farthest on each side, whose bounds hold for the rest)
    far = (max((a for a, _ in group), key=_span), max((b for _, b in group), key=_span))
    moved = left.reach[far[0].name] + right.reach[far[1].name]
    return values, stretches(values, between_rows(values, moved, lambda rows, frac: np.min(
        [gap(a, b, rows, frac) for a, b in group], axis=0)))


def _span(part: Part) -> float:
    """mm: how far the part's axis reaches from the ball centre."""
    return max(abs(part.s0), abs(part.s1))


def _pair_at(sides: dict[str, Side], group: list[tuple[Part, Part]], row: int) -> tuple[Part, Part]:
    """The pair of ``group`` that comes closest at ``row``."""
    one = np.array([row])
    gaps = [float(segment_gaps(*sides["left"].segment(a, one), *sides["right"].segment(b, one))[0]) - a.radius
            - b.radius for a, b in group]
    return group[int(np.argmin(gaps))]


def _groups(tool_parts: list[Part], heads: list[Part]) -> list[list[tuple[Part, Part]]]:
    """The pairs of parts of the two sides in three groups (each checked as its least clearance at a
    row): tool against tool, head against head, a tool against the other side's head."""
    groups = [[(a, b) for a in tool_parts for b in tool_parts], [(a, b) for a in heads for b in heads],
              [(a, b) for a in tool_parts for b in heads] + [(a, b) for a in heads for b in tool_parts]]
    return [g for g in groups if g]


def _line(side: str, part: str, against: str, s: Stretch, t: np.ndarray, path: np.ndarray) -> str:
    """One collision line: the part, what it hits, where (path and time) and how deep."""
    where = f"t = {float(t[s.row]):.0f} ms"
    if path[s.row] >= 0:
        where = f"path {int(path[s.row])}, {where}"
    who = f"the {side} {part}" if side != "both" else f"the left {part}"
    return f"{who} hits the {against} {s.depth:.3f} mm deep at {where}{' (between two rows)' if s.between else ''}"


def assembly_checks(folder: Path, left: dict, right: dict, inp: dict, x_clamp: float, index: DistanceIndex,
                    machine: bool) -> Report:
    """Findings of kind 'collision' and the figures for the folder's tool assembly (module docstring):
    ``left``, ``right`` the CL tables (core.verify.read.read_cl), ``inp`` plan.json's inputs, ``x_clamp``
    mm the clamp plane, ``index`` verify's index of the blade's tessellation made afresh, ``machine``
    whether the folder has machine.toml (the heads are checked with it)."""
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
    t0 = time.perf_counter()
    own = tool.parts()
    heads = [p for p in parts if p not in own]
    sides = {"left": Side(left, tool.ball_radius, parts), "right": Side(right, tool.ball_radius, parts)}
    box = clamp_box(index, x_clamp, model.clamp_half_width) if model is not None else None
    with ThreadPoolExecutor(2) as pool:  # (the searches release the GIL: a side a thread, while this one
        # reads blade.stl and checks the pairs; a foreign blade.stl leaves the rest unreported)
        jobs = [pool.submit(_one_side, sides[side], parts, heads, index, box) for side in SIDES]
        if not stl_matches(folder, index, rep):
            return rep
        pairs = _both(sides, list(own), heads)
        found = dict(zip(SIDES, (job.result() for job in jobs), strict=True))
    hits = [(side, part, against, s) for side in SIDES for part, against, s in found[side]["hits"]] + pairs["hits"]
    _report(hits, left["t"], {"left": left["path"], "right": right["path"]}, rep)
    for side in SIDES:
        for part, value in found[side]["blade"].items():
            rep.figures[f"{side}_{part.replace(' ', '_')}_blade_mm"] = value
    clamp_mm = min((found[side]["clamp"] for side in SIDES), default=np.inf)
    rep.figures.update({"collision_clamp_mm": round(clamp_mm, 4), "collision_tools_mm": round(pairs["tools"], 4),
                        "collision_heads_mm": round(pairs["heads"], 4),
                        "collision_check_s": round(time.perf_counter() - t0, 3)})
    return rep


def _both(sides: dict[str, Side], own: list[Part], heads: list[Part]) -> dict:
    """The two sides' parts against each other, in the groups of ``_groups``: {"tools": least mm of
    any pair, "heads": least mm of the heads' parts (inf without heads), "hits": [(side, part,
    against, Stretch), ...]} (side 'both', against the right part that comes closest at the row)."""
    out: dict = {"tools": np.inf, "heads": np.inf, "hits": []}
    for group in _groups(own, heads):
        values, runs = _pairs(sides, group)
        out["tools"] = min(out["tools"], float(values.min(initial=np.inf)))
        if group[0][0] in heads and group[0][1] in heads:
            out["heads"] = float(values.min(initial=np.inf))
        for s in runs:
            a, b = _pair_at(sides, group, s.row)
            out["hits"].append(("both", a.name, f"right {b.name}", s))
    return out


def _one_side(side: Side, parts: tuple[Part, ...], heads: list[Part], index: DistanceIndex,
              box: tuple[np.ndarray, np.ndarray] | None) -> dict:
    """One side's parts against the blade and its heads against the clamp: {"blade": {part: least
    mm}, "clamp": least mm (inf without heads), "hits": [(part, against, Stretch), ...]}."""
    out: dict = {"blade": {}, "clamp": np.inf, "hits": []}
    for part in parts:
        values, runs = _blade(side, part, index)
        out["blade"][part.name] = round(float(values.min(initial=np.inf)), 4)
        out["hits"] += [(part.name, "blade", s) for s in runs]
    for part in heads if box is not None else []:
        values, runs = _clamp(side, part, box)
        out["clamp"] = min(out["clamp"], float(values.min(initial=np.inf)))
        out["hits"] += [(part.name, "clamp", s) for s in runs]
    return out


def _report(hits: list[tuple[str, str, str, Stretch]], t: np.ndarray, paths: dict, rep: Report) -> None:
    """The collision lines, deepest first (SHOWN of them, the rest in one line that counts them), and
    the figure of how many stretches collide."""
    hits.sort(key=lambda h: -h[3].depth)
    for side, part, against, s in hits[:SHOWN]:
        rep.bad("collision", _line(side, part, against, s, t, paths["right" if side == "right" else "left"]))
    if len(hits) > SHOWN:
        rep.bad("collision", f"and {len(hits) - SHOWN} more collision stretches", count=len(hits) - SHOWN)
    rep.figures["collisions"] = len(hits)

"""The collision check of two sides' written rows: every part of both tool assemblies and heads
against the blade, the heads against the clamp, and each side's parts against the other's, on every
row and between rows (core.machine.clearance's sweep), gathered into a ClearanceProfile with the
stretches that collide."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from core.machine.clearance import (
    EXACT_MM,
    TOLERANCE,
    Clamp,
    clamp_of,
    interpolated,
    mesh_grid,
    part_blade,
    part_clamp,
    part_pair,
    row_steps,
    sweep,
)
from core.machine.tool import assembly
from core.paths.tessellation import FACET_CANDIDATES, TriangleIndex, surface_mesh
from core.util.parallel import per_side
from core.util.polyline import ball_centres

#: rows from which the two sides are checked in two threads
PARALLEL_ROWS = 20000

@dataclass(frozen=True)
class Collision:
    """One stretch of rows where a part collides: side ('left', 'right' or 'both'), part, what it hits
    ('blade', 'clamp', or the other side's part 'right spindle nose' ...), rows [first, last] of the
    stretch, the deepest row and its depth (mm, positive), and whether the deepest point lies between
    two rows (between)."""

    side: str
    part: str
    against: str
    first: int
    last: int
    row: int
    depth: float
    between: bool = False

    def describe(self, t_ms: np.ndarray | None = None, path: np.ndarray | None = None) -> str:
        """One line naming the part, what it hits, where (path and time when given) and how deep."""
        where = f"row {self.row}"
        if t_ms is not None:
            where = f"t = {float(t_ms[self.row]):.0f} ms"
        if path is not None and path[self.row] >= 0:
            where = f"path {int(path[self.row])}, {where}"
        who = f"the {self.side} {self.part}" if self.side != "both" else f"the left {self.part}"
        return (f"{who} hits the {self.against} {self.depth:.3f} mm deep at {where}"
                f"{' (between two rows)' if self.between else ''}")



#: the heads' parts (core.machine.tool.assembly): checked against the clamp and the other head
HEAD_PARTS = ("spindle housing", "platform")
SIDES = ("left", "right")


@dataclass
class ClearanceProfile:
    """The collision check of two sides' rows: parts (the part names, both sides alike); blade: side ->
    (n, P) float32 mm, each part's clearance from the blade; clamp: side -> (n, H) float32 mm, the
    heads' parts' from the clamp; tools (n,) float32 mm: the smallest clearance between any part of one
    side and any of the other, heads (n,) float32 mm: between the two heads' parts (each a lower bound,
    exact below EXACT_MM); collisions: the stretches that collide (``Collision``), deepest first;
    approach: (side, part, what) -> (row, mm) each item's closest approach (its least bound: exact
    below EXACT_MM, else no row comes closer), what being 'blade', 'clamp' or the other side's part
    ('right holder 2'), side 'both' for the latter."""

    parts: tuple[str, ...]
    blade: dict
    clamp: dict
    tools: np.ndarray
    heads: np.ndarray
    collisions: list
    approach: dict

    def at(self, row: int) -> dict[str, float]:
        """The clearances at one row: {'left neck': mm, ..., 'clamp': mm, 'tools': mm, 'heads': mm}."""
        out = {f"{side} {p}": float(self.blade[side][row, k]) for side in SIDES for k, p in enumerate(self.parts)}
        out["clamp"] = float(min(self.clamp[s][row].min(initial=np.inf) for s in SIDES))
        out["tools"], out["heads"] = float(self.tools[row]), float(self.heads[row])
        return out

    def closest(self, what: str) -> tuple[int, float, str]:
        """(row, mm, which) of the closest approach of ``what``: 'holder' (any holder stage of either
        side to the blade), 'heads' (a head's part to the other head's), 'tools' (any part to any of the
        other side), or a part name (either side, to the blade); ``which`` names the two."""
        def pick(key):
            side, part, other = key
            if what == "heads":
                return side == "both" and part in HEAD_PARTS and other.split(" ", 1)[1] in HEAD_PARTS
            if what == "tools":
                return side == "both"
            return other == "blade" and (part == what or (what == "holder" and part.startswith("holder")))

        keys = [k for k in self.approach if pick(k)]
        if not keys:
            raise KeyError(f"no part {what!r}: the parts are {', '.join(self.parts)}")
        key = min(keys, key=lambda k: self.approach[k][1])
        row, value = self.approach[key]
        side, part, other = key
        which = f"left {part} and {other}" if side == "both" else f"{side} {part} and the {other}"
        return row, value, which

    def figures(self) -> dict:
        """plan.json's figures: each part's closest approach to the blade per side, the heads' to the
        clamp, the tools' and the heads' to each other (mm: least bounds, exact below EXACT_MM), and the
        collisions counted."""
        def least(keys):
            return round(min((self.approach[k][1] for k in keys), default=float("inf")), 4)

        return {"tolerance_mm": TOLERANCE, "exact_below_mm": EXACT_MM,
                "blade_mm": {side: {p: least([(side, p, "blade")]) for p in self.parts} for side in SIDES},
                "clamp_mm": least([k for k in self.approach if k[2] == "clamp"]),
                "tools_mm": least([k for k in self.approach if k[0] == "both"]),
                "heads_mm": least([k for k in self.approach if k[0] == "both" and k[1] in HEAD_PARTS
                                   and k[2].split(" ", 1)[1] in HEAD_PARTS]),
                "collisions": len(self.collisions)}

    def rows_colliding(self) -> np.ndarray:
        """(n,) bool: the rows of a collision stretch (or next to a colliding interval)."""
        bad = np.zeros(len(self.tools), bool)
        for c in self.collisions:
            bad[c.first:c.last + 1] = True
        return bad


def _stretches(value: np.ndarray, hidden: list, side: str, part: str, against: str) -> list[Collision]:
    """The collision stretches of one clearance column (runs of rows below -TOLERANCE; a colliding
    pose between two rows is a stretch of the row before it)."""
    bad = value < -TOLERANCE
    out = []
    if bad.any():
        idx = np.flatnonzero(bad)
        cuts = np.flatnonzero(np.diff(idx) > 1)
        for lo, hi in zip(np.r_[0, cuts + 1], np.r_[cuts, len(idx) - 1], strict=True):
            first, last = int(idx[lo]), int(idx[hi])
            k = first + int(np.argmin(value[first:last + 1]))
            out.append(Collision(side, part, against, first, last, k, float(-value[k])))
    for row, _, v in hidden:
        out.append(Collision(side, part, against, row, row, row, float(-v), between=True))
    return out


def _item(evaluate, moves: np.ndarray, n: int) -> tuple[np.ndarray, list, tuple[int, float]]:
    """One item's sweep (``sweep``) and its closest approach (row, mm): the row of the least value (an
    evaluated row, ``sweep``): exact where below EXACT_MM (for the blade; the clamp's and the pairs'
    always), else a lower bound (no row comes closer)."""
    v, hidden = sweep(evaluate, moves, n)
    if not n:
        return v, hidden, (0, float("inf"))
    k = int(np.argmin(v))
    return v, hidden, (k, float(v[k]))


def check_rows(parts, index, clamp: Clamp, poses: dict) -> ClearanceProfile:
    """The collision check of two sides' rows (module docstring). ``parts``: core.machine.tool.assembly
    (both sides carry the same); ``index`` the blade's TriangleIndex (or its MeshGrid);
    ``poses``: side -> (centres (n, 3) mm, axes (n, 3) unit), W, one row each on a common time column."""
    parts = tuple(parts)
    n = len(poses["left"][0])
    names = tuple(p.name for p in parts)
    heads = [p for p in parts if p.name in HEAD_PARTS]
    found: list[Collision] = []
    closest: dict = {}
    pose = {side: tuple(np.asarray(x, float) for x in poses[side]) for side in SIDES}

    def at(side, rows, frac):
        c, w = pose[side]
        return (c[rows], w[rows]) if not frac.any() else interpolated(c, w, rows, frac)

    index = mesh_grid(index)  # (built once, before the two sides' threads share it)

    def one_side(side: str):
        c, w = pose[side]
        found, closest, moves = [], {}, {}
        blade = np.empty((n, len(parts)), np.float32)
        clamp_out = np.empty((n, len(heads)), np.float32)
        move, turn = row_steps(c, w)
        for k, part in enumerate(parts):
            moves[part.name] = move + max(abs(part.s0), abs(part.s1)) * turn
            v, hidden, closest[(side, part.name, "blade")] = _item(
                lambda rows, frac, part=part: part_blade(part, index, *at(side, rows, frac)), moves[part.name], n)
            blade[:, k] = v
            found += _stretches(v, hidden, side, part.name, "blade")
        for k, part in enumerate(heads):
            def ev(rows, frac, part=part):
                return part_clamp(part, clamp, *at(side, rows, frac))

            v, hidden, closest[(side, part.name, "clamp")] = _item(ev, moves[part.name], n)
            clamp_out[:, k] = v
            found += _stretches(v, hidden, side, part.name, "clamp")
        return blade, clamp_out, found, closest, moves

    done = per_side(one_side, parallel=n > PARALLEL_ROWS)
    blade = {side: done[side][0] for side in SIDES}
    clamp_out = {side: done[side][1] for side in SIDES}
    for side in SIDES:
        found += done[side][2]
        closest.update(done[side][3])
    moves = {(side, name): m for side in SIDES for name, m in done[side][4].items()}
    tools = np.full(n, np.inf)
    head_min = np.full(n, np.inf)
    tool_parts = [p for p in parts if p.name not in HEAD_PARTS]
    for group in _pair_groups(tool_parts, heads):
        def ev(rows, frac, group=group):
            left, right = at("left", rows, frac), at("right", rows, frac)
            return np.min([part_pair(a, b, *left, *right) for a, b in group], axis=0)

        # (a group's motion bound: its farthest parts' on each side)
        move = (np.max([moves[("left", a.name)] for a, _ in group], axis=0)
                + np.max([moves[("right", b.name)] for _, b in group], axis=0))
        v, hidden, (row, value) = _item(ev, move, n)
        a, b = _pair_at(group, pose, row)
        closest[("both", a.name, f"right {b.name}")] = (row, value)
        np.minimum(tools, v, out=tools)
        if a.name in HEAD_PARTS and b.name in HEAD_PARTS:
            np.minimum(head_min, v, out=head_min)
        for c in _stretches(v, hidden, "both", "", ""):
            a, b = _pair_at(group, pose, c.row)
            found.append(replace(c, part=a.name, against=f"right {b.name}"))
    found.sort(key=lambda f: -f.depth)
    return ClearanceProfile(names, blade, clamp_out, tools.astype(np.float32), head_min.astype(np.float32),
                            found, closest)


def _pair_groups(tool_parts: list, heads: list) -> list[list]:
    """The pairs of parts of the two sides in three groups swept one each (the least clearance of a
    group at a row): tool against tool, head against head, and a tool against the other side's head."""
    groups = [[(a, b) for a in tool_parts for b in tool_parts], [(a, b) for a in heads for b in heads],
              [(a, b) for a in tool_parts for b in heads] + [(a, b) for a in heads for b in tool_parts]]
    return [g for g in groups if g]


def _pair_at(group: list, pose: dict, row: int) -> tuple:
    """The pair of ``group`` (left part, right part) that comes closest at ``row``."""
    one = slice(row, row + 1)
    left, right = (pose["left"][0][one], pose["left"][1][one]), (pose["right"][0][one], pose["right"][1][one])
    return group[int(np.argmin([part_pair(a, b, *left, *right)[0] for a, b in group]))]


def rows_poses(tips_left, axes_left, tips_right, axes_right, tool_radius: float) -> dict:
    """side -> (ball centres, axes) of two sides' rows of tool tips and unit axes (n, 3), W."""
    return {"left": (ball_centres(tips_left, axes_left, tool_radius), axes_left),
            "right": (ball_centres(tips_right, axes_right, tool_radius), axes_right)}


def refusal(profile: ClearanceProfile, t_ms: np.ndarray, path_left: np.ndarray, path_right: np.ndarray,
            limit: int = 6) -> str:
    """The refusal's text: each colliding stretch (deepest first, up to ``limit``) with its path, time,
    part and depth, and what to change."""
    lines = []
    for c in profile.collisions[:limit]:
        path = path_right if c.side == "right" else path_left
        lines.append(c.describe(t_ms, path))
    more = len(profile.collisions) - limit
    return ("the tool assembly collides, nothing was written:\n  " + "\n  ".join(lines)
            + (f"\n  (and {more} more)" if more > 0 else "")
            + "\nuse a longer neck or stick-out, a slimmer holder (--tool FILE), or --force to write it anyway")


def tool_only(parts) -> tuple:
    """The parts of a tool assembly without the head's (a plan folder without machine.toml)."""
    return tuple(p for p in parts if p.name not in HEAD_PARTS)


def folder_findings(profile: ClearanceProfile, t_ms: np.ndarray, paths: dict, limit: int = 20) -> list[str]:
    """verify's lines for a folder's collisions: each stretch (deepest first, up to ``limit``) with
    its path, time, part and depth."""
    out = []
    for c in profile.collisions[:limit]:
        out.append(c.describe(t_ms, paths["right" if c.side == "right" else "left"]))
    return out


def blade_index(plan) -> TriangleIndex:
    """The mesh a PathPlan's tool assembly is checked against, the one ``bladecam verify`` measures
    balls against: its gouge guard's (a mesh blade's split facets, a table's check tessellation) when
    it has one, else the check tessellation built here."""
    guard = getattr(plan, "guard", None)
    if guard is not None and getattr(guard, "index", None) is not None:
        return guard.index
    faceted = hasattr(plan.blade, "facets")
    return TriangleIndex(surface_mesh(plan.blade, plan.frame), k=FACET_CANDIDATES if faceted else 8)


def plan_collisions(plan, timeline, tool, machine, index: TriangleIndex | None = None) -> ClearanceProfile:
    """The collision check of a plan's written rows (timeline: both sides' tips and axes on one time
    column) for a tool (core.machine.tool.Tool) on a machine; ``index`` the blade's mesh (default
    ``blade_index``)."""
    index = blade_index(plan) if index is None else index
    r = tool.ball_radius
    poses = rows_poses(timeline.left.tips, timeline.left.axes, timeline.right.tips, timeline.right.axes, r)
    return check_rows(assembly(tool, machine), index, clamp_of(index, plan.frame.x_clamp, machine.clamp_half_width),
                      poses)

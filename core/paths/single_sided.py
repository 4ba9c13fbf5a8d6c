"""Single-sided pairs: the tip region's (paper section 4), and paths taken out of collaborative
machining after the region division (the tip region entered later): when the schedule cannot keep the
safety rule round a path's transitions, that path is machined single-sided, alternately by each
cutter, like the tip region's paths.

**Each contact to the cutter it faces.** A section is split into its two sides at LE and TE (the
paper's split, core.paths.contours). Where a blade's side turns past its edge onto the other side (a
mesh whose face/back seam lies beyond the edge, a section that curls round a thin tip), a single-sided
path's end runs over contacts that face the other cutter: the left cutter works the side facing -Z_W,
so a contact whose normal has n_z > sin(FACING_DEG) faces the right cutter more than FACING_DEG past
the side's silhouette. No head reaches such a contact with its ball: the default head tilts 40 degrees
and the contact stays within 80 of the axis (core.machine.tool_axes), 120 in all from its own spindle,
which is FACING_DEG past the silhouette; beyond it the flutes and the neck would cut the blade. So
``facing_sides`` hands each end run of such contacts to the other cutter, whose path then continues
round the edge onto them (the two sides' paths meet at the same edge point, so the run is appended
reversed at that end); a section whose sides never turn that far is unchanged."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core.paths.alignment import align_single, sides
from core.paths.contours import ContourPath
from core.paths.guard import blade_guard, guard_pair
from core.paths.plan import PathPlan
from core.paths.regions import Regions
from core.records import PlanParameters

#: a contact whose normal faces the other cutter this many degrees past its side's silhouette (the
#: plane n_z = 0) is machined by the other cutter (module docstring)
FACING_DEG = 30.0


def _end_run(away: np.ndarray) -> int:
    """How many points from the start of a side belong to the other cutter: up to the farthest point
    facing it within the side's first half (0: none)."""
    head = np.flatnonzero(away[: len(away) // 2])
    return int(head[-1]) + 1 if head.size else 0


def _off(run: np.ndarray, seam: np.ndarray) -> np.ndarray:
    """The rows of a run not on the point ``seam`` (the side's own end point, shared at the edge)."""
    return np.linalg.norm(run - seam, axis=1) > 1e-9


def facing_sides(path: ContourPath) -> ContourPath:
    """``path`` with each side's end runs of contacts that face the other cutter more than FACING_DEG
    past the side's silhouette handed to the other cutter (module docstring); ``path`` itself when
    there are none.

    At an end where only one side turns that far, its run is appended to the other side round the
    shared edge point, reversed. Where both do, the sides cross: two sheets run side by side from the
    seam, each facing the other cutter, as a mesh's pieces can at a thin tip. If the left's run lies
    above the right's (on +Z_W, the side it faces), the sheets are the blade's with the cutters
    swapped, and the runs change sides in their own order. Else the sheets face each other across
    no material (the pieces pass through each other: a thickness below zero), and neither cutter
    machines them: both runs are left out."""
    limit = np.sin(np.radians(FACING_DEG))
    sides_ = {"left": (path.left_cc, path.left_normals), "right": (path.right_cc, path.right_normals)}
    away = {"left": path.left_normals[:, 2] > limit, "right": path.right_normals[:, 2] < -limit}
    runs = {side: (_end_run(a), _end_run(a[::-1])) for side, a in away.items()}
    if not any(any(r) for r in runs.values()):
        return path
    crossed = [False, False]  # per end: the runs change sides (else, both present: both left out)
    for end in (0, 1):
        k, m = runs["left"][end], runs["right"][end]
        if k and m:
            left_run = path.left_cc[:k] if end == 0 else path.left_cc[len(path.left_cc) - k:]
            right_run = path.right_cc[:m] if end == 0 else path.right_cc[len(path.right_cc) - m:]
            crossed[end] = bool(left_run[:, 2].mean() > right_run[:, 2].mean())
    new = {}
    for side, other in (("left", "right"), ("right", "left")):
        (pts, n), (o_pts, o_n) = sides_[side], sides_[other]
        (k0, k1), (m0, m1) = runs[side], runs[other]
        head_p, head_n, tail_p, tail_n = o_pts[:0], o_n[:0], o_pts[:0], o_n[:0]
        if m0 and k0:  # both turn at the start: the other's run in its order, or neither
            if crossed[0]:
                head_p, head_n = o_pts[:m0], o_n[:m0]
        elif m0:  # the other's run, reversed, up to this side's start
            keep = _off(o_pts[:m0], pts[0])
            head_p, head_n = o_pts[:m0][keep][::-1], o_n[:m0][keep][::-1]
        last = slice(len(o_pts) - m1, len(o_pts))
        if m1 and k1:
            if crossed[1]:
                tail_p, tail_n = o_pts[last], o_n[last]
        elif m1:
            keep = _off(o_pts[last], pts[-1])
            tail_p, tail_n = o_pts[last][keep][::-1], o_n[last][keep][::-1]
        mid = slice(k0, len(pts) - k1)
        new[side] = (np.concatenate([head_p, pts[mid], tail_p]), np.concatenate([head_n, n[mid], tail_n]))
    return replace(path, left_cc=new["left"][0], left_normals=new["left"][1], right_cc=new["right"][0],
                   right_normals=new["right"][1])


def single_sided_pair(path, fitted, symmetric, params: PlanParameters, guard):
    """The single-sided (tip region) pair of a contour path: aligned for single-sided machining
    (core.paths.alignment.align_single, from its fitted sides and its symmetrical pair), its balls
    kept out of the blade by ``guard`` (core.paths.guard). Its contacts are first handed to the cutter
    they face (``facing_sides``)."""
    p = params
    facing = facing_sides(path)
    if facing is not path:
        path, fitted = facing, sides(facing)
    single = align_single(path, p.dd, p.tool_radius, p.tool_length, fitted, symmetric=symmetric)
    return guard_pair(single, guard, p.tool_radius)


def to_single_sided(plan: PathPlan, indices: set[int], reason: str) -> PathPlan:
    """``plan`` with the pairs of path indices ``indices`` (AlignedPair.index) aligned for single-sided
    machining (core.paths.alignment.align_single, its balls kept out of the blade by core.paths.guard)
    and put in the tip region with ``reason`` recorded (and a warning); their staggered ratio stays
    the one measured. The other pairs are the same objects; pairs.csv's rows are formatted again."""
    p = plan.params
    guard = plan.guard if plan.guard is not None else blade_guard(plan.blade, plan.frame, p.tool_radius)
    by_index = {path.index: path for path in plan.paths}
    pairs, regions = [], []
    for pair, reg in zip(plan.pairs, plan.regions, strict=True):
        if pair.index in indices and not reg.is_tip:
            path = by_index[pair.index]
            pair = single_sided_pair(path, sides(path), pair, p, guard)
            reg = Regions(labels=np.full(len(pair.u), "tip"), staggered_ratio=reg.staggered_ratio, is_tip=True,
                          reason=reason)
        pairs.append(pair)
        regions.append(reg)
    moved = sorted(i for i in indices if i in by_index)
    listed = ", ".join(map(str, moved[:12])) + (f" and {len(moved) - 12} more" if len(moved) > 12 else "")
    warning = f"path{'s' if len(moved) > 1 else ''} {listed} machined single-sided: {reason}"
    return replace(plan, pairs=pairs, regions=regions, pairs_rows=None, warnings=[*plan.warnings, warning])

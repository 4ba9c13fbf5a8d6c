"""Paths taken out of collaborative machining after the region division (paper section 4's tip
region, entered later): when the schedule cannot keep the safety rule round a path's transitions,
that path is machined single-sided, alternately by each cutter, like the tip region's paths."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from core.paths.alignment import align_single, sides
from core.paths.guard import blade_guard, guard_pair
from core.paths.plan import PathPlan
from core.paths.regions import Regions
from core.records import PlanParameters


def single_sided_pair(path, fitted, symmetric, params: PlanParameters, guard):
    """The single-sided (tip region) pair of a contour path: aligned for single-sided machining
    (core.paths.alignment.align_single, from its fitted sides and its symmetrical pair), its balls
    kept out of the blade by ``guard`` (core.paths.guard)."""
    p = params
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

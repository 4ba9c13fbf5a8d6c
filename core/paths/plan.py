"""The paths stage's output: ``PathPlan``, the geometric plan (aligned pairs with their regions)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from core.paths.regions import REGIONS, Regions
from core.records import PlanParameters, Timings

if TYPE_CHECKING:  # (types only)
    from core.blade.frame import WorkpieceFrame
    from core.blade.model import Blade
    from core.paths.alignment import AlignedPair
    from core.paths.contours import ContourPath
    from core.paths.guard import Guard


class KeptPath(NamedTuple):
    """What one path keeps so that its regions can be divided again for a new h_safe / k_max without
    planning it again (core.paths.planning.replan_regions): the contour path, its fitted sides, its
    symmetrical pair and its single-sided (tip region) pair when one was made."""

    path: ContourPath
    fitted: object
    symmetric: AlignedPair
    tip_pair: AlignedPair | None


@dataclass(frozen=True)
class PathPlan:
    """The geometric plan: aligned pairs with their regions, tip path first, in machining order.

    timings: the path steps' seconds (core.paths.planning); pairs_rows: pairs.csv rows per path when
    the planning was asked to format them (in its workers); reuse: per pair what its path keeps
    (``KeptPath``), kept when asked, so that the regions can be divided
    again for a new h_safe / k_max without redoing the paths (core.paths.planning.replan_regions);
    guard: what keeps the balls out of the blade (core.paths.guard.Guard: a faceted blade's facets, a
    table's tessellation and concave places, or nothing to guard)."""

    blade: Blade
    frame: WorkpieceFrame
    params: PlanParameters
    paths: list[ContourPath]
    pairs: list[AlignedPair]
    regions: list[Regions]
    warnings: list[str] = field(default_factory=list)
    timings: Timings = field(default_factory=Timings)
    pairs_rows: list[bytes] | None = None
    reuse: list[KeptPath] | None = field(default=None, repr=False, compare=False)
    guard: Guard | None = field(default=None, repr=False, compare=False)

    def region_counts(self) -> dict:
        """Number of paths in the tip region and number of pair points per region."""
        points = {k: 0 for k in REGIONS}
        for reg in self.regions:
            names, counts = np.unique(reg.labels, return_counts=True)
            for n, c in zip(names, counts, strict=True):
                points[str(n)] += int(c)
        n_tip = sum(r.is_tip for r in self.regions)
        return {"paths": len(self.pairs), "tip_paths": n_tip, "collaborative_paths": len(self.pairs) - n_tip,
                "points": points}

    def fallback_paths(self) -> list[int]:
        """Indices of paths whose template side could not use the paper's y-parametrisation."""
        return [p.index for p in self.pairs if p.mode != "y"]

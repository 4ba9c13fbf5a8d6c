"""The planning pipeline: blade -> contour paths -> aligned pairs -> regions (-> schedule, axes).

``PlanParameters`` carries every planning input with the project's names and units (mm, mm/min,
mm/s^2 at this boundary); ``plan_paths`` chains the steps of paper sections 2-4 and reports the time
each step took. A Python loop over paths is used; every step inside is vectorised over points.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from .alignment import AlignedPair, align_single, align_symmetric, sides
from .blade import Blade
from .contour_paths import ContourPath, contour_paths
from .errors import PlanningError
from .frames import WorkpieceFrame, workpiece_frame
from .regions import Regions, check_region_parameters, divide

Progress = Callable[[float, str], None]


class Cancelled(Exception):
    """Raised inside the pipeline when the progress callback asks to stop."""


@dataclass(frozen=True)
class PlanParameters:
    """Planning inputs. None means the default derived from the tool radius.

    tool_radius : mm (ball radius; the paper's 3 mm ball nose mill has 1.5); dr : mm (default r/4);
    dd : mm, interpolation step; h_safe : mm (default 1.25 r); k_max : staggered-ratio limit;
    tool_length : mm, d_T of Eq. 1-2 (tip to tail point, the tool's stick-out);
    feed : mm/min; a_max : mm/s^2; mode : 'collaborative' | 'symmetric' | 'single'
    """

    tool_radius: float = 1.5
    dr: float | None = None
    dd: float = 0.2
    h_safe: float | None = None
    k_max: float = 0.15
    tool_length: float = 40.0
    feed: float = 1000.0
    a_max: float = 500.0
    mode: str = "collaborative"

    def resolved(self) -> PlanParameters:
        """The same parameters with the defaults filled in, validated (PlanningError)."""
        r = self.tool_radius
        if not isinstance(r, (int, float)) or not math.isfinite(r) or r <= 0:
            raise PlanningError(f"tool radius must be a positive number of mm, got {r}")
        p = replace(self, dr=r / 4 if self.dr is None else self.dr,
                    h_safe=1.25 * r if self.h_safe is None else self.h_safe)
        for name in ("dr", "dd", "tool_length", "feed", "a_max"):
            v = getattr(p, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise PlanningError(f"{name} must be a positive number, got {v}")
        check_region_parameters(p.h_safe, p.k_max, r)
        if p.dd > 5 * r:
            raise PlanningError(f"dd = {p.dd} mm is more than 5 tool radii: the path would be too coarse")
        if p.mode not in ("collaborative", "symmetric", "single"):
            raise PlanningError(f"mode must be collaborative, symmetric or single, got {p.mode!r}")
        return p

    def warnings(self) -> list[str]:
        out = []
        if self.dr is not None and self.dr > self.tool_radius / 4 + 1e-12:
            out.append(f"dR = {self.dr} mm is above tool_radius/4 = {self.tool_radius / 4:g} mm "
                       "(paper section 2): expect larger scallops")
        if self.h_safe is not None and not (1.0 - 1e-9 <= self.h_safe / self.tool_radius <= 1.5 + 1e-9):
            out.append(f"h_safe = {self.h_safe} mm is outside the paper's 1-1.5 tool radii")
        if not 0.1 - 1e-12 <= self.k_max <= 0.2 + 1e-12:
            out.append(f"k_max = {self.k_max} is outside the paper's 0.1-0.2")
        return out

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class PathPlan:
    """The geometric plan: aligned pairs with their regions, tip path first, in machining order."""

    blade: Blade
    frame: WorkpieceFrame
    params: PlanParameters
    paths: list[ContourPath]
    pairs: list[AlignedPair]
    regions: list[Regions]
    warnings: list[str] = field(default_factory=list)
    timings: dict = field(default_factory=dict)

    def region_counts(self) -> dict:
        """Number of paths in the tip region and number of pair points per region."""
        points = {k: 0 for k in ("tip", "edge", "variable", "internal")}
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


def check_blade_fits_tool(blade: Blade, params: PlanParameters) -> None:
    span = blade.tip_radius - blade.hub_radius
    if span < 4 * params.tool_radius:
        raise PlanningError(f"blade {blade.name!r} spans only {span:.3f} mm: too small for a tool of radius "
                            f"{params.tool_radius} mm")
    info = blade.info()
    chords = [c for c in info["chord_mm"].values() if c]
    if not chords or max(chords) < 4 * params.tool_radius:
        raise PlanningError(f"blade {blade.name!r} is too small for a tool of radius {params.tool_radius} mm "
                            f"(largest chord {max(chords, default=0):.3f} mm)")


def plan_paths(blade: Blade, params: PlanParameters, progress: Progress | None = None) -> PathPlan:
    """Contour paths, double-curve interpolation, alignment and region division of a blade."""
    p = params.resolved()
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    check_blade_fits_tool(blade, p)
    frame = workpiece_frame(blade)
    paths, warnings = contour_paths(blade, frame, p.dr)
    timings["contour_paths_s"] = time.perf_counter() - t0
    warnings = p.warnings() + warnings
    pairs, regions = [], []
    t_align = t_reg = 0.0
    for i, path in enumerate(paths):
        if progress is not None and progress(i / len(paths), f"path {i + 1} of {len(paths)}") is False:
            raise Cancelled()
        t1 = time.perf_counter()
        fitted = sides(path)
        pair = align_symmetric(path, p.dd, p.tool_radius, fitted)
        t2 = time.perf_counter()
        tmpl = pair.left_tip if pair.template == "left" else pair.right_tip
        reg = divide(pair.spacing, tmpl, p.h_safe, p.k_max)
        t3 = time.perf_counter()
        if reg.is_tip:
            pair = align_single(path, p.dd, p.tool_radius, p.tool_length, fitted)
            reg = replace(reg, labels=np.full(len(pair.u), "tip"))
        t_align += (t2 - t1) + (time.perf_counter() - t3)
        t_reg += t3 - t2
        pairs.append(pair)
        regions.append(reg)
    timings["interpolation_alignment_s"] = t_align
    timings["regions_s"] = t_reg
    if progress is not None:
        progress(1.0, "paths done")
    return PathPlan(blade=blade, frame=frame, params=p, paths=paths, pairs=pairs, regions=regions,
                    warnings=warnings, timings=timings)

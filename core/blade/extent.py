"""How much path a blade holds at a radius increment dR and an interpolation step dd, measured on a few
of its sections before any path is planned: what the command line's work estimate (core.cli)
multiplies out to refuse a runaway plan up front."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.blade.model import Blade
from core.errors import BladeInputError

#: sections measured for the estimate (spread over the span like the contour paths)
STATIONS = 9


@dataclass(frozen=True)
class PathExtent:
    """contours : the number of contour paths (float: it may be astronomically large); span_mm : hub to
    tip, mm; side_mm : the mean length of a section's longer side (face or back), mm; points : the
    contour points of one side over all paths at the step dd (what each path step handles)."""

    contours: float
    span_mm: float
    side_mm: float
    points: float


def path_extent(blade: Blade, dr: float, dd: float, stations: int = STATIONS) -> PathExtent | None:
    """The blade's contour paths at dR = ``dr`` mm and dd = ``dd`` mm, estimated from ``stations``
    sections (as core.paths.contours.path_radii counts them); None when no section could be measured
    (the planning then reports the blade's own problem)."""
    span = blade.tip_radius - blade.hub_radius
    contours = math.floor(span / dr + 0.5)
    lengths = []
    for k in range(stations):
        r = blade.tip_radius - (k + 0.5) * span / stations
        try:
            s = blade.section(float(r))
        except BladeInputError:
            continue
        side = max(float(np.linalg.norm(np.diff(part, axis=0), axis=1).sum()) for part in (s.face, s.back))
        if math.isfinite(side):
            lengths.append(side)
    if not lengths:
        return None
    side_mm = float(np.mean(lengths))
    return PathExtent(contours=float(contours), span_mm=float(span), side_mm=side_mm,
                      points=float(contours) * (side_mm / dd + 1.0))

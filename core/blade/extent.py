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
    contour points of one side over all paths at the step dd (what each path step handles);
    bend_mm : the mean over the sections of sum(sqrt(ds * turn)) along the more curved side (ds the
    step, turn the angle the polyline turns there): a chord of length c on an arc of radius rho strays
    c^2 / (8 rho) from it, so a side needs about bend / sqrt(8 tol) rows that stray at most tol
    (``chord_rows``); thickness_mm : the largest thickness of the measured sections, mm."""

    contours: float
    span_mm: float
    side_mm: float
    points: float
    bend_mm: float = 0.0
    thickness_mm: float = 0.0

    def chord_rows(self, tol: float) -> float:
        """Rows one side of all the contour paths needs at least so that the straight line between
        two rows strays at most ``tol`` mm from the path, whatever the period."""
        return self.contours * self.bend_mm / math.sqrt(8.0 * tol)


def path_extent(blade: Blade, dr: float, dd: float, stations: int = STATIONS) -> PathExtent | None:
    """The blade's contour paths at dR = ``dr`` mm and dd = ``dd`` mm, estimated from ``stations``
    sections (as core.paths.contours.path_radii counts them); None when no section could be measured
    (the planning then reports the blade's own problem)."""
    span = blade.tip_radius - blade.hub_radius
    contours = math.floor(span / dr + 0.5)
    lengths, bends, thick = [], [], [0.0]
    for k in range(stations):
        r = blade.tip_radius - (k + 0.5) * span / stations
        try:
            s = blade.section(float(r))
        except BladeInputError:
            continue
        side = max(float(np.linalg.norm(np.diff(part, axis=0), axis=1).sum()) for part in (s.face, s.back))
        if math.isfinite(side):
            lengths.append(side)
            bends.append(max(_bend(part) for part in (s.face, s.back)))
            thick.append(_thickness(s.face, s.back))
    if not lengths:
        return None
    side_mm = float(np.mean(lengths))
    return PathExtent(contours=float(contours), span_mm=float(span), side_mm=side_mm,
                      points=float(contours) * (side_mm / dd + 1.0), bend_mm=float(np.mean(bends)),
                      thickness_mm=float(max(thick)))


def _bend(part: np.ndarray) -> float:
    """sum(sqrt(ds * turn)) along a polyline (PathExtent.bend_mm): ds the mean of a vertex's two
    segments, turn the angle between them."""
    d = np.diff(part, axis=0)
    ds = np.linalg.norm(d, axis=1)
    d, ds = d[ds > 0], ds[ds > 0]
    if len(ds) < 2:
        return 0.0
    u = d / ds[:, None]
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", u[1:], u[:-1]), -1.0, 1.0))
    value = float(np.sqrt(0.5 * (ds[1:] + ds[:-1]) * turn).sum())
    return value if math.isfinite(value) else 0.0


def _thickness(face: np.ndarray, back: np.ndarray) -> float:
    """The largest distance from a face point to the back polyline's points (a section's thickness,
    roughly: its points are a few tenths of a millimetre apart)."""
    from scipy.spatial import cKDTree

    if len(face) == 0 or len(back) == 0:
        return 0.0
    d, _ = cKDTree(back).query(face)
    value = float(d.max())
    return value if math.isfinite(value) else 0.0

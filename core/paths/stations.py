"""Chordwise stations on a blade that evaluates its sections at any chordwise fraction (a geometry
table: ``section(r, xi)``, ``surface_points`` and ``stations``): of the contour paths
(``contour_stations``) and of the gouge check's tessellation (``tessellation_stations``).

A path's contact curve is a cubic spline through its section's stations, the normals fitted alongside
(core.paths.alignment.side_curve); a ball between two stations sits at c = CC + r n from the spline's
point and normal. Where the surface bends or its normal turns fast against the station spacing (the
nose of a very thin or sharp-edged section, the kinks of a tabulated thickness form on a very thick
one) the spline's point lies inside the surface and its normal leans: the ball then cuts into the
blade by about the point's sag plus r (1 - cos a), a the angle between the two normals (up to 0.06 mm
with the 241 stations of a table, against 5e-4 mm on the sample blade). So the stations are checked
on probe sections across the span and halved wherever that estimate exceeds STATION_TOLERANCE.

The check's tessellation (core.paths.tessellation.surface_mesh) joins its stations by straight chords: over a
concave stretch of surface a chord lies off it on the balls' side, and a ball exactly a tool radius
from the blade reads as cutting in (2.6 micrometres on a very thick section, against the 2 of bladecam
verify's tolerance). There a station is inserted until no chord lies more than the tessellation's
tolerance off (core.paths.tessellation.MESH_TOLERANCE).
"""

from __future__ import annotations

import numpy as np

from core.blade.frame import WorkpieceFrame
from core.blade.model import Blade
from core.errors import BladeInputError
from core.paths.interpolation import fit_curve

#: the cut a ball between two stations may make into the blade by the spline's error alone (mm)
STATION_TOLERANCE = 7.5e-4
#: rounds of halving (each halves the offending station intervals of every section)
STATION_ROUNDS = 8
#: probe sections across the span (denser towards the tip, where the section's shape changes fastest)
PROBES = 16


def contour_stations(blade: Blade, frame: WorkpieceFrame, tool_radius: float) -> np.ndarray | None:
    """The chordwise fractions (n,), 0 at the LE and 1 at the TE, of the contour paths' sections: the
    blade's own stations, with a station inserted halfway wherever a ball of ``tool_radius`` (mm)
    between two of them would cut more than STATION_TOLERANCE into the blade on a probe section
    (``interpolation_cut``), up to STATION_ROUNDS times. None where the blade's own sections do (no
    station inserted, or a blade without chordwise stations: a mesh's sections are its facets')."""
    if not hasattr(blade, "stations"):
        return None
    own = xi = blade.stations
    span = blade.tip_radius - blade.hub_radius
    radii = blade.tip_radius - span * np.linspace(0.0, 1.0, PROBES + 1)[1:] ** 2
    for _ in range(STATION_ROUNDS):
        bad = np.zeros(len(xi) - 1, bool)
        for r in radii:
            bad |= interpolation_cut(blade, frame, float(r), xi, tool_radius) > STATION_TOLERANCE
        if not bad.any():
            break
        xi = np.sort(np.concatenate([xi, 0.5 * (xi[:-1][bad] + xi[1:][bad])]))
    return None if len(xi) == len(own) else xi


def interpolation_cut(blade: Blade, frame: WorkpieceFrame, r: float, xi: np.ndarray,
                      tool_radius: float) -> np.ndarray:
    """(n-1,) mm, per interval of the stations xi (n,) of the section at radius r (mm), both sides: how
    far a ball of ``tool_radius`` placed from the fitted contact curve (points and normals, as a path
    fits them) halfway between two stations cuts into the blade, estimated against the exact point
    and normal there (sag of the point into the surface plus r (1 - cos a)). Zeros where the blade has
    no section at r."""
    both = np.empty(2 * len(xi) - 1)
    both[0::2], both[1::2] = xi, 0.5 * (xi[:-1] + xi[1:])  # stations and midpoints in one evaluation
    try:
        s = blade.section(r, both)
    except BladeInputError:
        return np.zeros(len(xi) - 1)
    cut = np.zeros(len(xi) - 1)
    for pts, nrm in ((s.face, s.face_normals), (s.back, s.back_normals)):
        curve = fit_curve(frame.points(pts[0::2]), extra=frame.vectors(nrm[0::2]))
        mid, mid_n = pts[1::2], nrm[1::2]
        if len(curve.t) != len(xi):  # (coincident stations: a section shrunk to a point)
            continue
        mid, mid_n = frame.points(mid), frame.vectors(mid_n)
        t = 0.5 * (curve.t[:-1] + curve.t[1:])
        # one Newton step along the curve to the parameter of the exact midpoint (the spline's
        # parameter is not the chordwise fraction), kept inside the interval
        d = curve.spline(t, 1)[:, :3]
        t += np.einsum("ij,ij->i", mid - curve.point(t), d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300)
        t = np.clip(t, curve.t[:-1], curve.t[1:])
        v = curve.spline(t)
        n = v[:, 3:] / np.linalg.norm(v[:, 3:], axis=1, keepdims=True)
        sag = -np.einsum("ij,ij->i", v[:, :3] - mid, mid_n)  # > 0: the spline's point inside the blade
        lean = tool_radius * (1.0 - np.clip(np.einsum("ij,ij->i", n, mid_n), -1.0, 1.0))
        cut = np.maximum(cut, np.maximum(sag, 0.0) + lean)
    return cut


def cosine_stations(m: int) -> np.ndarray:
    """(m,) chordwise fractions 0..1, cosine-spaced (dense at the LE and the TE)."""
    return 0.5 * (1.0 - np.cos(np.pi * np.linspace(0.0, 1.0, m)))


def tessellation_stations(blade: Blade, radii: np.ndarray, m: int, tolerance: float,
                          rounds: int) -> np.ndarray:
    """Chordwise fractions of the loops of a table blade's check tessellation at the radii (k,) mm
    (core.paths.tessellation.surface_mesh): m cosine-spaced, with one inserted halfway wherever, on up to 64
    of the radii, the straight chord between two of them lies more than ``tolerance`` (mm) off a
    concave surface on the balls' side, where it would read as a gouge (on a convex surface the chord
    lies inside, which reads as air), up to ``rounds`` times."""
    xi = cosine_stations(m)
    radii = radii[radii < blade.tip_radius * (1 - 1e-9)]
    probe = radii[:: max(1, len(radii) // 64)]
    step = np.minimum(probe + 0.05, blade.tip_radius * (1 - 1e-7)) - probe  # (along the radius, for normals)
    for _ in range(rounds):
        mid = 0.5 * (xi[:-1] + xi[1:])
        k, n = len(probe), len(mid)
        face, back = blade.surface_points(np.concatenate([np.repeat(probe, n + 1), np.repeat(probe, n),
                                                          np.repeat(probe + step, n)]),
                                          np.concatenate([np.tile(xi, k), np.tile(mid, k), np.tile(mid, k)]))
        over = np.zeros(n, bool)
        for side, other in ((face, back), (back, face)):
            a, b = k * (n + 1), k * (2 * n + 1)  # (stations, midpoints, midpoints a step out)
            at = side[:a].reshape(k, n + 1, 3)
            m_, o_, up = (v.reshape(k, n, 3) for v in (side[a:b], other[a:b], side[b:]))
            with np.errstate(invalid="ignore", divide="ignore"):
                nrm = np.cross(at[:, 1:] - at[:, :-1], up - m_)
                nrm /= np.linalg.norm(nrm, axis=2, keepdims=True)
                nrm *= np.sign(np.einsum("ijk,ijk->ij", m_ - o_, nrm))[..., None]  # outward
                off = np.einsum("ijk,ijk->ij", 0.5 * (at[:, 1:] + at[:, :-1]) - m_, nrm)
            over |= (off > tolerance).any(axis=0)
        if not over.any():
            break
        xi = np.sort(np.concatenate([xi, mid[over]]))
    return xi

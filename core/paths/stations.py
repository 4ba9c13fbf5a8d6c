"""Chordwise stations on a blade that evaluates its sections at any chordwise fraction (a geometry
table: ``surface_points``): of the gouge check's tessellation (``tessellation_stations``).

The check's tessellation (core.paths.gouge.surface_mesh) joins its stations by straight chords: over a
concave stretch of surface a chord lies off it on the balls' side, and a ball exactly a tool radius
from the blade reads as cutting in (2.6 micrometres on a very thick section, against the 2 of bladecam
verify's tolerance). There a station is inserted until no chord lies more than the tessellation's
tolerance off (core.paths.gouge.MESH_TOLERANCE).
"""

from __future__ import annotations

import numpy as np

from core.blade.model import Blade


def cosine_stations(m: int) -> np.ndarray:
    """(m,) chordwise fractions 0..1, cosine-spaced (dense at the LE and the TE)."""
    return 0.5 * (1.0 - np.cos(np.pi * np.linspace(0.0, 1.0, m)))


def tessellation_stations(blade: Blade, radii: np.ndarray, m: int, tolerance: float,
                          rounds: int) -> np.ndarray:
    """Chordwise fractions of the loops of a table blade's check tessellation at the radii (k,) mm
    (core.paths.gouge.surface_mesh): m cosine-spaced, with one inserted halfway wherever, on up to 64
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

"""The paths stage's gouge guard: no planned ball cuts into the blade, or the plan is refused.

Where a ball can cut into the blade, and what is done there (``guard_pair``):
- a faceted blade (a mesh): anywhere, in the concave creases between facets and on straight moves
  across convex facet edges: every ball is pushed out of the facets and every chord between two balls
  probed (core.paths.gouge.pushed_pair);
- a smooth blade (a geometry table): where its surface is more concave than a ball a few tool radii
  across can follow (``concave_points``): the hook of a sharp leading edge whose camber line rises
  faster than its thickness (the a=0.8 mean line's slope is log-singular at the LE: with the parabolic
  thickness form, t ~ x, the face curls over within 0.05 mm of the LE with radii down to micrometres,
  and a ball placed on the LE's normal cuts 0.07 mm into it), or a thin section of extreme camber.
  The balls within reach of such places are pushed out of the gouge check's own tessellation of the
  blade (core.paths.tessellation.surface_mesh, which ``bladecam verify`` measures against) and their chords
  probed, as on a mesh: the ball then leaves the material it cannot reach. Elsewhere a smooth blade's
  ball touches it at its contact point only: the surface is convex or gently concave there, and the
  contact points and normals follow it to core.paths.stations.STATION_TOLERANCE.
A pair that still cuts in deeper than the gouge check's TOLERANCE after the push-out (a centre on the
blade, whose normal points into it: a mesh read with the wrong propeller axis) is refused:
PlanningError naming the path, the cutter, the pair point, the depth and what to change.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from core.blade.frame import WorkpieceFrame
from core.blade.model import Blade
from core.errors import PlanningError
from core.paths.gouge import TOLERANCE, pushed_pair
from core.paths.tessellation import FACET_CANDIDATES, TriangleIndex, facet_mesh, surface_mesh
from core.util.polyline import ball_centres

#: a smooth blade is guarded where its surface is concave with a radius below this many tool radii
CONCAVE_RADII = 2.0
#: radial step of the grid on which a smooth blade's concavity is measured (mm)
GRID_STEP = 0.5


@dataclass(frozen=True)
class Guard:
    """What the paths stage checks planned balls against (built once per plan of the paths, inherited
    by the forked path workers, kept in the PathPlan).

    index : the mesh the balls are pushed out of (a mesh blade's facets, a smooth blade's check
        tessellation), or None where nothing needs it (a smooth blade concave nowhere near the tool);
    near : None (every ball is guarded: a mesh) or a search tree of the places (workpiece frame, mm)
        where a smooth blade is too concave; reach : mm, how near a ball centre must be to one of them;
    faceted : True for a mesh blade (the refusal's advice differs)."""

    index: TriangleIndex | None
    near: cKDTree | None = None
    reach: float = 0.0
    faceted: bool = False


def blade_guard(blade: Blade, frame: WorkpieceFrame, tool_radius: float,
                stations: np.ndarray | None = None) -> Guard | None:
    """The guard of a blade for a tool of radius ``tool_radius`` (mm): a mesh blade's facets (split to
    FACET_EDGE, searched by FACET_CANDIDATES, as bladecam verify does); for a smooth blade with
    chordwise stations (``stations``: the contour paths', default the blade's own), the places where
    it is more concave than CONCAVE_RADII tool radii and its check tessellation (searched by 8
    triangles, as bladecam verify does), if there are any; None for other blades."""
    if hasattr(blade, "facets"):
        return Guard(_searched(facet_mesh(blade, frame), FACET_CANDIDATES), faceted=True)
    if not hasattr(blade, "surface_points"):
        return None
    xi = blade.stations if stations is None else stations
    places = concave_points(blade, frame, xi, CONCAVE_RADII * tool_radius)
    if not len(places):
        return Guard(None)
    return Guard(_searched(surface_mesh(blade, frame), 8), cKDTree(places), reach=tool_radius + 2.0 * GRID_STEP)


def _searched(mesh, k: int) -> TriangleIndex:
    """The TriangleIndex of ``mesh`` (k candidates by centroid) with its exact search built: the guard
    is built before the path workers fork, and each would otherwise build that search again."""
    index = TriangleIndex(mesh, k=k)
    index.grid  # noqa: B018 - (built here, inherited by the workers)
    return index


def concave_points(blade: Blade, frame: WorkpieceFrame, xi: np.ndarray, radius: float) -> np.ndarray:
    """(m, 3) mm, workpiece frame: the points of a grid on both sides of a smooth blade (radii GRID_STEP
    apart from hub to tip, the chordwise fractions ``xi``) where the surface is concave with a radius
    below ``radius`` (mm) along the grid's lines or diagonals. At each inner grid point the normal
    curvature along a line through its two neighbours A, C is sum((A - B).n / |A - B|^2) over both
    (concave positive: 1/rho on a circle of radius rho), n the unit normal of the grid there."""
    span = blade.tip_radius - blade.hub_radius
    n_r = max(int(np.ceil(span / GRID_STEP)), 2)
    radii = blade.hub_radius + span * np.linspace(0.0, 1.0, n_r + 1)
    radii[-1] = blade.tip_radius - 1e-3 * GRID_STEP  # (a closed tip has no section at the tip radius)
    face, back = blade.surface_points(np.repeat(radii, len(xi)), np.tile(xi, len(radii)))
    face, back = (frame.points(p).reshape(len(radii), len(xi), 3) for p in (face, back))
    out = []
    for s, other in ((face, back), (back, face)):
        nrm = np.cross(np.gradient(s, axis=1), np.gradient(s, axis=0))
        length = np.linalg.norm(nrm, axis=2, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            nrm = nrm / length
            # outward: away from the other side, taken at mid-chord on each radius
            mid = len(xi) // 2
            nrm *= np.sign(np.einsum("ij,ij->i", s[:, mid] - other[:, mid], nrm[:, mid]))[:, None, None]
            b, n = s[1:-1, 1:-1], nrm[1:-1, 1:-1]
            curv = np.full(b.shape[:2], -np.inf)
            for (i0, j0), (i1, j1) in (((0, 1), (2, 1)), ((1, 0), (1, 2)),   # along the radius, the chord
                                       ((0, 0), (2, 2)), ((0, 2), (2, 0))):  # and the two diagonals
                k = 0.0
                for i, j in ((i0, j0), (i1, j1)):
                    d = s[i:i + b.shape[0], j:j + b.shape[1]] - b
                    k = k + np.einsum("ijk,ijk->ij", d, n) / np.einsum("ijk,ijk->ij", d, d)
                curv = np.fmax(curv, k)
            out.append(b[curv > 1.0 / radius])
    return np.concatenate(out)


def guard_pair(pair, guard: Guard | None, tool_radius: float):
    """The pair with its balls kept out of the blade (see the module): pushed out where the guard
    says so, and PlanningError when one still cuts in deeper than TOLERANCE."""
    if guard is None or guard.index is None:
        return pair
    where = None
    if guard.near is not None:
        r = tool_radius
        near = [np.isfinite(guard.near.query(ball_centres(tip, axis, r), distance_upper_bound=guard.reach)[0])
                for tip, axis in ((pair.left_tip, pair.left_axis), (pair.right_tip, pair.right_axis))]
        where = near[0] | near[1]
        if not where.any():
            return pair
    pushed, (depth, k, side) = pushed_pair(pair, guard.index, tool_radius, where, guard.faceted)
    if depth > TOLERANCE:
        advice = ("check the propeller axis (--axis) and that the mesh is one closed blade" if guard.faceted
                  else "the blade is too concave there for the tool: use a smaller tool radius")
        raise PlanningError(f"path {pair.index} (r = {pair.r:.3f} mm): the {side} cutter's ball would cut "
                            f"{depth:.4f} mm into the blade at pair point {k} even pushed out of it; "
                            f"{advice}")
    return pushed

"""Gouge check: no ball of a cutting point cuts into the blade (issue 3, item 6).

Checked by distance, not by construction: the blade is tessellated afresh from its sections (a
triangle mesh in the workpiece frame, independent of the tool-path steps), and for every ball centre
c = p + r w the exact distance to the nearest triangle is computed (closest point on a triangle,
Ericson, Real-Time Collision Detection 5.1.5) among the k triangles with the nearest centroids. The ball cuts into the blade where that distance < r - tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .blade import Blade, resample_polyline
from .errors import BladeInputError
from .frames import WorkpieceFrame

TOLERANCE = 1e-3  # mm


@dataclass(frozen=True)
class SurfaceMesh:
    """vertices : (V, 3) float, mm, workpiece frame; triangles : (T, 3) int."""

    vertices: np.ndarray
    triangles: np.ndarray


def surface_mesh(blade: Blade, frame: WorkpieceFrame, radial_step: float = 0.5,
                 chord_step: float = 0.25) -> SurfaceMesh:
    """Tessellate both sides of the blade between hub and tip from sections ``radial_step`` apart,
    each side resampled at about ``chord_step`` by arc length (same count on every section)."""
    span = blade.tip_radius - blade.hub_radius
    n_r = max(int(np.ceil(span / radial_step)), 2)
    radii = blade.hub_radius + span * np.linspace(0.0, 1.0, n_r + 1)[:-1]
    radii = np.append(radii, blade.tip_radius - 1e-3 * radial_step)
    sections = []
    for r in radii:
        try:
            sections.append(blade.section(float(r)))
        except BladeInputError:
            continue
    longest = max(np.linalg.norm(np.diff(s.face, axis=0), axis=1).sum() for s in sections)
    m = max(int(np.ceil(longest / chord_step)) + 1, 8)
    loops = []
    for s in sections:  # one closed loop per section: face LE->TE, back TE->LE
        face = resample_polyline(s.face, m)
        back = resample_polyline(s.back, m)
        loops.append(np.vstack([face, back[-2:0:-1]]))
    grid = frame.points(np.concatenate(loops))
    n_sec, n_loop = len(loops), 2 * m - 2
    i = np.arange(n_sec - 1)[:, None] * n_loop
    j = np.arange(n_loop)[None, :]
    a = (i + j).ravel()
    b = (i + (j + 1) % n_loop).ravel()
    c = a + n_loop
    d = b + n_loop
    tris = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    return SurfaceMesh(vertices=grid, triangles=tris)


def closest_point_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Exact distance from points p to triangles (a, b, c), row by row: (n, 3) each -> (n,)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
    bp = p - b
    d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
    cp = p - c
    d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = va + vb + vc
        v = np.where(denom != 0, vb / denom, 0.0)
        w = np.where(denom != 0, vc / denom, 0.0)
        q = a + ab * v[:, None] + ac * w[:, None]  # interior
        # edges
        t_ab = np.where(d1 - d3 != 0, d1 / (d1 - d3), 0.0)
        t_ac = np.where(d2 - d6 != 0, d2 / (d2 - d6), 0.0)
        t_bc = np.where((d4 - d3) + (d5 - d6) != 0, (d4 - d3) / ((d4 - d3) + (d5 - d6)), 0.0)
    cases = [
        ((d1 <= 0) & (d2 <= 0), a),
        ((d3 >= 0) & (d4 <= d3), b),
        ((d6 >= 0) & (d5 <= d6), c),
        ((vc <= 0) & (d1 >= 0) & (d3 <= 0), a + ab * t_ab[:, None]),
        ((vb <= 0) & (d2 >= 0) & (d6 <= 0), a + ac * t_ac[:, None]),
        ((va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0), b + (c - b) * t_bc[:, None]),
    ]
    done = np.zeros(len(p), bool)
    for cond, point in cases:
        use = cond & ~done
        q[use] = point[use]
        done |= use
    return np.linalg.norm(p - q, axis=1)


def distance_to_surface(points: np.ndarray, mesh: SurfaceMesh, k: int = 8) -> np.ndarray:
    """(n, 3) points, mm -> (n,) float, mm: exact distance to the nearest of the k triangles whose
    centroids are nearest to each point (the tessellation's triangles are small and regular, so the
    nearest triangle is always among them)."""
    tri = mesh.triangles
    v = mesh.vertices
    a, b, c = v[tri[:, 0]], v[tri[:, 1]], v[tri[:, 2]]
    tree = cKDTree((a + b + c) / 3.0)
    _, idx = tree.query(points, k=k, workers=-1)
    best = np.full(len(points), np.inf)
    for j in range(idx.shape[1]):  # loop over candidate slots, vectorised over points
        t = idx[:, j]
        best = np.minimum(best, closest_point_distance(points, a[t], b[t], c[t]))
    return best


@dataclass(frozen=True)
class GougeReport:
    """min_clearance : mm (distance of a ball centre to the blade minus the tool radius; >= -tol is
    clean); worst : (path, k, side) of the minimum; checked : number of balls; violations : count."""

    min_clearance: float
    worst: tuple[int, int, str]
    checked: int
    violations: int

    def as_dict(self) -> dict:
        return {"min_clearance_mm": round(self.min_clearance, 6), "worst_path_k_side": list(self.worst),
                "balls_checked": self.checked, "violations": self.violations,
                "tolerance_mm": TOLERANCE}


def gouge_check(plan, stride: int = 1, mesh: SurfaceMesh | None = None) -> GougeReport:
    """Check every ``stride``-th pair point of every path, both sides, of a PathPlan."""
    mesh = mesh or surface_mesh(plan.blade, plan.frame)
    r = plan.params.tool_radius
    centres, tags = [], []
    for pair in plan.pairs:
        k = np.arange(0, len(pair.u), stride)
        for side, tip, axis in (("left", pair.left_tip, pair.left_axis), ("right", pair.right_tip, pair.right_axis)):
            centres.append(tip[k] + r * axis[k])
            tags.append(np.column_stack([np.full(len(k), pair.index), k, np.full(len(k), side == "left")]))
    pts = np.concatenate(centres)
    tag = np.concatenate(tags)
    clearance = distance_to_surface(pts, mesh) - r
    i = int(np.argmin(clearance))
    worst = (int(tag[i, 0]), int(tag[i, 1]), "left" if tag[i, 2] else "right")
    return GougeReport(min_clearance=float(clearance[i]), worst=worst, checked=len(pts),
                       violations=int((clearance < -TOLERANCE).sum()))

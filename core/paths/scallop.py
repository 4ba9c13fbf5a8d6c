"""The scallop height left between adjacent contour paths (the cusps of material a ball-nose tool
leaves between two passes), from the stepover on the surface, the tool radius and the surface's
curvature across the paths.

In the plane across the paths the surface is taken as a circle of radius rho = 1 / |kappa| (a line for
kappa = 0): the two balls' centres lie on the offset circle (rho + r outside a convex surface, rho - r
inside a concave one), 2 * asin(w / (2 rho)) apart for contact points a chord w apart, and the cusp is
where the two balls' circles meet on the material's side. Exact for a plane and a cylinder across its
axis; to second order it is the usual h = w^2 / 8 * (1 / r + kappa).

The stepover w at a contact point is the distance to the nearest contact point of the next path by
radius (dR along the surface, longer where the surface slopes away from the radial direction), and
kappa the normal curvature from the turn of the surface normals over that chord (positive where the
surface is convex, the normals spreading apart).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def scallop_height(w: np.ndarray, r: float, kappa: np.ndarray) -> np.ndarray:
    """Scallop height (mm) between two ball passes of radius r (mm) whose contact points lie a chord
    w (mm) apart on a surface of normal curvature kappa (1/mm, > 0 convex) across the passes. NaN
    where the balls do not meet on the material's side (a stepover of 2 r or more, or a concave
    radius below the ball's)."""
    w = np.asarray(w, float)
    kappa = np.broadcast_to(np.asarray(kappa, float), w.shape)
    flat = np.abs(kappa) < 1e-12
    out = np.full(w.shape, np.nan)
    half = w / 2.0
    ok = flat & (half < r)
    out[ok] = r - np.sqrt(r * r - half[ok] ** 2)
    rho = 1.0 / np.where(flat, 1.0, np.abs(kappa))
    s = np.clip(half / rho, -1.0, 1.0)  # sin(theta / 2)
    c = np.sqrt(1.0 - s * s)
    convex = ~flat & (kappa > 0)
    rc = np.where(convex, rho + r, rho - r)  # the ball centres' circle
    disc = r * r - (rc * s) ** 2
    meet = ~flat & (disc >= 0) & (rc > 0)
    root = np.sqrt(np.where(meet, disc, 0.0))
    # convex: the cusp is the meeting point nearer the axis; concave: the one farther from it
    cusp = np.where(convex, rc * c - root, rc * c + root)
    out[meet & convex] = (cusp - rho)[meet & convex]
    out[meet & ~convex] = (rho - cusp)[meet & ~convex]
    return out


def across(points: np.ndarray, normals: np.ndarray, next_points: np.ndarray,
           next_normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(w, kappa) at each contact point (n, 3) of a path with unit normals (n, 3): the chord to the
    nearest contact point of the next path and the normal curvature across, from the normals' turn."""
    dist, j = cKDTree(next_points).query(points)
    chord = next_points[j] - points
    t = chord / np.maximum(dist, 1e-12)[:, None]
    kappa = np.einsum("ij,ij->i", next_normals[j] - normals, t) / np.maximum(dist, 1e-12)
    return dist, kappa


def path_scallops(paths, tool_radius: float) -> dict:
    """plan.json's "scallop" figures from a plan's contour paths (core.paths.contours.ContourPath): per
    path (its index), the largest scallop height between it and the next path by radius towards the
    hub on either face (both faces' contact points), None where the two balls never meet (a stepover
    of 2 r or more leaves a strip of stock uncut: 'uncut_paths'); the largest and the mean over
    every other contact point; mm. The innermost path has no next one."""
    ordered = sorted(paths, key=lambda p: -p.r)
    per_path: dict[str, float | None] = {}
    all_h: list[np.ndarray] = []
    uncut: list[int] = []
    for a, b in zip(ordered, ordered[1:], strict=False):
        hs = []
        for side in ("left", "right"):
            pa, na = getattr(a, f"{side}_cc"), getattr(a, f"{side}_normals")
            pb, nb = getattr(b, f"{side}_cc"), getattr(b, f"{side}_normals")
            if len(pa) and len(pb):
                w, kappa = across(pa, na, pb, nb)
                hs.append(scallop_height(w, tool_radius, kappa))
        h = np.concatenate(hs) if hs else np.zeros(0)
        if not np.isfinite(h).all():  # the balls never meet: a strip of stock left uncut
            per_path[str(a.index)] = None
            uncut.append(a.index)
        elif len(h):
            per_path[str(a.index)] = round(float(h.max()), 6)
            all_h.append(h)
    h = np.concatenate(all_h) if all_h else np.zeros(0)
    mean = float(h.mean()) if len(h) else 0.0
    return {"max_mm": round(float(h.max(initial=0.0)), 6), "mean_mm": round(mean, 6),
            "per_path_max_mm": per_path, "uncut_paths": sorted(uncut),
            "note": "between each path and the next by radius towards the hub, from the stepover on the "
                    "surface, the tool radius and the surface's curvature across the paths"}

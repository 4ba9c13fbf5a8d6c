"""Gouge check: no ball of a cutting point cuts into the blade (issue 3, item 6).

Checked by distance, not by construction: the blade is tessellated afresh from its sections (a
triangle mesh in the workpiece frame, independent of the tool-path steps), and for every ball centre
c = p + r w the exact distance to the nearest triangle is computed (closest point on a triangle,
Ericson, Real-Time Collision Detection 5.1.5) among the k triangles with the nearest centroids. The ball cuts into the blade where that distance < r - tolerance.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from core.blade.frame import WorkpieceFrame
from core.blade.model import Blade, resample_polyline
from core.errors import BladeInputError
from core.paths.cutter import symmetric_tools
from core.paths.stations import cosine_stations, tessellation_stations

TOLERANCE = 1e-3  # mm


@dataclass(frozen=True)
class SurfaceMesh:
    """vertices : (V, 3) float, mm, workpiece frame; triangles : (T, 3) int."""

    vertices: np.ndarray
    triangles: np.ndarray


#: longest triangle edge of a mesh blade's facets as searched (mm): raw meshes have strips tens of mm
#: long, whose centroids say nothing about nearness; split, the surface is the same
FACET_EDGE = 1.0
#: triangles (by nearest centroid) searched per point on a mesh blade's facets (the push-out and
#: bladecam verify): a ball sits a tool radius off facets up to FACET_EDGE long, so a dozen or more
#: centroids lie about as near as the nearest facet's; with 8, near the coarse BladeX closing tip the
#: other side's small facets crowded out facets that balls cut by up to 15 micrometres (three times
#: the push-out's time, which was the price)
FACET_CANDIDATES = 24


def facet_mesh(blade: Blade, frame: WorkpieceFrame, max_edge: float = FACET_EDGE) -> SurfaceMesh:
    """A mesh blade's own facets in the workpiece frame, split until no edge exceeds ``max_edge``."""
    import trimesh

    verts, tris = blade.facets()
    verts, tris = trimesh.remesh.subdivide_to_size(verts, tris, max_edge=max_edge)
    return SurfaceMesh(vertices=frame.points(np.asarray(verts)), triangles=np.asarray(tris))


#: how far the tessellation may stray from the blade between two sections before one is inserted (mm)
MESH_TOLERANCE = 2.5e-4


def _loops(blade: Blade, radii: np.ndarray, m: int, xi: np.ndarray | None = None) -> dict[float, np.ndarray]:
    """Closed loops of 2m-2 points, blade frame, one per radius that has a section: face LE->TE then
    back TE->LE, m points per side. A blade that evaluates its surface at given radii and chordwise
    stations (a geometry table: ``surface_points``) is sampled exactly there (at the chordwise
    fractions ``xi`` (m,), default cosine-spaced), all radii in one vectorised call; others are
    resampled by arc length along their section polylines."""
    out: dict[float, np.ndarray] = {}
    if hasattr(blade, "surface_points"):
        radii = np.asarray(radii, float)
        radii = radii[(radii >= blade.hub_radius) & (radii < blade.tip_radius * (1 - 1e-9))]
        if radii.size == 0:
            return out
        xi = cosine_stations(m) if xi is None else xi
        face, back = blade.surface_points(np.repeat(radii, m), np.tile(xi, radii.size))
        face, back = face.reshape(radii.size, m, 3), back.reshape(radii.size, m, 3)
        for k, r in enumerate(radii):
            out[float(r)] = np.vstack([face[k], back[k, -2:0:-1]])
        return out
    for r in radii:
        try:
            s = blade.section(float(r))
        except BladeInputError:
            continue
        out[float(r)] = np.vstack([resample_polyline(s.face, m), resample_polyline(s.back, m)[-2:0:-1]])
    return out


def surface_mesh(blade: Blade, frame: WorkpieceFrame, radial_step: float = 0.5,
                 chord_step: float | None = None, tolerance: float = MESH_TOLERANCE, rounds: int = 6) -> SurfaceMesh:
    """Tessellate both sides of the blade between hub and tip: sections ``radial_step`` apart, each
    side sampled at about ``chord_step`` (same count on every section; on a table, a station inserted
    halfway wherever a chord lies more than ``tolerance`` off a concave surface, up to ``rounds``
    times: core.paths.stations.tessellation_stations), then a section inserted halfway between two
    wherever the blade there is more than ``tolerance`` from the straight interpolation of its
    neighbours (near the closing tip the surface bends quickly along the radius), up to ``rounds``
    times."""
    if hasattr(blade, "facets"):  # a mesh blade is its facets: check against them, not a re-tessellation
        return facet_mesh(blade, frame)
    span = blade.tip_radius - blade.hub_radius
    n_r = max(int(np.ceil(span / radial_step)), 2)
    radii = blade.hub_radius + span * np.linspace(0.0, 1.0, n_r + 1)[:-1]
    radii = np.append(radii, blade.tip_radius - 1e-3 * radial_step)
    probe = [blade.section(float(r)) for r in radii[:: max(1, len(radii) // 16)] if _has_section(blade, float(r))]
    longest = max(np.linalg.norm(np.diff(s.face, axis=0), axis=1).sum() for s in probe)
    if chord_step is None:  # cosine-spaced exact stations need fewer points than arc-length resampling
        chord_step = 0.5 if hasattr(blade, "surface_points") else 0.25
    m = max(int(np.ceil(longest / chord_step)) + 1, 8)
    xi = None
    if hasattr(blade, "surface_points"):
        xi = tessellation_stations(blade, radii, m, tolerance, rounds)
        m = len(xi)
    loops = _loops(blade, radii, m, xi)
    for _ in range(rounds):
        rs = sorted(loops)
        pairs = [(r0, r1) for r0, r1 in zip(rs[:-1], rs[1:], strict=True) if r1 - r0 >= 1e-3]
        mids = _loops(blade, np.array([0.5 * (r0 + r1) for r0, r1 in pairs]), m, xi)
        added = 0
        for r0, r1 in pairs:
            rm = 0.5 * (r0 + r1)
            if rm in mids and np.linalg.norm(mids[rm] - 0.5 * (loops[r0] + loops[r1]), axis=1).max() > tolerance:
                loops[rm] = mids[rm]
                added += 1
        if not added:
            break
    rs = sorted(loops)
    grid = frame.points(np.concatenate([loops[r] for r in rs]))
    n_sec, n_loop = len(rs), 2 * m - 2
    i = np.arange(n_sec - 1)[:, None] * n_loop
    j = np.arange(n_loop)[None, :]
    a = (i + j).ravel()
    b = (i + (j + 1) % n_loop).ravel()
    c = a + n_loop
    d = b + n_loop
    tris = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    return SurfaceMesh(vertices=grid, triangles=tris)


def _has_section(blade: Blade, r: float) -> bool:
    try:
        blade.section(r)
    except BladeInputError:
        return False
    return True


def closest_point_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Exact distance from points p to triangles (a, b, c), row by row: (n, 3) each -> (n,)."""
    return np.linalg.norm(p - closest_point_on_triangle(p, a, b, c), axis=1)


def closest_point_on_triangle(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """The closest point of triangle (a, b, c) to p, row by row: (n, 3) each -> (n, 3) (Ericson 5.1.5)."""
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
    return q


def distance_to_surface(points: np.ndarray, mesh, k: int = 8) -> np.ndarray:
    """(n, 3) points, mm -> (n,) float, mm: exact distance to the nearest of the k triangles whose
    centroids are nearest to each point. ``mesh``: a SurfaceMesh, or its TriangleIndex when the caller
    built it already. Two threads share the points (numpy releases the GIL)."""
    index = mesh if isinstance(mesh, TriangleIndex) else TriangleIndex(mesh, k)
    points = np.asarray(points, float)
    if len(points) < 20000:
        return index.closest(points)[0]
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(2) as pool:
        return np.concatenate([d for d, _ in pool.map(index.closest, np.array_split(points, 8))])


class TriangleIndex:
    """Nearest-triangle queries on a SurfaceMesh: the triangles' corners and a search tree over their
    centroids, built once. Sound where the triangles are small against the query distance (the
    tessellations here, and mesh blades' facets split by facet_mesh)."""

    #: points per block of candidates evaluated together (keeps the temporaries a few MB)
    BLOCK = 1 << 14

    def __init__(self, mesh: SurfaceMesh, k: int = 8):
        tri, v = mesh.triangles, mesh.vertices
        a, b, c = v[tri[:, 0]], v[tri[:, 1]], v[tri[:, 2]]
        # corners and edges as (3, m) rows, and the edges' dot products: per query only the two
        # dot products with the point remain (Ericson 5.1.5 with d3..d6 from d1, d2)
        self.a, self.ab, self.ac = (np.ascontiguousarray(x.T) for x in (a, b - a, c - a))
        self.e00 = (self.ab * self.ab).sum(0)
        self.e01 = (self.ab * self.ac).sum(0)
        self.e11 = (self.ac * self.ac).sum(0)
        # large leaves, median-free splits: the queries sit a tool radius off a dense surface and need
        # many candidates each (measured on the check mesh: 1.7x faster queries, 2.3x faster build)
        from scipy.spatial import cKDTree  # here: planning a table blade needs no search tree

        self.tree = cKDTree((a + b + c) / 3.0, leafsize=64, balanced_tree=False)
        self.k = min(k, len(tri))

    def closest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n, 3) points, mm -> distances (n,) mm and closest points (n, 3) mm (among the k triangles
        with the nearest centroids)."""
        points = np.asarray(points, float)
        _, idx = self.tree.query(points, k=self.k)
        idx = idx.reshape(len(points), -1)
        dist = np.empty(len(points))
        best_q = np.empty((len(points), 3))
        for lo in range(0, len(points), self.BLOCK):
            sl = slice(lo, lo + self.BLOCK)
            dist[sl], best_q[sl] = self._nearest(points[sl], idx[sl])
        return dist, best_q

    def _nearest(self, points: np.ndarray, cand: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact closest points of the candidate triangles cand (n, k) to points (n, 3): the nearest
        per row, (n,) distances and (n, 3) points. Same regions and formulas as
        closest_point_on_triangle, in barycentric parameters (v, w): q = a + v ab + w ac."""
        n, k = cand.shape
        t = cand.ravel()
        ap = np.repeat(np.ascontiguousarray(points.T), k, axis=1) - self.a[:, t]
        ab, ac = self.ab[:, t], self.ac[:, t]
        d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2]
        d2 = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2]
        d3, d4 = d1 - self.e00[t], d2 - self.e01[t]
        d5, d6 = d1 - self.e01[t], d2 - self.e11[t]
        va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
        q43, q56 = d4 - d3, d5 - d6
        with np.errstate(divide="ignore", invalid="ignore"):
            denom = va + vb + vc
            v = np.where(denom != 0, vb / denom, 0.0)   # interior
            w = np.where(denom != 0, vc / denom, 0.0)
            t_ab = np.where(d1 - d3 != 0, d1 / (d1 - d3), 0.0)
            t_ac = np.where(d2 - d6 != 0, d2 / (d2 - d6), 0.0)
            t_bc = np.where(q43 + q56 != 0, q43 / (q43 + q56), 0.0)
        regions = [  # in Ericson's order: the first that holds wins, so they are applied last to first
            ((d1 <= 0) & (d2 <= 0), 0.0, 0.0),                      # corner a
            ((d3 >= 0) & (d4 <= d3), 1.0, 0.0),                     # corner b
            ((d6 >= 0) & (d5 <= d6), 0.0, 1.0),                     # corner c
            ((vc <= 0) & (d1 >= 0) & (d3 <= 0), t_ab, 0.0),         # edge ab
            ((vb <= 0) & (d2 >= 0) & (d6 <= 0), 0.0, t_ac),         # edge ac
            ((va <= 0) & (q43 >= 0) & (q56 >= 0), 1.0 - t_bc, t_bc),  # edge bc
        ]
        for cond, cv, cw in reversed(regions):
            v = np.where(cond, cv, v)
            w = np.where(cond, cw, w)
        g = ap - ab * v - ac * w                    # point - closest point
        d2sq = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).reshape(n, k)
        j = np.argmin(d2sq, axis=1)
        pick = np.arange(n) * k + j
        q = points - g[:, pick].T
        return np.sqrt(d2sq[np.arange(n), j]), q


def push_out(centres: np.ndarray, index: TriangleIndex, tool_radius: float, iterations: int = 12,
             tol: float = 1e-4, normals: bool = False):
    """Ball centres (n, 3) mm moved out of a faceted blade: wherever a ball of radius ``tool_radius``
    would cut into the mesh (centre closer than r - tol), the centre moves away from the closest point
    to distance r, repeatedly (a concave crease between facets needs a few rounds). Returns a copy,
    and with ``normals`` also the unit contact normals (n, 3) (from the closest point towards the
    centre, as last measured: a pushed centre keeps the direction it was pushed along)."""
    c, nrm, _ = pushed_out(centres, index, tool_radius, iterations, tol)
    return (c, nrm) if normals else c


def pushed_out(centres: np.ndarray, index: TriangleIndex, tool_radius: float, iterations: int = 12,
               tol: float = 1e-4) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """push_out's centres (n, 3) and contact normals (n, 3), and each centre's distance (n,) mm from
    the mesh where it ends (a centre that would not come out, lying on the mesh or still in after
    ``iterations`` rounds, keeps a distance below r - tol)."""
    c = np.array(centres, float)
    nrm = np.zeros_like(c)
    dist = np.full(len(c), np.inf)
    active = np.arange(len(c))
    moved = False
    for _ in range(iterations):
        if active.size == 0:
            break
        d, q = index.closest(c[active])
        dist[active], moved = d, False
        away = c[active] - q
        nrm[active] = away / np.maximum(d, 1e-300)[:, None]
        bad = d < tool_radius - tol
        if not bad.any():
            break
        i = active[bad]
        ok = d[bad] > 1e-12
        c[i[ok]] = q[bad][ok] + tool_radius * nrm[i[ok]] * (1.0 + 1e-6)
        active, moved = i, True
    if moved:  # the last round's pushes, measured
        dist[active] = index.closest(c[active])[0]
    return c, nrm, dist


#: the deepest a straight move between two ball centres may dip into a faceted blade (mm)
CREASE_TOLERANCE = 5e-4
CREASE_ROUNDS = 8
#: where on each chord the dip is measured (fractions of the chord)
CREASE_PROBES = (0.25, 0.5, 0.75)
#: on a smooth blade, how far a chord next to a pushed ball may pass off the blade (mm): where the ball
#: cannot follow a concave surface its pushed path turns a corner, and the chord across it cuts air
CHORD_MISS = 0.01


def _pushed(pair, cl: np.ndarray, cr: np.ndarray, tool_radius: float, wl: np.ndarray, wr: np.ndarray):
    """Tools through ball centres cl, cr (n, 3): symmetrical pairs' axes on the line through the
    centres; single-sided ones keep the axes wl, wr. Returns pl, wl, pr, wr, spacing (or None)."""
    if pair.kind == "symmetric":
        return symmetric_tools(cl, cr, tool_radius)
    return cl - tool_radius * wl, wl, cr - tool_radius * wr, wr, None


def push_pair_out(pair, guard: TriangleIndex | None, tool_radius: float):
    """The pair with its ball centres pushed out of a mesh (``pushed_pair``; the pair itself without
    one)."""
    return pair if guard is None else pushed_pair(pair, guard, tool_radius)[0]


def _midpoints(c: np.ndarray, k: np.ndarray, index: TriangleIndex, r: float, onto: bool) -> np.ndarray:
    """The midpoints of chords k of the centres c (n, 3), with ``onto`` put at distance r from the
    mesh along the line from their closest point (mm)."""
    mid = 0.5 * (c[k] + c[k + 1])
    if not onto:
        return mid
    d, q = index.closest(mid)
    return q + (r / np.maximum(d, 1e-300))[:, None] * (mid - q)


def pushed_pair(pair, index: TriangleIndex, tool_radius: float, where: np.ndarray | None = None,
                every_chord: bool = True):
    """The pair with its ball centres pushed out of the mesh ``index`` (a faceted blade's facets, or
    a smooth blade's check tessellation): symmetrical pairs keep their axes on the line through the
    (new) centres; single-sided ones keep their axes. ``where`` (n,) bool: the pair points to push
    (default: all); the others are left as they are. ``every_chord``: probe every chord next to a
    point of ``where`` (a mesh: any two balls may straddle a convex facet edge), else only the chords
    next to a point that moved (a smooth blade: its other chords follow the offset surface to
    core.paths.interpolation.CHORD_TOLERANCE), those at a quarter, half and three quarters, and those
    passing more than CHORD_MISS off the blade are split too (their midpoint put on the offset surface).

    A straight move between two centres on either side of a convex facet edge cuts the corner of the
    offset surface, which is rounded there (the ball rolls round the edge on an arc of radius r): up
    to 5 micrometres on BladeX at dd 0.2 mm. So every chord is probed at its middle, and those whose
    two balls touch the blade along different normals also at a quarter and three quarters; wherever
    a chord of either side dips more than CREASE_TOLERANCE there, a pair point is inserted at the
    chords' midpoints (centres pushed out, axes the normalised mean of the neighbours', u and spacing
    their mean), up to CREASE_ROUNDS times.

    Returns the pair and its deepest remaining cut (depth mm, pair point, 'left' or 'right'): r less
    the least distance from the mesh of a centre where it ends or of a chord's probe (<= 0: none)."""
    r = tool_radius
    where = np.ones(len(pair.u), bool) if where is None else np.asarray(where, bool)
    sel = np.flatnonzero(where)
    cl = pair.left_tip + r * pair.left_axis
    cr = pair.right_tip + r * pair.right_axis
    nl, ql, nr, qr = cl.copy(), np.zeros_like(cl), cr.copy(), np.zeros_like(cr)
    nl[sel], ql[sel], d_l = pushed_out(cl[sel], index, r)
    nr[sel], qr[sel], d_r = pushed_out(cr[sel], index, r)
    deepest = [(r - float(d.min()), int(sel[np.argmin(d)]), side)
               for d, side in ((d_l, "left"), (d_r, "right")) if d.size]
    wl, wr, u, spacing = pair.left_axis, pair.right_axis, pair.u, pair.spacing
    # every chord next to a point pushed is probed at its middle; those whose two balls touch the
    # blade along different normals (a facet edge between them: the rounded offset) also at a quarter
    # and three quarters
    n_chords = max(len(u) - 1, 0)
    edge = ((np.einsum("ij,ij->i", ql[:-1], ql[1:]) < 1.0 - 1e-12)
            | (np.einsum("ij,ij->i", qr[:-1], qr[1:]) < 1.0 - 1e-12))
    if every_chord:
        check = where[:-1] | where[1:]
        full = edge & check
    else:
        moved = np.any(nl != cl, axis=1) | np.any(nr != cr, axis=1)
        check = full = moved[:-1] | moved[1:]
    changed = not (np.array_equal(nl, cl) and np.array_equal(nr, cr))
    for round_ in range(CREASE_ROUNDS + 1):
        idx = np.flatnonzero(check)
        if idx.size == 0:
            break
        probe_at = [(idx, 0.5)] + [(np.flatnonzero(full), f) for f in CREASE_PROBES if f != 0.5]
        at = np.concatenate([k for k, _ in probe_at])
        dip = np.zeros(n_chords, bool)
        for c, side in ((nl, "left"), (nr, "right")):
            dist, _ = index.closest(np.concatenate([c[k] + f * (c[k + 1] - c[k]) for k, f in probe_at]))
            if round_ == CREASE_ROUNDS:  # the chords of the last insertion are measured, not split
                deepest.append((r - float(dist.min()), int(at[np.argmin(dist)]), side))
            dip[at[(dist < r - CREASE_TOLERANCE) | (not every_chord and dist > r + CHORD_MISS)]] = True
        if not dip.any() or round_ == CREASE_ROUNDS:
            break
        k = np.flatnonzero(dip)
        mid_l, _, dm_l = pushed_out(_midpoints(nl, k, index, r, not every_chord), index, r)
        mid_r, _, dm_r = pushed_out(_midpoints(nr, k, index, r, not every_chord), index, r)
        deepest += [(r - float(d.min()), int(k[np.argmin(d)]) + 1, side)
                    for d, side in ((dm_l, "left"), (dm_r, "right"))]
        mwl, mwr = (w[k] + w[k + 1] for w in (wl, wr))
        mwl /= np.linalg.norm(mwl, axis=1, keepdims=True)
        mwr /= np.linalg.norm(mwr, axis=1, keepdims=True)
        at = k + 1
        nl, nr = np.insert(nl, at, mid_l, axis=0), np.insert(nr, at, mid_r, axis=0)
        wl, wr = np.insert(wl, at, mwl, axis=0), np.insert(wr, at, mwr, axis=0)
        u = np.insert(u, at, 0.5 * (u[k] + u[k + 1]))
        spacing = np.insert(spacing, at, 0.5 * (spacing[k] + spacing[k + 1]))
        new = np.zeros(len(u), bool)
        new[at + np.arange(len(k))] = True
        check = full = new[:-1] | new[1:]  # the new chords, fully probed
        n_chords = len(u) - 1
        changed = True
    worst = max(deepest, default=(0.0, 0, "left"))
    if not changed:
        return pair, worst
    pl, wl, pr, wr, sp = _pushed(pair, nl, nr, r, wl, wr)
    return replace(pair, u=u, left_tip=pl, left_axis=wl, right_tip=pr, right_axis=wr,
                   spacing=spacing if sp is None else sp), worst


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

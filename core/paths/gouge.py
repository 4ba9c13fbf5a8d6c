"""Gouge check and push-out: no ball of a cutting point cuts into the blade.

Checked by distance, not by construction: for every ball centre c = p + r w the exact distance to the
nearest triangle of the blade's tessellation (core.paths.tessellation) is computed; the ball cuts into
the blade where that distance < r - tolerance. On a faceted blade, ``push_out`` moves the centres out
of the facets.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from core.paths.cutter import symmetric_tools
from core.paths.tessellation import SurfaceMesh, TriangleIndex, distance_to_surface, surface_mesh
from core.util.polyline import ball_centres, unit_rows

TOLERANCE = 1e-3  # mm


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
    cl = ball_centres(pair.left_tip, pair.left_axis, r)
    cr = ball_centres(pair.right_tip, pair.right_axis, r)
    nl, ql, nr, qr = cl.copy(), np.zeros_like(cl), cr.copy(), np.zeros_like(cr)
    nl[sel], ql[sel], d_l = pushed_out(cl[sel], index, r)
    nr[sel], qr[sel], d_r = pushed_out(cr[sel], index, r)
    deepest = [(r - float(d.min()), int(sel[np.argmin(d)]), side)
               for d, side in ((d_l, "left"), (d_r, "right")) if d.size]
    wl, wr, u, spacing = pair.left_axis, pair.right_axis, pair.u, pair.spacing
    # the contact normals (symmetrical pairs): the mesh's where a centre was pushed out
    ml, mr = pair.left_normal, pair.right_normal
    if ml is not None and mr is not None:
        ml, mr = ml.copy(), mr.copy()
        ml[sel], mr[sel] = ql[sel], qr[sel]
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
        if ml is not None and mr is not None:
            ml, mr = (np.insert(m, at, unit_rows(m[k] + m[k + 1]), axis=0) for m in (ml, mr))
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
                   spacing=spacing if sp is None else sp, left_normal=ml, right_normal=mr), worst


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
            centres.append(ball_centres(tip[k], axis[k], r))
            tags.append(np.column_stack([np.full(len(k), pair.index), k, np.full(len(k), side == "left")]))
    pts = np.concatenate(centres)
    tag = np.concatenate(tags)
    clearance = distance_to_surface(pts, mesh) - r
    i = int(np.argmin(clearance))
    worst = (int(tag[i, 0]), int(tag[i, 1]), "left" if tag[i, 2] else "right")
    return GougeReport(min_clearance=float(clearance[i]), worst=worst, checked=len(pts),
                       violations=int((clearance < -TOLERANCE).sum()))

"""Cylindrical sections of one triangle surface (``Surface.cut``), resampled along its facets
(``resample``), with facet normals: the machinery behind core.blade.mesh.MeshBlade.section, which
finds LE and TE and the two sides from these cuts.

Cuts: every triangle edge is cut where it crosses the cylinder, solved exactly (the radius along an
edge is convex: one crossing when its ends lie on both sides, two when a long edge dips inside between
two outer ends; boundary edges are cut once at most). In each facet's plane the inside of the cylinder
is convex, so each exit from it along the triangle's perimeter is joined to the next crossing by a
piece of the section lying in that facet; the pieces are chained by pointer jumping
(scipy.sparse.csgraph on a non-manifold mesh), no loop over points, and the longest chain of a surface
is its section. Crossings closer than MERGE_GAP are taken as one.

Resampling: the crossings are kept, and inside each piece points lie on the facet's own cut with the
cylinder, at most RESAMPLE_STEP (0.1 mm) apart, so a cubic spline through them follows the facets
closely (finer and graded near crossings where the facets turn, see resample).

Normals come from the facets, so that a ball-nose cutter at a point with its normal touches the
faceted surface there: a point inside a piece gets its facet's normal; a crossing (on a mesh edge) the
normalised mean of the normals of the facets on both sides (a ball at a convex corner then cuts
neither); beside a crossing where the facets turn, the normal turns from the one to the other over a
short ramp (8 CORNER_SAG / turn long) so that splines through the normals do not ring; the ends of an
open surface keep their facet's normal (the vertex normals are used only where no facet is known). A
concave corner of the mesh (a valley between facets, or a notch where two surfaces meet) cannot be
followed by a ball without cutting into a facet; nothing here hides it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, depth_first_order

if TYPE_CHECKING:
    import trimesh

#: sections are resampled along their facets at most this far apart, mm (see the module notes)
RESAMPLE_STEP = 0.1
#: crossings closer than this (mm) along a section are taken as one (a cut through or next to a vertex)
MERGE_GAP = 1e-4
#: at a crossing where the facet normals turn by phi, the normal turns over a ramp 8 CORNER_SAG / phi
#: long (mm): a ball rolling round a convex corner cuts a facet by about CORNER_SAG at most
CORNER_SAG = 1e-4
#: largest turn of the normal between two points of a ramp, rad
RAMP_ANGLE = np.radians(5.0)
#: away from a ramp or a short step the spacing grows by about this factor per point
GROWTH = 1.5


def _cross_cylinder(p: np.ndarray, d: np.ndarray, radius: float) -> np.ndarray:
    """Parameters s with |(p + s d)_xy| = radius, row by row (p, d (n, 3)): the root reached moving
    outwards from p inside the cylinder (d with an outward radial part)."""
    px, py, dx, dy = p[:, 0], p[:, 1], d[:, 0], d[:, 1]
    a = dx * dx + dy * dy
    b = px * dx + py * dy
    c = px * px + py * py - radius * radius
    den = b + np.sqrt(np.maximum(b * b - a * c, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, -c / den, 0.0)


def _norm(v: np.ndarray) -> np.ndarray:
    """Lengths of the rows of v (n, 3)."""
    return np.sqrt(np.einsum("ij,ij->i", v, v))


def _slerp(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Unit vectors turned from a towards b by the fraction w (row by row: (n, 3), (n, 3), (n,))."""
    cos = np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)
    om = np.arccos(cos)
    s = np.sin(om)
    with np.errstate(divide="ignore", invalid="ignore"):
        ca = np.where(s > 1e-9, np.sin((1.0 - w) * om) / s, 1.0 - w)
        cb = np.where(s > 1e-9, np.sin(w * om) / s, w)
    v = ca[:, None] * a + cb[:, None] * b
    size = _norm(v)
    return np.where((size > 1e-12)[:, None], v / np.where(size > 1e-12, size, 1.0)[:, None], b)


def _graded_points(length: np.ndarray, a: np.ndarray, b: np.ndarray, la: np.ndarray, lb: np.ndarray,
                   h: np.ndarray, growth: float = GROWTH) -> tuple[np.ndarray, np.ndarray]:
    """Inner sample points of segments, graded from the spacing wanted at their ends up to h.

    length (n,) mm; a, b (n,) mm, > 0: the spacing over the first la and the last lb mm (n,) of each
    segment (la + lb <= length); between them the spacing grows by about `growth` per point up to
    h (n,): size(x) = min(a + c (x - la), h, b + c (L - lb - x)), c = ln(growth). The points lie at equal
    steps of the integral of 1 / size (analytic, five pieces), so consecutive intervals differ by
    about `growth` at most and none is longer than h.
    Returns (segment index (k,), distance from the segment's start (k,) mm), in order."""
    c = np.log(growth)
    a, b = np.minimum(a, h), np.minimum(b, h)
    span = np.maximum(length - la - lb, 0.0)
    p = np.clip((h - a) / c, 0.0, span)  # where the spacing reaches h from the start
    q = np.clip(span - (h - b) / c, 0.0, span)  # ... and from the end
    mid = np.clip((b - a + c * span) / (2 * c), 0.0, span)  # where they meet when h is not reached
    p, q = np.where(p <= q, p, mid), np.where(p <= q, q, mid)
    f_a = la / a
    f_p = f_a + np.log1p(c * p / a) / c
    f_q = f_p + (q - p) / h
    f_b = f_q + np.log1p(c * (span - q) / b) / c
    total = f_b + lb / b
    pieces = np.maximum(np.ceil(total * (1.0 - 1e-9)), 1).astype(int)
    inner = pieces - 1
    k = np.repeat(np.arange(len(length)), inner)
    f = (np.arange(k.size) - np.repeat(np.cumsum(inner) - inner, inner) + 1) * (total / pieces)[k]
    ak, bk, lak, pk, qk, sk, hk = a[k], b[k], la[k], p[k], q[k], span[k], h[k]
    with np.errstate(over="ignore"):
        x = np.where(f <= f_a[k], f * ak, np.where(
            f <= f_p[k], lak + ak * np.expm1(c * (f - f_a[k])) / c, np.where(
                f <= f_q[k], lak + pk + (f - f_p[k]) * hk, np.where(
                    f <= f_b[k], lak + sk - ((bk + c * (sk - qk)) * np.exp(-c * (f - f_q[k])) - bk) / c,
                    length[k] - (total[k] - f) * bk))))
    return k, np.minimum(np.maximum(x, 0.0), length[k])


@dataclass(frozen=True)
class Polyline:
    """A section polyline through the crossings of mesh edges (on the cylinder r_cut, blade frame).

    points (n, 3) mm; normals (n, 3) unit, at the crossings: the mean of the facet normals on both
    sides; turn (n,) rad, the angle between those two facet normals (0 at an open end);
    facet_normals (s, 3) unit, the normal of the facet each step i -> i + 1 lies in (zero where
    unknown); s = n - 1, or n when closed (the last step returns to the first point);
    facets (s,) int, the triangle each step lies in (-1 where unknown; None: not recorded), what a
    surface parametrised per triangle corner (core.blade.cad) maps back to its parameters."""

    points: np.ndarray
    normals: np.ndarray
    turn: np.ndarray
    facet_normals: np.ndarray
    closed: bool
    facets: np.ndarray | None = None

    def _with(self, points: np.ndarray, normals: np.ndarray, turn: np.ndarray, steps: np.ndarray,
              closed: bool) -> Polyline:
        """A polyline of these points, normals and turns, its steps' data taken at ``steps``."""
        return Polyline(points, normals, turn, self.facet_normals[steps], closed,
                        None if self.facets is None else self.facets[steps])

    def part(self, index: np.ndarray) -> Polyline:
        """The open polyline through the points `index` (consecutive along the loop, either way).

        Its two ends are open ends: each keeps the normal of its own end step's facet (turn 0), not the
        mean with the facet beyond it, which belongs to the other part (where a closed blade's section
        is split at LE and TE, face and back then get their own normals there, as two surfaces do)."""
        steps = np.where(index[1:] == (index[:-1] + 1) % len(self.points), index[:-1], index[1:])
        normals, turn, fn = self.normals[index], self.turn[index], self.facet_normals[steps]
        for end, step in ((0, 0), (-1, -1)):
            if _norm(fn[step:step + 1 or None])[0] > 0.5:  # (a step on no known facet keeps the mean)
                normals[end], turn[end] = fn[step], 0.0
        return self._with(self.points[index], normals, turn, steps, False)

    def reversed(self) -> Polyline:
        return self._with(self.points[::-1], self.normals[::-1], self.turn[::-1],
                          np.arange(len(self.facet_normals))[::-1], self.closed)


def resample(parts: Sequence[Polyline], r_cut: float, r: float,
              step: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Points along the facets of open polylines (all in one pass), placed on the cylinder r at the end.

    Every crossing is kept with its mean normal. Inside a step the points lie on the facet's own cut
    with the cylinder r_cut, at most `step` mm apart, with the facet's normal; except on a short ramp
    beside a crossing where the facet normals turn by phi: there the normal turns from the
    crossing's to the facet's (slerp, about RAMP_ANGLE per point) over a length 8 CORNER_SAG / phi
    (at most a third of the step), so that a ball rolls round the corner instead of its normal
    jumping (a cubic spline through a jump rings by several degrees); a convex corner then cuts a
    facet by about CORNER_SAG at most. From a ramp, or a crossing beside a short step, the spacing
    grows by GROWTH per point up to `step`. Returns [(points (m, 3), normals (m, 3))] per part."""
    gap = np.zeros((1, 3))
    pts = np.concatenate([p.points for p in parts])
    cn = np.concatenate([p.normals for p in parts])
    turn = np.concatenate([p.turn for p in parts])
    fn = np.concatenate([x for p in parts for x in (gap, p.facet_normals)][1:])
    p0, p1 = pts[:-1], pts[1:]
    length = _norm(p1 - p0)
    joint = np.cumsum([len(p.points) for p in parts])[:-1] - 1  # the steps from one part to the next
    length[joint] = np.inf
    valid = _norm(fn) > 0.5
    beside = np.minimum(np.append(np.inf, length), np.append(length, np.inf))  # the shorter step beside
    ramp = np.where(turn > 0, np.minimum(8.0 * CORNER_SAG / np.maximum(turn, 1e-12), step), 0.0)
    ramp = np.minimum(ramp, beside / 3.0)
    count = np.ceil(0.5 * turn / RAMP_ANGLE)
    size = np.maximum(np.where(ramp > 0, ramp / np.maximum(count, 1.0), np.minimum(step, beside)), 1e-9 * r)
    # out from the chords to the cylinder within the facets' planes: along the facet direction closest
    # to the radial one at each step's middle (across the cylinder where there is none)
    unit = (p1 - p0) / np.where(valid, length, 1.0)[:, None]
    mid = 0.5 * (p0 + p1)
    radial = np.zeros_like(mid)
    radial[:, :2] = mid[:, :2] / np.hypot(mid[:, 0], mid[:, 1])[:, None]
    out_dir = radial - np.einsum("ij,ij->i", radial, fn)[:, None] * fn
    flat = np.einsum("ij,ij->i", out_dir, radial) < 1e-6
    out_dir[flat] = radial[flat]
    # spacing along the chords: moving out stretches it by up to 1 + 4 sagitta / chord (a parabola's
    # end slope), and from r_cut to r near the hub or tip by r / r_cut
    sagitta = _cross_cylinder(mid, out_dir, r_cut) * _norm(out_dir)
    stretch = (1.0 + 4.0 * sagitta / np.where(valid, length, np.inf)) * max(r / r_cut, 1.0)
    la, lb = np.where(valid, ramp[:-1], 0.0), np.where(valid, ramp[1:], 0.0)  # no points off the facets
    k, x = _graded_points(np.where(valid, length, 0.0), size[:-1], size[1:], la, lb,
                          step * (1.0 - 1e-6) / stretch)
    # the normal: the facet's, turned towards a crossing's on its ramp
    nrm = fn[k]
    ra, rb, lk = ramp[k], ramp[k + 1], length[k]
    back = np.where(ra > 0, 1.0 - x / np.where(ra > 0, ra, 1.0), 0.0)
    ahead = np.where(rb > 0, 1.0 - (lk - x) / np.where(rb > 0, rb, 1.0), 0.0)
    on = np.flatnonzero((back > 0) | (ahead > 0))
    to_back = back[on] >= ahead[on]
    nrm[on] = _slerp(nrm[on], np.where(to_back[:, None], cn[k[on]], cn[k[on] + 1]),
                     np.where(to_back, back[on], ahead[on]))
    q = p0[k] + x[:, None] * unit[k]  # on the chord: inside the cylinder
    d = out_dir[k]
    q += _cross_cylinder(q, d, r_cut)[:, None] * d
    at = np.arange(len(pts)) + np.concatenate([[0], np.cumsum(np.bincount(k, minlength=len(p0)))])
    out = np.empty((len(pts) + len(q), 3))
    nout = np.empty_like(out)
    inside = np.ones(len(out), bool)
    inside[at] = False
    out[at], nout[at] = pts, cn
    out[inside], nout[inside] = q, nrm
    out[:, :2] *= (r / np.hypot(out[:, 0], out[:, 1]))[:, None]
    cuts = at[np.cumsum([len(p.points) for p in parts])[:-1]]
    return list(zip(np.split(out, cuts), np.split(nout, cuts), strict=True))


def _longest_chain(seg: np.ndarray, seg_len: np.ndarray,
                   m: int) -> tuple[np.ndarray, np.ndarray, bool] | None:
    """The longest chain of segments (seg (s, 2) node indices < m, seg_len (s,)): (its nodes in
    order, the segment of each step between them (the last one back to the start when closed),
    closed); None if a node lies on more than two segments (the caller then walks a graph).

    Pointer jumping over directed segments (state 2i runs seg[i, 0] -> seg[i, 1], 2i + 1 back), in
    log2(s) rounds of array operations: the component of every segment (the smallest segment reached
    forwards either way), then the distance of every state from the end of its run."""
    degree = np.bincount(seg.ravel(), minlength=m)
    if degree.max() > 2:
        return None
    n = 2 * len(seg)
    state = np.arange(n)
    tail, head = seg.ravel(), seg[:, ::-1].ravel()
    by_tail = np.argsort(tail, kind="stable")
    first = np.searchsorted(tail[by_tail], np.arange(m))
    leave0 = by_tail[np.minimum(first, n - 1)]
    leave1 = np.where(degree > 1, by_tail[np.minimum(first + 1, n - 1)], -1)
    a, b = leave0[head], leave1[head]
    nxt = np.where(a == (state ^ 1), b, a)  # leave the head by its other segment (-1: dead end)
    rounds = int(np.ceil(np.log2(n))) + 1
    jump, lab = np.where(nxt >= 0, nxt, state), state // 2
    for _ in range(rounds):
        lab, jump = np.minimum(lab, lab[jump]), jump[jump]
    comp = np.minimum(lab[0::2], lab[1::2])
    longest = int(np.argmax(np.bincount(comp, weights=seg_len)))
    ends = np.flatnonzero(degree[tail] == 1)  # states leaving an end node
    ends = ends[comp[ends // 2] == longest]
    closed = ends.size == 0
    start = 2 * longest if closed else int(ends[0])
    if closed:
        nxt = np.where(nxt == start, -1, nxt)  # cut the loop just before start
    jump, dist = np.where(nxt >= 0, nxt, state), (nxt >= 0).astype(int)
    for _ in range(rounds):
        dist, jump = dist + dist[jump], jump[jump]
    run = np.flatnonzero(jump == jump[start])  # the states of start's run, all downstream of it
    run = run[np.argsort(-dist[run], kind="stable")]
    nodes = np.concatenate([tail[run[:1]], head[run]])
    return (nodes[:-1] if closed else nodes), run // 2, closed


class Surface:
    """One triangle surface prepared for cylindrical slicing (blade frame, mm)."""

    def __init__(self, mesh: trimesh.Trimesh, rot: np.ndarray, origin: np.ndarray, file: str):
        self.file = file
        self.vertices = (np.asarray(mesh.vertices) - origin) @ rot.T
        self.normals = np.asarray(mesh.vertex_normals) @ rot.T
        self.faces = np.asarray(mesh.faces)
        tri = self.vertices[self.faces]
        fn = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])  # the winding's side: outward
        area = np.linalg.norm(fn, axis=1, keepdims=True)
        self.face_normals = np.where(area > 0, fn / np.where(area > 0, area, 1.0), 0.0)
        self.radii = np.hypot(self.vertices[:, 0], self.vertices[:, 1])
        self.edges = np.asarray(mesh.edges_unique)
        self.face_edges = np.asarray(mesh.faces_unique_edges)  # side k of a face: vertex k -> k + 1
        # |a + t (b - a)|_xy^2 = qa t^2 + 2 qb t + qc along an edge: a convex function of t
        a, b = self.vertices[self.edges[:, 0]], self.vertices[self.edges[:, 1]]
        d = b[:, :2] - a[:, :2]
        self.qa = np.einsum("ij,ij->i", d, d)
        self.qb = np.einsum("ij,ij->i", a[:, :2], d)
        self.qc = np.einsum("ij,ij->i", a[:, :2], a[:, :2])
        ends = self.radii[self.edges]
        self.edge_rmax = ends.max(axis=1)
        # boundary edges (one facet) are cut once at most: where a boundary row (hub, tip) dips
        # between its vertices, the section runs on across the dip in the facet's plane
        self.edge_inner = np.bincount(self.face_edges.ravel(), minlength=len(self.edges)) > 1
        t_min = np.clip(-self.qb / np.where(self.qa > 0, self.qa, 1.0), 0.0, 1.0)
        dip = np.sqrt(np.maximum(self.qa * t_min**2 + 2 * self.qb * t_min + self.qc, 0.0))
        self.edge_rmin = np.where(self.edge_inner, np.minimum(dip, ends.min(axis=1)), ends.min(axis=1))
        self.adjacency = np.asarray(mesh.face_adjacency)

    def sag_estimate(self, r: float) -> float:
        """An estimate (mm) of how far a cut at r along the facets can lie from the smooth surface their
        vertices sample: over the pairs of adjacent facets the cylinder r crosses both of, the largest
        phi d / 4, phi the angle between their normals and d the distance between their centroids: the
        sag kappa L^2 / 8 of an arc of the curvature kappa = phi / d between them over a chord
        L = sqrt(2) d (a facet's extent across the turn). 0 where no such pair is cut."""
        fr = self.radii[self.faces]
        cut = (fr.min(axis=1) <= r) & (fr.max(axis=1) >= r)
        adj = self.adjacency[cut[self.adjacency].all(axis=1)] if len(self.adjacency) else self.adjacency
        if len(adj) == 0:
            return 0.0
        n = self.face_normals
        phi = np.arccos(np.clip(np.einsum("ij,ij->i", n[adj[:, 0]], n[adj[:, 1]]), -1.0, 1.0))
        centre = self.vertices[self.faces].mean(axis=1)
        d = np.linalg.norm(centre[adj[:, 0]] - centre[adj[:, 1]], axis=1)
        return float(np.max(phi * d / 4.0))

    def _crossings(self, r_cut: float) -> tuple[np.ndarray, np.ndarray]:
        """Every crossing of an edge with the cylinder r_cut: (edge (n,), t (n,) from its first
        vertex), sorted by edge, then t. An edge is crossed once when its ends lie on both sides,
        twice when both ends lie outside (radius >= r_cut) and its middle dips inside (a long edge)."""
        e = np.flatnonzero((self.edge_rmin < r_cut) & (self.edge_rmax >= r_cut))
        qa, qb, qc = self.qa[e], self.qb[e], self.qc[e] - r_cut * r_cut
        disc = np.sqrt(np.maximum(qb * qb - qa * qc, 0.0))
        big = -(qb + np.copysign(disc, qb))  # both roots in their well-conditioned forms (qa > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            r1, r2 = big / qa, np.where(big != 0, qc / big, 0.0)
        lo = np.clip(np.minimum(r1, r2), 0.0, 1.0)
        hi = np.clip(np.maximum(r1, r2), 0.0, 1.0)
        out_a = self.radii[self.edges[e, 0]] >= r_cut
        out_b = self.radii[self.edges[e, 1]] >= r_cut
        twice = out_a & out_b
        edge = np.concatenate([e, e[twice]])
        t = np.concatenate([np.where(out_a, lo, hi), hi[twice]])
        order = np.lexsort((t, edge))
        return edge[order], t[order]

    def _segments(self, r_cut: float, edge: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pieces of the section inside the facets: (pairs of crossings (s, 2), facet (s,)).

        In a facet's plane the inside of the cylinder is convex, so is its part inside the triangle:
        walking the triangle's perimeter, each exit from the cylinder is joined by an arc of the
        section to the next crossing along the perimeter."""
        count = np.bincount(edge, minlength=len(self.edges))
        first = np.cumsum(count) - count  # the crossings of edge e: first[e], first[e] + 1
        nc = count[self.face_edges]
        hit = np.flatnonzero(nc.sum(axis=1) >= 2)
        side_edge, side_n = self.face_edges[hit].ravel(), nc[hit].ravel()
        rec = np.repeat(np.arange(side_edge.size), side_n)  # one record per crossing of a side
        j = np.arange(rec.size) - np.repeat(np.cumsum(side_n) - side_n, side_n)
        node = first[side_edge[rec]] + j
        side, face = rec % 3, hit[rec // 3]
        start = self.faces[face, side]  # the side runs from vertex `side` to `side + 1`
        forward = self.edges[edge[node], 0] == start
        pos = side + np.where(forward, t[node], 1.0 - t[node])
        # one crossing: an exit when the side starts inside; two: the second along the side exits
        leaves = np.where(count[edge[node]] == 2, (j == 1) == forward, self.radii[start] < r_cut)
        srt = np.lexsort((pos, face))
        node, face, leaves = node[srt], face[srt], leaves[srt]
        n = node.size
        last = np.append(face[1:] != face[:-1], True)
        group = np.flatnonzero(np.concatenate([[True], last[:-1]]))
        nxt = np.where(last, np.repeat(group, np.diff(np.append(group, n))), np.arange(n) + 1)
        ex = np.flatnonzero(leaves)
        return np.column_stack([node[ex], node[nxt[ex]]]), face[ex]

    def cut(self, r_cut: float) -> Polyline | None:
        """The longest polyline of the section at r_cut through the crossings, or None if the surface
        misses r_cut."""
        edge, t = self._crossings(r_cut)
        if edge.size < 2:
            return None
        seg, seg_face = self._segments(r_cut, edge, t)
        if len(seg) == 0:
            return None
        a, b = self.edges[edge, 0], self.edges[edge, 1]
        pts = self.vertices[a] + t[:, None] * (self.vertices[b] - self.vertices[a])
        m = edge.size
        seg_len = _norm(pts[seg[:, 0]] - pts[seg[:, 1]])
        chain = _longest_chain(seg, seg_len, m)
        if chain is not None:
            order, step_seg, closed = chain
            walk = np.append(order, order[0]) if closed else order
            face = seg_face[step_seg]
        else:  # a node on three or more pieces (a non-manifold mesh): walk the graph
            graph = coo_matrix((np.ones(len(seg)), (seg[:, 0], seg[:, 1])), shape=(m, m)).tocsr()
            labels = connected_components(graph, directed=False)[1]
            longest = int(np.argmax(np.bincount(labels[seg[:, 0]], weights=seg_len)))
            degree = np.bincount(seg.ravel(), minlength=m)
            ends = np.flatnonzero((labels == longest) & (degree == 1))
            closed = ends.size == 0
            start = int(ends[0]) if not closed else int(np.flatnonzero(labels == longest)[0])
            order = depth_first_order(graph, start, directed=False, return_predecessors=False)
            walk = np.append(order, order[0]) if closed else order
            # the facet of each step walk[i] -> walk[i + 1] (none where no facet joins the two)
            key = np.sort(seg, axis=1) @ np.array([m, 1])
            by_key = np.argsort(key)
            step_key = np.sort(np.column_stack([walk[:-1], walk[1:]]), axis=1) @ np.array([m, 1])
            pos = np.minimum(np.searchsorted(key[by_key], step_key), len(key) - 1)
            face = np.where(key[by_key[pos]] == step_key, seg_face[by_key[pos]], -1)
        fn = np.where(face[:, None] >= 0, self.face_normals[np.maximum(face, 0)], 0.0)
        # steps shorter than MERGE_GAP (crossings at or next to a vertex) are dropped with their end
        real = _norm(pts[walk[1:]] - pts[walk[:-1]]) > MERGE_GAP
        keep = walk[1:][real]
        if not closed:
            keep = np.concatenate([walk[:1], keep])
        fn, face = fn[real], face[real]
        # crossings: the mean of the facet normals on both sides (the vertex normals where unknown)
        if closed:  # point keep[i] ends step i and starts step i + 1
            prev_fn, next_fn = fn, np.roll(fn, -1, axis=0)
        else:
            zero = np.zeros((1, 3))
            prev_fn, next_fn = np.vstack([zero, fn]), np.vstack([fn, zero])
        nrm = prev_fn + next_fn
        size = _norm(nrm)
        vn = self.normals[a[keep]] + t[keep, None] * (self.normals[b[keep]] - self.normals[a[keep]])
        nrm = np.where((size > 1e-6)[:, None], nrm, vn)
        nrm /= _norm(nrm)[:, None]
        both = (_norm(prev_fn) > 0.5) & (_norm(next_fn) > 0.5)
        cos = np.minimum(np.maximum(np.einsum("ij,ij->i", prev_fn, next_fn), -1.0), 1.0)
        turn = np.where(both, np.arccos(cos), 0.0)
        if closed:  # start the loop at its first point again: point i, step i -> i + 1
            keep, nrm, turn = np.roll(keep, 1), np.roll(nrm, 1, axis=0), np.roll(turn, 1)
        return Polyline(pts[keep], nrm, turn, fn, closed, face)

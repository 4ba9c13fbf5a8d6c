"""A blade read from a triangle mesh (STL, OBJ, PLY via trimesh).

Two kinds of source (``load_mesh_blade``):
- one file: a closed blade (face, back and the caps in one mesh);
- two files: two open surfaces, the first is used as the face and the second as the back, in the
  files' order, whatever side they lie on (a pair given the other way round is kept and noted in
  ``MeshBlade.warnings``); cap files (tip, root) are not wanted.

Frame: the vertices are moved into the blade frame of core.blade: minus ``origin`` (file coordinates),
then the propeller axis ('x', 'y' or 'z') is turned onto +Z by a cyclic permutation of the axes
(right-handed), then the whole mesh is turned about Z so that the area-weighted centroid of the blade
lies at theta = 0 (the generator line along +X). ``MeshBlade.transform`` is that 4x4 map.

Sections (``MeshBlade.section(r)``): every triangle edge is cut where it crosses the cylinder, solved
exactly (the radius along an edge is convex: one crossing when its ends lie on both sides, two when a
long edge dips inside between two outer ends; boundary edges are cut once at most). In each facet's
plane the inside of the cylinder is convex, so each exit from it along the triangle's perimeter is
joined to the next crossing by a piece of the section lying in that facet; the pieces are chained by
pointer jumping (scipy.sparse.csgraph on a non-manifold mesh), no loop over points, and the longest
chain of a surface is its section. Crossings closer than MERGE_GAP are taken as one.
- Two surfaces: one open polyline each; LE and TE are where they meet: the matched end points are
  averaged (the two sides need not share vertices) and put back on the cylinder.
- One closed mesh: one closed loop; LE and TE are its two crossings farthest apart in the unrolled
  (r theta, z) plane; the face is the part to the right of the other walking LE -> TE (the smaller v
  of core.blade.chord_frame, the one definition of the sides used here and in the pair check).
The LE is the end with the larger r theta; both parts run LE -> TE and share their end points.
Then each part is resampled along its facets: the crossings are kept, and inside each piece points
lie on the facet's own cut with the cylinder, at most ``MeshBlade.step`` (RESAMPLE_STEP, 0.1 mm)
apart, so a cubic spline through them follows the facets closely (finer and graded near crossings
where the facets turn, see _resample). Radii within 1e-3 of the span from the hub or the tip are cut
1e-3 span inside the blade (the boundary rows of a real mesh are noisy), then put on the requested
cylinder.

Normals come from the facets, so that a ball-nose cutter at a point with its normal touches the
faceted surface there: a point inside a piece gets its facet's normal; a crossing (on a mesh edge) the
normalised mean of the normals of the facets on both sides (a ball at a convex corner then cuts
neither); beside a crossing where the facets turn, the normal turns from the one to the other over a
short ramp (8 CORNER_SAG / turn long) so that splines through the normals do not ring; the ends of an
open surface keep their facet's normal (the vertex normals are used only where no facet is known). On
the LE/TE step of two surfaces the averaged end moves the last piece off its facet by up to half the
gap between the sides' ends. A concave corner of the mesh (a valley between facets, or a notch where
two surfaces meet) cannot be followed by a ball without cutting into a facet; nothing here hides it.
Outward: a closed mesh gets a consistent winding and a positive volume; each open surface gets a
consistent winding and is turned so that its normals point away from the other surface; the facet
normals follow that winding.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, depth_first_order
from scipy.spatial import ConvexHull, QhullError, cKDTree

from .blade import Blade, Section, chord_frame, unroll
from .errors import BladeInputError

MESH_SUFFIXES = (".stl", ".obj", ".ply")
#: file axes -> blade frame (rows: new X, Y, Z), cyclic permutations (right-handed)
AXIS_ROTATIONS = {
    "x": np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]),
    "y": np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
    "z": np.eye(3),
}
#: cuts closer than this fraction of the span to the hub or tip are moved inside the blade
EDGE_MARGIN = 1e-3
#: a blade subtending a larger angle about the axis is refused (axis through the mesh, or a propeller)
MAX_ANGLE_DEG = 180.0
#: face and back ends farther apart than this share of the chord are refused (not one blade)
MAX_EDGE_GAP = 0.25
#: an open section of a closed mesh is accepted (and closed) if its gap is below this share of its length
MAX_LOOP_GAP = 0.05
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


def read_mesh(path: str | Path) -> trimesh.Trimesh:
    """One triangle mesh from an STL, OBJ or PLY file (file coordinates, mm).

    Raises BladeInputError naming the file: missing, empty, unsupported format, unreadable, no faces.
    """
    p = Path(path)
    if not p.is_file():
        raise BladeInputError(f"{p}: mesh file not found; check the path")
    if p.suffix.lower() not in MESH_SUFFIXES:
        raise BladeInputError(f"{p}: unsupported mesh format {p.suffix!r}; give an STL, OBJ or PLY file")
    if p.stat().st_size == 0:
        raise BladeInputError(f"{p}: the file is empty; export the mesh again")
    fmt = p.suffix[1:].upper()
    try:
        loaded = trimesh.load(str(p), file_type=p.suffix.lower()[1:], process=True)
    except Exception as exc:  # trimesh raises many types on bad bytes
        raise BladeInputError(f"{p}: not a readable {fmt} mesh ({type(exc).__name__}: {exc}); "
                              f"export the blade as a triangle mesh") from exc
    parts = list(loaded.dump()) if isinstance(loaded, trimesh.Scene) else [loaded]  # transforms applied
    if not parts:
        raise BladeInputError(f"{p}: not a readable {fmt} mesh (no geometry found); "
                              f"export the blade as a triangle mesh")
    meshes = [m for m in parts if isinstance(m, trimesh.Trimesh) and len(m.faces) > 0]
    if not meshes:
        raise BladeInputError(f"{p}: the mesh has no triangles (points or lines only?); "
                              f"export the blade surface as a triangle mesh")
    mesh = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)
    if isinstance(loaded, trimesh.Scene) and len(meshes) > 1:
        mesh.merge_vertices()
    mesh.remove_unreferenced_vertices()
    return mesh


def fix_winding(mesh: trimesh.Trimesh) -> None:
    """Make the winding of every connected piece of a mesh consistent (in place, vectorised).

    Each face is a pair of graph nodes (kept, flipped); adjacent faces whose shared edge runs the same
    way link kept to flipped, the others kept to kept; a face is flipped when its flipped node lies in
    the component of its piece's first kept face. (trimesh.repair.fix_winding needs networkx.)"""
    if mesh.is_winding_consistent:
        return
    f = mesh.faces
    adj, edges = mesh.face_adjacency, mesh.face_adjacency_edges

    def runs_forward(faces: np.ndarray) -> np.ndarray:
        nxt = np.roll(faces, -1, axis=1)
        return np.any((faces == edges[:, :1]) & (nxt == edges[:, 1:]), axis=1)

    same_way = runs_forward(f[adj[:, 0]]) == runs_forward(f[adj[:, 1]])  # needs a relative flip
    n = len(f)
    a, b = 2 * adj[:, 0], 2 * adj[:, 1] + same_way
    a2, b2 = 2 * adj[:, 0] + 1, 2 * adj[:, 1] + 1 - same_way
    rows, cols = np.concatenate([a, a2]), np.concatenate([b, b2])
    g = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(2 * n, 2 * n))
    labels = connected_components(g, directed=False)[1]
    pieces = connected_components(coo_matrix((np.ones(len(adj)), (adj[:, 0], adj[:, 1])),
                                             shape=(n, n)), directed=False)[1]
    first = np.full(pieces.max() + 1, n)
    np.minimum.at(first, pieces, np.arange(n))
    flip = labels[2 * np.arange(n) + 1] == labels[2 * first[pieces]]
    mesh.faces = np.where(flip[:, None], f[:, ::-1], f)


def _orient_away(mesh: trimesh.Trimesh, other: trimesh.Trimesh) -> None:
    """Turn an open surface (consistent winding) so that its normals point away from `other`."""
    _, idx = cKDTree(other.vertices).query(mesh.vertices)
    vote = np.einsum("ij,ij->", mesh.vertex_normals, mesh.vertices - other.vertices[idx])
    if vote < 0:
        mesh.invert()


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
class _Polyline:
    """A section polyline through the crossings of mesh edges (on the cylinder r_cut, blade frame).

    points (n, 3) mm; normals (n, 3) unit, at the crossings: the mean of the facet normals on both
    sides; turn (n,) rad, the angle between those two facet normals (0 at an open end);
    facet_normals (s, 3) unit, the normal of the facet each step i -> i + 1 lies in (zero where
    unknown); s = n - 1, or n when closed (the last step returns to the first point)."""

    points: np.ndarray
    normals: np.ndarray
    turn: np.ndarray
    facet_normals: np.ndarray
    closed: bool

    def part(self, index: np.ndarray) -> _Polyline:
        """The open polyline through the points `index` (consecutive along the loop, either way)."""
        steps = np.where(index[1:] == (index[:-1] + 1) % len(self.points), index[:-1], index[1:])
        return _Polyline(self.points[index], self.normals[index], self.turn[index],
                         self.facet_normals[steps], False)

    def reversed(self) -> _Polyline:
        return _Polyline(self.points[::-1], self.normals[::-1], self.turn[::-1],
                         self.facet_normals[::-1], self.closed)


def _resample(parts: Sequence[_Polyline], r_cut: float, r: float,
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


class _Surface:
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

    def cut(self, r_cut: float) -> _Polyline | None:
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
        fn = fn[real]
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
        return _Polyline(pts[keep], nrm, turn, fn, closed)


def _farthest_pair(uv: np.ndarray) -> tuple[int, int]:
    """Indices of the two points of uv (n, 2) farthest apart (candidates: the convex hull, compared in
    blocks of rows to bound the memory)."""
    cand = np.arange(len(uv))
    if len(uv) > 3:
        try:
            cand = ConvexHull(uv).vertices
        except QhullError:
            pass
    h, best, pair = uv[cand], -1.0, (0, 0)
    for start in range(0, len(h), 512):
        d = np.linalg.norm(h[start:start + 512, None, :] - h[None, :, :], axis=2)
        i, j = np.unravel_index(int(np.argmax(d)), d.shape)
        if d[i, j] > best:
            best, pair = float(d[i, j]), (int(cand[start + i]), int(cand[j]))
    return pair


def _face_on_back_side(section: Section) -> bool:
    """True if the face part lies on the back's side of the other part: left of it walking LE -> TE
    in the unrolled section (core.blade.chord_frame: v grows towards the back)."""
    fuv, buv, _ = chord_frame(section)
    return bool(fuv[:, 1].mean() > buv[:, 1].mean())


class MeshBlade(Blade):
    """A blade from one closed mesh or from two open surfaces (face, back), in the blade frame.

    meshes : one or two trimesh.Trimesh in file coordinates (mm); files : their file names (messages);
    axis : 'x', 'y' or 'z', the propeller axis in the file; origin : (3,) mm, a point of the axis.
    step : mm, the largest distance between section points along a facet (RESAMPLE_STEP).
    Attributes: transform (4, 4) file -> blade frame, closed (one closed mesh), warnings (list of str).
    """

    def __init__(self, meshes: Sequence[trimesh.Trimesh], files: Sequence[str], axis: str = "z",
                 origin: Sequence[float] = (0.0, 0.0, 0.0), step: float = RESAMPLE_STEP):
        if not step > 0:
            raise ValueError(f"step must be positive, got {step}")
        self.step = float(step)
        names = [Path(f).name for f in files]
        self.name = " + ".join(names)
        self.source = ",".join(str(f) for f in files)
        self.files = [str(f) for f in files]
        self.closed = len(meshes) == 1
        self.warnings: list[str] = []
        axis = str(axis).strip().lower()
        if axis not in AXIS_ROTATIONS:
            raise BladeInputError(f"{self.name}: axis {axis!r} is not one of x, y, z")
        org = np.asarray(origin, float).reshape(3)
        meshes = [m.copy() for m in meshes]
        for m in meshes:
            fix_winding(m)
        if self.closed:
            if meshes[0].volume < 0:
                meshes[0].invert()
        else:
            _orient_away(meshes[0], meshes[1])
            _orient_away(meshes[1], meshes[0])
        rot = AXIS_ROTATIONS[axis]
        both = trimesh.util.concatenate(meshes)
        c = (np.asarray(both.triangles_center) - org) @ rot.T
        cxy = (np.asarray(both.area_faces)[:, None] * c[:, :2]).sum(axis=0)
        phi = -float(np.arctan2(cxy[1], cxy[0])) if np.hypot(*cxy) > 0 else 0.0
        rz = np.array([[np.cos(phi), -np.sin(phi), 0.0], [np.sin(phi), np.cos(phi), 0.0], [0.0, 0.0, 1.0]])
        rot = rz @ rot
        self.transform = np.eye(4)
        self.transform[:3, :3] = rot
        self.transform[:3, 3] = -rot @ org
        self._surfaces = [_Surface(m, rot, org, n) for m, n in zip(meshes, names, strict=True)]
        radii = np.concatenate([s.radii for s in self._surfaces])
        self._hub, self._tip = float(radii.min()), float(radii.max())
        self._check_axis(f"axis {axis!r} through origin {tuple(float(v) for v in org)} mm")
        mid = self.section(0.5 * (self._hub + self._tip))  # fail early on an unusable mesh
        if not self.closed:
            if _face_on_back_side(mid):
                self.warnings.append(
                    f"{names[0]} lies left of {names[1]} walking LE -> TE in the unrolled section, so by "
                    f"the project's convention it is the back; used as given: {names[0]} = face, "
                    f"{names[1]} = back")

    def facets(self) -> tuple[np.ndarray, np.ndarray]:
        """The mesh itself: vertices (V, 3) float, mm, blade frame, and triangles (T, 3) int."""
        verts, faces, base = [], [], 0
        for srf in self._surfaces:
            verts.append(srf.vertices)
            faces.append(srf.faces + base)
            base += len(srf.vertices)
        return np.concatenate(verts), np.concatenate(faces)

    def _check_axis(self, where: str) -> None:
        """Refuse a mesh that does not lie beside the axis as one blade does."""
        hub, tip = self._hub, self._tip
        if not tip > 0 or tip - hub <= 1e-6 * tip:
            raise BladeInputError(f"{self.name}: the mesh spans no radius about the {where} "
                                  f"(radius {hub:.4g} to {tip:.4g} mm); check the axis and origin")
        if hub < 1e-3 * tip:
            raise BladeInputError(f"{self.name}: the {where} passes through the mesh (hub radius "
                                  f"{hub:.4g} mm); check the axis and origin")
        v = np.concatenate([s.vertices for s in self._surfaces])
        theta = np.sort(np.arctan2(v[:, 1], v[:, 0]))
        span = 360.0 - np.degrees(np.max(np.diff(np.concatenate([theta, [theta[0] + 2 * np.pi]]))))
        if span > MAX_ANGLE_DEG:
            raise BladeInputError(f"{self.name}: the mesh surrounds the {where} ({span:.0f} degrees): the "
                                  f"axis passes through it, or it holds several blades; check the axis and "
                                  f"origin, and give one blade")

    @property
    def hub_radius(self) -> float:
        return self._hub

    @property
    def tip_radius(self) -> float:
        return self._tip

    def section(self, r: float) -> Section:
        """The cylindrical section at radius r (mm), face and back LE -> TE with outward unit normals."""
        self._check_radius(r)
        r = float(r)
        margin = EDGE_MARGIN * (self._tip - self._hub)
        r_cut = min(max(r, self._hub + margin), self._tip - margin)
        cuts = [s.cut(r_cut) for s in self._surfaces]
        for s, c in zip(self._surfaces, cuts, strict=True):
            if c is None:
                raise BladeInputError(f"{s.file}: no blade surface at r = {r:.3f} mm (the mesh spans "
                                      f"{self._hub:.3f} to {self._tip:.3f} mm); check the axis and origin, "
                                      f"or choose a radius on the blade")
        if self.closed:
            face, back = self._split_loop(r, cuts[0])  # type: ignore[arg-type]
        else:
            face, back = self._join_sides(r, r_cut, cuts[0], cuts[1])  # type: ignore[arg-type]
        (f, fn), (b, bn) = _resample([face, back], r_cut, r, self.step)
        b[0], b[-1] = f[0], f[-1]  # the same points (vector and scalar float paths may differ by an ulp)
        return Section(r=r, face=f, back=b, face_normals=fn, back_normals=bn)

    def _split_loop(self, r: float, loop: _Polyline) -> tuple[_Polyline, _Polyline]:
        """Split the closed loop of a one-mesh blade at its LE and TE: (face, back), LE -> TE."""
        pts = loop.points
        length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
        gap = float(np.linalg.norm(pts[-1] - pts[0]))
        if len(pts) < 3 or (not loop.closed and gap > MAX_LOOP_GAP * length):
            raise BladeInputError(
                f"{self.files[0]}: the section at r = {r:.3f} mm is not a closed loop (gap {gap:.3f} mm): "
                f"the mesh is not a closed blade; repair it, or give face and back as two files")
        if not loop.closed:  # a small gap: closed by a straight step on no known facet
            loop = _Polyline(pts, loop.normals, loop.turn, np.vstack([loop.facet_normals, np.zeros((1, 3))]),
                             True)
        uv = unroll(pts, r)
        i, j = _farthest_pair(uv)
        le, te = (i, j) if uv[i, 0] >= uv[j, 0] else (j, i)
        n = len(pts)
        k = (te - le) % n
        fwd = loop.part((le + np.arange(k + 1)) % n)
        bwd = loop.part((le - np.arange(n - k + 1)) % n)
        sec = Section(r=r, face=fwd.points, back=bwd.points, face_normals=fwd.normals,
                      back_normals=bwd.normals)
        return (bwd, fwd) if _face_on_back_side(sec) else (fwd, bwd)

    def _join_sides(self, r: float, r_cut: float, face: _Polyline,
                    back: _Polyline) -> tuple[_Polyline, _Polyline]:
        """Join the open face and back polylines of a two-surface blade at their common ends:
        (face, back), LE -> TE, sharing their end points."""
        for s, c in zip(self._surfaces, (face.closed, back.closed), strict=True):
            if c:
                raise BladeInputError(f"{s.file}: the section at r = {r:.3f} mm is a closed loop; a face or "
                                      f"back surface must be open (give a closed blade as one file)")
        f, b = face.points, back.points
        d_same = np.linalg.norm(f[0] - b[0]) + np.linalg.norm(f[-1] - b[-1])
        d_swap = np.linalg.norm(f[0] - b[-1]) + np.linalg.norm(f[-1] - b[0])
        if d_swap < d_same:
            back = back.reversed()
            b = back.points
        gap = max(np.linalg.norm(f[0] - b[0]), np.linalg.norm(f[-1] - b[-1]))
        ends = 0.5 * (np.array([f[0], f[-1]]) + np.array([b[0], b[-1]]))
        if gap > MAX_EDGE_GAP * np.linalg.norm(ends[1] - ends[0]):
            raise BladeInputError(
                f"{self.name}: at r = {r:.3f} mm the two surfaces do not meet at LE and TE "
                f"(gap {gap:.3f} mm); give the face and back of one blade")
        ends[:, :2] *= (r_cut / np.hypot(ends[:, 0], ends[:, 1]))[:, None]
        if unroll(ends, r)[0, 0] < unroll(ends, r)[1, 0]:
            face, back, ends = face.reversed(), back.reversed(), ends[::-1]
        out = []
        for side in (face, back):
            p = side.points.copy()
            p[0], p[-1] = ends[0], ends[1]
            out.append(_Polyline(p, side.normals, side.turn, side.facet_normals, False))
        return out[0], out[1]


def load_mesh_blade(paths: str | Path | Sequence[str | Path], axis: str = "z",
                    origin: Sequence[float] = (0.0, 0.0, 0.0)) -> MeshBlade:
    """A MeshBlade from one closed blade mesh, or from two open surfaces: (face, back) in that order.

    paths : one path, or a sequence of one or two paths (STL, OBJ, PLY), mm; axis : 'x', 'y' or 'z',
    the propeller axis in the file's coordinates; origin : (3,) mm, a point on that axis.
    Raises BladeInputError naming the file for every unusable input.
    """
    files = [paths] if isinstance(paths, str | Path) else list(paths)
    if not 1 <= len(files) <= 2:
        raise BladeInputError(
            f"{', '.join(str(f) for f in files) or 'no mesh file'}: give one closed blade mesh, or two "
            f"open surfaces (face, back); got {len(files)} files (leave out tip and root caps)")
    meshes = [read_mesh(f) for f in files]
    return MeshBlade(meshes, [str(f) for f in files], axis=axis, origin=origin)

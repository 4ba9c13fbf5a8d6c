"""One blade out of a mesh of a whole propeller: the hub cut off, the blades found, face and back split.

A whole propeller comes as one mesh (blades, hub and caps, in one or many pieces, sharing vertices or
not). ``split_propeller`` turns it into the face and back surfaces of each blade, which
core.blade.mesh.MeshBlade then reads as a face/back pair. All of it happens in the axis frame
(core.blade.placement: the axis turned onto +Z through its point, mm):

1. The hub's end (``hub_end``): the surface, sampled SAMPLE_DEG of the tip radius apart (at most about
   MAX_SAMPLES points), covers every angle about the axis where the hub is (its cylinder and end
   faces); between the blades above it, it leaves gaps. The hub ends at the outer edge of the
   outermost radius band (BANDS bands from the axis to the tip) whose widest angular gap is below
   GAP_DEG; the default cut ``r_min`` lies HUB_MARGIN of the blades' span above it (a mesh that
   surrounds the axis out to its tip has no blades about it).
2. The cut: facets wholly inside r_min are dropped, facets across it are clipped where their edges
   cross the cylinder (solved exactly on each edge, one new vertex an edge so that the pieces stay
   connected; between two crossings the cut is the facet's straight chord).
3. The blades: the pieces left (connected by shared vertices) are joined when their open boundaries
   come within JOIN_SHARE of the tip radius of each other (a face and a back that meet at the edges
   without sharing vertices). Blade 1 is the one whose area centroid has the smallest angle in
   [0, 360) degrees about the axis from the frame's first direction (file y for axis x, z for y, x for
   z, core.blade.placement.AXIS_ROTATIONS), the others follow counter-clockwise (right-handed about the
   axis). A propeller's blades are alike: pieces whose tip radii or areas differ by more than
   ALIKE_SHARE are refused (a wrong axis cuts one blade into unlike pieces).
4. Face and back: each connected piece is turned to face outwards (its normals, weighted by area,
   point away from the mean of the blade's points in their radius band, the tip's lid left out) and
   the caps are dropped: facets lying within TIP_BAND of the span from the tip radius (the tip's lid),
   and facets whose outward normal lies within CAP_DEG of the direction to the axis (a root plate).
   Facets facing outwards along the radius are kept: next to a rounded tip the sides themselves turn
   to face the tip;
   each facet goes to the back when its normal, in the unrolled (r theta, z) plane, points to the left
   of the chord walking LE -> TE (core.blade.model.chord_frame's side of the back), else to the face.
   The chord of a radius band is the farthest pair of the blade's points in it (LE: the larger
   r theta), in CHORD_BANDS bands over the blade, its direction interpolated between the bands' middles. So
   face and back part where the normal turns across the chord: at the leading and trailing edges.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from core.blade.mesh_sections import _cross_cylinder
from core.blade.mesh_tools import farthest_pair, fix_winding
from core.errors import BladeInputError

if TYPE_CHECKING:
    import trimesh

#: radius bands for the hub's end and for the chord's direction
BANDS = 200
#: sample spacing on the surface for the hub's end, degrees of the tip radius
SAMPLE_DEG = 0.25
#: at most about this many sample points (coarser than SAMPLE_DEG on a mesh that is long and thin about
#: the axis: no propeller, the memory bounded)
MAX_SAMPLES = 2_000_000
#: a radius band whose widest empty arc is below this many degrees surrounds the axis (hub)
GAP_DEG = 2.0
#: the default cut lies this share of the span (hub's end to tip) above the hub's end
HUB_MARGIN = 0.02
#: pieces whose open boundaries come this close (share of the tip radius) are one blade
JOIN_SHARE = 0.01
#: facets whose outward normal lies within this angle (degrees) of the direction to the axis are caps
CAP_DEG = 30.0
#: facets whose corners all lie within this share of the span from the tip radius are the tip's lid
#: (whatever their normal: a lid's slivers have no reliable one)
TIP_BAND = 1e-3
#: the blades of a propeller are alike: their tip radii and their areas (caps included) within this
#: share of the largest (pieces that are not alike: a wrong axis, or no propeller)
ALIKE_SHARE = 0.05
#: bands over one blade for its chord's direction
CHORD_BANDS = 24


@dataclass(frozen=True)
class PropellerBlade:
    """One blade found in a propeller mesh: its face and back (trimesh.Trimesh, file coordinates in
    the file's units), the angle of its area centroid about the axis (degrees, [0, 360)), its radii
    (mm, after the cut) and its number of facets before the split (caps included)."""

    face: trimesh.Trimesh
    back: trimesh.Trimesh
    angle_deg: float
    r_from: float
    r_to: float
    facets: int
    area: float


@dataclass(frozen=True)
class Propeller:
    """The blades of a propeller mesh, numbered from 1 (see the module), and where its hub was cut:
    ``r_min`` (mm) the cut, ``hub_end`` (mm) the radius where the hub's full circle ends (None when the
    mesh surrounds the axis nowhere: no hub), ``r_min_given`` whether the operator gave r_min."""

    blades: list[PropellerBlade]
    r_min: float
    hub_end: float | None
    r_min_given: bool

    def summary(self) -> dict:
        """The figures ``blade info`` shows of the propeller (mm, degrees)."""
        return {"blades": len(self.blades), "r_min_mm": round(self.r_min, 4),
                "hub_end_mm": None if self.hub_end is None else round(self.hub_end, 4),
                "r_min_given": self.r_min_given,
                "found": [{"index": k + 1, "angle_deg": round(b.angle_deg, 3), "r_from_mm": round(b.r_from, 4),
                           "r_to_mm": round(b.r_to, 4), "facets": b.facets} for k, b in enumerate(self.blades)]}


def listing(summary: dict, unpicked: bool) -> list[str]:
    """The lines of ``bladecam blade info`` that list the blades of a propeller: ``summary`` is
    Propeller.summary() with "picked" (the measured blade's number); ``unpicked``: no blade was asked
    for (blade 1 is measured)."""
    end = summary["hub_end_mm"]
    hub = "no hub found" if end is None else f"hub's full circle ends at r = {end:.3f} mm"
    how = "given" if summary["r_min_given"] else f"found: {hub}"
    lines = [f"  a whole propeller: {summary['blades']} blades outside the hub cut r = {summary['r_min_mm']:.3f} mm "
             f"({how})", "  blade   angle deg   r from mm     r to mm   facets"]
    for b in summary["found"]:
        mark = "  <- these sizes" if b["index"] == summary["picked"] else ""
        lines.append(f"  {b['index']:>5} {b['angle_deg']:11.3f} {b['r_from_mm']:11.3f} {b['r_to_mm']:11.3f} "
                     f"{b['facets']:8d}{mark}")
    if unpicked and summary["blades"] > 1:
        lines.append("  (blade 1 measured below; --blade-index K picks another)")
    return lines


def _sample_points(tri: np.ndarray, h: float) -> np.ndarray:
    """Points on the triangles tri (T, 3, 3) at most about h apart, about area / h^2 + 2 a triangle however
    thin: rows parallel to each triangle's longest edge, ceil(height / h) + 1 rows from that edge to the
    opposite corner, each row cut into pieces of at most h."""
    edge = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=2)  # edge k: corner k -> k + 1
    k = np.argmax(edge, axis=1)
    idx = (k[:, None] + np.arange(3)[None, :]) % 3
    t = np.take_along_axis(tri, idx[:, :, None], axis=1)  # corners a, b (the longest edge), apex c
    length = edge[np.arange(len(tri)), k]
    height = np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1) / np.maximum(length, 1e-300)
    rows = np.ceil(height / h).astype(int) + 1  # rows at w = 0, 1/(rows-1), ..., 1 (the apex)
    tri_of_row = np.repeat(np.arange(len(tri)), rows)
    w = (np.arange(tri_of_row.size) - np.repeat(np.cumsum(rows) - rows, rows)) / np.maximum(rows - 1, 1)[tri_of_row]
    tr = t[tri_of_row]
    start = tr[:, 0] + w[:, None] * (tr[:, 2] - tr[:, 0])
    end = tr[:, 1] + w[:, None] * (tr[:, 2] - tr[:, 1])
    per = np.ceil((1.0 - w) * length[tri_of_row] / h).astype(int) + 1  # points on each row
    row_of_pt = np.repeat(np.arange(per.size), per)
    f = (np.arange(row_of_pt.size) - np.repeat(np.cumsum(per) - per, per)) / np.maximum(per - 1, 1)[row_of_pt]
    return start[row_of_pt] + f[:, None] * (end - start)[row_of_pt]


def hub_end(vertices: np.ndarray, faces: np.ndarray) -> float | None:
    """The radius (mm) where the propeller's hub ends (see the module, step 1); None when no radius band
    surrounds the axis. vertices (V, 3) mm in the axis frame, faces (T, 3)."""
    r = np.hypot(vertices[:, 0], vertices[:, 1])
    tip = float(r.max())
    tri = vertices[faces]
    area = 0.5 * float(np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1).sum())
    pts = _sample_points(tri, max(tip * np.radians(SAMPLE_DEG), np.sqrt(area / MAX_SAMPLES)))
    pr = np.hypot(pts[:, 0], pts[:, 1])
    band = np.minimum((pr / tip * BANDS).astype(int), BANDS - 1)
    bins = int(round(360.0 / (GAP_DEG / 4)))
    ang = ((np.arctan2(pts[:, 1], pts[:, 0]) % (2 * np.pi)) / (2 * np.pi) * bins).astype(int) % bins
    hit = np.zeros((BANDS, bins), bool)
    hit[band, ang] = True
    # the widest run of empty bins in each band, round the circle: the gaps between a band's hit bins
    # (row-major order) and the one across 360 degrees
    b, a = np.nonzero(hit)
    same = b[1:] == b[:-1]
    gaps = np.zeros(BANDS, np.int64)
    np.maximum.at(gaps, b[1:][same], (a[1:] - a[:-1] - 1)[same])
    rows, first = np.unique(b, return_index=True)
    last = np.append(first[1:], len(b)) - 1
    np.maximum.at(gaps, rows, a[first] + bins - a[last] - 1)
    widest = gaps * (360.0 / bins)
    occupied = hit.any(axis=1)
    round_ = np.flatnonzero(occupied & (widest < GAP_DEG))
    if round_.size == 0:
        return None
    return float((round_.max() + 1) * tip / BANDS)


def clip_outside(vertices: np.ndarray, faces: np.ndarray,
                 r_min: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The part of the mesh (axis frame, mm) outside the cylinder r = r_min: facets wholly inside
    dropped, facets across it clipped at their edges' crossings (one new vertex an edge). Returns the
    vertices (the input's first), the facets, and the index of the input facet each comes from."""
    r = np.hypot(vertices[:, 0], vertices[:, 1])
    out = r >= r_min
    n_out = out[faces].sum(axis=1)
    whole = np.flatnonzero(n_out == 3)
    keep = faces[whole]
    across = np.flatnonzero((n_out == 1) | (n_out == 2))
    part = faces[across]
    if part.size == 0:
        return vertices, keep, whole
    po = out[part]
    # roll each facet (keeping its winding) so that its odd vertex comes first: the outside one of a
    # facet with one outside, the inside one of a facet with two
    odd = np.where(po.sum(axis=1) == 1, np.argmax(po, axis=1), np.argmin(po, axis=1))
    idx = (odd[:, None] + np.arange(3)[None, :]) % 3
    f = np.take_along_axis(part, idx, axis=1)
    # crossings on the edges (odd, second) and (odd, third), one per undirected edge
    edges = np.concatenate([f[:, [0, 1]], f[:, [0, 2]]])
    key = np.sort(edges, axis=1)
    uniq, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.reshape(-1)
    a, b = uniq[:, 0], uniq[:, 1]
    inner = np.where(out[a], b, a)
    outer = np.where(out[a], a, b)
    p, d = vertices[inner], vertices[outer] - vertices[inner]
    s = np.clip(_cross_cylinder(p, d, r_min), 0.0, 1.0)
    new = p + s[:, None] * d
    base = len(vertices)
    verts = np.concatenate([vertices, new])
    n = len(f)
    c1, c2 = base + inv[:n], base + inv[n:]
    one = po.sum(axis=1) == 1
    tri_one = np.column_stack([f[one, 0], c1[one], c2[one]])
    two = ~one  # odd vertex inside: the quad (c1, second, third, c2)
    tri_two = np.concatenate([np.column_stack([c1[two], f[two, 1], f[two, 2]]),
                              np.column_stack([c1[two], f[two, 2], c2[two]])])
    source = np.concatenate([whole, across[one], across[two], across[two]])
    return verts, np.concatenate([keep, tri_one, tri_two]), source


def _components(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """Label (T,) of each facet's piece (facets connected through shared vertices)."""
    rows = np.concatenate([faces[:, 0], faces[:, 1]])
    cols = np.concatenate([faces[:, 1], faces[:, 2]])
    g = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_vertices, n_vertices))
    labels = connected_components(g, directed=False)[1]
    return labels[faces[:, 0]]


def _join_near(vertices: np.ndarray, faces: np.ndarray, piece: np.ndarray, tol: float) -> np.ndarray:
    """Labels (T,) of the blades: pieces joined when their open boundaries come within tol (mm)."""
    _, piece = np.unique(piece, return_inverse=True)
    n = int(piece.max()) + 1
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    owner = np.tile(piece, 3)
    uniq, first, count = np.unique(e, axis=0, return_index=True, return_counts=True)
    open_edges = first[count == 1]
    bv = e[open_edges].reshape(-1)
    bl = np.repeat(owner[open_edges], 2)
    rows, cols = list(range(n)), list(range(n))
    if bv.size:
        pairs = cKDTree(vertices[bv]).query_pairs(tol, output_type="ndarray")
        if len(pairs):
            la, lb = bl[pairs[:, 0]], bl[pairs[:, 1]]
            other = la != lb
            rows += list(la[other])
            cols += list(lb[other])
    g = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    return connected_components(g, directed=False)[1][piece]


def _split_sides(v: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Facets (indices into faces) of the face and of the back of one blade (axis frame, mm; caps
    dropped): step 4 of the module."""
    import trimesh

    mesh = trimesh.Trimesh(v, faces, process=False)
    fix_winding(mesh)
    f = np.asarray(mesh.faces)
    tri = v[f]
    centre = tri.mean(axis=1)
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    area = 0.5 * np.linalg.norm(normal, axis=1)
    unit = normal / np.maximum(2 * area, 1e-300)[:, None]
    rc = np.hypot(centre[:, 0], centre[:, 1])
    radial = np.column_stack([centre[:, 0], centre[:, 1], np.zeros(len(f))]) / np.maximum(rc, 1e-300)[:, None]
    rv_all = np.hypot(v[:, 0], v[:, 1])
    on_tip = rv_all[f].min(axis=1) >= rv_all.max() - TIP_BAND * (rv_all.max() - rv_all.min())
    if on_tip.all():
        return np.zeros(0, int), np.zeros(0, int), f
    # outwards: each piece's normals away from the mean of the blade's points in their radius band
    used = np.unique(f[~on_tip])
    rv = np.hypot(v[used, 0], v[used, 1])
    lo, hi = float(rv.min()), float(rv.max())
    width = max(hi - lo, 1e-9) / CHORD_BANDS
    band_v = np.minimum(((rv - lo) / width).astype(int), CHORD_BANDS - 1)
    sums = np.zeros((CHORD_BANDS, 3))
    np.add.at(sums, band_v, v[used])
    counts = np.bincount(band_v, minlength=CHORD_BANDS)
    mids = sums / np.maximum(counts, 1)[:, None]
    band_c = np.clip(((rc - lo) / width).astype(int), 0, CHORD_BANDS - 1)
    piece = _components(f, len(v))
    vote = np.bincount(piece, weights=area * np.einsum("ij,ij->i", unit, centre - mids[band_c]))
    unit = unit * np.where(vote[piece] < 0, -1.0, 1.0)[:, None]
    # a root plate faces the axis; next to a rounded tip the sides face outwards along the radius (kept)
    cap = on_tip | (np.einsum("ij,ij->i", unit, radial) < -np.cos(np.radians(CAP_DEG)))
    if cap.all():
        return np.zeros(0, int), np.zeros(0, int), f
    # the chord's left normal (towards the back) in each band, from its farthest pair of points
    phi0 = np.arctan2(mids[counts > 0, 1].mean(), mids[counts > 0, 0].mean())
    theta = np.arctan2(v[used, 1], v[used, 0]) - phi0
    theta = (theta + np.pi) % (2 * np.pi) - np.pi
    uv = np.column_stack([rv * theta, v[used, 2]])
    centres, angles = [], []
    for k in range(CHORD_BANDS):
        pts = uv[band_v == k]
        if len(pts) < 2:
            continue
        i, j = farthest_pair(pts)
        le, te = (pts[i], pts[j]) if pts[i, 0] >= pts[j, 0] else (pts[j], pts[i])
        chord = te - le
        angles.append(np.arctan2(chord[0], -chord[1]))  # the left normal (-chord_z, chord_u)'s angle
        centres.append(lo + (k + 0.5) * width)
    if not angles:
        raise BladeInputError("a blade of the propeller has no extent across its radius bands")
    ang = np.interp(rc, centres, np.unwrap(angles))
    tc = np.arctan2(centre[:, 1], centre[:, 0])
    n_u = -unit[:, 0] * np.sin(tc) + unit[:, 1] * np.cos(tc)
    back = (n_u * np.cos(ang) + unit[:, 2] * np.sin(ang)) > 0
    return np.flatnonzero(~cap & ~back), np.flatnonzero(~cap & back), f


@dataclass(frozen=True)
class BladeParts:
    """One blade in a cut propeller (Cut): its facets (indices into Cut.faces, caps included) and those
    of its face and of its back (caps dropped), the angle of its area centroid about the axis (degrees,
    [0, 360)), its radii and its area (mm, mm^2, caps included)."""

    facets: np.ndarray
    face: np.ndarray
    back: np.ndarray
    angle_deg: float
    r_from: float
    r_to: float
    area: float


@dataclass(frozen=True)
class Cut:
    """A propeller mesh cut at its hub (module steps 1-4): vertices (V, 3) mm in the axis frame, facets
    (T, 3) (each blade's wound consistently), the input facet each comes from (T,), the blades found
    (numbered from 1 as in the module), the cut r_min (mm), the hub's end (mm or None) and whether
    r_min was given."""

    vertices: np.ndarray
    faces: np.ndarray
    source: np.ndarray
    blades: list[BladeParts]
    r_min: float
    hub_end: float | None
    r_min_given: bool


def find_blades(v: np.ndarray, faces: np.ndarray, r_min: float | None = None) -> Cut:
    """The blades of a whole propeller's surface (module steps 1-4): v (V, 3) mm in the axis frame,
    faces (T, 3); r_min the hub cut, mm (None: found, see ``hub_end``).
    BladeInputError when the cut leaves no blade, r_min lies beyond the tip, or the pieces are unlike."""
    faces = np.asarray(faces)
    tip = float(np.hypot(v[:, 0], v[:, 1]).max())
    if not tip > 0:
        raise BladeInputError("the mesh spans no radius about the axis")
    end = hub_end(v, faces)
    given = r_min is not None
    if r_min is None:
        if end is not None and end >= tip * (1.0 - 1.0 / BANDS):
            raise BladeInputError(f"the mesh covers every angle about the axis out to its tip radius {tip:.4g} mm: "
                                  "no blades about it (a hub only, or the wrong axis); check the axis")
        r_min = 0.0 if end is None else end + HUB_MARGIN * (tip - end)
    if not 0 <= r_min < tip:
        raise BladeInputError(f"the hub cut r_min = {r_min:.4g} mm lies beyond the mesh's tip radius "
                              f"{tip:.4g} mm; give --r-min between the hub and the tip")
    cv, cf, source = clip_outside(v, faces, r_min)
    if len(cf) == 0:
        raise BladeInputError(f"nothing of the mesh lies outside r_min = {r_min:.4g} mm")
    label = _join_near(cv, cf, _components(cf, len(cv)), JOIN_SHARE * tip)
    blades = []
    for lab in np.unique(label):
        sel = np.flatnonzero(label == lab)
        used, local = np.unique(cf[sel], return_inverse=True)
        bv = cv[used]
        face_idx, back_idx, bf = _split_sides(bv, local.reshape(-1, 3))
        cf[sel] = used[bf]  # (the winding _split_sides made consistent)
        if face_idx.size == 0 or back_idx.size == 0:
            continue  # (a loose lid or shard: no blade)
        tri = bv[bf]
        area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        c = (area[:, None] * tri.mean(axis=1)).sum(axis=0)
        rb = np.hypot(bv[:, 0], bv[:, 1])
        blades.append(BladeParts(sel, sel[face_idx], sel[back_idx], float(np.degrees(np.arctan2(c[1], c[0])) % 360.0),
                                 float(rb.min()), float(rb.max()), float(area.sum())))
    if not blades:
        raise BladeInputError(f"no blade found outside r_min = {r_min:.4g} mm (no piece with a face and a back)")
    tips, areas = np.array([b.r_to for b in blades]), np.array([b.area for b in blades])
    if np.ptp(tips) > ALIKE_SHARE * tips.max() or np.ptp(areas) > ALIKE_SHARE * areas.max():
        raise BladeInputError(
            f"the {len(blades)} pieces outside r = {r_min:.4g} mm are not alike blades about this axis (tip radii "
            f"{tips.min():.4g} to {tips.max():.4g} mm, areas {areas.min():.4g} to {areas.max():.4g} mm^2): no "
            "propeller about it; check the axis")
    blades.sort(key=lambda b: b.angle_deg)
    return Cut(cv, cf, source, blades, float(r_min), end, given)


def cut_propeller(vertices: np.ndarray, faces: np.ndarray, rot: np.ndarray, org_mm: np.ndarray,
                  scale: float, r_min: float | None = None) -> tuple[Propeller, Cut]:
    """The blades of a whole propeller mesh (``find_blades``), with each blade's face and back as meshes.

    vertices (V, 3) in the file's units, faces (T, 3); rot (3, 3) file -> axis frame, org_mm (3,) the
    axis's point in mm; scale mm per file unit; r_min the hub cut, mm (None: found, see ``hub_end``).
    The blades' face and back come back in the file's coordinates and units; the Cut in the axis frame.
    """
    import trimesh

    cut = find_blades((np.asarray(vertices, float) * scale - org_mm) @ rot.T, faces, r_min)
    back_to_file = (cut.vertices @ rot + org_mm) / scale
    blades = []
    for b in cut.blades:
        sides = []
        for idx in (b.face, b.back):
            m = trimesh.Trimesh(back_to_file, cut.faces[idx], process=False)
            m.remove_unreferenced_vertices()
            sides.append(m)
        blades.append(PropellerBlade(sides[0], sides[1], b.angle_deg, b.r_from, b.r_to, len(b.facets), b.area))
    return Propeller(blades, cut.r_min, cut.hub_end, cut.r_min_given), cut


def split_propeller(vertices: np.ndarray, faces: np.ndarray, rot: np.ndarray, org_mm: np.ndarray,
                    scale: float, r_min: float | None = None) -> Propeller:
    """The blades of a whole propeller mesh: ``cut_propeller``'s Propeller."""
    return cut_propeller(vertices, faces, rot, org_mm, scale, r_min)[0]


def picked_index(prop: Propeller, index: int | None, file: str, axis: str) -> tuple[int, str | None]:
    """The number (from 1) of the blade to take of ``prop`` read from ``file`` about ``axis``: ``index``
    (None: blade 1), and the warning to give when none was asked for of several (else None).
    BladeInputError naming the file when index is not one of the blades."""
    n = len(prop.blades)
    where = f"outside r = {prop.r_min:.3f} mm about axis {axis!r}"
    if index is not None and not 1 <= index <= n:
        raise BladeInputError(f"{file}: blade {index} asked, but the propeller has {n} blade{'s' * (n > 1)} "
                              f"{where}; give --blade-index 1 to {n}")
    if index is None and n > 1:
        return 1, (f"{Path(file).name} is a whole propeller: {n} blades {where}; blade 1 is used (give "
                   "--blade-index K for another; 'bladecam blade info' lists them)")
    return (1 if index is None else index), None


def label_picked(blade, name: str, k: int, prop: Propeller, file: str, warning: str | None):
    """``blade``, blade ``k`` of ``prop`` read from ``file`` (named ``name``), labelled as such: its name,
    file, propeller and index, and ``warning`` (picked_index's) among its warnings when there is one."""
    blade.name = f"{name} blade {k} of {len(prop.blades)}"
    blade.files = [file]
    blade.propeller, blade.blade_index = prop, k
    if warning is not None:
        blade.warnings.append(warning)
    return blade

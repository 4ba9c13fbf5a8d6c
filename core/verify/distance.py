"""verify's own distance engine: how far points, segments and capsules are from the blade's triangles,
built once per verify from the blade's tessellation (``DistanceIndex``), with the closed-form
distances verify needs besides (segment to segment, segment to box). It shares no code with the
planner's searches (core.paths.tessellation's, core.machine's): a planner bug cannot pass both.

The index (built by compiled loops, core.verify._index, without the GIL; the queries themselves are
compiled too: core.verify._distance, whose docstring says how a query goes):
- a uniform grid of cells of about CELL_FACTOR typical triangles' extent; each triangle lies in the
  cell of its centroid, the occupied cells column by column (x, y) in order of z, and within a cell
  the triangles in groups of GROUP near each other (ordered by quarter-cell), the groups in blocks of
  GROUP;
- an oriented bounding box per triangle, group and block (along a long edge, across it, along the
  normal: thin for the slivers of a closing tip), and per occupied cell the box of its triangles;
- the coarse field: per cell, a lower bound of the distance from any point in it to the mesh: the
  distance from its centre to the nearest centre of a cell that a triangle's box overlaps (an exact
  Euclidean distance transform of verify's own), less the cell's diagonal (both points lie within
  half a diagonal of their centres). A query whose field bound lies beyond its cutoff ends there:
  tools parked or lifted far off the blade, and the heads, cost a few lookups.
Every distance is exact (to rounding, micrometres' billionths) where it is at most the query's
cutoff, and a lower bound above it.

How the tessellation's own error counts: the triangles are a tessellation of a smooth blade (chords
within core.paths.tessellation.MESH_TOLERANCE of it on a table blade; a mesh blade's own facets are
the blade). Distances here are to the triangles; the tolerances stated where they are used
(core.verify.cutters' MISS_TOLERANCE and ROW_DIP, core.verify.assembly's TOLERANCE) are what they
allow for it.
"""

from __future__ import annotations

import numpy as np

from core.paths.tessellation import SurfaceMesh
from core.verify._distance import Kernel, box_distances, box_sweep, pair_sweep, segment_distances, turn_angles
from core.verify._index import (
    build_groups,
    build_triangles,
    cell_boxes,
    cell_order,
    distance_field,
    extents,
    mark_cells,
    total_area,
)

#: cell size in typical (median) triangle extents: a query 1.5 mm off the surface visits a few dozen
#: columns and a handful of cells of a few groups each
CELL_FACTOR = 2.5
#: triangles per group, and groups per block (a block's box is tested before its groups', a group's
#: before its triangles')
GROUP = 8
#: the most cells the grid's field holds (float32): its cells grow to keep within it
MAX_CELLS = 4_000_000


class DistanceIndex:
    """The blade's triangles indexed for distance queries (module docstring). ``mesh``: the blade's
    tessellation (vertices (V, 3) mm, workpiece frame; triangles (T, 3) int), kept as given;
    ``cell``: the grid's cell size, mm (default: ``_cell_size``)."""

    def __init__(self, mesh: SurfaceMesh, cell: float | None = None):
        self.mesh = mesh
        v, tris = np.ascontiguousarray(mesh.vertices, float), np.ascontiguousarray(mesh.triangles, np.int64)
        extent, lo, hi = np.empty(len(tris)), np.empty(3), np.empty(3)
        extents(v, tris, extent, lo, hi)
        self.box = (lo, hi)
        self.h = h = float(cell) if cell is not None else _cell_size(extent, self.box)
        self.origin = lo - h  # (one empty cell round the mesh: the field's edge cells)
        self.dims = np.floor((hi - lo) / h).astype(np.int64) + 3
        # the triangles in the order of their centroids' cells (column by column, z within a column),
        # within a cell by quarter-cell: a group of GROUP consecutive ones lies close together
        self.order, key = np.empty(len(tris), np.int64), np.empty(len(tris), np.int64)
        cell_order(v, tris, np.ascontiguousarray(self.origin), h, self.dims, self.order, key)
        first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])  # (key sorted: each cell's first triangle)
        cells, counts = key[first], np.diff(np.append(first, len(key)))
        gfirst, bfirst, cfirst = _groups(first, counts)
        tri, tbox = np.empty((len(key), 9)), np.empty((len(key), 16), np.float32)
        build_triangles(v, tris, self.order, tri, tbox)
        gbox, bbox = np.empty((len(gfirst) - 1, 16), np.float32), np.empty((len(bfirst) - 1, 16), np.float32)
        build_groups(tri, gfirst, gbox)
        build_groups(tri, np.ascontiguousarray(gfirst[bfirst]), bbox)
        cbox = np.empty((len(first), 6))
        cell_boxes(tri, np.append(first, len(key)), cbox)
        column, iz = np.divmod(cells, self.dims[2])
        colfirst = np.append(0, np.cumsum(np.bincount(column, minlength=self.dims[0] * self.dims[1])))
        # how far a cell's box of triangles reaches beyond the cell (a query widens its cells by it)
        cell_lo = self.origin + h * np.stack([column // self.dims[1], column % self.dims[1], iz], axis=1)
        self.ext = float(max(0.0, (cbox[:, 3:] - (cell_lo + h)).max(initial=0.0),
                             (cell_lo - cbox[:, :3]).max(initial=0.0)))
        self.field = _field(tri, self.origin, self.dims, h)
        tgroup = np.repeat(np.arange(len(gfirst) - 1, dtype=np.int32), np.diff(gfirst))
        self.tri = tri
        self.kernel = Kernel(tri, tbox, gbox, gfirst, tgroup, bbox, bfirst, cbox, cfirst, iz.astype(np.int32),
                             colfirst.astype(np.int32), self.field, np.ascontiguousarray(self.origin, float), h,
                             self.ext)

    @property
    def corners(self) -> np.ndarray:
        """(T, 3, 3) float mm: each triangle's three corners, in the mesh's order."""
        return np.asarray(self.mesh.vertices, float)[np.asarray(self.mesh.triangles)]

    @property
    def area(self) -> float:
        """mm^2: the triangles' total area (compiled: core.verify._index.total_area)."""
        return float(total_area(self.tri))

    def distances(self, p0: np.ndarray, p1: np.ndarray | None = None, cutoff: float | np.ndarray = 1e9
                  ) -> np.ndarray:
        """(n,) mm: the distance of each point p0 (n, 3) mm, or segment p0-p1, from the triangles:
        exact where at most ``cutoff`` mm (a number or (n,)), a lower bound above it. Neighbours in
        the order given share the search's start: give a path's points in order."""
        p0 = np.ascontiguousarray(p0, float).reshape(-1, 3)
        p1 = p0 if p1 is None else np.ascontiguousarray(p1, float).reshape(-1, 3)
        cut = np.ascontiguousarray(np.broadcast_to(np.minimum(np.asarray(cutoff, float), 1e9), (len(p0),)))
        out = np.empty(len(p0))
        self.kernel.distances(p0, p1, cut, out)
        return out

    def field_bounds(self, p0: np.ndarray, p1: np.ndarray | None = None) -> np.ndarray:
        """(n,) mm: the coarse field's lower bounds of the distances of points or segments (as in
        ``distances``) from the triangles."""
        p0 = np.ascontiguousarray(p0, float).reshape(-1, 3)
        p1 = p0 if p1 is None else np.ascontiguousarray(p1, float).reshape(-1, 3)
        out = np.empty(len(p0))
        self.kernel.field_bounds(p0, p1, out)
        return out

    def sweep(self, centres: np.ndarray, axes: np.ndarray, part: tuple[float, float, float], reach: np.ndarray,
              exact: float, cap: float, tolerance: float) -> tuple[np.ndarray, np.ndarray]:
        """A capsule along rows: its clearance from the triangles (the distance of its axis segment
        c + s w, s0 <= s <= s1, less its radius; ``part`` = (s0, s1, radius), mm) at each of n rows
        of ball centres c (n, 3) mm and unit axes w (n, 3). ``reach`` (n,) mm: the cumulative bound
        of how far any point of the segment moves along the rows (core.verify.sweep.motion). A row is
        measured (exact where the clearance is at most ``exact``, else a lower bound), the others
        bounded from the measured rows either side by the motion since, as long as that bound stays at
        least the least clearance measured or ``cap`` (<= exact), whichever is less, and at least
        -``tolerance`` (core.verify._distance.step_rows). So every row's value is a lower bound, a row
        below -tolerance (a collision) is measured, and the least value is exact where it is below
        ``cap``. Returns (values (n,) mm, measured (n,) bool)."""
        n = len(centres)
        out = np.empty(n)
        measured = np.zeros(n, np.uint8)
        if n:
            s0, s1, radius = (float(x) for x in part)
            self.kernel.sweep(np.ascontiguousarray(centres, float), np.ascontiguousarray(axes, float), s0, s1, radius,
                              np.ascontiguousarray(reach, float), float(exact), float(min(cap, exact)),
                              float(tolerance), out, measured)
        return out, measured.astype(bool)


def _groups(first: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The groups of up to GROUP consecutive triangles of each occupied cell (its triangles from
    first[s], counts[s] of them) and the blocks of up to GROUP of its groups: (first triangle of
    each group (G + 1,), first group of each block (B + 1,), first block of each cell (S + 1,)),
    int32, each closed by the total."""
    groups = (counts + GROUP - 1) // GROUP
    within = np.arange(groups.sum()) - np.repeat(np.cumsum(groups) - groups, groups)
    gfirst = np.append(np.repeat(first, groups) + GROUP * within, counts.sum())
    blocks = (groups + GROUP - 1) // GROUP
    within = np.arange(blocks.sum()) - np.repeat(np.cumsum(blocks) - blocks, blocks)
    bfirst = np.append(np.repeat(np.cumsum(groups) - groups, blocks) + GROUP * within, groups.sum())
    cfirst = np.append(np.cumsum(blocks) - blocks, blocks.sum())
    return gfirst.astype(np.int32), bfirst.astype(np.int32), cfirst.astype(np.int32)


def _cell_size(extent: np.ndarray, box: tuple[np.ndarray, np.ndarray]) -> float:
    """mm: CELL_FACTOR times the triangles' median extent (``extent`` (T,) mm: each one's largest
    along x, y or z), larger where the grid would hold more than MAX_CELLS cells."""
    typical = float(np.partition(extent, len(extent) // 2)[len(extent) // 2]) if len(extent) else 1.0
    h = max(CELL_FACTOR * typical, 1e-3)
    size = box[1] - box[0]
    while np.prod(np.floor(size / h) + 3) > MAX_CELLS:
        h *= 1.1
    return h


def _field(tri: np.ndarray, origin: np.ndarray, dims: np.ndarray, h: float) -> np.ndarray:
    """(nx, ny, nz) float32 mm: per cell, a lower bound of the distance from any of its points to the
    mesh (tri (T, 9) = a, b - a, c - a mm; module docstring; core.verify._index.distance_field), rounded
    down."""
    occupied = np.zeros(tuple(int(d) for d in dims), np.uint8)
    mark_cells(tri, np.ascontiguousarray(origin, float), h, occupied)
    field = np.empty(occupied.shape, np.float32)
    distance_field(occupied, h, field)
    return field


def segment_gaps(a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray) -> np.ndarray:
    """(n,) mm: the distance between the segments a0-a1 and b0-b1 (each (n, 3) mm), row by row, in
    closed form (compiled)."""
    arrays = [np.ascontiguousarray(x, float).reshape(-1, 3) for x in (a0, a1, b0, b1)]
    out = np.empty(len(arrays[0]))
    segment_distances(*arrays, out)
    return out


def box_gaps(p0: np.ndarray, p1: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n,) mm: the distance of each segment p0-p1 (n, 3) mm from the box lo..hi (3,) mm (an infinite
    side: -inf or inf), exact, in closed form (compiled)."""
    p0, p1 = (np.ascontiguousarray(x, float).reshape(-1, 3) for x in (p0, p1))
    out = np.empty(len(p0))
    box_distances(p0, p1, np.clip(np.asarray(lo, float), -1e300, 1e300), np.clip(np.asarray(hi, float), -1e300, 1e300),
                  out)
    return out


def turns(axes: np.ndarray) -> np.ndarray:
    """(n - 1,) rad: the angle between consecutive axes (n, 3) (the arc a point at unit distance along
    the axis travels when it turns from one row to the next, centres fixed)."""
    axes = np.ascontiguousarray(axes, float).reshape(-1, 3)
    out = np.empty(max(len(axes) - 1, 0))
    turn_angles(axes, out)
    return out


def pair_sweeps(centres: tuple[np.ndarray, np.ndarray], axes: tuple[np.ndarray, np.ndarray],
                parts: tuple[tuple[float, float, float], tuple[float, float, float]], reach: np.ndarray,
                cap: float, tolerance: float) -> np.ndarray:
    """(n,) mm: the clearance between two capsules along n rows, one on each side (``parts``: (s0,
    s1, radius) each round c + s w, centres (n, 3) mm and unit axes (n, 3) per side), each a lower
    bound, exact (closed form) where measured, measured as ``DistanceIndex.sweep`` measures a part
    (``reach`` (n,) mm: the cumulative bound of both parts' motion)."""
    n = len(reach)
    out = np.empty(n)
    if n:
        (s0, s1, r), other = parts
        pair_sweep(*_rows(centres[0], axes[0]), float(s0), float(s1), float(r), *_rows(centres[1], axes[1]),
                   tuple(float(x) for x in other), np.ascontiguousarray(reach, float), float(cap), float(tolerance),
                   out, np.zeros(n, np.uint8))
    return out


def box_sweeps(centres: np.ndarray, axes: np.ndarray, part: tuple[float, float, float],
               box: tuple[np.ndarray, np.ndarray], reach: np.ndarray, cap: float, tolerance: float) -> np.ndarray:
    """(n,) mm: a capsule's clearance from the box (lo, hi) (3,) mm along n rows (as ``pair_sweeps``;
    an infinite side of the box: -inf or inf)."""
    n = len(reach)
    out = np.empty(n)
    if n:
        s0, s1, r = (float(x) for x in part)
        lo, hi = (np.clip(np.asarray(x, float), -1e300, 1e300) for x in box)
        box_sweep(*_rows(centres, axes), s0, s1, r, lo, hi, np.ascontiguousarray(reach, float), float(cap),
                  float(tolerance), out, np.zeros(n, np.uint8))
    return out


def _rows(centres: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.ascontiguousarray(centres, float), np.ascontiguousarray(axes, float)

"""The blade index's exact search: distances from segments and points to a blade's triangles by a
compiled search (core.paths._meshdist) over a uniform grid of cells, with lower and upper bounds from
the grid alone (``MeshGrid``). A blade's TriangleIndex builds it once, on first use
(``TriangleIndex.grid``); the air moves, the tool axes' clearance and the whole-tool check ask it.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from core.paths._meshdist import (
    block_cells,
    centroid_cells,
    distance_fields,
    fill_grid,
    segment_bounds,
    segment_distances,
)


class Triangles(Protocol):
    """A triangle mesh as core.paths.tessellation.TriangleIndex holds it: corners a and edges ab, ac,
    each (3, m) mm."""

    a: np.ndarray
    ab: np.ndarray
    ac: np.ndarray


#: the most cells a blade's grid holds: its cells grow past the mesh's triangles' size to keep within it
MAX_CELLS = 4_000_000


class MeshGrid:
    """Distances from segments (parts' axes) to a triangle mesh (a TriangleIndex's triangles):
    - exact ones, up to a cutoff, from the compiled search (core.paths._meshdist) over a uniform grid
      of cells (size h), each listing the triangles whose centroid it holds, with the largest
      bounding sphere among them (``cell_reach``; ``tri_reach`` the largest of all);
    - lower bounds from the grid alone (``bound``): every point m of the mesh lies in a cell D that
      its triangle's bounding box overlaps (an occupied cell), within h sqrt 3 / 2 of D's centre, so
      a point q in cell C (centre c) is at least F - h sqrt 3 / 2 - |q - c| from the mesh, F the
      distance from c to the nearest occupied cell's centre (``floor`` holds F - h sqrt 3 / 2, from
      an exact Euclidean distance transform of the cells, rounded down); a point p outside the grid,
      whose projection onto it is q, is at least sqrt(|p - q|^2 + bound(q)^2) from any point m of
      the mesh inside the grid (the angle at q between p and m is at least a right angle). The bound
      loses at most h sqrt 3 (h sqrt 3 / 2 where q is a cell's centre) against the cell centres'
      distances;
    - upper bounds the same way (``upper``), from the cells that hold the centroid of a triangle (a
      point of the mesh): ``ceiling`` + |q - c| + |p - q|, ``ceiling`` the distance from c to the
      nearest such cell's centre plus h sqrt 3 / 2 (rounded up).
    The cell size is the triangles' typical extent (the 90th percentile), larger where the blade's box
    would need more than MAX_CELLS."""

    def __init__(self, index: Triangles):
        a, ab, ac = (np.ascontiguousarray(x, float) for x in (index.a, index.ab, index.ac))
        lo_pt = a + np.minimum(np.minimum(ab, ac), 0.0)
        hi_pt = a + np.maximum(np.maximum(ab, ac), 0.0)
        self.box = (lo_pt.min(axis=1), hi_pt.max(axis=1))
        size = self.box[1] - self.box[0]
        extent = float(np.percentile((hi_pt - lo_pt).max(axis=0), 90))
        h = max(extent, float(np.prod(size + 2.0 * extent) / MAX_CELLS) ** (1.0 / 3.0), 1e-3)
        for _ in range(8):  # (one cell of padding round the box; grown until within MAX_CELLS)
            dims = np.floor(size / h).astype(np.int64) + 3
            if dims.prod() <= MAX_CELLS:
                break
            h *= 1.1
        self.h, self.dims = h, dims
        self.origin = np.ascontiguousarray(self.box[0] - h)
        # the triangles in the order of their centroids' cells: a search reads a cell's together
        self.start = centroid_cells(a, ab, ac, self.origin, h, dims)
        cells, side = int(dims.prod()), block_cells()
        self.tri = np.empty((a.shape[1], 13))
        self.cell_reach = np.zeros(cells, np.float32)
        self.blocks = np.full(int(np.prod(-(-dims // side))), -1.0)
        occupied = np.zeros(cells, np.uint8)
        fill_grid(a, ab, ac, self.origin, h, dims, self.start, self.tri, self.cell_reach, self.blocks, occupied)
        self.tri_reach = float(self.tri[:, 12].max(initial=0.0))
        self.floor, self.ceiling = np.empty(cells, np.float32), np.empty(cells, np.float32)
        distance_fields(occupied, self.start, dims, h, self.floor, self.ceiling)

    def point_bound(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) points, mm -> (n,) lower bounds of their distances from the mesh, mm (class docstring)."""
        return self.bound(points, points, 1.0)

    def point_upper(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) points, mm -> (n,) upper bounds of their distances from the mesh, mm (class docstring)."""
        return self.bound(points, points, 1.0, upper=True)

    def bound(self, p0: np.ndarray, p1: np.ndarray, step: float, upper: bool = False) -> np.ndarray:
        """(n,) lower bounds of the distances of the segments p0-p1 (n, 3) (all of one length) from the
        mesh: the least of ``point_bound`` at points at most ``step`` apart along each, less half their
        spacing (every point of a segment lies within it of one of them); with ``upper``, upper bounds:
        the least of ``point_upper`` at those points."""
        p0, p1 = np.ascontiguousarray(p0, float), np.ascontiguousarray(p1, float)
        n_s = max(int(np.ceil(float(np.linalg.norm(p1[0] - p0[0])) / step)), 1) if len(p0) else 1
        out = np.empty(len(p0))
        segment_bounds(self.ceiling if upper else self.floor, self.origin, self.h, self.dims, p0, p1, n_s, upper,
                       out)
        return out

    def distance(self, p0: np.ndarray, p1: np.ndarray, cutoff: np.ndarray | float,
                 reach: np.ndarray | float = 0.0, enough: np.ndarray | float = -1.0) -> np.ndarray:
        """(n,) mm: min(exact distance of each segment p0-p1 (n, 3) from the mesh, cutoff); ``reach``:
        how far the search reaches out first (a little beyond a lower bound of the distance: every
        reach that finds nothing is searched again farther); where a distance at or below ``enough``
        is found, that distance (an upper bound, the search not taken further)."""
        p0, p1 = np.ascontiguousarray(p0, float), np.ascontiguousarray(p1, float)

        def each(x):
            return np.ascontiguousarray(np.broadcast_to(np.asarray(x, float), (len(p0),)))

        out = np.empty(len(p0))
        segment_distances(self.tri, self.start, self.cell_reach, self.blocks, self.tri_reach, self.origin, self.h,
                          self.dims, p0, p1, each(cutoff), each(reach), each(enough), out)
        return out

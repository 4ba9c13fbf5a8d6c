"""The blade index's exact search: distances from segments and points to a blade's triangles by a
compiled search (core.paths._meshdist) over a uniform grid of cells, with lower and upper bounds from
the grid alone (``MeshGrid``). A blade's TriangleIndex builds it once, on first use
(``TriangleIndex.grid``); the air moves, the tool axes' clearance and the whole-tool check ask it.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from core.paths._meshdist import block_cells, fill_cells, segment_distances


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
      of cells listing the triangles whose bounding box overlaps each;
    - lower bounds from the grid alone (``bound``): a point p in cell C is at least
      |centre C - centre D| - h sqrt 3 from any point of the mesh in cell D (cell size h), so the
      distance from C's centre to the nearest occupied cell's (a Euclidean distance transform of the
      occupied cells, scipy.ndimage), less h sqrt 3, bounds every point of C; a point p outside the
      grid, whose projection onto it is q, is at least sqrt(|p - q|^2 + bound(q)^2) from any point m
      of the mesh inside the grid (the angle at q between p and m is at least a right angle);
    - upper bounds the same way (``upper``), from the cells that hold the centroid of a triangle (a
      point of the mesh), plus h sqrt 3, and for a point outside the grid its distance from its
      projection.
    The cell size is the triangles' typical extent (the 90th percentile), larger where the blade's box
    would need more than MAX_CELLS."""

    def __init__(self, index: Triangles):
        from scipy.ndimage import distance_transform_edt

        a, ab, ac = (np.ascontiguousarray(x.T) for x in (index.a, index.ab, index.ac))
        b, c = a + ab, a + ac
        lo_pt, hi_pt = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
        self.box = (lo_pt.min(axis=0), hi_pt.max(axis=0))
        size = self.box[1] - self.box[0]
        extent = float(np.percentile((hi_pt - lo_pt).max(axis=1), 90))
        h = max(extent, float(np.prod(size + 2.0 * extent) / MAX_CELLS) ** (1.0 / 3.0), 1e-3)
        for _ in range(8):  # (one cell of padding round the box; grown until within MAX_CELLS)
            dims = np.floor(size / h).astype(np.int64) + 3
            if dims.prod() <= MAX_CELLS:
                break
            h *= 1.1
        self.h, self.dims = h, dims
        self.origin = np.ascontiguousarray(self.box[0] - h)
        # the triangles in the order of their centroids' cells: a search reads neighbours together
        centre = (a + b + c) / 3.0
        order = np.argsort(self._cell(centre), kind="stable")
        a, ab, ac, b, c, centre, lo_pt, hi_pt = (x[order] for x in (a, ab, ac, b, c, centre, lo_pt, hi_pt))
        cell_lo = np.floor((lo_pt - self.origin) / h).astype(np.int64)
        cell_hi = np.floor((hi_pt - self.origin) / h).astype(np.int64)
        self.start, self.cells = fill_cells(np.ascontiguousarray(cell_lo), np.ascontiguousarray(cell_hi), dims)
        radius = np.sqrt(np.max([((x - centre) ** 2).sum(axis=1) for x in (a, b, c)], axis=0))
        self.tri = np.hstack([a, ab, ac, centre, radius[:, None]])
        occupied = (np.diff(self.start) > 0).reshape(dims)
        side = block_cells()  # (the blocks that list a triangle: padded to whole blocks)
        padded = np.zeros(-(-dims // side) * side, bool)
        padded[:dims[0], :dims[1], :dims[2]] = occupied
        nb = padded.shape[0] // side, padded.shape[1] // side, padded.shape[2] // side
        self.blocks = np.ascontiguousarray(padded.reshape(nb[0], side, nb[1], side, nb[2], side)
                                           .any(axis=(1, 3, 5)).astype(np.uint8).ravel())
        self.floor = np.maximum(distance_transform_edt(~occupied, sampling=h) - h * np.sqrt(3.0), 0.0
                                ).astype(np.float32).ravel()
        held = np.zeros(dims.prod(), bool)
        held[self._cell(centre)] = True
        self.ceiling = (distance_transform_edt(~held.reshape(dims), sampling=h) + h * np.sqrt(3.0)
                        ).astype(np.float32).ravel()

    def _cell(self, points: np.ndarray) -> np.ndarray:
        """(n,) flat index of the cell holding each point (n, 3) (points outside: their projection's)."""
        k = np.floor((points - self.origin) / self.h).astype(np.int64)
        np.maximum(k, 0, out=k)
        np.minimum(k, self.dims - 1, out=k)
        return (k[:, 0] * self.dims[1] + k[:, 1]) * self.dims[2] + k[:, 2]

    def point_bound(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) points, mm -> (n,) lower bounds of their distances from the mesh, mm (class docstring)."""
        top = self.origin + self.dims * self.h
        off = points - np.clip(points, self.origin, top)
        return np.sqrt((off * off).sum(axis=1) + self.floor[self._cell(points)].astype(float) ** 2)

    def point_upper(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) points, mm -> (n,) upper bounds of their distances from the mesh, mm (class docstring)."""
        top = self.origin + self.dims * self.h
        off = np.linalg.norm(points - np.clip(points, self.origin, top), axis=1)
        return self.ceiling[self._cell(points)] + off

    def bound(self, p0: np.ndarray, p1: np.ndarray, step: float, upper: bool = False) -> np.ndarray:
        """(n,) lower bounds of the distances of the segments p0-p1 (n, 3) (all of one length) from the
        mesh: the least of ``point_bound`` at points at most ``step`` apart along each, less step / 2
        (every point of a segment lies within step / 2 of one of them); with ``upper``, upper bounds:
        the least of ``point_upper`` at those points."""
        n_s = max(int(np.ceil(float(np.linalg.norm(p1[0] - p0[0])) / step)), 1) if len(p0) else 1
        f = np.linspace(0.0, 1.0, n_s + 1)
        pts = (p0[:, None, :] + f[None, :, None] * (p1 - p0)[:, None, :]).reshape(-1, 3)
        if upper:
            return self.point_upper(pts).reshape(len(p0), -1).min(axis=1)
        spacing = np.linalg.norm(p1 - p0, axis=1) / n_s
        return np.maximum(self.point_bound(pts).reshape(len(p0), -1).min(axis=1) - 0.5 * spacing, 0.0)

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
        segment_distances(self.tri, self.start, self.cells, self.blocks, self.origin, self.h, self.dims, p0, p1,
                          each(cutoff), each(reach), each(enough), out)
        return out

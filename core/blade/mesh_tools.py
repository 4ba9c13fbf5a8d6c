"""Small tools on triangle meshes that the mesh blade and the propeller split share: a consistent
winding, and the farthest pair of points of a plane cloud."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import ConvexHull, QhullError

if TYPE_CHECKING:
    import trimesh


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


def farthest_pair(uv: np.ndarray) -> tuple[int, int]:
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

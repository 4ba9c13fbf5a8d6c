"""The blade as a binary STL (a plan folder's blade.stl, in the workpiece frame: core.paths.tessellation.
export_mesh, within its EXPORT_TOLERANCE of the blade): what outside checks measure the tool assembly
against, and what the workbench opens as the blade of a plan folder under review."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from core.errors import OutputError
from core.paths.tessellation import SurfaceMesh

_RECORD = np.dtype([("n", "<3f4"), ("v", "<9f4"), ("a", "<u2")])


def stl_bytes(mesh: SurfaceMesh, name: str = "bladecam blade") -> bytes:
    """A mesh's triangles as a binary STL (float32 corners: 1.5e-5 mm at 250 mm)."""
    corners = mesh.vertices[mesh.triangles]
    a = corners[:, 0]
    nrm = np.cross(corners[:, 1] - a, corners[:, 2] - a)
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    rec = np.zeros(len(a), _RECORD)
    rec["n"] = nrm
    rec["v"] = corners.reshape(len(a), 9)
    head = name.encode()[:80].ljust(80, b" ")
    return head + np.uint32(len(a)).tobytes() + rec.tobytes()


def read_stl(path: str | Path) -> SurfaceMesh:
    """A binary STL's triangles as a SurfaceMesh (each triangle its own three vertices, mm).
    OutputError where the file is missing, short, or not a binary STL."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise OutputError(f"cannot read {p}: {exc.strerror or exc}") from None
    if len(raw) < 84:
        raise OutputError(f"{p}: not a binary STL ({len(raw)} bytes, shorter than its header)")
    n = int(np.frombuffer(raw[80:84], "<u4")[0])
    if n == 0 or len(raw) != 84 + 50 * n:
        raise OutputError(f"{p}: not a binary STL of {n} triangles ({len(raw)} bytes, expected {84 + 50 * n})")
    rec = np.frombuffer(raw, _RECORD, count=n, offset=84)
    v = rec["v"].astype(float).reshape(-1, 3)
    if not np.isfinite(v).all():
        raise OutputError(f"{p}: corners that are not finite numbers")
    return SurfaceMesh(vertices=v, triangles=np.arange(3 * n).reshape(n, 3))

"""Benchmark: capsule-against-blade distance queries, the project's grid search (MeshGrid, exact at
every pose here) against FCL
(python-fcl) and coal (hpp-fcl), on the sample blade's check tessellation (about 1.1 million
triangles), paired with calib.py.

Run: .venv/bin/python tests/benchmarks/bench_clearance.py [N]
N poses (default 20000): ball centres one tool radius off the blade along its surface normal, tool
axes tilted up to 30 degrees from it. For each library: the time to build its search structure, the
time per pose of the neck's (r 1.5, 0.75-12 mm) and the holder's (r 14, 38.5-80.5 mm) capsule distance
query, and the largest disagreement with the project's own figure. FCL and coal are imported when
installed (they are not bladecam's dependencies; PYTHONPATH may point at a folder holding them).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from common import calib  # noqa: E402

from core.blade.frame import workpiece_frame  # noqa: E402
from core.blade.source import load_blade  # noqa: E402
from core.machine.clearance import MeshGrid, part_blade  # noqa: E402
from core.machine.tool import Part  # noqa: E402
from core.paths.tessellation import TriangleIndex, surface_mesh  # noqa: E402

PARTS = (Part("neck", 1.5, 0.75, 12.0), Part("holder", 14.0, 38.5, 80.5))


def poses(mesh, index: TriangleIndex, n: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """n ball centres 1.5 mm off the blade on the mesh's triangle normals (the side where the centre
    is 1.5 mm from the whole mesh: off the blade, not into it) and axes tilted up to 30 degrees from
    them."""
    tri = mesh.vertices[mesh.triangles]
    t = tri[rng.integers(0, len(tri), n)]
    nrm = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    centre_t = t.mean(axis=1)
    out = np.abs(index.closest(centre_t + 1.5 * nrm)[0] - 1.5) < 1e-3
    nrm[~out] *= -1.0
    tilt = rng.normal(size=(n, 3)) * np.tan(np.radians(30)) / 2
    axes = nrm + tilt - np.einsum("ij,ij->i", tilt, nrm)[:, None] * nrm
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    return centre_t + 1.5 * nrm, axes


def _rotation_z_to(w: np.ndarray) -> np.ndarray:
    """A rotation taking +z to the unit vector w."""
    z = np.array([0.0, 0.0, 1.0])
    v, c = np.cross(z, w), float(z @ w)
    if np.linalg.norm(v) < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx / (1 + c)


def own(mesh, centres, axes, index: TriangleIndex, build_s: float) -> dict:
    t0 = time.perf_counter()
    grid = MeshGrid(index)
    out = {"build_s": build_s + time.perf_counter() - t0}
    for part in PARTS:
        t0 = time.perf_counter()
        out[part.name] = part_blade(part, grid, centres, axes, exact_below=np.inf)
        out[f"{part.name}_us"] = 1e6 * (time.perf_counter() - t0) / len(centres)
    return out


def with_fcl(mesh, centres, axes) -> dict | None:
    try:
        import fcl
    except ImportError:
        return None
    t0 = time.perf_counter()
    model = fcl.BVHModel()
    model.beginModel(len(mesh.vertices), len(mesh.triangles))
    model.addSubModel(mesh.vertices.astype(float), mesh.triangles.astype(np.int32))
    model.endModel()
    blade = fcl.CollisionObject(model, fcl.Transform())
    out = {"build_s": time.perf_counter() - t0}
    for part in PARTS:
        cap = fcl.Capsule(part.radius, part.s1 - part.s0)
        mid = 0.5 * (part.s0 + part.s1)
        got = np.empty(len(centres))
        t0 = time.perf_counter()
        for k in range(len(centres)):
            obj = fcl.CollisionObject(cap, fcl.Transform(_rotation_z_to(axes[k]), centres[k] + mid * axes[k]))
            got[k] = fcl.distance(obj, blade, fcl.DistanceRequest(), fcl.DistanceResult())
        out[f"{part.name}_us"] = 1e6 * (time.perf_counter() - t0) / len(centres)
        out[part.name] = got
    return out


def with_coal(mesh, centres, axes) -> dict | None:
    try:
        import coal
    except ImportError:
        return None
    t0 = time.perf_counter()
    model = coal.BVHModelOBBRSS()
    model.beginModel(len(mesh.triangles), len(mesh.vertices))
    model.addVertices(mesh.vertices.astype(float))
    model.addTriangles(mesh.triangles.astype(np.int64))
    model.endModel()
    out = {"build_s": time.perf_counter() - t0}
    eye = coal.Transform3s()
    for part in PARTS:
        cap = coal.Capsule(part.radius, part.s1 - part.s0)
        mid = 0.5 * (part.s0 + part.s1)
        req, res = coal.DistanceRequest(), coal.DistanceResult()
        got = np.empty(len(centres))
        t0 = time.perf_counter()
        for k in range(len(centres)):
            res.clear()
            got[k] = coal.distance(cap, coal.Transform3s(_rotation_z_to(axes[k]), centres[k] + mid * axes[k]),
                                   model, eye, req, res)
        out[f"{part.name}_us"] = 1e6 * (time.perf_counter() - t0) / len(centres)
        out[part.name] = got
    return out


def main() -> None:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20000
    ref = calib()
    print(f"calib.py: {ref:.3f} s")
    blade = load_blade("sample")
    mesh = surface_mesh(blade, workpiece_frame(blade))
    t0 = time.perf_counter()
    index = TriangleIndex(mesh, 8)
    build_s = time.perf_counter() - t0
    centres, axes = poses(mesh, index, n, np.random.default_rng(7))
    print(f"{len(mesh.triangles)} triangles, {n} poses", flush=True)
    base = own(mesh, centres, axes, index, build_s)
    for name, fn in (("own index", lambda: base), ("python-fcl", with_fcl), ("coal", with_coal)):
        got = fn() if name == "own index" else fn(mesh, centres, axes)
        if got is None:
            print(f"{name}: not installed")
            continue
        line = f"{name}: build {got['build_s']:.2f} s ({got['build_s'] / ref:.2f} calib)"
        for part in PARTS:
            us = got[f"{part.name}_us"]
            diff = np.abs(np.maximum(got[part.name], 0) - np.maximum(base[part.name], 0))
            line += (f"; {part.name} {us:.1f} us/pose ({us * 1e5 / 1e6 / ref:.3f} calib per 1e5 poses), "
                     f"max |diff| {diff.max():.4f} mm")
        print(line, flush=True)


if __name__ == "__main__":
    main()

"""Whole-propeller test meshes made of a real blade: the BladeX blade (its two sides and caps, the STL
files of ../shared/data/bladex-test-blade) turned about the file's X axis, on a hub cylinder."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

HUB_RADIUS = 36.0
N_BLADES = 5


def turn_x(deg: float) -> np.ndarray:
    """Rotation (3, 3) by deg about the file's X axis (right-handed)."""
    return trimesh.transformations.rotation_matrix(np.radians(deg), [1, 0, 0])[:3, :3]


def bladex_propeller(bladex_dir: Path, path: Path, blades: int = N_BLADES, hub_radius: float = HUB_RADIUS) -> Path:
    """The BladeX blade (sides and caps) in ``blades`` copies 360/blades degrees apart about X, and a
    closed hub cylinder of ``hub_radius`` (the blades' roots, r 34.4 mm, inside it) from x = -30 to 50 mm,
    merged into one STL at ``path``."""
    parts = [trimesh.load(Path(bladex_dir) / f"{k}.stl") for k in ("upper", "lower", "tip", "root")]
    blade = trimesh.util.concatenate(parts)
    copies = []
    for k in range(blades):
        m = blade.copy()
        m.vertices = m.vertices @ turn_x(360.0 * k / blades).T
        copies.append(m)
    copies.append(trimesh.creation.cylinder(radius=hub_radius, segment=[[-30, 0, 0], [50, 0, 0]], sections=128))
    trimesh.util.concatenate(copies).export(path)
    return Path(path)

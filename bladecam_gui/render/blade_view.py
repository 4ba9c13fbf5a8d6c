"""Render adapter for the blade's face and back surfaces, in the workpiece frame W."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from ..plan_data import BladeData
from ..style import BLADE_BACK, BLADE_FACE


def grid_surface(points: np.ndarray) -> pv.StructuredGrid:
    """(n_r, n_c, 3) float, mm -> a pyvista surface with the same points."""
    x, y, z = (points[..., i] for i in range(3))
    return pv.StructuredGrid(x, y, z)


class BladeView:
    """Owns the two surface actors of the blade in one plotter."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actors: dict[str, object] = {}
        self.opacity = 1.0
        self.visible = True

    def show(self, blade: BladeData) -> None:
        self.clear()
        for key, grid, colour in (("face", blade.face, BLADE_FACE), ("back", blade.back, BLADE_BACK)):
            self.actors[key] = self.plotter.add_mesh(grid_surface(grid), color=colour, smooth_shading=True,
                                                     name=f"blade-{key}", render=False, reset_camera=False)
        self.set_opacity(self.opacity)
        self.set_visible(self.visible)

    def set_opacity(self, opacity: float) -> None:
        """0 (invisible) .. 1 (opaque), both surfaces: see the cutter behind the blade."""
        self.opacity = float(opacity)
        for actor in self.actors.values():
            actor.prop.opacity = self.opacity

    def set_visible(self, visible: bool) -> None:
        self.visible = bool(visible)
        for actor in self.actors.values():
            actor.SetVisibility(self.visible)

    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(lo, hi) (3,) mm of the blade in W, or None."""
        if not self.actors:
            return None
        b = np.array([a.GetBounds() for a in self.actors.values()])
        return b[:, 0::2].min(axis=0), b[:, 1::2].max(axis=0)

    def clear(self) -> None:
        for actor in self.actors.values():
            self.plotter.remove_actor(actor, render=False)
        self.actors.clear()

"""Render adapter for the blade's face and back surfaces."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from core.blade import Blade

FACE_COLOUR = "#b8c4d6"
BACK_COLOUR = "#d9cfb8"


def grid_surface(points: np.ndarray) -> pv.StructuredGrid:
    """(n_r, n_c, 3) float, mm -> a pyvista surface with the same points."""
    x, y, z = (points[..., i] for i in range(3))
    return pv.StructuredGrid(x, y, z)


class BladeView:
    """Owns the two surface actors of the blade in one plotter."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actors: dict[str, object] = {}

    def show(self, blade: Blade) -> None:
        self.clear()
        face, back = blade.surface_grids()
        self.actors["face"] = self.plotter.add_mesh(grid_surface(face), color=FACE_COLOUR,
                                                    smooth_shading=True, name="blade-face")
        self.actors["back"] = self.plotter.add_mesh(grid_surface(back), color=BACK_COLOUR,
                                                    smooth_shading=True, name="blade-back")

    def clear(self) -> None:
        for actor in self.actors.values():
            self.plotter.remove_actor(actor, render=False)
        self.actors.clear()

"""Render adapter for the tool paths (both sides), coloured by region, with a legend."""

from __future__ import annotations

import numpy as np
import pyvista as pv

from ..plan_data import PathLines
from ..style import REGION_ORDER, REGIONS, hex_rgb

_RGB = np.zeros((len(REGIONS), 3), np.uint8)
for _code, _colour in REGIONS.values():
    _RGB[_code] = hex_rgb(_colour)


class PathsView:
    """Owns one line actor (every pair path, cell colours by region) and the region legend."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actor = None
        self.legend = None
        self.mesh: pv.PolyData | None = None
        self.lines: PathLines | None = None

    def show(self, lines: PathLines | None) -> None:
        self.clear()
        if lines is None:
            return
        self.lines = lines
        mesh = pv.PolyData(lines.points, lines=lines.cells)
        mesh.cell_data["region"] = lines.region
        mesh.cell_data["rgb"] = _RGB[lines.region]
        self.mesh = mesh
        self.actor = self.plotter.add_mesh(mesh, scalars="rgb", rgb=True, lighting=False, line_width=1,
                                           name="paths", render=False, reset_camera=False)
        present = set(np.unique(lines.region).tolist())
        entries = [[f"{name} region", REGIONS[name][1]] for name in REGION_ORDER
                   if REGIONS[name][0] in present]
        self.legend = self.plotter.add_legend(entries, bcolor="#20242c", border=True, size=(0.17, 0.12),
                                              loc="upper right", face="rectangle")

    def set_visible(self, visible: bool) -> None:
        if self.actor is not None:
            self.actor.SetVisibility(visible)

    def counts(self) -> dict[str, int]:
        """Segments per region name in the shown mesh (for the tests and the status)."""
        if self.mesh is None:
            return {}
        codes = np.asarray(self.mesh.cell_data["region"])
        return {name: int((codes == code).sum()) for name, (code, _) in REGIONS.items()}

    def clear(self) -> None:
        if self.actor is not None:
            self.plotter.remove_actor(self.actor, render=False)
        if self.legend is not None:
            self.plotter.remove_legend(render=False)
        self.actor = self.legend = self.mesh = self.lines = None

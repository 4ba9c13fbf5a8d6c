"""Render adapter for the tool paths (both sides), coloured by region, with a legend.

The operator may show one face only (the left or the right cutter's paths) and emphasise the contour
being machined at the cursor and its neighbours: those are drawn again, thicker, in a second actor,
over the others dimmed.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from ..plan_data import PathLines
from ..style import REGION_ORDER, REGIONS, hex_rgb

_RGB = np.zeros((len(REGIONS), 3), np.uint8)
for _code, _colour in REGIONS.values():
    _RGB[_code] = hex_rgb(_colour)

FACES = ("both", "left", "right")
DIMMED = 0.22  # opacity of the other paths while the current contour is emphasised
EMPHASIS_WIDTH = 4


def segment_paths(lines: PathLines) -> tuple[np.ndarray, np.ndarray]:
    """(pair index, side 0 left / 1 right) : (k,) int per segment of ``lines``: plan_data.path_lines
    lays every pair's left then right polyline end to end, each segment joining consecutive points,
    so a new polyline starts wherever a segment does not continue the one before."""
    first = lines.cells.reshape(-1, 3)[:, 1]
    new = np.ones(len(first), bool)
    new[1:] = first[1:] != first[:-1] + 1
    polyline = np.cumsum(new) - 1
    return polyline // 2, polyline % 2


class PathsView:
    """Owns one line actor (every pair path, cell colours by region), the region legend and the
    emphasis actor (the current contour and its neighbours)."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actor = None
        self.emphasis = None
        self.legend = None
        self.mesh: pv.PolyData | None = None
        self.lines: PathLines | None = None
        self.face = "both"
        self.emphasise = False
        self.neighbours = 1
        self.visible = True
        self.current: int | None = None  # the emphasised contour (pair index)
        self._pair = self._side = None

    def show(self, lines: PathLines | None) -> None:
        self.clear()
        if lines is None:
            return
        self.lines = lines
        self._pair, self._side = segment_paths(lines)
        self._draw()
        present = set(np.unique(lines.region).tolist())
        entries = [[f"{name} region", REGIONS[name][1]] for name in REGION_ORDER
                   if REGIONS[name][0] in present]
        self.legend = self.plotter.add_legend(entries, bcolor="#20242c", border=True, size=(0.17, 0.12),
                                              loc="upper right", face="rectangle")

    def _subset(self, mask: np.ndarray) -> pv.PolyData:
        lines = self.lines
        cells = lines.cells.reshape(-1, 3)[mask].ravel()
        mesh = pv.PolyData(lines.points, lines=cells) if len(cells) else pv.PolyData(lines.points)
        mesh.cell_data["region"] = lines.region[mask]
        mesh.cell_data["rgb"] = _RGB[lines.region[mask]]
        return mesh

    def _face_mask(self) -> np.ndarray:
        if self.face == "both":
            return np.ones(len(self._side), bool)
        return self._side == FACES.index(self.face) - 1

    def _draw(self) -> None:
        """The main actor for the face shown (rebuilt when the face changes), then the emphasis."""
        if self.actor is not None:
            self.plotter.remove_actor(self.actor, render=False)
            self.actor = None
        self.mesh = self._subset(self._face_mask())
        self.actor = self.plotter.add_mesh(self.mesh, scalars="rgb", rgb=True, lighting=False, line_width=1,
                                           name="paths", render=False, reset_camera=False)
        self.actor.SetVisibility(self.visible)
        self._draw_emphasis()

    def _draw_emphasis(self) -> None:
        if self.emphasis is not None:
            self.plotter.remove_actor(self.emphasis, render=False)
            self.emphasis = None
        on = self.emphasise and self.current is not None and self.lines is not None
        if self.actor is not None:
            self.actor.prop.opacity = DIMMED if on else 1.0
        if not on:
            return
        mask = self._face_mask() & (np.abs(self._pair - self.current) <= self.neighbours)
        if not mask.any():
            return
        self.emphasis = self.plotter.add_mesh(self._subset(mask), scalars="rgb", rgb=True, lighting=False,
                                              line_width=EMPHASIS_WIDTH, name="paths-current", render=False,
                                              reset_camera=False, pickable=False)
        self.emphasis.SetVisibility(self.visible)

    # -- operator's choices ----------------------------------------------------------------------
    def set_face(self, face: str) -> None:
        """'both', 'left' or 'right': whose paths are drawn."""
        if face not in FACES:
            raise ValueError(f"unknown face {face!r}: use one of {FACES}")
        if face != self.face:
            self.face = face
            if self.lines is not None:
                self._draw()

    def set_emphasis(self, on: bool) -> None:
        if bool(on) != self.emphasise:
            self.emphasise = bool(on)
            self._draw_emphasis()

    def set_current(self, pair: int | None) -> None:
        """The contour (pair index) being machined at the cursor; redraws the emphasis when it changes."""
        if pair is not None and pair < 0:
            return  # between paths: keep the last one
        if pair != self.current:
            self.current = pair
            if self.emphasise:
                self._draw_emphasis()

    def set_visible(self, visible: bool) -> None:
        self.visible = bool(visible)
        for actor in (self.actor, self.emphasis):
            if actor is not None:
                actor.SetVisibility(self.visible)

    def counts(self) -> dict[str, int]:
        """Segments per region name in the shown mesh (for the tests and the status)."""
        if self.mesh is None:
            return {}
        codes = np.asarray(self.mesh.cell_data["region"])
        return {name: int((codes == code).sum()) for name, (code, _) in REGIONS.items()}

    def clear(self) -> None:
        for actor in (self.actor, self.emphasis):
            if actor is not None:
                self.plotter.remove_actor(actor, render=False)
        if self.legend is not None:
            self.plotter.remove_legend(render=False)
        self.actor = self.emphasis = self.legend = self.mesh = self.lines = None
        self._pair = self._side = None

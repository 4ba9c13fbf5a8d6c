"""Render adapter for the tool paths (both sides), coloured by region, with a legend.

In the modes that do not use the regions ('symmetric': every path machined by both cutters at once;
'single': every path single-sided) the paths are drawn in that mode's one colour (style.MODE_PATHS),
and the legend says so.

The operator may show one face only (the left or the right cutter's paths) and emphasise the contour
being machined at the cursor and its neighbours: those are drawn again, thicker, in a second actor,
over the others dimmed.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from ..plan_data import PathLines
from ..style import MODE_PATHS, REGION_ORDER, REGIONS, hex_rgb
from .legend_view import ScreenLegend

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
        self.legend = ScreenLegend(plotter)
        self.mode = "collaborative"
        self.mesh: pv.PolyData | None = None
        self.lines: PathLines | None = None
        self.face = "both"
        self.emphasise = False
        self.neighbours = 1
        self.visible = True
        self.current: int | None = None  # the emphasised contour (pair index)
        self.pair = self.side = None  # per segment of the lines: pair index, side (segment_paths)

    def show(self, lines: PathLines | None, mode: str = "collaborative") -> None:
        """Draw ``lines`` as the job's ``mode`` (core.records.MODES) machines them: by region when
        collaborative, in the mode's one colour else."""
        self.clear()
        if lines is None:
            return
        self.lines = lines
        self.mode = mode
        self.pair, self.side = segment_paths(lines)
        self._draw()
        if mode in MODE_PATHS:
            entries = [(f"{mode} mode: {MODE_PATHS[mode][0]}", MODE_PATHS[mode][1])]
        else:
            present = set(np.unique(lines.region).tolist())
            entries = [(f"{name} region", REGIONS[name][1]) for name in REGION_ORDER
                       if REGIONS[name][0] in present]
        self.legend.show(entries)
        self.legend.set_visible(self.visible)

    def colours(self, mask: np.ndarray) -> np.ndarray:
        """(k, 3) uint8: the drawn colour of the segments ``mask`` selects."""
        if self.mode in MODE_PATHS:
            return np.tile(np.array(hex_rgb(MODE_PATHS[self.mode][1]), np.uint8), (int(mask.sum()), 1))
        return _RGB[self.lines.region[mask]]

    def subset(self, mask: np.ndarray) -> pv.PolyData:
        lines = self.lines
        cells = lines.cells.reshape(-1, 3)[mask].ravel()
        mesh = pv.PolyData(lines.points, lines=cells) if len(cells) else pv.PolyData(lines.points)
        mesh.cell_data["region"] = lines.region[mask]
        mesh.cell_data["rgb"] = self.colours(mask)
        return mesh

    def face_mask(self) -> np.ndarray:
        if self.face == "both":
            return np.ones(len(self.side), bool)
        return self.side == FACES.index(self.face) - 1

    def _draw(self) -> None:
        """The main actor for the face shown (rebuilt when the face changes), then the emphasis."""
        if self.actor is not None:
            self.plotter.remove_actor(self.actor, render=False)
            self.actor = None
        self.mesh = self.subset(self.face_mask())
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
        mask = self.face_mask() & (np.abs(self.pair - self.current) <= self.neighbours)
        if not mask.any():
            return
        self.emphasis = self.plotter.add_mesh(self.subset(mask), scalars="rgb", rgb=True, lighting=False,
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
        self.legend.set_visible(self.visible)

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
        self.legend.clear()
        self.actor = self.emphasis = self.mesh = self.lines = None
        self.pair = self.side = None

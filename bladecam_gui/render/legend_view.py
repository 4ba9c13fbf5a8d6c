"""A legend in the 3D view's upper right corner whose text keeps one pixel size whatever the view's
size (a VTK legend box scales its text with the view: tiny in a small window, oversized in a large
one).

Each entry is a swatch (a few spaces on the entry's colour) and a label in white on a dark
background, both vtkTextActors with no text scaling, placed in pixels from the view's corner (a
display coordinate referred to the normalised corner (1, 1), so that no resize moves them).
"""

from __future__ import annotations

import pyvista as pv
import vtk

from ..style import LEGEND_BACKGROUND, LEGEND_FONT_PX

MARGIN_PX = 10      # from the view's top and right edges
SWATCH = "    "     # the swatch's text: spaces on the entry's colour
GAP_PX = 4          # between a label and its swatch


def _text_actor(text: str, font_px: int, colour: str, background: str) -> vtk.vtkTextActor:
    actor = vtk.vtkTextActor()
    actor.SetInput(text)
    actor.SetTextScaleModeToNone()
    prop = actor.GetTextProperty()
    prop.SetFontSize(font_px)  # points at the render window's 72 DPI: pixels
    prop.SetColor(pv.Color(colour).float_rgb)
    prop.SetBackgroundColor(pv.Color(background).float_rgb)
    prop.SetBackgroundOpacity(0.9)
    prop.SetJustificationToRight()
    prop.SetVerticalJustificationToTop()
    return actor


class ScreenLegend:
    """Entries (label, colour) in a column at the view's upper right corner, text LEGEND_FONT_PX
    pixels high."""

    def __init__(self, plotter, font_px: int = LEGEND_FONT_PX):
        self.plotter = plotter
        self.font_px = font_px
        self.corner = vtk.vtkCoordinate()
        self.corner.SetCoordinateSystemToNormalizedViewport()
        self.corner.SetValue(1.0, 1.0)
        self.entries: list[tuple[str, str]] = []
        self.labels: list[vtk.vtkTextActor] = []
        self.swatches: list[vtk.vtkTextActor] = []
        self.visible = True

    def _place(self, actor: vtk.vtkTextActor, dx: float, dy: float) -> None:
        coord = actor.GetPositionCoordinate()
        coord.SetCoordinateSystemToDisplay()
        coord.SetReferenceCoordinate(self.corner)
        coord.SetValue(dx, dy)

    def show(self, entries: list[tuple[str, str]]) -> None:
        """Replace the entries: (label, colour '#rrggbb') each, top to bottom."""
        self.clear()
        self.entries = list(entries)
        renderer = self.plotter.renderer
        row = round(1.6 * self.font_px)
        for k, (label, colour) in enumerate(self.entries):
            swatch = _text_actor(SWATCH, self.font_px, colour, colour)
            text = _text_actor(label, self.font_px, "#f0f0f0", LEGEND_BACKGROUND)
            y = -MARGIN_PX - k * row
            self._place(swatch, -MARGIN_PX, y)
            box = [0.0] * 4
            swatch.GetBoundingBox(renderer, box)
            self._place(text, -MARGIN_PX - (box[1] - box[0]) - GAP_PX, y)
            for actor in (swatch, text):
                actor.SetVisibility(self.visible)
                actor.SetPickable(False)
                renderer.AddViewProp(actor)
            self.swatches.append(swatch)
            self.labels.append(text)

    def text_size(self, k: int = 0) -> tuple[float, float]:
        """(width, height) px of entry k's label as the view draws it."""
        box = [0.0] * 4
        self.labels[k].GetBoundingBox(self.plotter.renderer, box)
        return box[1] - box[0], box[3] - box[2]

    def set_visible(self, visible: bool) -> None:
        self.visible = bool(visible)
        for actor in self.labels + self.swatches:
            actor.SetVisibility(self.visible)

    def clear(self) -> None:
        for actor in self.labels + self.swatches:
            self.plotter.renderer.RemoveViewProp(actor)
        self.labels, self.swatches, self.entries = [], [], []

"""Render adapter for the 3D view's measuring tool: the distance between two points picked on the
blade (or any pickable actor: the paths, the cutters are not), drawn as a line with its length.

A click picks the surface point under the cursor (vtkCellPicker at the clicked pixel); the third
click starts a new measurement."""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkCellPicker

MEASURE_COLOUR = "#ffffff"


def pick_point(plotter, x: float, y: float) -> np.ndarray | None:
    """(3,) mm in W of the surface under the pixel (x, y) of the render window (origin top left, in
    the render window's pixels), or None where there is none."""
    picker = vtkCellPicker()
    picker.SetTolerance(0.0005)
    height = plotter.ren_win.GetSize()[1]
    if not picker.Pick(float(x), float(height - 1 - y), 0.0, plotter.renderer):
        return None
    return np.array(picker.GetPickPosition(), float)


class MeasureView:
    """The picked points (at most two), the line between them and its length's label."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.points: list[np.ndarray] = []
        self.actors: list = []
        self.text = ""  # the drawn label

    @property
    def distance(self) -> float | None:
        """mm between the two picked points, or None before both are picked."""
        if len(self.points) < 2:
            return None
        return float(np.linalg.norm(self.points[1] - self.points[0]))

    def add(self, point: np.ndarray) -> None:
        """One more picked point (a third one starts again from it)."""
        if len(self.points) >= 2:
            self.points = []
        self.points.append(np.asarray(point, float))
        self._draw()

    def _draw(self) -> None:
        self._remove()
        pts = np.array(self.points)
        kw = dict(render=False, reset_camera=False, pickable=False)
        self.actors.append(self.plotter.add_points(pts, color=MEASURE_COLOUR, point_size=10,
                                                   render_points_as_spheres=True, name="measure-points",
                                                   **kw))
        self.text = "" if len(pts) < 2 else f"{self.distance:.3f} mm"
        if len(pts) == 2:
            self.actors.append(self.plotter.add_mesh(pv.Line(pts[0], pts[1]), color=MEASURE_COLOUR,
                                                     line_width=3, lighting=False, name="measure-line", **kw))
            self.actors.append(self.plotter.add_point_labels(
                pts.mean(axis=0)[None], [self.text], font_size=14, text_color=MEASURE_COLOUR,
                shape_color="#20242c", always_visible=True, name="measure-label", render=False,
                reset_camera=False))

    def _remove(self) -> None:
        for actor in self.actors:
            self.plotter.remove_actor(actor, render=False)
        self.actors = []

    def clear(self) -> None:
        self._remove()
        self.points = []
        self.text = ""

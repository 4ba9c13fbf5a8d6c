"""Render adapter for the workpiece frame W: three arrows at its origin, labelled X_W, Y_W, Z_W."""

from __future__ import annotations

import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkTextActor

AXES = (("X_W", (1.0, 0.0, 0.0), "#e05050"), ("Y_W", (0.0, 1.0, 0.0), "#50c050"),
        ("Z_W", (0.0, 0.0, 1.0), "#5080ff"))


class FrameAxesView:
    """Owns three arrow actors and one label actor, sized to the blade."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actors: list = []

    def show(self, size: float) -> None:
        self.clear()
        origin = np.zeros(3)
        tips = []
        for name, direction, colour in AXES:
            arrow = pv.Arrow(start=origin, direction=direction, scale=size, tip_length=0.15, tip_radius=0.04,
                             shaft_radius=0.012)
            self.actors.append(self.plotter.add_mesh(arrow, color=colour, name=f"frame-{name}", render=False,
                                                     reset_camera=False, pickable=False))
            tips.append(np.asarray(direction) * size * 1.06)
        for (name, _, _), tip in zip(AXES, tips, strict=True):
            # a 2D text anchored at a world point: about 0.1 ms a frame, where a point-label actor
            # placed its labels again at every frame (1-1.5 ms of a timeline drag's render)
            label = vtkTextActor()
            label.SetInput(name)
            label.GetTextProperty().SetFontSize(12)
            label.GetTextProperty().SetColor(1.0, 1.0, 1.0)
            anchor = label.GetPositionCoordinate()
            anchor.SetCoordinateSystemToWorld()
            anchor.SetValue(*(float(x) for x in tip))
            self.plotter.add_actor(label, name=f"frame-label-{name}", reset_camera=False, render=False,
                                   pickable=False)
            self.actors.append(label)

    def clear(self) -> None:
        for actor in self.actors:
            self.plotter.remove_actor(actor, render=False)
        self.actors.clear()

"""Render adapter for the workpiece frame W: three arrows at its origin, labelled X_W, Y_W, Z_W."""

from __future__ import annotations

import numpy as np
import pyvista as pv

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
        self.actors.append(self.plotter.add_point_labels(
            np.array(tips), [a[0] for a in AXES], font_size=12, text_color="white", shape=None,
            show_points=False, name="frame-labels", always_visible=True, render=False))

    def clear(self) -> None:
        for actor in self.actors:
            self.plotter.remove_actor(actor, render=False)
        self.actors.clear()

"""Render adapter for the two cutters: the tool assembly (ball, flutes, neck, shank, holder stages,
spindle nose; or a ball, shank and holder stub), moved by user matrices.

Each tool mesh is built once in a local frame (tip at the origin, tool axis +Z, towards the holder)
and placed at a time sample by a 4x4 matrix [e1 e2 axis tip]; meshes are rebuilt only when the tool
radius or stick-out change. Both turn red when the tip spacing is below h_safe or the capsules touch.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from ..style import DANGER_COLOUR, LEFT_COLOUR, RIGHT_COLOUR

HOLDER_LENGTH = 15.0  # mm, the stub of the holder drawn beyond the stick-out


def tool_top(tool_radius: float, tool_length: float, tool=None) -> float:
    """mm from the tip along the axis to the top of what ``tool_mesh`` draws (the spindle nose's end
    for a tool assembly)."""
    if tool is not None:
        return tool.length
    return tool_radius + max(tool_length - tool_radius, tool_radius) + HOLDER_LENGTH


def _cylinder(radius: float, z0: float, z1: float) -> pv.PolyData:
    return pv.Cylinder(center=(0, 0, 0.5 * (z0 + z1)), direction=(0, 0, 1), radius=radius, height=z1 - z0,
                       resolution=32 if radius > 4 else 24).triangulate()


def tool_mesh(tool_radius: float, tool_length: float, tool=None) -> pv.PolyData:
    """Ball end (centre r above the tip), then with a tool assembly (core.machine.tool.Tool) its
    flutes, neck, shank, holder stages and spindle nose as they are, else the shank up to the
    stick-out and a holder stub; tip at the origin."""
    r, length = tool_radius, tool_length
    ball = pv.Sphere(radius=r, center=(0, 0, r), theta_resolution=24, phi_resolution=16)
    if tool is not None:
        r = tool.ball_radius
        ball = pv.Sphere(radius=r, center=(0, 0, r), theta_resolution=24, phi_resolution=16)
        z = [r, tool.flute_length, tool.neck_length, tool.stick_out]
        parts = [_cylinder(rad, z0, z1) for rad, z0, z1 in
                 ((r, z[0], z[1]), (tool.neck_radius, z[1], z[2]), (tool.shank_radius, z[2], z[3])) if z1 > z0]
        top = tool.stick_out
        for h, rad in (*tool.holder, (tool.nose_length, tool.nose_radius)):
            parts.append(_cylinder(rad, top, top + h))
            top += h
        mesh = ball
        for p in parts:
            mesh = mesh + p
        return mesh.clean()
    shank_len = max(length - r, r)
    shank = pv.Cylinder(center=(0, 0, r + shank_len / 2), direction=(0, 0, 1), radius=r, height=shank_len,
                        resolution=24)
    holder_r = max(3.0 * r, r + 4.0)
    holder = pv.Cylinder(center=(0, 0, r + shank_len + HOLDER_LENGTH / 2), direction=(0, 0, 1),
                         radius=holder_r, height=HOLDER_LENGTH, resolution=32)
    return (ball + shank.triangulate() + holder.triangulate()).clean()


def placement(tip: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """4x4 matrix taking the local tool frame (tip at 0, axis +Z) to tip (3,) mm and unit axis (3,)."""
    w = np.asarray(axis, float) / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(helper, w)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(w, e1)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = e1, e2, w, tip
    return m


class CuttersView:
    """Owns the two tool actors ('left', 'right')."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actors: dict[str, object] = {}
        self.colours = {"left": LEFT_COLOUR, "right": RIGHT_COLOUR}
        self._tool: tuple | None = None
        self.danger = False
        self.shown = {"left": True, "right": True}  # the operator's choice (View options)
        self._visible = False  # whether the plan has cutters to show

    def set_tool(self, tool_radius: float, tool_length: float, tool=None) -> None:
        """Draw ``tool`` (a core.machine.tool.Tool, as it is) or a ball of tool_radius with a shank of
        tool_length; the meshes are rebuilt only when that changes."""
        if self._tool == (tool_radius, tool_length, tool) and self.actors:
            return
        old = {k: (a.user_matrix, a.GetVisibility()) for k, a in self.actors.items()}
        self.clear()
        mesh = tool_mesh(tool_radius, tool_length, tool)
        for side in ("left", "right"):
            self.actors[side] = self.plotter.add_mesh(
                mesh, color=self.colours[side], smooth_shading=True, name=f"cutter-{side}", render=False,
                reset_camera=False, pickable=False)
            if side in old:
                self.actors[side].user_matrix = old[side][0]
                self.actors[side].SetVisibility(old[side][1] and self.shown[side])
        self._tool = (tool_radius, tool_length, tool)
        self._paint(self.danger)

    def place(self, left_tip, left_axis, right_tip, right_axis, danger: bool) -> None:
        for side, tip, axis in (("left", left_tip, left_axis), ("right", right_tip, right_axis)):
            actor = self.actors.get(side)
            if actor is not None:
                actor.user_matrix = placement(tip, axis)
        if danger != self.danger:
            self._paint(danger)

    def _paint(self, danger: bool) -> None:
        self.danger = danger
        for side, actor in self.actors.items():
            actor.prop.color = DANGER_COLOUR if danger else self.colours[side]

    def set_visible(self, visible: bool) -> None:
        """Both shown (a plan with a schedule) or hidden, each as the operator's ``shown`` allows."""
        self._visible = bool(visible)
        for side, actor in self.actors.items():
            actor.SetVisibility(self._visible and self.shown[side])

    def set_shown(self, side: str, shown: bool) -> None:
        """The operator's show/hide of one cutter ('left' or 'right')."""
        self.shown[side] = bool(shown)
        self.set_visible(self._visible)

    def matrix(self, side: str) -> np.ndarray:
        return np.asarray(self.actors[side].user_matrix)

    def clear(self) -> None:
        for actor in self.actors.values():
            self.plotter.remove_actor(actor, render=False)
        self.actors.clear()
        self._tool = None

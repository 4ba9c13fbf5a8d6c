"""Render adapter for the two XYZ-3RPS machines: stage carriage, three legs, moving platform, spindle.

Drawn at the machine's own scale in the workpiece frame W (they hold the cutters, so any other scale
would detach the spindles from the tools); the view's "fit" then takes them in. Every part is a mesh
built once in a local frame and placed by a 4x4 user matrix, so a cursor move only sets matrices:

- carriage: the XYZ stage's moving plate with the 3-RPS base ring and its three joints, in the base
  frame (parallel to the side's machine frame M, origin o = (x, y, z) of the axis table);
- legs: each a unit cylinder (z 0..1) stretched from the base joint b_i to the platform joint P_i,
  so the drawn leg length is the length of the matrix's third column;
- head: the platform (joint circle r_p) and the spindle down to the tool holder, in a frame at the
  platform centre with z along the tool axis w (tip -> spindle).

The geometry is core's (core.machine.kinematics, core.machine.model): the base joints at the stage's
x, y, z, the platform joints solved from the leg values d1-d3 (``platform_joint_positions``, the
forward kinematics' solve of the mechanism), the spindle on the cutter's tip and axis at the gauge
length (the model's p = o + c - e w), the axis values from the plan's axis tables (the rows an export
writes). Nothing is derived here beyond placing meshes on those points.
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from core.errors import MachineError
from core.machine.kinematics import base_joints, platform_joint_positions
from core.machine.model import SIDES, Machine, machine_to_toml

from ..style import LEFT_COLOUR, RIGHT_COLOUR, hex_rgb

FRAME_COLOUR = "#8a93a3"
HEAD_COLOUR = "#c7ccd6"
LEG_RADIUS = 6.0  # mm
SPINDLE_RADIUS = 22.0  # mm
MOTOR_HEIGHT = 60.0  # mm of spindle motor drawn above the platform
PLATE = 12.0  # mm, plate thickness


def _box(lo, hi) -> pv.PolyData:
    return pv.Box(bounds=(lo[0], hi[0], lo[1], hi[1], lo[2], hi[2])).triangulate()


def carriage_mesh(machine: Machine) -> pv.PolyData:
    """Base frame: the stage carriage (a square frame round the base ring), the ring and its joints."""
    rb = machine.base_radius
    half, inner, t = 1.3 * rb, 1.12 * rb, PLATE
    parts = [_box((-half, -half, -t), (half, -inner, 0.0)), _box((-half, inner, -t), (half, half, 0.0)),
             _box((-half, -inner, -t), (-inner, inner, 0.0)), _box((inner, -inner, -t), (half, inner, 0.0))]
    ring = pv.Disc(inner=0.8 * rb, outer=1.15 * rb, r_res=1, c_res=36).extrude((0, 0, -t), capping=True)
    parts.append(ring.triangulate())
    for b in base_joints(machine):
        parts.append(pv.Sphere(radius=2.0 * LEG_RADIUS, center=b, theta_resolution=10, phi_resolution=8))
    mesh = parts[0]
    for p in parts[1:]:
        mesh = mesh + p
    return mesh.clean()


def head_mesh(machine: Machine, tool_top: float) -> pv.PolyData:
    """Platform frame (centre at 0, z = tool axis w): the platform plate, the spindle from its motor
    above the platform down to ``tool_top`` mm above the tool tip (where the cutter's holder ends)."""
    rp, e = machine.platform_radius, machine.gauge_length
    plate = pv.Cylinder(center=(0, 0, 0), direction=(0, 0, 1), radius=1.15 * rp, height=PLATE,
                        resolution=24).triangulate()
    low = -(e - tool_top)  # the holder's top, in the platform frame
    spindle = pv.Cylinder(center=(0, 0, 0.5 * (MOTOR_HEIGHT + low)), direction=(0, 0, 1),
                          radius=SPINDLE_RADIUS, height=MOTOR_HEIGHT - low, resolution=20).triangulate()
    parts = [plate, spindle]
    for a in np.radians([0.0, 120.0, 240.0]):
        parts.append(pv.Sphere(radius=1.6 * LEG_RADIUS, center=(rp * np.cos(a), rp * np.sin(a), 0.0),
                               theta_resolution=10, phi_resolution=8))
    mesh = parts[0]
    for p in parts[1:]:
        mesh = mesh + p
    return mesh.clean()


def leg_mesh() -> pv.PolyData:
    """A unit leg: a cylinder from z = 0 to 1 (stretched by its user matrix to b_i -> P_i)."""
    return pv.Cylinder(center=(0, 0, 0.5), direction=(0, 0, 1), radius=LEG_RADIUS, height=1.0,
                       resolution=10).triangulate()


def frame_matrix(origin: np.ndarray, z: np.ndarray, x_hint: np.ndarray) -> np.ndarray:
    """4x4 rigid matrix with its z axis along ``z`` and x towards ``x_hint`` (orthogonalised)."""
    w = z / np.sqrt(z @ z)
    x = x_hint - (x_hint @ w) * w
    x /= np.sqrt(x @ x)
    m = np.eye(4)
    m[:3, 0], m[:3, 2], m[:3, 3] = x, w, origin
    m[:3, 1] = (w[1] * x[2] - w[2] * x[1], w[2] * x[0] - w[0] * x[2], w[0] * x[1] - w[1] * x[0])
    return m


def leg_matrix(b: np.ndarray, p: np.ndarray) -> np.ndarray:
    """4x4 matrix taking the unit leg (z 0..1) to the segment b -> p (W, mm), its radius kept."""
    d = p - b
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 * np.sqrt(d @ d) else np.array([0.0, 1.0, 0.0])
    m = frame_matrix(b, d, helper)
    m[:3, 2] = d
    return m


PARTS = ("carriage", "head", "leg0", "leg1", "leg2")


class MachinesView:
    """Owns one actor per machine ('left', 'right'): its parts (PARTS: carriage, head, three legs) in
    one mesh whose points are placed part by part at each pose (one actor each keeps a drag frame's
    render cheap: ten actors a side cost more to draw than their few triangles).

    ``show_plan(machine, tables, tool_top)`` gives the machine and the axis tables (side ->
    core.machine.tables.AxisTable, or None: the machines hidden); ``place(i, t_ms, tips, axes)``
    poses both at a time sample. ``note`` says how they are posed (and which is hidden because no
    platform pose solves its leg values)."""

    def __init__(self, plotter):
        self.plotter = plotter
        self.actors: dict[str, object] = {}
        self.meshes: dict[str, pv.PolyData] = {}
        self.matrices: dict[str, dict[str, np.ndarray]] = {}
        self.machine: Machine | None = None
        self.tables: dict | None = None
        self.values: dict[str, np.ndarray | None] = {s: None for s in SIDES}
        self.enabled = False
        self.opacity = 1.0
        self.note = ""
        self._built: tuple | None = None
        self._tool_top = 0.0
        self._local: dict[str, np.ndarray] = {}  # part -> (k, 3) local points
        self._slices: dict[str, slice] = {}  # part -> its rows in a side's mesh
        self._reachable = {s: False for s in SIDES}

    # -- plan ------------------------------------------------------------------------------------
    def show_plan(self, machine: Machine | None, tables: dict | None, tool_top: float) -> None:
        """The machine and its axis tables for the plan shown; meshes built when changed. A result
        without them (None) has nothing to pose the machines from: they are hidden."""
        if machine is None or not tables:
            self.clear()
            self.machine = self.tables = None
            self.note = "the plan shown has no axis tables to pose the machines from"
            return
        self.machine, self.tables = machine, tables
        self._tool_top = float(tool_top)
        if self.enabled:
            self._ensure_built()
        self.note = "posed from the plan's axis tables"

    def _ensure_built(self) -> None:
        """The meshes of the plan's machine, built when first drawn (the machines are off by default:
        building them costs a tenth of a second of the GUI thread) and kept while the machine file
        and the tool's height stay the same (every plan loads its machine afresh)."""
        if self.machine is None:
            return
        key = (machine_to_toml(self.machine), round(self._tool_top, 6))
        if self._built != key:
            self.clear()
            self._build(self.machine, self._tool_top)
            self._built = key

    def _build(self, machine: Machine, tool_top: float) -> None:
        leg = leg_mesh()
        local = {"carriage": carriage_mesh(machine), "head": head_mesh(machine, tool_top),
                 "leg0": leg, "leg1": leg, "leg2": leg}
        tint = {"left": LEFT_COLOUR, "right": RIGHT_COLOUR}
        start = 0
        for part in PARTS:
            n = local[part].n_points
            self._local[part] = np.asarray(local[part].points, float)
            self._slices[part] = slice(start, start + n)
            start += n
        for side in SIDES:
            colours = {"carriage": FRAME_COLOUR, "head": HEAD_COLOUR}
            mesh = pv.merge([local[part] for part in PARTS], merge_points=False)
            rgb = np.concatenate([np.tile(hex_rgb(colours.get(part, tint[side])), (local[part].n_cells, 1))
                                  for part in PARTS]).astype(np.uint8)
            mesh.cell_data["rgb"] = rgb
            self.meshes[side] = mesh
            self.actors[side] = self.plotter.add_mesh(
                mesh, scalars="rgb", rgb=True, name=f"machine-{side}", render=False, reset_camera=False,
                pickable=False, opacity=self.opacity)
            self.actors[side].SetVisibility(False)

    # -- pose ------------------------------------------------------------------------------------
    def axis_values(self, side: str, i: int, t_ms: float) -> np.ndarray:
        """(6,) x, y, z, d1, d2, d3 mm of ``side`` at sample i (time t_ms): the axis table's row (the
        row at t_ms if the table's rows are not the time column's)."""
        table = self.tables[side]
        if not (0 <= i < len(table.t) and table.t[i] == t_ms):
            i = int(np.clip(np.searchsorted(table.t, t_ms), 0, len(table.t) - 1))
        return table.values[i]

    def place(self, i: int, t_ms: float, tips: dict, axes: dict) -> None:
        """Pose both machines at sample i; tips, axes: side -> (3,) of the cutters in W (the spindle
        holds the cutter: the platform centre is tip + e w)."""
        if self.machine is None or not self.tables or not self.actors:
            return
        values = {}
        for side in SIDES:
            values[side] = self.values[side] = self.axis_values(side, i, t_ms)
        joints = {}
        for side in SIDES:  # the legs' platform joints (forward kinematics of d1-d3)
            try:
                joints[side] = platform_joint_positions(self.machine, values[side][None, 3:], side)[0]
            except MachineError:
                pass
        hidden = []
        for side in SIDES:
            self._reachable[side] = side in joints
            if side in joints:
                self._pose(side, values[side], joints[side], np.asarray(tips[side], float),
                           np.asarray(axes[side], float))
            else:
                hidden.append(side)
        base = self.note.split(";")[0]
        self.note = base + ("; " + " and ".join(hidden) + " hidden: no platform pose for its leg values "
                            "here" if hidden else "")
        self._apply_visibility()

    def _pose(self, side: str, values: np.ndarray, joints: np.ndarray, tip: np.ndarray,
              w: np.ndarray) -> None:
        m = self.machine
        tr = m.side(side)
        o = values[:3]
        base = np.eye(4)
        base[:3, :3], base[:3, 3] = tr.rotation, tr.to_workpiece(o[None])[0]
        b_w = tr.to_workpiece(base_joints(m) + o)
        p_w = tr.to_workpiece(joints + o)
        centre = tip + m.gauge_length * w
        mats = {"carriage": base, "head": frame_matrix(centre, w, p_w[0] - centre)}
        for k in range(3):
            mats[f"leg{k}"] = leg_matrix(b_w[k], p_w[k])
        self.matrices[side] = mats
        pts = np.empty((self.meshes[side].n_points, 3))
        for part, mat in mats.items():
            pts[self._slices[part]] = self._local[part] @ mat[:3, :3].T + mat[:3, 3]
        self.meshes[side].points = pts

    # -- display ---------------------------------------------------------------------------------
    def set_enabled(self, enabled: bool) -> None:
        self.enabled = bool(enabled)
        if self.enabled:
            self._ensure_built()
        self._apply_visibility()

    def set_opacity(self, opacity: float) -> None:
        self.opacity = float(opacity)
        for actor in self.actors.values():
            actor.prop.opacity = self.opacity

    def _apply_visibility(self) -> None:
        for side, actor in self.actors.items():
            actor.SetVisibility(self.enabled and self._reachable[side])

    def hide(self) -> None:
        """Hidden until the next ``place`` (a blade without a plan yet)."""
        self._reachable = {s: False for s in SIDES}
        self._apply_visibility()

    def visible(self, side: str) -> bool:
        return bool(self.actors) and bool(self.actors[side].GetVisibility())

    def part_points(self, side: str, part: str) -> np.ndarray:
        """(k, 3) mm, W: the drawn points of one part (PARTS) of a machine, as its actor has them."""
        return np.asarray(self.actors[side].mapper.dataset.points)[self._slices[part]]

    def leg_lengths(self, side: str) -> np.ndarray:
        """(3,) mm: the drawn legs' lengths (base joint to platform joint), read off the actor's points:
        the distance between the centres of each leg's two end circles."""
        z = self._local["leg0"][:, 2]
        out = []
        for k in range(3):
            pts = self.part_points(side, f"leg{k}")
            out.append(np.linalg.norm(pts[z > 0.5].mean(axis=0) - pts[z < 0.5].mean(axis=0)))
        return np.array(out)

    def clear(self) -> None:
        for actor in self.actors.values():
            self.plotter.remove_actor(actor, render=False)
        self.actors.clear()
        self.meshes.clear()
        self.matrices.clear()
        self._built = None
        self._reachable = {s: False for s in SIDES}

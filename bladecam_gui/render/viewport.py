"""The 3D view: a pyvista plotter with the render adapters, driven by the state's signals.

The plotter is pyvistaqt's QtInteractor on a hardware OpenGL, and an off-screen pyvista plotter
shown by bladecam_gui.render.raster_view.RasterView on a software one (see that module: Qt's OpenGL
composition of the whole window cost a third of every frame there). ``BLADECAM_VIEW`` = ``opengl``
or ``raster`` chooses one whatever the OpenGL.
"""

from __future__ import annotations

import logging
import os

import numpy as np
import pyvista as pv
from PySide6.QtCore import QEvent, QObject, Qt, Slot
from PySide6.QtWidgets import QVBoxLayout, QWidget
from pyvistaqt import QtInteractor

from ..plan_data import BladeData, PlanData
from ..state import WorkbenchState
from ..style import BACKGROUND
from .blade_view import BladeView
from .cutters_view import CuttersView, tool_top
from .drag_detail import DragDetail
from .frame_axes import FrameAxesView
from .machines_view import MachinesView
from .measure_view import MeasureView, pick_point
from .paths_view import PathsView
from .raster_view import RasterView, offscreen_plotter, opengl_renderer, software_opengl

log = logging.getLogger(__name__)

#: camera choices: the view stays where the operator put it, or its focal point follows a cutter's tip
#: (or the pair's midpoint) as the cursor moves, the view's direction and distance kept
FOLLOW = ("off", "left", "right", "midpoint")
VIEWS = ("front", "side", "iso", "bottom", "top", "fit")


class Viewport(QObject):
    """Owns the interactor (``plotter``; its widget is ``widget``) and one adapter per thing drawn."""

    def __init__(self, state: WorkbenchState, parent_widget):
        super().__init__(parent_widget)
        self.state = state
        # render on change only; no multisampling and one headlight: a software renderer (Xvfb, remote
        # desktops) spends most of a frame shading the blade's pixels once per light
        choice = os.environ.get("BLADECAM_VIEW", "auto").strip().lower()
        self.raster: RasterView | None = None
        self.opengl = ""
        if choice != "opengl":
            try:
                plotter = offscreen_plotter()
            except Exception:  # (no off-screen OpenGL here: the interactive widget still may work)
                log.warning("no off-screen rendering; the 3D view uses pyvistaqt's widget", exc_info=True)
                plotter = None
            if plotter is not None:
                self.opengl = opengl_renderer(plotter.ren_win)
                if choice == "raster" or software_opengl(self.opengl):
                    self.plotter = plotter
                    self.raster = RasterView(plotter, parent_widget)
                else:
                    plotter.close()
        if self.raster is None:
            self.plotter = QtInteractor(parent_widget, auto_update=False, multi_samples=0, lighting="none")
        self.plotter.add_light(pv.Light(light_type="headlight"))
        self.plotter.set_background(BACKGROUND[0])
        self.plotter.add_axes()
        if self.raster is not None:
            self.widget = self.raster
        else:
            self.widget = self.plotter.interactor if hasattr(self.plotter, "interactor") else self.plotter
        # the interactor paints on screen; in an opaque holder Qt no longer repaints the main window's
        # background under it on every frame (a third of a drag frame on a software renderer)
        self.container = QWidget(parent_widget)
        self.container.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.container.setAttribute(Qt.WidgetAttribute.WA_NoSystemBackground)
        layout = QVBoxLayout(self.container)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.widget)
        self.blade = BladeView(self.plotter)
        self.paths = PathsView(self.plotter)
        self.cutters = CuttersView(self.plotter)
        self.frame_axes = FrameAxesView(self.plotter)
        self.machines = MachinesView(self.plotter)
        self.measure = MeasureView(self.plotter)
        self.drag = DragDetail(self)  # light frames while the timeline is dragged (begin / end)
        self.follow = "off"
        self.measuring = False  # clicks pick the measuring tool's points
        self.scallop_shown = False  # the blade coloured by the scallop height
        self.section_shown = False  # the blade cut at the cursor's contour
        self._press = None
        self.widget.installEventFilter(self)
        state.blade_changed.connect(self._on_blade_changed)
        state.plan_changed.connect(self._on_plan_changed)
        state.regions_changed.connect(self._on_regions_changed)
        state.cursor_changed.connect(self._on_cursor_changed)
        self._closed = False

    # -- state -----------------------------------------------------------------------------------
    @Slot(object)
    def _on_blade_changed(self, blade: BladeData) -> None:
        try:
            self.blade.show(blade)
            self.measure.clear()
            lo, hi = self.blade.bounds()
            self.frame_axes.show(0.25 * float(np.max(hi - lo)))
            self.paths.clear()
            self.cutters.set_visible(False)
            self.machines.hide()
            self.view("iso")
        except Exception:  # slots never raise
            log.exception("showing the blade failed")

    @Slot(object)
    def _on_regions_changed(self, data: PlanData) -> None:
        try:
            mode = data.job.params.mode
            if data.lines is not self.paths.lines or mode != self.paths.mode:
                self.paths.show(data.lines, mode)
                self.render()
        except Exception:  # slots never raise
            log.exception("showing the paths failed")

    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            if data.has_schedule:
                p = data.result.plan.params
                self.cutters.set_tool(p.tool_radius, p.tool_length, getattr(data.result, "tool", None))
                self._show_machines(data)
                self._place(self.state.cursor)
                self.cutters.set_visible(True)
            else:
                self.cutters.set_visible(False)
                self.machines.hide()
            self._show_scallop()
            self._show_section()
            self.render()
        except Exception:  # slots never raise
            log.exception("showing the plan failed")

    @Slot(int)
    def _on_cursor_changed(self, index: int) -> None:
        try:
            self._place(index)
            self.drag.moved()
            self.render()
        except Exception:  # slots never raise
            log.exception("moving the cutters failed")

    def _place(self, i: int) -> None:
        data = self.state.plan
        if data is None or not data.has_schedule or not self.cutters.actors:
            return
        tl = data.timeline
        i = max(0, min(i, len(tl.t) - 1))
        self.cutters.place(tl.left.tips[i], tl.left.axes[i], tl.right.tips[i], tl.right.axes[i],
                           bool(data.danger[i]))
        if self.machines.enabled:
            self.machines.place(i, float(tl.t[i]), {"left": tl.left.tips[i], "right": tl.right.tips[i]},
                                {"left": tl.left.axes[i], "right": tl.right.axes[i]})
        pair = int(tl.left.path[i]) if tl.left.path[i] >= 0 else int(tl.right.path[i])
        self.paths.set_current(pair)
        if self.section_shown:
            self._show_section()
        if self.follow != "off":
            self._follow(self.follow_target(i))

    # -- inspection: the scallop map, the section, the measuring tool ------------------------------
    def set_scallop_shown(self, shown: bool) -> None:
        """Colour the blade by the shown plan's scallop heights (or plainly)."""
        self.scallop_shown = bool(shown)
        self._show_scallop()
        self.render()

    def _show_scallop(self) -> None:
        data = self.state.plan
        fig = None if data is None or data.result is None else data.result.figures
        per_path = (fig or {}).get("scallop", {}).get("per_path_max_mm")
        if self.scallop_shown and per_path is not None:
            self.blade.set_scallop(data.result.plan.paths, per_path)
        elif self.blade.scallop is not None:
            self.blade.set_scallop(None, None)

    def section_radius(self) -> float | None:
        """The radius mm of the contour at the cursor (the shown plan's), or None."""
        data = self.state.plan
        if data is None or not data.has_schedule:
            return None
        tl, i = data.timeline, self.state.cursor
        pair = int(tl.left.path[i]) if tl.left.path[i] >= 0 else int(tl.right.path[i])
        if pair < 0:
            pair = self.paths.current
        pairs = data.result.plan.pairs
        return None if pair is None or not 0 <= pair < len(pairs) else float(pairs[pair].r)

    def set_section_shown(self, shown: bool) -> None:
        """Cut the blade at the cursor's contour (following the cursor), or show it whole."""
        self.section_shown = bool(shown)
        self._show_section()
        self.render()

    def _show_section(self) -> None:
        self.blade.set_section(self.section_radius() if self.section_shown else None)

    def set_measuring(self, on: bool) -> None:
        """Clicks in the view pick the measuring tool's points (on), or turn the view (off: the
        measurement is removed)."""
        self.measuring = bool(on)
        if not on:
            self.measure.clear()
        self.render()

    def measure_at(self, x: float, y: float) -> bool:
        """Pick the measuring tool's next point at the widget's pixel (x, y); False where nothing
        is under it."""
        w, h = self.plotter.ren_win.GetSize()
        sx, sy = w / max(self.widget.width(), 1), h / max(self.widget.height(), 1)
        point = pick_point(self.plotter, x * sx, y * sy)
        if point is None:
            return False
        self.measure.add(point)
        self.render()
        return True

    def eventFilter(self, obj, event) -> bool:  # noqa: N802 (Qt name)
        """While measuring, a click (a press and a release without a drag) picks a point; the view
        still turns on a drag."""
        try:
            if self.measuring and obj is self.widget:
                kind = event.type()
                if kind == QEvent.Type.MouseButtonPress and event.button() == Qt.MouseButton.LeftButton:
                    self._press = event.position()
                elif kind == QEvent.Type.MouseButtonRelease and self._press is not None:
                    moved = event.position() - self._press
                    self._press = None
                    if abs(moved.x()) + abs(moved.y()) <= 4:
                        self.measure_at(event.position().x(), event.position().y())
        except Exception:  # (an event filter never raises)
            log.exception("measuring failed")
        return False

    # -- machines and camera ---------------------------------------------------------------------
    def _show_machines(self, data: PlanData) -> None:
        """The plan's machine and its axis tables (a result without them: the machines hidden)."""
        res = data.result
        p = res.plan.params
        self.machines.show_plan(res.machine, res.axes, tool_top(p.tool_radius, p.tool_length,
                                                                getattr(res, "tool", None)))

    def set_machines_shown(self, shown: bool) -> None:
        """Draw both machines (posed at the cursor) or not."""
        self.machines.set_enabled(shown)
        if shown:
            data = self.state.plan
            if data is not None and data.has_schedule and self.machines.machine is None:
                self._show_machines(data)
            self._place(self.state.cursor)
        self.render()

    def follow_target(self, i: int | None = None) -> np.ndarray | None:
        """(3,) mm in W: what the follow camera centres, at sample i (default: the cursor)."""
        data = self.state.plan
        if data is None or not data.has_schedule or self.follow == "off":
            return None
        tl = data.timeline
        i = max(0, min(self.state.cursor if i is None else i, len(tl.t) - 1))
        if self.follow == "left":
            return np.asarray(tl.left.tips[i], float)
        if self.follow == "right":
            return np.asarray(tl.right.tips[i], float)
        return 0.5 * (np.asarray(tl.left.tips[i], float) + np.asarray(tl.right.tips[i], float))

    def _follow(self, target: np.ndarray | None) -> None:
        if target is None:
            return
        cam = self.plotter.camera
        focal = np.asarray(cam.focal_point, float)
        position = np.asarray(cam.position, float)
        cam.focal_point = tuple(target)
        cam.position = tuple(position + (target - focal))
        self.plotter.renderer.ResetCameraClippingRange()

    def set_follow(self, which: str) -> None:
        """'off', 'left', 'right' or 'midpoint' (see FOLLOW)."""
        if which not in FOLLOW:
            raise ValueError(f"unknown camera follow {which!r}: use one of {FOLLOW}")
        self.follow = which
        self._follow(self.follow_target())
        self.render()

    # -- views -----------------------------------------------------------------------------------
    def view(self, name: str) -> None:
        """'front' (along Z_W, onto the face), 'side' (along Y_W, the chord), 'iso', 'bottom' (from
        -Z_W, onto the back, where the left cutter works), 'top' (from the blade tip, +X_W, down the
        span, Z_W up: the section with a cutter either side), or 'fit'. With the follow camera on, the
        view turns and fits, then centres the followed cutter again."""
        p = self.plotter
        if name == "front":
            p.view_xy(render=False)
        elif name == "side":
            p.view_xz(render=False)
        elif name == "iso":
            p.view_isometric(render=False)
        elif name == "bottom":
            p.view_xy(negative=True, render=False)
        elif name == "top":
            p.view_yz(render=False)
        p.renderer.reset_camera(render=False)  # (the plotter's own reset_camera renders, whatever asked)
        self._follow(self.follow_target())
        self.render()

    def render(self) -> None:
        """Ask for a repaint: Qt coalesces the requests of one event-loop pass into one render."""
        if not self._closed:
            if self.raster is not None:
                self.raster.request_render()
            else:
                self.widget.update()

    @property
    def kind(self) -> str:
        """Which 3D view this is, for the About box: the widget and the OpenGL renderer."""
        widget = "off-screen VTK in a raster widget" if self.raster is not None else "pyvistaqt QtInteractor"
        return f"{widget}, OpenGL: {self.opengl or 'as the window got it'}"

    def screenshot(self) -> np.ndarray:
        """(h, w, 3) uint8 of the 3D view as shown at rest (full detail)."""
        self.drag.end()
        self.plotter.render()
        return np.asarray(self.plotter.screenshot(return_img=True))[..., :3]

    def close(self) -> None:
        if not self._closed:
            self.drag.end()  # (no rest timer left to fire on a closed view)
            self._closed = True
            self.widget.removeEventFilter(self)
            if self.raster is not None:
                self.raster.close_view()  # (closes the plotter)
            else:
                self.plotter.close()

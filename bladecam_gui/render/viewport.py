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
from PySide6.QtCore import QObject, Qt, Slot
from PySide6.QtWidgets import QVBoxLayout, QWidget
from pyvistaqt import QtInteractor

from ..plan_data import BladeData, PlanData
from ..state import WorkbenchState
from ..style import BACKGROUND
from .blade_view import BladeView
from .cutters_view import CuttersView
from .frame_axes import FrameAxesView
from .paths_view import PathsView
from .raster_view import RasterView, offscreen_plotter, opengl_renderer, software_opengl

log = logging.getLogger(__name__)


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
            lo, hi = self.blade.bounds()
            self.frame_axes.show(0.25 * float(np.max(hi - lo)))
            self.paths.clear()
            self.cutters.set_visible(False)
            self.view("iso")
        except Exception:  # slots never raise
            log.exception("showing the blade failed")

    @Slot(object)
    def _on_regions_changed(self, data: PlanData) -> None:
        try:
            if data.lines is not self.paths.lines:
                self.paths.show(data.lines)
                self.render()
        except Exception:  # slots never raise
            log.exception("showing the paths failed")

    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            if data.has_schedule:
                p = data.result.plan.params
                self.cutters.set_tool(p.tool_radius, p.tool_length)
                self._place(self.state.cursor)
                self.cutters.set_visible(True)
            else:
                self.cutters.set_visible(False)
            self.render()
        except Exception:  # slots never raise
            log.exception("showing the plan failed")

    @Slot(int)
    def _on_cursor_changed(self, index: int) -> None:
        try:
            self._place(index)
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

    # -- views -----------------------------------------------------------------------------------
    def view(self, name: str) -> None:
        """'front' (along Z_W, onto the face), 'side' (along Y_W, the chord), 'iso', or 'fit'."""
        p = self.plotter
        if name == "front":
            p.view_xy(render=False)
        elif name == "side":
            p.view_xz(render=False)
        elif name == "iso":
            p.view_isometric(render=False)
        p.reset_camera(render=False)
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
        """(h, w, 3) uint8 of the 3D view as shown."""
        self.plotter.render()
        return np.asarray(self.plotter.screenshot(return_img=True))[..., :3]

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            if self.raster is not None:
                self.raster.close_view()  # (closes the plotter)
            else:
                self.plotter.close()

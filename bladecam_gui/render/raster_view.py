"""The 3D view for a software OpenGL: VTK renders off screen and a plain QWidget shows its pixels.

With a software OpenGL (Mesa's llvmpipe: Xvfb, most remote desktops and virtual machines, any machine
without a GPU driver) a QOpenGLWidget anywhere in a window makes Qt compose the whole window through
OpenGL on every repaint, whatever changed: measured on the sample plan, 10-12 ms of a 26-38 ms
timeline-drag frame for a 1500 x 940 window, on top of VTK's own 13-15 ms. Qt keeps composing that
way for the window's lifetime, even once the widget is hidden. Here pyvistaqt's QtInteractor
(a QOpenGLWidget) is replaced by:

- the plotter: a pyvista ``Plotter(off_screen=True)``, the same BasePlotter API the render adapters
  use (add_mesh, remove_actor, camera, screenshot ...), rendering into an off-screen framebuffer;
- ``RasterView``: a QWidget that renders the plotter when it is painted after a change, reads the
  pixels back (0.3 ms for the view's 0.5 Mpx) and draws them; Qt's raster backing store then sends
  only the view's rectangle to the X server;
- the mouse, wheel and key events go to the plotter's VTK interactor (pyvista's trackball style)
  through pyvistaqt's own event translation (``pyvistaqt.rwi.QVTKRenderWindowInteractor``'s
  handlers, reused as they are).

``software_opengl`` tells which OpenGL the plotter got; the Viewport uses this view on a software
OpenGL and pyvistaqt's QtInteractor on a hardware one (docs/DECISIONS.md, "The 3D view").
"""

from __future__ import annotations

import math
import re

import numpy as np
import pyvista as pv
from PySide6.QtCore import Qt, QTimer
from PySide6.QtGui import QColor, QImage, QPainter
from PySide6.QtWidgets import QSizePolicy, QWidget
from pyvistaqt.rwi import QVTKRenderWindowInteractor as _Rwi
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkUnsignedCharArray

#: renderer names of Mesa's software OpenGL drivers (and Windows' and macOS' fallbacks)
SOFTWARE_RENDERERS = ("llvmpipe", "softpipe", "swrast", "software rasterizer", "gdi generic",
                      "microsoft basic render driver", "apple software renderer", "swiftshader")


def opengl_renderer(ren_win) -> str:
    """The OpenGL renderer string of a VTK render window that has rendered once ('' if unknown)."""
    match = re.search(r"OpenGL renderer string:\s*(.+)", ren_win.ReportCapabilities() or "")
    return match.group(1).strip() if match else ""


def software_opengl(renderer: str) -> bool:
    low = renderer.lower()
    return any(name in low for name in SOFTWARE_RENDERERS)


def offscreen_plotter(width: int = 400, height: int = 400) -> pv.Plotter:
    """A pyvista plotter rendering off screen as the workbench's 3D view: no multisampling (a
    software renderer would shade every pixel four times), no default lights (the viewport adds a
    headlight), rendered once so that its OpenGL is known."""
    plotter = pv.Plotter(off_screen=True, window_size=(width, height), lighting="none")
    plotter.ren_win.SetMultiSamples(0)
    plotter._first_time = False  # as pyvistaqt's QtInteractor: render() renders, add_mesh keeps the camera
    plotter.ren_win.Render()
    return plotter


def _while_open(handler):
    """An event handler that passes the event on to ``handler`` while the view has its interactor."""

    def event(self, ev) -> None:
        if self._Iren is not None:
            handler(self, ev)

    return event


class RasterView(QWidget):
    """Shows an off-screen pyvista plotter and passes the input events to its VTK interactor."""

    # pyvistaqt's translation of Qt input events into VTK interactor events (VTK's own
    # QVTKRenderWindowInteractor.py, ported): plain functions on the same state (_Iren, _save_x, ...),
    # called while the view is open (after close_view, events are dropped)
    _GetKeyCharAndKeySym = _Rwi._GetKeyCharAndKeySym
    _GetCtrlShift = _Rwi._GetCtrlShift
    _setEventInformation = _Rwi._setEventInformation
    enterEvent = _while_open(_Rwi.enterEvent)
    leaveEvent = _while_open(_Rwi.leaveEvent)
    mousePressEvent = _while_open(_Rwi.mousePressEvent)
    mouseDoubleClickEvent = _while_open(_Rwi.mousePressEvent)
    mouseReleaseEvent = _while_open(_Rwi.mouseReleaseEvent)
    mouseMoveEvent = _while_open(_Rwi.mouseMoveEvent)
    keyPressEvent = _while_open(_Rwi.keyPressEvent)
    keyReleaseEvent = _while_open(_Rwi.keyReleaseEvent)
    wheelEvent = _while_open(_Rwi.wheelEvent)

    def __init__(self, plotter: pv.Plotter, parent=None):
        super().__init__(parent)
        self.plotter = plotter
        self._Iren = plotter.iren.interactor
        self._active_button = Qt.MouseButton.NoButton
        self._save_x = self._save_y = 0
        self._save_modifiers = Qt.KeyboardModifier.NoModifier
        self._wheel_delta = 0
        self._pixels = vtkUnsignedCharArray()
        self._image: QImage | None = None
        self._image_data: np.ndarray | None = None
        self._stale = True
        self._painting = False
        self.scale = 1.0  # rendered pixels per device pixel, each way (set_scale)
        self._scaled = False
        self._dpi = plotter.ren_win.GetDPI()
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)
        self.setMouseTracking(True)  # (as pyvistaqt's: VTK sees where the pointer is for key picks)
        self.setFocusPolicy(Qt.FocusPolicy.WheelFocus)
        self.setSizePolicy(QSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding))
        self.setMinimumSize(50, 50)
        # every render (asked for here, by the plotter, or by the interactor's camera moves) is shown
        self._observer = plotter.ren_win.AddObserver("EndEvent", self._rendered)
        # the interactor's timers (pyvista's timer events, animated styles), as pyvistaqt's widget
        self._timer = QTimer(self)
        self._timer.timeout.connect(self._timer_event)
        iren = self._Iren
        self._iren_observers = [iren.AddObserver("CreateTimerEvent", lambda *_: self._timer.start(10)),
                                iren.AddObserver("DestroyTimerEvent", self._destroy_timer)]

    def _destroy_timer(self, *_) -> int:
        self._timer.stop()
        return 1

    def _timer_event(self) -> None:
        if self._Iren is not None:
            self._Iren.TimerEvent()

    def _device_size(self) -> tuple[int, int]:
        """The size rendered: the widget's size in device pixels times ``scale`` (rounded up: at scale
        1 the backing store's, never a pixel short)."""
        f = self.devicePixelRatioF() * self.scale
        return max(1, math.ceil(self.width() * f - 1e-9)), max(1, math.ceil(self.height() * f - 1e-9))

    def set_scale(self, scale: float) -> None:
        """Render ``scale`` (0 < scale <= 1) of the view's pixels each way, shown scaled up to the
        widget (bladecam_gui.render.drag_detail: a light frame while the timeline is dragged)."""
        scale = min(1.0, max(0.1, float(scale)))
        if scale != self.scale:
            self.scale = scale
            # (text sizes are in points at the window's DPI: kept in proportion to the view)
            self.plotter.ren_win.SetDPI(max(1, round(self._dpi * scale)))
            self.request_render()

    def request_render(self) -> None:
        """Render at the next paint (Qt coalesces the requests of one event-loop pass into one)."""
        self._stale = True
        self.update()

    def _rendered(self, _obj=None, _event=None) -> None:
        """Read the frame just rendered and show it."""
        ren_win = self.plotter.ren_win
        if ren_win is None:
            return
        w, h = ren_win.GetSize()
        if w < 1 or h < 1:
            return
        ren_win.GetPixelData(0, 0, w - 1, h - 1, 0, self._pixels, 0)
        rgb = vtk_to_numpy(self._pixels)
        if rgb.size != w * h * 3:
            return
        self._image_data = np.ascontiguousarray(rgb.reshape(h, w, 3)[::-1])  # (VTK's rows go up)
        image = QImage(self._image_data.data, w, h, 3 * w, QImage.Format.Format_RGB888)
        image.setDevicePixelRatio(self.devicePixelRatioF())
        fitted = (w, h) == self._device_size()
        self._image = image
        self._scaled = fitted and self.scale != 1.0  # (drawn scaled up over the whole widget)
        # (a frame of another size, e.g. a screenshot at a chosen size, is shown but rendered again)
        self._stale = not fitted
        if not self._painting:
            self.update()

    def _fit(self) -> bool:
        """Size the render window to the widget (device pixels); True if it changed."""
        ren_win = self.plotter.ren_win
        size = self._device_size()
        if tuple(ren_win.GetSize()) == size:
            return False
        ren_win.SetSize(*size)
        self.plotter.iren.interactor.UpdateSize(*size)
        return True

    def resizeEvent(self, ev) -> None:
        self._stale = True
        super().resizeEvent(ev)

    def paintEvent(self, ev) -> None:
        if self.plotter.ren_win is None:  # closed
            QPainter(self).fillRect(self.rect(), QColor("black"))
            return
        if self._fit() or self._stale or self._image is None:
            self._painting = True
            try:
                self.plotter.ren_win.Render()  # -> _rendered
            finally:
                self._painting = False
        painter = QPainter(self)
        if self._image is not None and self._scaled:
            painter.drawImage(self.rect(), self._image)
        elif self._image is not None:
            painter.drawImage(0, 0, self._image)
        else:
            painter.fillRect(self.rect(), QColor("black"))
        painter.end()

    def close_view(self) -> None:
        """Stop showing the plotter's frames and close it, with its OpenGL context and its connection
        to the X server (a render window left to the garbage collector closed its display at exit,
        after a test session's X server had gone: Xlib then ended the process with status 1)."""
        ren_win = self.plotter.ren_win
        self._timer.stop()
        if self._Iren is not None:
            for tag in self._iren_observers:
                self._Iren.RemoveObserver(tag)
        if ren_win is not None:
            if self._observer is not None:
                ren_win.RemoveObserver(self._observer)
            self.plotter.close()
            ren_win.Finalize()
        self._observer = self._Iren = None
        self._iren_observers = []
        self._image = self._image_data = None

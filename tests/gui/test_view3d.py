"""The 3D view's two widgets (bladecam_gui.render.raster_view): on a software OpenGL (Xvfb's llvmpipe
here) an off-screen plotter shown by a raster widget, which shows exactly what VTK rendered and passes
the mouse to VTK's camera; on request (BLADECAM_VIEW=opengl) pyvistaqt's QtInteractor; and a window
closed before its X server goes lets the process exit cleanly."""

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt
from PySide6.QtGui import QImage, QMouseEvent, QWheelEvent

from bladecam_gui.render.raster_view import software_opengl
from bladecam_gui.style import LEFT_COLOUR, RIGHT_COLOUR

from .conftest import COARSE, PLAN_TIMEOUT, hue_mask, side_view_instant, wait_plan

pytestmark = pytest.mark.gui
REPO = Path(__file__).resolve().parents[2]


def _grab(widget) -> np.ndarray:
    """(h, w, 3) uint8 of what the widget paints."""
    img = widget.grab().toImage().convertToFormat(QImage.Format.Format_RGB888)
    w, h = img.width(), img.height()
    return np.frombuffer(img.constBits(), np.uint8, count=img.bytesPerLine() * h).reshape(
        h, img.bytesPerLine())[:, :3 * w].reshape(h, w, 3).copy()


def _mouse(widget, kind, x, y, button, buttons):
    pos = QPointF(x, y)
    widget.event(QMouseEvent(kind, pos, widget.mapToGlobal(pos), button, buttons,
                             Qt.KeyboardModifier.NoModifier))


def test_software_opengl_names():
    assert software_opengl("llvmpipe (LLVM 15.0.6, 256 bits)")
    assert software_opengl("softpipe") and software_opengl("Mesa X11 swrast")
    assert software_opengl("GDI Generic") and software_opengl("SwiftShader Device (Subzero)")
    assert not software_opengl("NVIDIA GeForce RTX 3060/PCIe/SSE2")
    assert not software_opengl("AMD Radeon Pro 5500M OpenGL Engine")
    assert not software_opengl("Mesa Intel(R) UHD Graphics 620 (KBL GT2)")
    assert not software_opengl("")


def test_raster_view_shows_what_vtk_rendered(planned, qtbot):
    w = planned
    vp = w.viewport
    assert software_opengl(vp.opengl), vp.opengl  # Xvfb: Mesa's llvmpipe
    assert vp.raster is not None and vp.widget is vp.raster and "raster widget" in vp.kind
    data = w.state.plan
    both = np.nonzero(data.timeline.left.cutting & data.timeline.right.cutting & ~data.danger)[0]
    w.state.set_cursor(side_view_instant(data))
    tl, i = data.timeline, w.state.cursor
    centre = 0.5 * (tl.left.tips[i] + tl.right.tips[i])
    vp.view("side")
    cam = vp.plotter.camera
    cam.focal_point, cam.position, cam.up = centre, centre + np.array([0.0, -250.0, 0.0]), (1.0, 0.0, 0.0)
    qtbot.wait(50)
    rendered = vp.screenshot()  # VTK's own frame buffer, read by pyvista
    shown = _grab(vp.widget)  # what the widget paints
    assert shown.shape == rendered.shape, (shown.shape, rendered.shape)
    # the same pixels (to the display's depth: pytest-xvfb's server has 16 bits, 5-6-5)
    depth = vp.widget.grab().depth()
    tol = 0 if depth >= 24 else 8
    diff = np.abs(shown.astype(int) - rendered.astype(int))
    assert diff.max() <= tol, (depth, diff.max(), int((diff > tol).any(axis=2).sum()))
    assert hue_mask(shown, LEFT_COLOUR).sum() > 20 and hue_mask(shown, RIGHT_COLOUR).sum() > 20
    # a cursor move repaints the widget with the cutters elsewhere, without asking for a screenshot
    w.state.set_cursor(int(both[len(both) // 4]))
    qtbot.waitUntil(lambda: not np.array_equal(_grab(vp.widget), shown))
    # a resized window renders at the new size
    size = (vp.widget.width(), vp.widget.height())
    w.resize(w.width() - 200, w.height() - 100)
    qtbot.waitUntil(lambda: (vp.widget.width(), vp.widget.height()) != size)
    shown = _grab(vp.widget)
    assert shown.shape[:2] == (vp.widget.height(), vp.widget.width())
    assert tuple(vp.plotter.ren_win.GetSize()) == (vp.widget.width(), vp.widget.height())
    assert np.abs(shown.astype(int) - vp.screenshot().astype(int)).max() <= tol


def test_raster_view_mouse_turns_and_wheel_zooms_the_camera(planned, qtbot):
    vp = planned.viewport
    widget = vp.widget
    cam = vp.plotter.camera
    vp.view("iso")
    qtbot.wait(50)
    before = _grab(widget)
    pos0, focal = np.array(cam.position), np.array(cam.focal_point)
    cx, cy = widget.width() / 2, widget.height() / 2
    left, none = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton
    _mouse(widget, QEvent.Type.MouseButtonPress, cx, cy, left, left)
    for k in range(1, 11):
        _mouse(widget, QEvent.Type.MouseMove, cx + 10 * k, cy, none, left)
    _mouse(widget, QEvent.Type.MouseButtonRelease, cx + 100, cy, left, none)
    pos1 = np.array(cam.position)
    # turned about the focal point: same distance, another direction
    assert np.linalg.norm(pos1 - focal) == pytest.approx(np.linalg.norm(pos0 - focal), rel=1e-6)
    assert np.degrees(np.arccos(np.clip(np.dot(pos0 - focal, pos1 - focal)
                                        / np.linalg.norm(pos0 - focal) ** 2, -1, 1))) > 5.0
    qtbot.waitUntil(lambda: not np.array_equal(_grab(widget), before))
    # the wheel forward brings the camera closer
    dist = np.linalg.norm(np.array(cam.position) - np.array(cam.focal_point))
    centre = QPointF(cx, cy)
    widget.event(QWheelEvent(centre, widget.mapToGlobal(centre), QPoint(0, 0), QPoint(0, 120),
                             Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier,
                             Qt.ScrollPhase.NoScrollPhase, False))
    assert np.linalg.norm(np.array(cam.position) - np.array(cam.focal_point)) < 0.99 * dist


def test_opengl_view_on_request(monkeypatch, qtbot):
    """BLADECAM_VIEW=opengl: pyvistaqt's QtInteractor (what a hardware OpenGL gets), with the plan."""
    from pyvista.plotting import plotter as pv_plotter
    from pyvistaqt import QtInteractor

    from bladecam_gui.main_window import MainWindow
    from core.records import PlanParameters

    monkeypatch.setenv("BLADECAM_VIEW", "opengl")
    before = set(pv_plotter._ALL_PLOTTERS)
    w = MainWindow(params=PlanParameters(**COARSE), debounce_ms=50, restore=False)
    qtbot.addWidget(w)
    try:
        w.resize(1200, 800)
        with qtbot.waitExposed(w):
            w.show()
        assert isinstance(w.viewport.plotter, QtInteractor) and w.viewport.raster is None
        assert "QtInteractor" in w.viewport.kind
        data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
        assert data.has_schedule
        tl = data.timeline
        w.state.set_cursor(side_view_instant(data))
        i = w.state.cursor
        centre = 0.5 * (tl.left.tips[i] + tl.right.tips[i])
        cam = w.viewport.plotter.camera
        cam.focal_point, cam.position, cam.up = centre, centre + np.array([0.0, -250.0, 0.0]), (1.0, 0.0, 0.0)
        img = w.viewport.screenshot()
        assert len(np.unique(img.reshape(-1, 3), axis=0)) > 100
        assert hue_mask(img, LEFT_COLOUR).sum() > 20 and hue_mask(img, RIGHT_COLOUR).sum() > 20
    finally:
        w.close()
    assert w.viewport.plotter._closed
    assert not set(pv_plotter._ALL_PLOTTERS) - before


@pytest.mark.skipif(shutil.which("Xvfb") is None, reason="needs Xvfb")
def test_process_exits_cleanly_after_its_x_server_goes(tmp_path):
    """The workbench closed, then its X server gone (as pytest-xvfb stops its server before the test
    process ends): the process still exits with status 0. A render window left to the garbage
    collector closed its X display at exit, and Xlib ended the process with status 1."""
    read_fd, write_fd = os.pipe()
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "1024x768x24",
                             "-nolisten", "tcp"], pass_fds=(write_fd,), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    os.close(write_fd)
    try:
        with os.fdopen(read_fd) as fh:
            display = fh.readline().strip()
        assert display, "Xvfb gave no display"
        script = tmp_path / "run.py"
        script.write_text(textwrap.dedent(f"""
            import sys
            sys.path.insert(0, {str(REPO)!r})
            from PySide6.QtCore import QEventLoop, QTimer
            from PySide6.QtWidgets import QApplication
            app = QApplication([])
            from bladecam_gui.main_window import MainWindow
            from core.records import PlanParameters
            w = MainWindow(params=PlanParameters(dr={COARSE['dr']}, dd={COARSE['dd']}), debounce_ms=0,
                           restore=False)
            w.show()
            loop = QEventLoop()
            w.controller.idle.connect(loop.quit)
            QTimer.singleShot({PLAN_TIMEOUT}, loop.quit)
            w.open_blade_source("sample")
            loop.exec()
            print("planned" if w.state.plan is not None and w.state.plan.has_schedule else "not planned",
                  flush=True)
            w.close()
            app.processEvents()
            print("closed", flush=True)
            sys.stdin.readline()  # the X server is stopped meanwhile
        """))
        env = dict(os.environ, DISPLAY=f":{display}", QT_QPA_PLATFORM="xcb", QT_API="pyside6")
        proc = subprocess.Popen([sys.executable, str(script)], env=env, stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        lines = [proc.stdout.readline().strip(), proc.stdout.readline().strip()]
        xvfb.terminate()
        xvfb.wait(timeout=30)
        out, err = proc.communicate("\n", timeout=120)
        assert lines == ["planned", "closed"], (lines, err[-2000:])
        assert proc.returncode == 0, err[-2000:]
    finally:
        if xvfb.poll() is None:
            xvfb.kill()
            xvfb.wait()


def test_no_offscreen_rendering_falls_back_to_pyvistaqt(monkeypatch, qtbot):
    """Where no off-screen OpenGL can be made (the plotter fails), the window still opens, with
    pyvistaqt's QtInteractor."""
    from pyvistaqt import QtInteractor

    import bladecam_gui.render.viewport as viewport
    from bladecam_gui.main_window import MainWindow
    from core.records import PlanParameters

    def broken(*args, **kwargs):
        raise RuntimeError("no off-screen OpenGL context")

    monkeypatch.setattr(viewport, "offscreen_plotter", broken)
    w = MainWindow(params=PlanParameters(**COARSE), debounce_ms=50, restore=False)
    qtbot.addWidget(w)
    try:
        with qtbot.waitExposed(w):
            w.show()
        assert isinstance(w.viewport.plotter, QtInteractor) and w.viewport.raster is None
    finally:
        w.close()
    assert w.viewport.plotter._closed


def test_raster_view_after_close_and_at_a_fractional_scale(qtbot):
    """The raster widget alone: input events after close_view are dropped (no error), and at a device
    pixel ratio of 1.5 the render window covers every device pixel of the widget."""
    from bladecam_gui.render.raster_view import RasterView, offscreen_plotter

    plotter = offscreen_plotter()
    view = RasterView(plotter)
    qtbot.addWidget(view)
    try:
        _scaled_then_closed(qtbot, view, plotter)
    finally:
        view.close_view()  # (a plotter left open closes its X display at exit: see the test above)


def _scaled_then_closed(qtbot, view, plotter):
    import sys

    view.resize(255, 255)
    with qtbot.waitExposed(view):
        view.show()
    view.devicePixelRatioF = lambda: 1.5  # (as on a screen scaled by 150 %)
    view.request_render()
    view.repaint()
    assert tuple(plotter.ren_win.GetSize()) == (383, 383)  # 255 * 1.5 = 382.5: rounded up, not down
    errors = []
    view.close_view()
    assert plotter.ren_win is None and view._Iren is None
    hook = sys.excepthook
    sys.excepthook = lambda *exc: errors.append(exc)
    try:
        _mouse(view, QEvent.Type.MouseMove, 10, 10, Qt.MouseButton.NoButton, Qt.MouseButton.NoButton)
        left = Qt.MouseButton.LeftButton
        _mouse(view, QEvent.Type.MouseButtonPress, 10, 10, left, left)
        view.repaint()
    finally:
        sys.excepthook = hook
    assert errors == []

"""The 3D view's level of detail while the timeline is dragged (bladecam_gui.render.drag_detail):
light copies of the blade and the paths (and fewer pixels) during the drag, the cutters where the plan
puts them, the full scene back at the release and when the cursor rests."""

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt
from PySide6.QtGui import QMouseEvent
from PySide6.QtWidgets import QApplication

import bladecam_gui.render.drag_detail as drag_detail

from .test_timeline import assert_cutters_at

pytestmark = pytest.mark.gui


def press(qtbot, bar, x: int) -> None:
    qtbot.mousePress(bar, Qt.MouseButton.LeftButton, pos=QPoint(x, bar.height() // 3))


def move(bar, x: float) -> None:
    pos = QPointF(float(x), bar.height() / 3)
    QApplication.sendEvent(bar, QMouseEvent(QEvent.Type.MouseMove, pos, bar.mapToGlobal(pos),
                                            Qt.MouseButton.NoButton, Qt.MouseButton.LeftButton,
                                            Qt.KeyboardModifier.NoModifier))


def release(qtbot, bar, x: int) -> None:
    qtbot.mouseRelease(bar, Qt.MouseButton.LeftButton, pos=QPoint(x, bar.height() // 3))


def kept(n: int, stride: int) -> int:
    """Grid lines kept along a direction of n: every stride-th and the last."""
    return len(set(range(0, n, stride)) | {n - 1})


def full_scene(w) -> dict:
    """Cells of the blade's surfaces (the grids' quads) and of the shown paths, computed from the plan."""
    out = {}
    for key, grid in (("face", w.state.plan.blade.face), ("back", w.state.plan.blade.back)):
        out[f"blade-{key}"] = (grid.shape[0] - 1) * (grid.shape[1] - 1)
    out["paths"] = len(w.state.plan.lines.cells) // 3
    return out


def test_a_drag_shows_light_actors_and_the_release_the_full_scene(planned, qtbot, monkeypatch):
    w = planned
    vp, bar = w.viewport, w.timeline.bar
    full = full_scene(w)
    assert vp.drag.shown() == full
    # (the coarse sample plan's paths are few: a budget of a fifth of them makes the light copy thin them)
    monkeypatch.setattr(drag_detail, "PATH_SEGMENTS", full["paths"] // 5)
    vp.drag.set_rest_ms(600_000)  # (the cursor never rests during this drag, however slow the machine)
    x0, x1 = int(bar.width() * 0.3), int(bar.width() * 0.6)
    press(qtbot, bar, x0)
    assert not vp.drag.light  # (a press alone, a click's jump: drawn in full)
    actors = [*vp.blade.actors.values(), vp.paths.actor]
    with qtbot.waitSignal(vp.drag.changed, timeout=5000) as light:
        move(bar, x0 + 5)
    assert light.args == [True] and vp.drag.light
    for x in np.linspace(x0 + 5, x1, 5)[1:]:
        move(bar, x)
    shown = vp.drag.shown()
    for key in ("face", "back"):
        n_r, n_c = getattr(w.state.plan.blade, key).shape[:2]
        s = drag_detail.BLADE_STRIDE
        assert shown[f"blade-{key}"] == (kept(n_r, s) - 1) * (kept(n_c, s) - 1) < full[f"blade-{key}"]
    pair = vp.paths.pair
    stride = int(np.ceil(len(pair) / (full["paths"] // 5)))
    assert stride > 1 and shown["paths"] == int((pair % stride == 0).sum())
    if vp.raster is not None:
        assert vp.raster.scale == drag_detail.RENDER_SCALE
        qtbot.waitUntil(lambda: vp.raster.plotter.ren_win.GetSize()[0] < vp.raster.width(), timeout=5000)
    # the moving actors follow the cursor in full
    i = w.state.cursor
    assert i == w.state.plan.index_at(bar.t_of(x1))
    assert_cutters_at(w, i)
    # the release: the full scene again, the actors' own datasets
    with qtbot.waitSignal(vp.drag.changed, timeout=5000) as back:
        release(qtbot, bar, int(x1))
    assert back.args == [False] and not vp.drag.light and not vp.drag.dragging
    assert vp.drag.shown() == full
    # the adapters' own actors are shown again, and nothing else of the blade's or the paths'
    assert [*vp.blade.actors.values(), vp.paths.actor] == actors and all(a.GetVisibility() for a in actors)
    assert not any(light.GetVisibility() for _, light in vp.drag._copies.values())
    if vp.raster is not None:
        assert vp.raster.scale == 1.0
        qtbot.waitUntil(lambda: tuple(vp.raster.plotter.ren_win.GetSize()) == vp.raster._device_size()
                        and vp.raster.plotter.ren_win.GetSize()[0] >= vp.raster.width(), timeout=5000)
    assert_cutters_at(w, i)


def test_the_full_scene_comes_back_when_the_cursor_rests(planned, qtbot):
    w = planned
    vp, bar = w.viewport, w.timeline.bar
    full = full_scene(w)
    vp.drag.set_rest_ms(50)
    x0 = int(bar.width() * 0.4)
    press(qtbot, bar, x0)
    seen = []
    vp.drag.changed.connect(seen.append)
    move(bar, x0 + 20)  # light, then at rest: full while the button is still held
    qtbot.waitUntil(lambda: len(seen) == 2, timeout=10_000)
    assert seen == [True, False]
    assert vp.drag.dragging and not vp.drag.light and vp.drag.shown() == full
    with qtbot.waitSignal(vp.drag.changed, timeout=5000) as again:
        move(bar, x0 + 40)  # moving on: light again
    assert again.args == [True]
    release(qtbot, bar, x0 + 40)
    qtbot.waitUntil(lambda: not vp.drag.light and vp.drag.shown() == full, timeout=5000)


def test_light_frames_off_and_a_screenshot_in_full(planned, qtbot):
    w = planned
    vp, bar = w.viewport, w.timeline.bar
    full = full_scene(w)
    vp.drag.set_rest_ms(600_000)
    vp.drag.enabled = False
    x0 = int(bar.width() * 0.2)
    press(qtbot, bar, x0)
    move(bar, x0 + 30)
    assert not vp.drag.light and vp.drag.shown() == full
    release(qtbot, bar, x0 + 30)
    vp.drag.enabled = True
    press(qtbot, bar, x0)
    move(bar, x0 + 30)
    assert vp.drag.light
    img = vp.screenshot()  # (the report's picture) ends the light frames: the full scene, at full size
    assert not vp.drag.light and vp.drag.shown() == full
    assert img.shape[:2] == (vp.plotter.ren_win.GetSize()[1], vp.plotter.ren_win.GetSize()[0])
    release(qtbot, bar, x0 + 30)

"""The timeline: dragging it places both cutters at their planned positions; step jumps; plot clicks;
play."""

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt
from PySide6.QtGui import QMouseEvent
from PySide6.QtWidgets import QApplication

from .conftest import PLAN_TIMEOUT

pytestmark = pytest.mark.gui


def drag(qtbot, widget, x0: int, x1: int, steps: int = 6) -> None:
    """Press at x0, move with the left button held to x1, release (mid-height)."""
    y = widget.height() // 3
    qtbot.mousePress(widget, Qt.MouseButton.LeftButton, pos=QPoint(x0, y))
    for x in np.linspace(x0, x1, steps)[1:]:
        pos = QPointF(float(x), float(y))
        event = QMouseEvent(QEvent.Type.MouseMove, pos, widget.mapToGlobal(pos), Qt.MouseButton.NoButton,
                            Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier)
        QApplication.sendEvent(widget, event)
    qtbot.mouseRelease(widget, Qt.MouseButton.LeftButton, pos=QPoint(x1, y))


def assert_cutters_at(window, i: int) -> None:
    tl = window.state.plan.timeline
    for side, s in (("left", tl.left), ("right", tl.right)):
        m = window.viewport.cutters.matrix(side)
        np.testing.assert_allclose(m[:3, 3], s.tips[i], atol=1e-9)   # the tip (local origin)
        np.testing.assert_allclose(m[:3, 2], s.axes[i], atol=1e-9)   # the tool axis (local +Z)
        np.testing.assert_allclose(m[:3, :3].T @ m[:3, :3], np.eye(3), atol=1e-9)


def test_drag_moves_both_cutters_to_the_planned_positions(planned, qtbot):
    w = planned
    bar = w.timeline.bar
    tl = w.state.plan.timeline
    seen = []
    for frac0, frac1 in ((0.1, 0.55), (0.55, 0.8)):
        x0, x1 = int(bar.width() * frac0), int(bar.width() * frac1)
        drag(qtbot, bar, x0, x1)
        i = w.state.cursor
        assert i == w.state.plan.index_at(bar.t_of(x1))
        assert abs(tl.t[i] - bar.t_of(x1)) <= np.diff(tl.t).max()
        assert_cutters_at(w, i)
        seen.append({s: w.viewport.cutters.matrix(s)[:3, 3].copy() for s in ("left", "right")})
        # the read-out states the instant (it follows a drag a few times a second)
        spacing = f"tip spacing {w.state.plan.spacing[i]:.3f} mm"
        qtbot.waitUntil(lambda s=spacing: s in w.timeline.readout.text())
        text = w.timeline.readout.text()
        assert f"step {w.state.plan.step[i]}" in text and f"path {tl.left.path[i]}" in text
    for side in ("left", "right"):
        assert not np.allclose(seen[0][side], seen[1][side])
    # the keyboard moves it too (a shortcut of the window: it has to be the active one)
    before = w.state.cursor
    w.activateWindow()
    qtbot.waitUntil(w.isActiveWindow)
    bar.setFocus()
    qtbot.keyClick(bar, Qt.Key.Key_Right)
    assert w.state.cursor > before
    assert_cutters_at(w, w.state.cursor)


def test_step_buttons_jump_to_step_starts(planned, qtbot):
    w = planned
    data = w.state.plan
    # each step's first band, in time order
    starts = sorted(data.bands[np.flatnonzero(data.bands[:, 2] == k)[0], 0] for k in range(1, 8))
    w.state.set_cursor(0)
    for expected in starts[1:4]:
        qtbot.mouseClick(w.timeline.next_button, Qt.MouseButton.LeftButton)
        assert w.state.cursor_time == pytest.approx(expected)
        assert w.timeline.bar.step_at(w.state.cursor_time) == data.step[w.state.cursor]
    qtbot.mouseClick(w.timeline.prev_button, Qt.MouseButton.LeftButton)
    assert w.state.cursor_time == pytest.approx(starts[2])
    assert_cutters_at(w, w.state.cursor)


def test_clicking_the_spacing_plot_jumps_the_timeline(planned, qtbot):
    from bladecam_gui.widgets.plots import MS

    w = planned
    plot = w.spacing_plot
    tl = w.state.plan.timeline
    w.state.set_cursor(0)
    target = 0.62 * tl.t[-1] / MS  # plot units (minutes)
    vb = plot.view_box
    pos = plot.mapFromScene(vb.mapViewToScene(QPointF(target, 1.0)))
    qtbot.mouseClick(plot.viewport(), Qt.MouseButton.LeftButton, pos=pos)
    t = w.state.cursor_time / MS
    pixel = (vb.viewRange()[0][1] - vb.viewRange()[0][0]) / vb.width()
    assert abs(t - target) < 3 * pixel + np.diff(tl.t).max() / MS
    qtbot.waitUntil(lambda: plot.cursor.value() == pytest.approx(w.state.cursor_time / MS)
                    and w.feed_plot.cursor.value() == pytest.approx(w.state.cursor_time / MS))
    assert_cutters_at(w, w.state.cursor)


def test_play_advances_and_pauses(planned, qtbot):
    w = planned
    w.state.set_cursor(0)
    w.timeline.speed.setCurrentText("1000×")
    qtbot.mouseClick(w.timeline.play_button, Qt.MouseButton.LeftButton)
    assert w.timeline.play_button.isChecked()
    qtbot.waitUntil(lambda: w.state.cursor_time > 5000.0, timeout=PLAN_TIMEOUT)
    qtbot.mouseClick(w.timeline.play_button, Qt.MouseButton.LeftButton)
    stopped = w.state.cursor
    assert not w.timeline._timer.isActive() and not w.timeline.play_button.isChecked()
    QApplication.processEvents()
    assert w.state.cursor == stopped
    assert_cutters_at(w, stopped)


def test_plots_ranges_set_before_the_curves(window, qtbot, monkeypatch):
    """The first plan of a window: the spacing plot shows the whole job, the feed plot a window round
    the cursor, each curve holding every sample, and each curve is clipped and downsampled about once,
    not once per range change."""
    import pyqtgraph as pg

    from bladecam_gui.plan_data import new_planner, prepare
    from bladecam_gui.widgets.plots import FEED_PLOT_TOP, MS

    from .conftest import _CACHE

    w = window
    if "sample" not in _CACHE:
        _CACHE["sample"] = prepare(w.state.job(), None, new_planner())
    data = _CACHE["sample"]
    assert data.job == w.state.job()
    passes = []
    real = pg.PlotDataItem._getDisplayDataset

    def counted(item):
        if item._dataset is not None and len(item._dataset.x) > 0:  # (empty curves cost nothing)
            passes.append(item)
        return real(item)

    curves = [w.spacing_plot.spacing_curve, w.spacing_plot.clearance_curve, w.spacing_plot.violation_curve,
              w.feed_plot.left_curve, w.feed_plot.right_curve]
    axes_curves = list(w.axes_plot.curves.values())
    monkeypatch.setattr(pg.PlotDataItem, "_getDisplayDataset", counted)
    w.state.set_plan(data)
    assert sum(p in curves for p in passes) <= 2 * len(curves)  # 27 when the ranges were set after the curves
    assert sum(p in axes_curves for p in passes) <= 2 * len(axes_curves)  # (the machine axes plot's)
    for c in curves:
        assert len(c.getOriginalDataset()[0]) == len(data.timeline.t)
    end = float(data.timeline.t[-1]) / MS
    (x0, x1), (y0, y1) = w.spacing_plot.view_box.viewRange()
    h = data.result.plan.params.h_safe
    assert x0 <= 0.0 < end <= x1 and x1 - x0 < 1.05 * end
    assert y0 <= min(-0.1 * h, float(data.clearance.min())) and y1 >= 8.0 * h
    # round the cursor, kept inside the job: at its start the window starts at 0 (never a negative time)
    assert w.state.cursor == 0
    qtbot.waitUntil(lambda: abs(w.feed_plot.view_box.viewRange()[0][0]) < 1e-9)
    (x0, x1), (y0, y1) = w.feed_plot.view_box.viewRange()
    assert x0 == pytest.approx(0.0, abs=1e-9)
    assert x1 - x0 == pytest.approx(w.feed_plot.WINDOW_MIN) and y1 == pytest.approx(
        FEED_PLOT_TOP * data.result.plan.params.feed)

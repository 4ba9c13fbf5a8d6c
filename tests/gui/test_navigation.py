"""Finding a moment: the timeline zooms and pans, the jumps (contour, step, violation, minimum) land
on the right samples, the keyboard works from anywhere in the window, the Help menu lists it; and
the defects of the first series (a plan switch, failed files in Recent blades, the status's verdict
on a plan that is hardly collaborative)."""

import numpy as np
import pytest
from PySide6.QtCore import QEvent, QPoint, QPointF, Qt
from PySide6.QtGui import QColor, QWheelEvent
from PySide6.QtWidgets import QApplication

from bladecam_gui.style import DANGER_COLOUR

from .conftest import PLAN_TIMEOUT, wait_plan
from .test_timeline import assert_cutters_at

pytestmark = pytest.mark.gui

_SYMMETRIC: dict = {}


def active(window, qtbot):
    """The window active (window shortcuts need it, as for an operator)."""
    window.activateWindow()
    qtbot.waitUntil(window.isActiveWindow)
    return window


def key(qtbot, widget, k, modifier=Qt.KeyboardModifier.NoModifier):
    qtbot.keyClick(widget, k, modifier)
    QApplication.processEvents()


def is_red(c: QColor) -> bool:
    red = QColor(DANGER_COLOUR)
    return all(abs(a - b) < 12 for a, b in zip(c.getRgb()[:3], red.getRgb()[:3], strict=True))


def wheel(widget, x: float, clicks: float, modifiers=Qt.KeyboardModifier.NoModifier) -> None:
    pos = QPointF(x, widget.height() / 2)
    event = QWheelEvent(pos, widget.mapToGlobal(pos), QPoint(0, 0), QPoint(0, int(120 * clicks)),
                        Qt.MouseButton.NoButton, modifiers, Qt.ScrollPhase.NoScrollPhase, False)
    QApplication.sendEvent(widget, event)


def symmetric(window, qtbot):
    """The window showing the sample's coarse symmetric plan (planned once per session)."""
    if "plan" in _SYMMETRIC:
        window.params_panel.combos["mode"].setCurrentText("symmetric")
        window.controller.cancel()
        window.state.set_plan(_SYMMETRIC["plan"])
        qtbot.waitUntil(lambda: not window.state.stale and not window.controller.running)
    else:
        _SYMMETRIC["plan"] = wait_plan(qtbot, window,
                                       lambda: window.params_panel.combos["mode"].setCurrentText("symmetric"))
    data = window.state.plan
    assert data.result.plan.params.mode == "symmetric"
    return data


def test_wheel_zooms_round_the_mouse_drag_pans_fit_restores(planned, qtbot):
    w = planned
    bar, data = w.timeline.bar, w.state.plan
    end = float(data.timeline.t[-1])
    assert (bar.view0, bar.view1) == (0.0, pytest.approx(end))
    x = 0.6 * bar.width()
    t_under = bar.t_of(x)
    for _ in range(12):
        wheel(bar, x, 1)
    assert bar.span < 0.1 * end
    assert bar.t_of(x) == pytest.approx(t_under, abs=bar.span / bar.width())  # the time under the mouse stays
    # at this zoom a click lands within a pixel's time of where it is aimed
    qtbot.mouseClick(bar, Qt.MouseButton.LeftButton, pos=QPoint(int(0.3 * bar.width()), bar.height() // 2))
    aimed = bar.t_of(int(0.3 * bar.width()))
    assert abs(w.state.cursor_time - aimed) <= max(bar.span / bar.width(), np.diff(data.timeline.t).max())
    # a right-button drag pans (the cursor stays)
    cursor, v0 = w.state.cursor, bar.view0
    y = bar.height() // 2
    qtbot.mousePress(bar, Qt.MouseButton.RightButton, pos=QPoint(400, y))
    from PySide6.QtGui import QMouseEvent
    move = QMouseEvent(QEvent.Type.MouseMove, QPointF(300, y), bar.mapToGlobal(QPointF(300, y)),
                       Qt.MouseButton.NoButton, Qt.MouseButton.RightButton, Qt.KeyboardModifier.NoModifier)
    QApplication.sendEvent(bar, move)
    qtbot.mouseRelease(bar, Qt.MouseButton.RightButton, pos=QPoint(300, y))
    dragged = 100 / (bar.width() - bar.left - bar.MARGIN) * bar.span
    assert bar.view0 - v0 == pytest.approx(dragged, rel=1e-6) and w.state.cursor == cursor
    # shift + wheel pans too; the fit button shows the whole job again
    v0 = bar.view0
    wheel(bar, x, -1, Qt.KeyboardModifier.ShiftModifier)
    assert bar.view0 > v0
    qtbot.mouseClick(w.timeline.fit_button, Qt.MouseButton.LeftButton)
    assert (bar.view0, bar.view1) == (0.0, pytest.approx(end))


def test_zoomed_view_follows_the_cursor_and_labels_contours(planned, qtbot):
    w = planned
    bar, data = w.timeline.bar, w.state.plan
    tl = data.timeline
    w.state.set_cursor(0)
    for _ in range(6):
        qtbot.mouseClick(w.timeline.zoom_in_button, Qt.MouseButton.LeftButton)
    assert bar.span < 0.1 * tl.t[-1]
    w.state.set_cursor(len(tl.t) - 1)  # a jump out of the view brings the view along
    assert bar.view0 <= tl.t[-1] <= bar.view1
    # the contour numbers under the bands: every start of a left path, as the plan has them
    t, n = bar.contours["left"]
    starts = np.concatenate([[0], np.flatnonzero(np.diff(tl.left.path)) + 1])
    starts = starts[tl.left.path[starts] >= 0]
    np.testing.assert_array_equal(n, tl.left.path[starts])
    np.testing.assert_array_equal(t, tl.t[starts])
    bar.fit()
    # painted: the left cutter's colour shows in the contour row of the bar
    img = bar.grab().toImage()
    top, band_h = bar._band_rect()
    row_y = top + band_h + bar.CONTOUR_H // 2
    colours = {img.pixelColor(x, row_y).name() for x in range(bar.width())}
    assert any(QColor(c).hue() in range(280, 320) for c in colours), colours  # magenta labels


def test_jump_to_contour_n(planned, qtbot):
    w = active(planned, qtbot)
    tl = w.state.plan.timeline
    spin = w.timeline.contour
    w.state.set_cursor(0)
    spin.setFocus()
    spin.lineEdit().selectAll()
    qtbot.keyClicks(spin.lineEdit(), "30")
    key(qtbot, spin.lineEdit(), Qt.Key.Key_Return)
    i = w.state.cursor
    cuts = ((tl.left.path == 30) & tl.left.cutting) | ((tl.right.path == 30) & tl.right.cutting)
    assert cuts[i] and not cuts[:i].any()
    assert_cutters_at(w, i)
    qtbot.waitUntil(lambda: "path 30" in w.timeline.readout.text())


def test_step_boundaries_and_step_starts_by_keyboard(planned, qtbot):
    w = active(planned, qtbot)
    data = w.state.plan
    w.viewport.container.setFocus()  # the 3D view has the keyboard, not the timeline
    w.state.set_cursor(0)
    # PgDown visits the seven steps' first samples in time order, the samples Alt+1 ... Alt+7 go to
    firsts = sorted(int(np.flatnonzero(data.step == k)[0]) for k in range(1, 8))
    for expected in firsts[1:]:
        key(qtbot, w.viewport.container, Qt.Key.Key_PageDown)
        assert w.state.cursor == expected and data.step[expected] != data.step[expected - 1]
        k = int(data.step[expected])
        assert (data.step[:expected] != k).all()  # the first sample of its step
    key(qtbot, w.viewport.container, Qt.Key.Key_PageDown)
    assert w.state.cursor == len(data.step) - 1
    key(qtbot, w.viewport.container, Qt.Key.Key_PageUp)
    assert w.state.cursor == firsts[-1]
    key(qtbot, w.viewport.container, Qt.Key.Key_PageUp)
    assert w.state.cursor == firsts[-2]
    for step in (5, 2, 7):
        key(qtbot, w.viewport.container, Qt.Key.Key_0 + step, Qt.KeyboardModifier.AltModifier)
        i = w.state.cursor
        assert data.step[i] == step and (data.step[:i] != step).all()
    key(qtbot, w.viewport.container, Qt.Key.Key_End)
    assert w.state.cursor == len(data.step) - 1
    key(qtbot, w.viewport.container, Qt.Key.Key_Home)
    assert w.state.cursor == 0


def test_space_and_arrows_work_from_anywhere(planned, qtbot):
    w = active(planned, qtbot)
    w.state.set_cursor(0)
    for widget in (w.spacing_plot, w.viewport.container, w.timeline.speed):
        widget.setFocus()
        key(qtbot, widget, Qt.Key.Key_Space)
        assert w.timeline.play_button.isChecked(), widget
        key(qtbot, widget, Qt.Key.Key_Space)
        assert not w.timeline.play_button.isChecked(), widget
    before = w.state.cursor
    w.spacing_plot.setFocus()
    key(qtbot, w.spacing_plot, Qt.Key.Key_Right)
    assert w.state.cursor > before
    i = w.state.cursor
    key(qtbot, w.spacing_plot, Qt.Key.Key_Right, Qt.KeyboardModifier.ShiftModifier)
    assert w.state.cursor == i + 1
    key(qtbot, w.spacing_plot, Qt.Key.Key_Left, Qt.KeyboardModifier.ShiftModifier)
    assert w.state.cursor == i
    # a text field keeps the keys it types: a space in a spin box does not play
    spin = w.params_panel.spins["feed"]
    spin.setFocus()
    key(qtbot, spin.lineEdit(), Qt.Key.Key_Space)
    assert not w.timeline.play_button.isChecked()


def test_minimum_spacing_and_clearance(planned, qtbot):
    w = planned
    data = w.state.plan
    w.state.set_cursor(0)
    qtbot.mouseClick(w.timeline.min_spacing, Qt.MouseButton.LeftButton)
    assert data.spacing[w.state.cursor] == data.spacing.min()
    qtbot.waitUntil(lambda: f"tip spacing {data.spacing.min():.3f} mm" in w.timeline.readout.text())
    assert f"min spacing {data.spacing.min():.3f} mm" in w.figures.text()
    qtbot.mouseClick(w.timeline.min_clearance, Qt.MouseButton.LeftButton)
    assert data.clearance[w.state.cursor] == data.clearance.min()


def test_violations_none_in_collaborative(planned, qtbot):
    w = active(planned, qtbot)
    data = w.state.plan
    assert not data.danger.any()
    assert not w.timeline.next_violation.isEnabled() and len(w.timeline.bar.violations) == 0
    w.state.set_cursor(10)
    w.viewport.container.setFocus()
    key(qtbot, w.viewport.container, Qt.Key.Key_V)
    assert w.state.cursor == 10


def test_violations_jumped_to_and_marked_in_symmetric(window, qtbot):
    w = active(window, qtbot)
    data = symmetric(w, qtbot)
    danger = data.danger
    starts = np.flatnonzero(danger & ~np.concatenate([[False], danger[:-1]]))
    assert len(starts) >= 3
    w.state.set_cursor(0)
    w.viewport.container.setFocus()
    for expected in starts[:3]:
        key(qtbot, w.viewport.container, Qt.Key.Key_V)
        assert w.state.cursor == expected and danger[w.state.cursor]
    key(qtbot, w.viewport.container, Qt.Key.Key_V, Qt.KeyboardModifier.ShiftModifier)
    assert w.state.cursor == starts[1]
    qtbot.mouseClick(w.timeline.next_violation, Qt.MouseButton.LeftButton)
    assert w.state.cursor == starts[2]
    qtbot.waitUntil(lambda: "VIOLATION" in w.timeline.readout.text())
    # marked on the timeline itself: red in the marks' row above the violation, not elsewhere
    bar = w.timeline.bar
    bar.fit()
    img = bar.grab().toImage()
    x = int(bar.x_of(data.timeline.t[starts[0]]))
    assert is_red(img.pixelColor(x, 1))
    safe = np.flatnonzero(~danger)
    gaps = [t for t in data.timeline.t[safe[::50]]
            if not np.any(np.abs(bar.violations - t).min(axis=1) < 3 * bar.span / bar.width())
            and not np.any((bar.violations[:, 0] <= t) & (t <= bar.violations[:, 1]))]
    assert gaps and not is_red(img.pixelColor(int(bar.x_of(gaps[0])), 1))


def test_help_lists_the_shortcuts(planned, qtbot):
    from bladecam_gui.widgets.shortcuts import show_shortcuts

    w = planned
    help_menu = [a for a in w.menuBar().actions() if a.text() == "&Help"][0].menu()
    assert any(a.text() == "&Keyboard shortcuts" and a.shortcut().toString() == "F1"
               for a in help_menu.actions())
    dialog = show_shortcuts(w)
    qtbot.addWidget(dialog)
    from PySide6.QtWidgets import QLabel
    text = dialog.findChild(QLabel, "shortcuts-table").text()
    for keys, what in (("Space", "Play / pause"), ("V", "Next violation"), ("Shift+V", "Previous violation"),
                       ("Ctrl+G", "Contour N"), ("F", "Fit the whole job"), ("F5", "Re-plan now")):
        assert f"<b>{keys}</b>" in text and what in text, (keys, what)
    dialog.close()


def test_set_plan_moves_the_cursor_before_announcing_the_plan(window, qtbot):
    """Switching to a shorter plan: every listener of plan_changed reads a cursor inside it."""
    w = window
    sym = symmetric(w, qtbot)
    coll = wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText("collaborative"))
    long, short = sorted((sym, coll), key=lambda d: -len(d.timeline.t))
    assert len(short.timeline.t) < len(long.timeline.t)
    w.state.set_plan(long)
    w.state.set_cursor(len(long.timeline.t) - 1)
    seen, moved = [], []
    w.state.plan_changed.connect(lambda d: seen.append(w.state.cursor < len(d.timeline.t)))
    w.state.cursor_changed.connect(lambda i: moved.append(i))
    w.state.set_plan(short)
    assert seen == [True] and moved == [w.state.cursor] and w.state.cursor == len(short.timeline.t) - 1
    assert_cutters_at(w, w.state.cursor)


def test_a_blade_that_fails_is_not_a_recent_blade(planned, qtbot, tmp_path, dialogs):
    import shutil

    from bladecam_gui.settings import recent
    from core.blade.source import sample_table_path

    w = planned
    bad = tmp_path / "broken.csv"
    bad.write_text("not, a, blade\n")
    with qtbot.waitSignal(w.controller.failed, timeout=PLAN_TIMEOUT):
        w.files.open_blade(str(bad))
    qtbot.waitUntil(lambda: not w.controller.running, timeout=PLAN_TIMEOUT)
    assert not any(str(bad) in e for e in recent("blades"))
    good = tmp_path / "good.csv"
    shutil.copy(sample_table_path(), good)
    wait_plan(qtbot, w, lambda: w.files.open_blade(str(good)))
    assert recent("blades")[0] == f"z|{good}"


def test_status_says_how_collaborative_the_plan_is(planned, qtbot):
    w = planned
    regions = w.state.plan.result.plan.regions
    n, collab = len(regions), sum(not r.is_tip for r in regions)
    assert 0 < collab < n / 2  # the coarse sample: fewer than half
    text = w.figures.text()
    assert f"only {collab} of {n} paths collaborative ({100 * collab / n:.0f} %)" in text
    assert "raise K_max (now 0.15)" in text and w.figures.warning
    data = wait_plan(qtbot, w, lambda: w.params_panel.spins["k_max"].setValue(0.02))
    regions = data.result.plan.regions
    assert not any(not r.is_tip for r in regions)  # brute force: none collaborative
    text = w.figures.text()
    assert f"NOT COLLABORATIVE: all {len(regions)} paths single-sided" in text
    assert "raise K_max (now 0.02)" in text

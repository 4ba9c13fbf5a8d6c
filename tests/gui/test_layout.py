"""The layout gives the 3D view the space: usable at 1280x800 and 1024x700 (the read-out whole), the
side docks give way when the window shrinks, one action hides and brings back the side panels."""

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt
from PySide6.QtWidgets import QDockWidget

from bladecam_gui.widgets.dock_layout import CENTRAL_MIN, side_docks

from .conftest import wait_plan

pytestmark = pytest.mark.gui


def resized(window, qtbot, w: int, h: int):
    window.resize(w, h)
    qtbot.waitUntil(lambda: window.width() == w and window.height() == h)
    qtbot.wait(50)  # (the docks give way on the next turn of the event loop; nothing to wait on)
    return window


def inside_window(window, widget) -> bool:
    top_left = widget.mapTo(window, QPoint(0, 0))
    return (top_left.x() >= 0 and top_left.y() >= 0 and top_left.x() + widget.width() <= window.width()
            and top_left.y() + widget.height() <= window.height())


def readout_lines_fit(timeline) -> bool:
    """Every line of the read-out (two, by design) is no wider than the label shows."""
    from PySide6.QtGui import QTextDocument

    doc = QTextDocument()
    doc.setHtml(timeline.readout.text())
    lines = doc.toPlainText().split("\u2028") if "\u2028" in doc.toPlainText() else \
        doc.toPlainText().splitlines()
    metrics = timeline.readout.fontMetrics()
    width = timeline.readout.width()
    return len(lines) == 2 and all(metrics.horizontalAdvance(line) <= width for line in lines)


@pytest.mark.parametrize("size", [(1280, 800), (1024, 700)])
def test_usable_at_small_screens(planned, qtbot, size):
    w = resized(planned, qtbot, *size)
    view = w.viewport.container
    assert view.isVisible() and view.width() >= CENTRAL_MIN[0] and view.height() >= CENTRAL_MIN[1]
    if size[0] >= 1280:
        assert view.width() >= 0.38 * size[0], view.width()
    # the read-out shown whole: inside the window, both lines fit its width
    w.state.set_cursor(len(w.state.plan.timeline.t) // 2)
    qtbot.waitUntil(lambda: f"sample {w.state.cursor}" in w.timeline.readout.text())
    assert w.timeline.readout.isVisible() and inside_window(w, w.timeline.readout)
    assert readout_lines_fit(w.timeline)
    # the timeline's controls and the 3D view all on screen
    for b in (w.timeline.play_button, w.timeline.fit_button, w.timeline.next_violation, w.timeline.contour):
        assert b.isVisible() and inside_window(w, b), b
    assert inside_window(w, w.timeline.bar) and w.timeline.bar.width() > 0.9 * size[0]
    for dock in w.findChildren(QDockWidget):
        if dock.isVisible() and not dock.isFloating() and not dock.visibleRegion().isEmpty():
            assert inside_window(w, dock), dock.objectName()


def test_side_docks_give_way_when_the_window_shrinks(planned, qtbot):
    w = resized(planned, qtbot, 1600, 900)
    dock = w.params_dock
    w.resizeDocks([dock], [700], Qt.Orientation.Horizontal)  # an operator widened the left panels
    qtbot.waitUntil(lambda: dock.width() >= 650)
    resized(w, qtbot, 1150, 760)
    view = w.viewport.container
    # the 3D view gets half the window back, or the left docks are down to their column's minimum
    column = max(d.minimumSizeHint().width() for d in side_docks(w, Qt.DockWidgetArea.LeftDockWidgetArea))
    qtbot.waitUntil(lambda: view.width() >= 0.5 * 1150 - 4 or dock.width() <= column + 4)
    assert dock.width() < 600 and view.width() >= CENTRAL_MIN[0]


def test_panels_hide_and_come_back(planned, qtbot):
    w = resized(planned, qtbot, 1280, 800)
    shown = [d for d in w.findChildren(QDockWidget) if d.isVisible() and d is not w.timeline_dock]
    assert shown
    before = w.viewport.container.width()
    w.panels_action.trigger()
    qtbot.waitUntil(lambda: w.viewport.container.width() > 0.95 * w.width())
    assert all(not d.isVisible() for d in shown) and w.timeline_dock.isVisible()
    assert w.viewport.container.width() > before
    w.panels_action.trigger()
    qtbot.waitUntil(lambda: all(d.isVisible() for d in shown))
    # and each dock still has its own toggle in the View menu
    view_menu = [a for a in w.menuBar().actions() if a.text() == "&View"][0].menu()
    toggles = {a.text() for a in view_menu.actions()}
    assert {"Parameters", "Timeline", "Plots"} <= toggles


def shown_whole(window, label) -> bool:
    """A label on screen, inside the window, its text no wider than the room it has."""
    text_px = label.fontMetrics().horizontalAdvance(label.text())
    return (label.isVisible() and not label.visibleRegion().isEmpty() and inside_window(window, label)
            and text_px <= label.contentsRect().width())


@pytest.mark.parametrize("size", [(1280, 800), (1024, 700)])
def test_key_figures_always_readable(window, qtbot, size):
    """The verdict, total time, minimum spacing and clearance are shown whole at 1280x800 and
    1024x700: for a safe plan, for an unsafe one (symmetric mode, the longest verdict), while a job
    runs (the progress bar beside them) and while the status bar shows a message."""
    from .test_navigation import symmetric

    w = resized(window, qtbot, *size)
    labels = w.key_figures.labels
    for plan in ("collaborative", "symmetric"):
        if plan == "collaborative":
            data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
        else:
            data = symmetric(w, qtbot)
        fig = data.result.figures
        expected = {"total": f"total {fig['total_time_s'] / 60:.1f} min",
                    "spacing": f"min spacing {fig['min_tip_spacing_mm']:.3f} mm",
                    "clearance": f"min clearance {fig['min_capsule_clearance_mm']:.3f} mm"}
        for name, text in expected.items():
            assert labels[name].text() == text
        verdict = labels["verdict"].text()
        if plan == "collaborative":
            assert verdict == "SAFE" and data.result.safe
        else:
            d = data.danger.astype(int)
            runs = int(np.sum(np.diff(np.concatenate([[0], d])) == 1))  # runs of unsafe samples
            assert not data.result.safe and verdict == f"UNSAFE: {runs} violations"
        qtbot.waitUntil(lambda: all(shown_whole(w, label) for label in labels.values()))
        w.statusBar().showMessage("a long message " * 20, 5000)
        w.progress.set_busy(True)
        w.progress.set_progress(0.42, "planning the paths · about 20 s left")
        qtbot.waitUntil(lambda: w.progress.isVisible())
        qtbot.waitUntil(lambda: all(shown_whole(w, label) for label in labels.values()))
        assert inside_window(w, w.progress.cancel_button)
        w.progress.set_busy(False)
        w.statusBar().clearMessage()


@pytest.mark.parametrize("size", [(1280, 800), (1024, 700)])
def test_tab_titles_and_the_collab_panel_whole(planned, qtbot, size):
    """Every dock tab's title whole (never 'P...'), the Collab. panel's table and ratio plot inside
    its own width (no horizontal scrolling), and Parameters showing every field of a group."""
    from PySide6.QtWidgets import QScrollArea, QTabBar

    w = resized(planned, qtbot, *size)
    w.share_dock.raise_()
    qtbot.waitUntil(lambda: w.share_panel.isVisible())
    bars = [b for b in w.findChildren(QTabBar) if b.isVisible() and b.count()]
    assert bars
    for bar in bars:
        for i in range(bar.count()):
            text = bar.tabText(i)
            assert bar.fontMetrics().horizontalAdvance(text) <= bar.tabRect(i).width(), (text, bar.tabRect(i))
            assert inside_window(w, bar)
    scroll = w.share_panel.findChild(QScrollArea)
    content = scroll.widget()
    assert content.width() <= scroll.viewport().width()
    for cell in w.share_panel.cells.values():
        assert cell.mapTo(scroll.viewport(), QPoint(cell.width(), 0)).x() <= scroll.viewport().width()
    plot = w.share_panel.plot
    assert plot.mapTo(scroll.viewport(), QPoint(plot.width(), 0)).x() <= scroll.viewport().width()
    # the Parameters tab in front again: the Regions group's fields within the column's height
    w.params_dock.raise_()
    spin = w.params_panel.spins["k_max"]
    qtbot.waitUntil(spin.isVisible)
    assert spin.mapTo(w, QPoint(0, spin.height())).y() <= w.params_dock.mapTo(w, QPoint(0, 0)).y() \
        + w.params_dock.height()

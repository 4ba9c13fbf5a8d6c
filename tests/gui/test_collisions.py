"""Collision preview: symmetric mode shows red cutters and marked violations, collaborative none."""

import numpy as np
import pytest
from PySide6.QtGui import QColor

from bladecam_gui.style import DANGER_COLOUR, LEFT_COLOUR, RIGHT_COLOUR

from .conftest import hue_mask, wait_plan

pytestmark = pytest.mark.gui


def colour_of(window, side: str) -> str:
    return QColor.fromRgbF(*window.viewport.cutters.actors[side].prop.color).name()


def test_collaborative_shows_no_collision(planned):
    w = planned
    data = w.state.plan
    assert not data.danger.any() and data.result.safe
    assert len(w.spacing_plot.violation_times) == 0
    assert np.isnan(w.spacing_plot.violation_curve.getOriginalDataset()[1]).all()
    # at the closest approach the cutters keep their colours
    w.state.set_cursor_time(data.result.figures["min_tip_spacing_time_ms"])
    assert colour_of(w, "left") == QColor(LEFT_COLOUR).name()
    assert colour_of(w, "right") == QColor(RIGHT_COLOUR).name()
    assert data.spacing.min() >= data.result.plan.params.h_safe
    assert "UNSAFE" not in w.figures.text()


def test_symmetric_shows_red_cutters_and_violations(planned, qtbot):
    w = planned
    data = wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText("symmetric"))
    assert data.reused == "schedule"  # the same paths, another schedule
    assert data.danger.any() and not data.result.safe
    # the plot marks them: red markers at each violation's start, a red curve over them
    starts = w.spacing_plot.violation_times
    assert len(starts) > 0
    y = w.spacing_plot.violation_curve.getOriginalDataset()[1]
    assert np.isfinite(y).sum() == data.danger.sum()
    assert "UNSAFE" in w.figures.text() and DANGER_COLOUR in w.figures.styleSheet()
    # at the first violation both cutters are red, and the screenshot shows red there
    first = int(np.argmax(data.danger))
    w.state.set_cursor(first)
    assert colour_of(w, "left") == colour_of(w, "right") == QColor(DANGER_COLOUR).name()
    tl = data.timeline
    centre = 0.5 * (tl.left.tips[first] + tl.right.tips[first])
    cam = w.viewport.plotter.camera
    cam.focal_point, cam.position, cam.up = centre, centre + np.array([0.0, -200.0, 0.0]), (1.0, 0.0, 0.0)
    red = hue_mask(w.viewport.screenshot(), DANGER_COLOUR, hue_tol=8).sum()
    w.viewport.cutters.set_visible(False)
    red_without = hue_mask(w.viewport.screenshot(), DANGER_COLOUR, hue_tol=8).sum()
    w.viewport.cutters.set_visible(True)
    assert red - red_without > 200, (red, red_without)
    qtbot.waitUntil(lambda: f"tip spacing {data.spacing[first]:.3f} mm" in w.timeline.readout.text())
    assert DANGER_COLOUR in w.timeline.readout.text()
    # a safe instant: the colours come back
    safe = int(np.argmin(data.danger[first:])) + first
    w.state.set_cursor(safe)
    assert colour_of(w, "left") == QColor(LEFT_COLOUR).name()
    # back to collaborative: none again
    data = wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText("collaborative"))
    assert not data.danger.any() and len(w.spacing_plot.violation_times) == 0

"""Both XYZ-3RPS machines drawn at the cursor (bladecam_gui.render.machines_view) and their axes plotted
(bladecam_gui.widgets.axes_plot): with machine timing on, the drawn legs are the axis table's d1-d3 plus
the home length and the spindle holds the cutter; without it the machines are posed by core's inverse
kinematics of the cutters' pose (and a machine whose cutter is beyond the head's tilt is hidden)."""

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt

from core.errors import MachineError
from core.machine.kinematics import inverse_kinematics
from core.machine.model import AXES

from .conftest import wait_plan

pytestmark = pytest.mark.gui

_AXES_CACHE: dict = {}


@pytest.fixture
def timed(window, qtbot):
    """The window with the sample blade planned with machine timing on (the Parameters box ticked)."""
    box = window.params_panel.axes_box
    qtbot.mouseClick(box, Qt.MouseButton.LeftButton, pos=QPoint(8, box.height() // 2))
    assert window.state.axes
    if "data" in _AXES_CACHE:
        window.controller.cancel()
        window.state.set_plan(_AXES_CACHE["data"])
        qtbot.waitUntil(lambda: window.state.plan is _AXES_CACHE["data"] and not window.state.stale)
    else:
        wait_plan(qtbot, window, lambda: window.open_blade_source("sample"))
        _AXES_CACHE["data"] = window.state.plan
    assert window.state.plan.result.axes is not None
    return window


def _samples(n: int, k: int = 12) -> list[int]:
    return [int(i) for i in np.linspace(0, n - 1, k)]


def test_machine_legs_are_the_axis_tables_at_the_cursor(timed, qtbot):
    w = timed
    data = w.state.plan
    res = data.result
    machines = w.viewport.machines
    w.view_options.boxes["machines"].setChecked(True)
    assert machines.machine is res.machine and "axis tables" in w.view_options.note.text()
    l0 = res.machine.home_leg_length
    for i in _samples(len(data.timeline.t)):
        w.state.set_cursor(i)
        for side in ("left", "right"):
            table = res.axes[side]
            assert machines.visible(side)
            np.testing.assert_allclose(machines.leg_lengths(side), table.values[i, 3:] + l0, atol=1e-6)
            # the carriage sits at the table's x, y, z (the base origin in M, placed in W)
            carriage = machines.matrices[side]["carriage"]
            np.testing.assert_allclose(carriage[:3, 3], res.machine.side(side).to_workpiece(
                table.values[i:i + 1, :3])[0], atol=1e-6)
            # the spindle holds the cutter: platform centre - e w is the drawn cutter's tip
            head = machines.matrices[side]["head"]
            cutter = w.viewport.cutters.matrix(side)
            np.testing.assert_allclose(head[:3, 3] - res.machine.gauge_length * head[:3, 2], cutter[:3, 3],
                                       atol=1e-6)
            np.testing.assert_allclose(head[:3, 2], cutter[:3, 2], atol=1e-8)
            # and the legs (solved from d1-d3) end on the platform's joint circle round that centre
            tops = [machines.matrices[side][f"leg{k}"] @ np.array([0.0, 0.0, 1.0, 1.0]) for k in range(3)]
            for top in tops:
                r = top[:3] - head[:3, 3]
                assert abs(r @ head[:3, 2]) < 1e-6
                assert np.linalg.norm(r) == pytest.approx(res.machine.platform_radius, abs=1e-6)


def test_axes_plot_shows_the_tables_and_the_limits(timed, qtbot):
    w = timed
    data = w.state.plan
    plot = w.axes_plot
    w.axes_dock.raise_()
    assert plot.graphics.isVisible() and not plot.note.isVisible()
    machine = data.result.machine
    for key, column in (("position", "values"), ("speed", "velocities"), ("accel", "accelerations")):
        plot.quantity.setCurrentIndex(plot.quantity.findData(key))
        for k, axis in enumerate(AXES):
            lim = machine.limits.axis(axis)
            expected = {"position": (lim.min_mm, lim.max_mm),
                        "speed": (-lim.max_speed_mm_s, lim.max_speed_mm_s),
                        "accel": (-lim.max_accel_mm_s2, lim.max_accel_mm_s2)}[key]
            assert [line.value() for line in plot.limits[axis]] == pytest.approx(expected)
            for side in ("left", "right"):
                table = data.result.axes[side]
                x, y = plot.curves[(axis, side)].getOriginalDataset()
                factor = {"position": 1.0, "speed": 1e3, "accel": 1e6}[key]
                np.testing.assert_allclose(y, getattr(table, column)[:, k] * factor)
    i = len(data.timeline.t) // 2
    w.state.set_cursor(i)
    plot._throttle.flush()
    qtbot.waitUntil(lambda: all(c.value() == pytest.approx(data.timeline.t[i] / 60000.0)
                                for c in plot.cursors))
    # dragging a cursor line moves the timeline
    plot.cursors[3].setValue(data.timeline.t[i // 2] / 60000.0)
    assert w.state.cursor == i // 2


def test_without_axis_tables_machines_are_posed_by_inverse_kinematics(planned, qtbot):
    w = planned
    data = w.state.plan
    assert data.result.axes is None
    machines = w.viewport.machines
    w.view_options.boxes["machines"].setChecked(True)
    assert "inverse kinematics" in w.view_options.note.text()
    assert not w.axes_plot.graphics.isVisible() and "Machine timing" in w.axes_plot.note.text()
    m = machines.machine
    tl = data.timeline
    reachable = unreachable = 0
    for i in range(0, len(tl.t), max(1, len(tl.t) // 400)):
        w.state.set_cursor(i)
        for side in ("left", "right"):
            s = getattr(tl, side)
            try:
                values = inverse_kinematics(m, side, s.tips[i:i + 1], s.axes[i:i + 1])[0]
            except MachineError:
                unreachable += 1
                assert not machines.visible(side)
                assert f"{side}" in w.view_options.note.text() and "hidden" in w.view_options.note.text()
                continue
            reachable += 1
            assert machines.visible(side)
            np.testing.assert_allclose(machines.leg_lengths(side), values[3:] + m.home_leg_length, atol=1e-6)
    assert reachable > 0 and unreachable > 0  # the sample has tool axes beyond the head's 40 deg

"""Both XYZ-3RPS machines drawn at the cursor (bladecam_gui.render.machines_view) and their axes plotted
(bladecam_gui.widgets.axes_plot) from the plan's axis tables: the drawn legs are the axis table's
d1-d3 plus the home length and the spindle holds the cutter; a result without axis tables hides the
machines and the axes plot shows a note."""

from dataclasses import replace

import numpy as np
import pytest

from core.machine.model import AXES

pytestmark = pytest.mark.gui


def _samples(n: int, k: int = 12) -> list[int]:
    return [int(i) for i in np.linspace(0, n - 1, k)]


def test_machine_legs_are_the_axis_tables_at_the_cursor(planned, qtbot):
    w = planned
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


def test_axes_plot_shows_the_tables_and_the_limits(planned, qtbot):
    w = planned
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
                want = (np.diff(table.velocities, axis=0) / np.diff(table.t)[:, None] if column == "accelerations"
                        else getattr(table, column))
                np.testing.assert_allclose(y, want[:, k] * factor)
    i = len(data.timeline.t) // 2
    w.state.set_cursor(i)
    plot._throttle.flush()
    qtbot.waitUntil(lambda: all(c.value() == pytest.approx(data.timeline.t[i] / 60000.0)
                                for c in plot.cursors))
    # dragging a cursor line moves the timeline
    plot.cursors[3].setValue(data.timeline.t[i // 2] / 60000.0)
    assert w.state.cursor == i // 2


def test_a_result_without_axis_tables_hides_the_machines(planned, qtbot):
    """The workbench's plans always have the axis tables; a result without them (as ``bladecam plan
    --no-axes`` returns) has nothing to pose the machines from: they are hidden and say why, and the
    axes plot shows its note; the next plan with tables shows them again."""
    w = planned
    data = w.state.plan
    assert data.result.axes is not None
    machines = w.viewport.machines
    w.view_options.boxes["machines"].setChecked(True)
    assert machines.visible("left") and machines.visible("right")
    bare = replace(data, result=replace(data.result, axes=None))
    w.state.set_plan(bare)
    w.state.set_cursor(len(bare.timeline.t) // 2)
    assert not machines.visible("left") and not machines.visible("right")
    assert "no axis tables" in w.view_options.note.text()
    assert not w.axes_plot.graphics.isVisibleTo(w.axes_plot) and w.axes_plot.note.isVisibleTo(w.axes_plot)
    assert "timing" not in w.axes_plot.note.text().lower()
    w.state.set_plan(data)
    assert machines.visible("left") and machines.visible("right")
    assert "axis tables" in w.view_options.note.text() and "no axis" not in w.view_options.note.text()
    assert w.axes_plot.graphics.isVisibleTo(w.axes_plot) and not w.axes_plot.note.isVisibleTo(w.axes_plot)


def test_a_hidden_axes_plot_draws_when_shown(planned, qtbot):
    """A plan arriving while the Axes tab lies behind another is drawn when the tab is shown (its
    curves would hold the GUI thread as the plan arrives); the machine meshes are built when the
    machines are first shown and kept across plans of the same machine file."""
    w = planned
    data = w.state.plan
    plot = w.axes_plot
    w.plots_dock.raise_()
    qtbot.waitUntil(lambda: not plot.on_screen)
    w.view_options.boxes["machines"].setChecked(True)
    built = dict(w.viewport.machines.meshes)
    assert built
    copy = replace(data, result=replace(data.result, axes={k: replace(v) for k, v in data.result.axes.items()},
                                        machine=replace(data.result.machine)))
    w.state.set_plan(copy)
    assert plot._pending and plot.graphics.isVisibleTo(plot)
    assert w.viewport.machines.meshes == built  # (an equal machine: not built again)
    w.view_options.boxes["machines"].setChecked(False)
    machine = copy.result.machine
    other = replace(copy, result=replace(copy.result, machine=replace(machine, base_radius=machine.base_radius + 1)))
    w.state.set_plan(other)  # (machines off: nothing built for it)
    assert w.viewport.machines.meshes == built
    w.axes_dock.raise_()
    qtbot.waitUntil(lambda: plot.on_screen and not plot._pending)
    for side in ("left", "right"):
        x, y = plot.curves[(AXES[0], side)].getOriginalDataset()
        np.testing.assert_array_equal(y, copy.result.axes[side].values[:, 0])

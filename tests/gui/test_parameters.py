"""Parameter panels: edits re-plan (reusing paths where they can), warnings, undo / redo, bad values."""

import pytest
from PySide6.QtCore import Qt

from bladecam_gui.style import REGIONS

from .conftest import PLAN_TIMEOUT, wait_plan

pytestmark = pytest.mark.gui


def type_value(qtbot, spin, text: str) -> None:
    """Type a value into a spin box as an operator does: select, type, Enter."""
    spin.setFocus()
    spin.lineEdit().selectAll()
    qtbot.keyClicks(spin.lineEdit(), text)
    qtbot.keyClick(spin.lineEdit(), Qt.Key.Key_Return)


def test_h_safe_changes_regions_and_status(planned, qtbot):
    w = planned
    before = w.state.plan
    counts_before = before.result.plan.region_counts()
    status_before = w.figures.text()
    segments_before = w.viewport.paths.counts()
    drawn = []
    w.state.regions_changed.connect(lambda d: drawn.append((d, w.viewport.paths.counts(), w.state.plan)))
    data = wait_plan(qtbot, w, lambda: type_value(qtbot, w.params_panel.spins["h_safe"], "2.25"))
    # the new regions are drawn first (paths reused), while the previous plan's timeline stays shown
    preview, preview_counts, shown = drawn[0]
    assert not preview.has_schedule and preview.reused == "regions" and shown is before
    assert preview_counts != segments_before
    assert drawn[-1][0] is data and drawn[-1][1] == preview_counts
    assert data.result.plan.params.h_safe == 2.25 and data.reused == "regions"  # paths reused, not re-planned
    counts = data.result.plan.region_counts()
    assert counts != counts_before
    assert counts["tip_paths"] > counts_before["tip_paths"]  # a larger h_safe sends more paths to the tip
    assert w.figures.text() != status_before and f"{counts['tip_paths']} tip" in w.figures.text()
    seg = w.viewport.paths.counts()
    assert seg != segments_before and seg["tip"] > segments_before["tip"]
    assert w.spacing_plot.h_line.value() == pytest.approx(2.25)
    assert not w.state.stale


def test_recommended_ranges_and_warning_colour(window, qtbot):
    panel = window.params_panel
    assert panel.is_warning("dr")  # the coarse test plans use dR = 4 mm > r/4
    assert "r/4 = 0.375 mm" in panel.hints["dr"].text()
    assert "1.5–2.25 mm" in panel.hints["h_safe"].text() and "0.1–0.2" in panel.hints["k_max"].text()
    assert not panel.is_warning("k_max")
    panel.spins["k_max"].setValue(0.3)
    assert panel.is_warning("k_max") and "k_max" in panel.spins["k_max"].toolTip()
    assert "background" in panel.spins["k_max"].styleSheet()
    panel.spins["h_safe"].setValue(1.2)
    assert panel.is_warning("h_safe")
    panel.spins["h_safe"].setValue(1.6)
    assert not panel.is_warning("h_safe") and panel.spins["h_safe"].styleSheet() == ""
    panel.spins["tool_radius"].setValue(16.0)  # now dR = 4 <= r/4: no warning
    assert not panel.is_warning("dr")
    window.controller.cancel()


def test_undo_redo_of_edits(planned, qtbot):
    w = planned
    original = w.state.plan.result.plan.region_counts()
    wait_plan(qtbot, w, lambda: w.params_panel.spins["h_safe"].setValue(2.25))
    changed = w.state.plan.result.plan.region_counts()
    assert changed != original
    assert w.undo_action.isEnabled()
    data = wait_plan(qtbot, w, w.undo_action.trigger)
    assert w.state.params.h_safe == 1.875 and w.params_panel.spins["h_safe"].value() == 1.875
    assert data.result.plan.region_counts() == original
    data = wait_plan(qtbot, w, w.redo_action.trigger)
    assert w.params_panel.spins["h_safe"].value() == 2.25 and data.result.plan.region_counts() == changed
    # the mode combo is undoable too
    wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText("single"))
    assert w.state.plan.result.figures["mode"] == "single"
    wait_plan(qtbot, w, w.undo_action.trigger)
    assert w.params_panel.combos["mode"].currentText() == "collaborative"
    assert w.state.plan.result.figures["mode"] == "collaborative"


def test_quick_edits_plan_once_with_the_last_values(planned, qtbot):
    w = planned
    shown = []
    w.state.plan_changed.connect(shown.append)
    spin = w.params_panel.spins["k_max"]
    data = wait_plan(qtbot, w, lambda: [spin.setValue(v) for v in (0.16, 0.17, 0.18, 0.19)])
    assert data.result.plan.params.k_max == 0.19
    assert len(shown) == 1  # debounced: the intermediate values were never planned
    assert w.editor.stack.count() == 1  # quick edits of one field merge into one undo step
    command = w.editor.stack.command(0)
    assert (command.old, command.new) == (0.15, 0.19)


def test_impossible_value_gives_a_dialog_and_keeps_the_plan(planned, qtbot, dialogs):
    w = planned
    before = w.state.plan
    with qtbot.waitSignal(w.controller.failed, timeout=PLAN_TIMEOUT):
        w.params_panel.spins["h_safe"].setValue(20.0)  # above 10 tool radii: core refuses it
    qtbot.waitUntil(lambda: not w.controller.running, timeout=PLAN_TIMEOUT)
    title, text = dialogs["warning"][-1]
    assert title == "Cannot plan" and "h_safe" in text and "Undo" in text
    assert w.state.plan is before and w.state.stale
    # the status and the field say which input the plan shown does not have
    assert w.figures.text().startswith("[out of date: not planned: h_safe 20 (plan: 1.875)")
    assert w.params_panel.is_unplanned("h_safe") and not w.params_panel.is_unplanned("k_max")
    assert "the plan shown has 1.875" in w.params_panel.spins["h_safe"].toolTip()
    assert len(w.viewport.paths.counts()) == len(REGIONS)  # the previous paths are still drawn
    # still usable: undo goes back and plans again
    data = wait_plan(qtbot, w, w.undo_action.trigger)
    assert data.result.plan.params.h_safe == 1.875 and not w.state.stale
    assert not w.params_panel.is_unplanned("h_safe") and not w.figures.text().startswith("[")


def test_no_machine_timing_switch_every_job_has_the_axis_tables(planned):
    """The panel has no switch between planning modes: every job the workbench plans is timed for the
    machines and carries their axis tables, the plan an export writes."""
    from PySide6.QtWidgets import QAbstractButton

    from bladecam_gui.commands import NAMES

    w = planned
    assert not w.params_panel.findChildren(QAbstractButton)  # (only spin and combo boxes)
    assert not hasattr(w.params_panel, "axes_box") and "axes" not in NAMES
    with pytest.raises(KeyError):
        w.state.set_schedule_option("axes", False)
    assert w.state.job().axes
    res = w.state.plan.result
    assert set(res.axes) == {"left", "right"} and res.warp is not None and res.machine is not None
    assert res.axes["left"].t[-1] == res.timeline.t[-1]


def test_cancel_keeps_the_previous_plan(planned, qtbot):
    w = planned
    before = w.state.plan
    with qtbot.waitSignal(w.state.busy_changed, timeout=PLAN_TIMEOUT):
        w.params_panel.spins["dd"].setValue(0.3)  # new paths: a few seconds of work
    qtbot.mouseClick(w.progress.cancel_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not w.state.busy, timeout=PLAN_TIMEOUT)
    assert w.state.plan is before and w.state.stale
    assert not w.progress.isVisible()


def test_undo_to_a_recent_plan_shows_it_without_planning(planned, qtbot):
    """The controller keeps the last plans by job: undoing an edit back to one of them shows that plan
    at once (the same result, no job started); opening a blade forgets them."""
    w = planned
    first = wait_plan(qtbot, w, lambda: w.params_panel.spins["h_safe"].setValue(2.25))
    second = wait_plan(qtbot, w, lambda: w.params_panel.spins["k_max"].setValue(0.19))
    assert second is not first and second.result.plan.params.k_max == 0.19
    jobs, reused = w.controller._next_id, w.controller.reused_recent
    data = wait_plan(qtbot, w, w.undo_action.trigger)
    assert data is first and w.state.plan is first and not w.state.stale
    assert w.controller._next_id == jobs and w.controller.reused_recent == reused + 1  # nothing planned
    assert w.params_panel.spins["k_max"].value() == 0.15 and w.params_panel.spins["h_safe"].value() == 2.25
    assert w.spacing_plot.h_line.value() == pytest.approx(2.25) and not w.controller.running
    data = wait_plan(qtbot, w, w.redo_action.trigger)
    assert data is second and w.controller._next_id == jobs
    # a blade opened again (its file may have changed) is planned afresh
    wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
    assert w.controller._next_id == jobs + 1
    data = wait_plan(qtbot, w, w.undo_action.trigger) if w.undo_action.isEnabled() else w.state.plan
    assert data is not first


def test_replan_now_plans_afresh_and_kept_plans_keep_to_their_budget(planned, qtbot, monkeypatch):
    """Re-plan now (F5) plans even when a kept plan has the same inputs (machine.toml may have
    changed); kept plans stay within RECENT_BYTES (the newest always kept), so undoing past them
    plans again."""
    import bladecam_gui.worker as worker
    from bladecam_gui.plan_data import plan_bytes

    w = planned
    first = wait_plan(qtbot, w, lambda: w.params_panel.spins["h_safe"].setValue(2.25))
    jobs = w.controller._next_id
    again = wait_plan(qtbot, w, lambda: w.controller.request(immediate=True, fresh=True))
    assert again is not first and w.controller._next_id == jobs + 1
    assert again.result.plan.region_counts() == first.result.plan.region_counts()
    monkeypatch.setattr(worker, "RECENT_BYTES", int(1.5 * plan_bytes(again)))  # room for one plan
    wait_plan(qtbot, w, lambda: w.params_panel.spins["k_max"].setValue(0.19))
    assert len(w.controller._recent) == 1
    jobs = w.controller._next_id
    data = wait_plan(qtbot, w, w.undo_action.trigger)
    assert data is not again and w.controller._next_id == jobs + 1  # planned again, not kept


def test_undo_and_redo_keys_right_after_typing_a_value(planned, qtbot):
    """Ctrl+Z straight after typing a value and Enter (the spin box keeps the focus) undoes the edit
    and plans the previous value again; Ctrl+Y and the platform's redo key bring it back."""
    from PySide6.QtGui import QKeySequence

    from .test_navigation import active

    w = active(planned, qtbot)
    original = w.state.plan.result.plan.region_counts()
    spin = w.params_panel.spins["h_safe"]
    wait_plan(qtbot, w, lambda: type_value(qtbot, spin, "2.25"))
    changed = w.state.plan.result.plan.region_counts()
    assert w.state.params.h_safe == 2.25 and changed != original
    qtbot.waitUntil(spin.hasFocus)  # the operator's keyboard is still in the field
    data = wait_plan(qtbot, w, lambda: qtbot.keyClick(spin.lineEdit(), Qt.Key.Key_Z,
                                                      Qt.KeyboardModifier.ControlModifier))
    assert spin.hasFocus() and spin.value() == 1.875 and w.state.params.h_safe == 1.875
    assert data.result.plan.params.h_safe == 1.875 and data.result.plan.region_counts() == original
    data = wait_plan(qtbot, w, lambda: qtbot.keyClick(spin.lineEdit(), Qt.Key.Key_Y,
                                                      Qt.KeyboardModifier.ControlModifier))
    assert spin.value() == 2.25 and data.result.plan.region_counts() == changed
    # the platform's own redo key too (Ctrl+Shift+Z here), after an undo from the K_max field
    other = w.params_panel.spins["k_max"]
    other.setFocus()
    qtbot.waitUntil(other.hasFocus)
    wait_plan(qtbot, w, lambda: qtbot.keyClick(other.lineEdit(), Qt.Key.Key_Z,
                                               Qt.KeyboardModifier.ControlModifier))
    assert spin.value() == 1.875
    redo = QKeySequence.keyBindings(QKeySequence.StandardKey.Redo)[0][0]
    wait_plan(qtbot, w, lambda: qtbot.keyClick(other.lineEdit(), redo.key(), redo.keyboardModifiers()))
    assert spin.value() == 2.25 and w.state.params.h_safe == 2.25
    # the timeline's contour field hands the keys on as well
    w.timeline.contour.setFocus()
    qtbot.waitUntil(w.timeline.contour.hasFocus)
    wait_plan(qtbot, w, lambda: qtbot.keyClick(w.timeline.contour.lineEdit(), Qt.Key.Key_Z,
                                               Qt.KeyboardModifier.ControlModifier))
    assert spin.value() == 1.875

"""One verdict for everything the plan checks: a tool whose neck cuts into the blade is UNSAFE in the
verdict, the status line, the log, the violation list (kind, part, depth, time), the read-out and the
export's question, with advice about the tool (not K_max or the feed); the Parameters panel names the
tool file; the status line and the verdict count the same violations."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from PySide6.QtCore import Qt
from PySide6.QtWidgets import QFileDialog, QMessageBox

from bladecam_gui.style import DANGER_COLOUR
from bladecam_gui.widgets.step_bar import clock
from core.util.resources import resources_dir

from .conftest import wait_plan

pytestmark = pytest.mark.gui
EXPORT_TIMEOUT = 120_000  # ms: write + bladecam verify of a coarse plan


def fat_neck_tool(folder: Path) -> Path:
    """The shipped tool assembly with a neck 3 mm in radius (the shank's): it cuts into the sample
    blade where the paths tilt most."""
    text = (resources_dir() / "tool.toml").read_text()
    fat, n = re.subn(r"(?m)^neck_radius_mm = [\d.]+", "neck_radius_mm = 3.0", text)
    assert n == 1
    path = folder / "fat_neck.toml"
    path.write_text(fat)
    return path


def with_tool(window, qtbot, path: Path):
    """The window's plan of the sample with the tool file ``path``, opened as an operator does."""
    data = wait_plan(qtbot, window, lambda: window.files.open_tool(path))
    assert data.job.tool == str(path.resolve()) and data.has_schedule
    return data


def test_a_neck_in_the_blade_is_unsafe_everywhere(planned, qtbot, tmp_path):
    w = planned
    assert w.key_figures.labels["verdict"].text() == "SAFE"
    assert "shipped tool.toml" in w.params_panel.tool_label.text()
    data = with_tool(w, qtbot, fat_neck_tool(tmp_path))
    res = data.result
    necks = [c for c in res.clearance.collisions if c.part == "neck" and c.against == "blade"]
    assert necks, "the fat neck must cut into the blade"
    deepest = max(necks, key=lambda c: c.depth)
    # the Parameters panel names the tool file and the neck the plan used
    label = w.params_panel.tool_label.text()
    assert "fat_neck.toml" in label and "neck r 3 " in label
    # the verdict: UNSAFE, red, counting the runs and naming the neck
    n = w.violation_list.model.rowCount()
    assert n >= 1
    verdict = w.key_figures.labels["verdict"]
    assert verdict.text() == f"UNSAFE: {n} violation{'s' if n != 1 else ''}"
    assert DANGER_COLOUR in verdict.styleSheet()
    assert "part – blade" in verdict.toolTip() and f"{deepest.side} neck" in verdict.toolTip()
    # the status line says the same thing (runs, not samples), and the log too
    status = w.figures.text()
    assert verdict.text() in status and "clearance violations" not in status
    assert DANGER_COLOUR in w.figures.styleSheet()
    plan_lines = [text for kind, text in w.job_panel.messages.entries if kind == "plan"]
    assert verdict.text() in plan_lines[-1] and "neck" in plan_lines[-1]
    assert w.job_dock.windowTitle() == "Job ⚠"
    # the list: each row names its kind, the part, the depth and the time
    model = w.violation_list.model
    rows = model.rows
    texts = [[model.text(k, c) for c in range(model.columnCount())] for k in range(n)]
    columns = [model.headerData(c, Qt.Orientation.Horizontal) for c in range(model.columnCount())]
    assert columns[1] == "time" and columns[4] == "kind" and columns[5] == "depth mm" and columns[6] == "part"
    for c in necks:
        k = int(np.flatnonzero((rows["start"] <= c.first) & (c.last <= rows["end"]))[0])
        assert "part – blade" in texts[k][4] and f"{c.side} neck" in texts[k][6]
        assert texts[k][1] == clock(data.timeline.t[rows["start"][k]])
    k = int(np.argmax(rows["depth"]))
    assert f"{deepest.depth:.3f}" in texts[k][5]
    assert f"{deepest.side} neck {deepest.depth:.3f} mm into the blade" in model.tooltip(k)
    # the advice fits the kind: another tool, not K_max, h_safe or the feed
    summary = w.violation_list.summary.text()
    assert "neck" in summary and "tool file" in summary and "K_max" not in summary
    # a click on the deepest goes there, and the read-out names the neck and how deep it is there
    w.job_dock.raise_()
    table = w.violation_list.table
    qtbot.waitUntil(table.isVisible)
    table.scrollTo(model.index(k, 0))
    qtbot.mouseClick(table.viewport(), Qt.MouseButton.LeftButton, pos=table.visualRect(model.index(k, 1)).center())
    assert w.state.cursor == rows["start"][k]
    qtbot.waitUntil(lambda: f"sample {w.state.cursor} " in w.timeline.readout.text())
    readout = w.timeline.readout.text()
    assert "VIOLATION · " in readout and f"{deepest.side} neck" in readout and "into the blade" in readout


def test_the_export_question_gives_the_tool_advice(planned, qtbot, dialogs, tmp_path, monkeypatch):
    w = planned
    data = with_tool(w, qtbot, fat_neck_tool(tmp_path))
    deepest = max(data.result.clearance.collisions, key=lambda c: c.depth)
    dest = tmp_path / "plan"
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", lambda *a, **k: str(dest))
    dialogs["answers"]["question"] = QMessageBox.StandardButton.No
    with qtbot.waitSignal(w.exporter.busy_changed, timeout=EXPORT_TIMEOUT, check_params_cb=lambda busy: not busy):
        w.files.export_dialog()
    assert "collision" in w.exporter.last_report.counts
    title, text = dialogs["question"][-1]
    assert title == "The plan fails verification"
    advice = text.split("What to change:")[1]
    assert "tool file" in advice and "longer neck" in advice and "K_max" not in advice and "feed" not in advice
    assert f"{deepest.side} {deepest.part} {deepest.depth:.3f} mm into the blade" in advice
    assert not dest.exists()


def test_the_status_line_counts_what_the_verdict_counts(window, qtbot):
    from .test_navigation import symmetric

    w = window
    data = symmetric(w, qtbot)
    found = data.violations
    n = found.n
    assert n >= 3 and w.key_figures.labels["verdict"].text() == f"UNSAFE: {n} violations"
    status = w.figures.text()
    assert f"UNSAFE: {n} violations: " in status and "clearance violations" not in status
    # the kinds it names add up with the list's rows (a run may have both)
    counted = {kind: int(m) for m, kind in re.findall(r"(\d+) (tip spacing|tool clearance) \(deepest", status)}
    kinds = w.violation_list.model.rows["kind"]
    for kind, m in counted.items():
        assert m == sum(kind in k for k in kinds)
    assert counted and max(counted.values()) <= n <= sum(counted.values())
    # the advice for the safety rule's kinds, by mode
    assert "collaborative" in w.violation_list.summary.text()

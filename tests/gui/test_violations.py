"""Symmetric mode's read-outs agree: one count of violations (runs of consecutive unsafe samples) in
the status bar, the timeline and the violation list; the list against ``bladecam verify``'s findings
on the written plan; a click on a row goes there; the read-out gives the value at the breach."""

import re

import numpy as np
import pytest
from PySide6.QtCore import Qt

from bladecam_gui.widgets import navigation as nav

from .test_navigation import active, symmetric

pytestmark = pytest.mark.gui


def runs_of(flags: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) sample of each run of True, by walking the samples."""
    out, start = [], None
    for i, f in enumerate(flags):
        if f and start is None:
            start = i
        if not f and start is not None:
            out.append((start, i - 1))
            start = None
    if start is not None:
        out.append((start, len(flags) - 1))
    return out


def test_one_count_and_the_list_against_verify(window, qtbot, tmp_path):
    from core.output.writer import write_result
    from core.verify.check import verify

    w = active(window, qtbot)
    data = symmetric(w, qtbot)
    runs = runs_of(data.danger)
    n = len(runs)
    assert n >= 3
    # one count, everywhere, saying what it counts
    assert w.key_figures.labels["verdict"].text() == f"UNSAFE: {n} violations"
    assert "runs of consecutive time samples" in w.key_figures.labels["verdict"].toolTip()
    assert len(w.timeline.bar.violations) == n and f"{n} in this plan" in w.timeline.next_violation.toolTip()
    assert w.job_dock.windowTitle() == "Job ⚠"
    assert w.violation_list.summary.text().startswith(f"<b>{n} violations</b>: runs of consecutive")
    model = w.violation_list.model
    assert model.rowCount() == n
    rows = model.rows
    assert [(int(a), int(b)) for a, b in zip(rows["start"], rows["end"], strict=True)] == runs
    # against verify's findings on the written plan
    folder = write_result(data.result, tmp_path / "plan", force=True)  # (unsafe: written on purpose)
    rep = verify(folder, surface_stride=400)
    assert rep.counts["tip spacing"] == int(rows["spacing_n"].sum())
    assert rep.counts.get("tool clearance", 0) == int(rows["clearance_n"].sum())
    assert float(rows["min_spacing"].min()) == pytest.approx(rep.figures["min_tip_spacing_mm"], abs=1e-5)
    assert float(rows["min_clearance"].min()) == pytest.approx(rep.figures["min_capsule_gap_mm"], abs=1e-5)
    t0, t1 = rows["t0"], rows["t1"]
    for kind, msg in zip(rep.kinds, rep.findings, strict=True):
        if kind not in ("tip spacing", "tool clearance"):
            continue
        t = float(re.match(r"t = ([\d.]+) ms", msg).group(1))
        k = int(np.flatnonzero((t0 - 0.1 <= t) & (t <= t1 + 0.1))[0])  # in a listed violation ...
        assert kind in rows["kind"][k], (msg, rows["kind"][k])  # ... of that kind
    # each row's text: time, step, both paths, kind, depth
    tl = data.timeline
    k = n // 2
    s = int(rows["start"][k])
    texts = [model.text(k, c) for c in range(model.columnCount())]
    assert texts[2] == str(int(data.step[s])) and texts[3] == f"{tl.left.path[s]} / {tl.right.path[s]}"
    depth = data.result.plan.params.h_safe - min(data.spacing[s:rows["end"][k] + 1].min(),
                                                 data.result.safety.between[s:rows["end"][k]].min(initial=9e9))
    assert f"{max(depth, 0):.3f}" in texts[5] or rows["spacing_n"][k] == 0
    # a click on a row goes to the violation's first sample
    w.state.set_cursor(0)
    table = w.violation_list.table
    w.job_dock.raise_()
    qtbot.waitUntil(table.isVisible)
    table.scrollTo(model.index(k, 0))
    rect = table.visualRect(model.index(k, 1))
    qtbot.mouseClick(table.viewport(), Qt.MouseButton.LeftButton, pos=rect.center())
    assert w.state.cursor == s and data.danger[s]
    qtbot.waitUntil(lambda: "VIOLATION" in w.timeline.readout.text())


def test_readout_gives_the_value_at_the_breach(window, qtbot):
    w = window
    data = symmetric(w, qtbot)
    h = data.result.plan.params.h_safe
    between = data.result.safety.between
    # a violating sample whose own spacing and clearance keep the rule: the breach is between samples
    i = next(i for i in np.flatnonzero(data.danger)
             if data.spacing[i] >= h and data.clearance[i] >= 0 and 0 < i < len(between))
    w.state.set_cursor(i)
    low = min(between[i - 1], between[i])
    assert low < h
    qtbot.waitUntil(lambda: f"sample {i} " in w.timeline.readout.text())
    text = w.timeline.readout.text()
    assert f"VIOLATION · tip spacing {low:.3f} mm between samples" in text
    # symmetric mode: a cutting cutter is 'symmetric', never a collaborative region's name
    j = int(np.flatnonzero(data.timeline.left.cutting & data.timeline.right.cutting)[0])
    w.state.set_cursor(j)
    qtbot.waitUntil(lambda: f"sample {j} " in w.timeline.readout.text())
    sides = w.timeline.readout.text().split("<br>")[1]
    assert sides.count("symmetric") == 2 and " tip" not in sides and "internal" not in sides
    assert nav.violation_list(data)["start"].size == len(runs_of(data.danger))

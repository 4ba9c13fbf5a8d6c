"""The Job tab: the cycle time per step against a walk of the time column, and the messages log
keeping the planner's warnings and the status bar's messages."""

import pytest

from bladecam_gui.style import STEPS

from .conftest import wait_plan

pytestmark = pytest.mark.gui


def test_cycle_time_per_step(planned, qtbot):
    w = planned
    data = w.state.plan
    tl = data.timeline
    walked = dict.fromkeys(STEPS, 0.0)
    t, left, right = tl.t.tolist(), tl.left.step.tolist(), tl.right.step.tolist()
    for i in range(len(t) - 1):
        walked[min(left[i], right[i])] += (t[i + 1] - t[i]) / 1000.0
    rows = w.job_panel.cycle.texts()
    total = t[-1] / 1000.0
    assert len(rows) == 8
    for (name, time_text, share), k in zip(rows, STEPS, strict=False):
        minutes, seconds = time_text.split(":")
        assert name == STEPS[k][0]
        assert int(minutes) * 60 + float(seconds) == pytest.approx(walked[k], abs=0.051)
        assert float(share.rstrip(" %")) == pytest.approx(100 * walked[k] / total, abs=0.051)
    minutes, seconds = rows[-1][1].split(":")
    assert rows[-1][0] == "total" and int(minutes) * 60 + float(seconds) == pytest.approx(total, abs=0.051)


def test_messages_keep_warnings_and_status(planned, qtbot):
    w = planned
    log = w.job_panel.messages
    data = wait_plan(qtbot, w, lambda: w.params_panel.spins["h_safe"].setValue(2.1))
    expected = [*data.result.plan.params.warnings(), *data.result.plan.warnings]
    assert expected  # (dR 4 mm is above r/4: core warns)
    for text in expected:
        assert ("warning", text) in log.entries
        assert text in log.toPlainText()
    assert any(kind == "plan" and f"total {data.result.figures['total_time_s'] / 60:.1f} min" in text
               for kind, text in log.entries)
    # a status message stays in the log after the status bar has cleared it
    w.statusBar().showMessage("exported to /tmp/somewhere", 50)
    qtbot.waitUntil(lambda: w.statusBar().currentMessage() == "")
    assert ("status", "exported to /tmp/somewhere") in log.entries


def test_readout_gives_the_scallop_of_the_contour(planned, qtbot):
    from bladecam_gui.widgets import navigation as nav

    w = planned
    data = w.state.plan
    per = data.result.figures["scallop"]["per_path_max_mm"]
    i = len(data.timeline.t) // 2
    w.state.set_cursor(i)
    qtbot.waitUntil(lambda: f"sample {i} " in w.timeline.readout.text())
    h = per[str(nav.contour_at(data, i))]
    # (the coarse test plans' dR of 4 mm is above 2 r: the balls never meet, a strip is left uncut)
    want = "scallop: a strip uncut (stepover ≥ 2 r)" if h is None else f"scallop {h:.3f} mm"
    assert want in w.timeline.readout.text()

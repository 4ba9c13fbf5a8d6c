"""The Job tab: the cycle time per step against a walk of the time column, and the messages log
keeping the planner's warnings and the status bar's messages."""

import re

import numpy as np
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
    # at the feed: the schedule's own time of each interval (the machine clock's warp), by the same step
    tau = data.result.warp.schedule_t.tolist()
    at_feed = dict.fromkeys(STEPS, 0.0)
    for i in range(len(t) - 1):
        at_feed[min(left[i], right[i])] += (tau[i + 1] - tau[i]) / 1000.0
    rows = w.job_panel.cycle.texts()
    total = t[-1] / 1000.0

    def seconds(text):
        minutes, secs = text.split(":")
        return int(minutes) * 60 + float(secs)

    assert len(rows) == 8
    for (name, time_text, feed_text, share), k in zip(rows, STEPS, strict=False):
        assert name == STEPS[k][0]
        assert seconds(time_text) == pytest.approx(walked[k], abs=0.051)
        assert seconds(feed_text) == pytest.approx(at_feed[k], abs=0.051)
        assert seconds(feed_text) <= seconds(time_text) + 0.05  # the machines never run faster
        assert float(share.rstrip(" %")) == pytest.approx(100 * walked[k] / total, abs=0.051)
    assert rows[-1][0] == "total" and seconds(rows[-1][1]) == pytest.approx(total, abs=0.051)
    assert seconds(rows[-1][2]) == pytest.approx((tau[-1] - tau[0]) / 1000.0, abs=0.051)


def test_the_job_summary_says_how_much_of_the_cutting_crawls(planned, qtbot):
    """The summary line's figures against a walk of the time column: a cutter cuts below the minimum
    feed (by default 30 % of the feed) over an interval where it cuts at its start and covers less than
    min_feed * dt."""
    w = planned
    data = w.state.plan
    tl, fig = data.timeline, data.result.figures
    feed = 0.3 * fig["feed_mm_min"] / 60000.0
    assert f"minimum feed {0.3 * fig['feed_mm_min']:g} mm/min" in w.job_panel.summary.text()
    text = w.job_panel.summary.text()
    shares = {}
    for side in ("left", "right"):
        smp = getattr(tl, side)
        cut = smp.cutting[:-1].astype(bool)
        dt = (tl.t[1:] - tl.t[:-1])
        v = ((smp.tips[1:] - smp.tips[:-1]) ** 2).sum(axis=1) ** 0.5 / dt
        shares[side] = 100 * dt[cut & (v < feed)].sum() / dt[cut].sum()
    found = dict(zip(("left", "right"), (float(x) for x in re.findall(r"(?:left|right) ([0-9.]+) %", text)),
                     strict=True))
    for side in ("left", "right"):
        assert found[side] == pytest.approx(shares[side], abs=0.6), (side, text)
    total = tl.t[-1] / 60000.0
    assert f"on the machines {total:.1f} min" in text


def test_the_slow_paths_list_and_jump(planned, qtbot):
    """The list of paths cut below the minimum feed: one row per path in plan.json's list, in its order;
    each row's seconds against a walk of the time column on that cutter and path; a click puts the
    cursor where the path first runs below the minimum feed, where that cutter cuts that path slowly."""
    w = planned
    data = w.state.plan
    tl, fig = data.timeline, data.result.figures
    items = fig["job"]["below_min_feed"]
    table = w.job_panel.slow
    assert table.rowCount() == len(items) > 0
    min_feed = fig["job"]["min_feed_mm_min"] / 60000.0
    dt = tl.t[1:] - tl.t[:-1]
    for r in (0, table.rowCount() - 1):
        side, path = table.item(r, 0).text(), int(table.item(r, 1).text())
        assert (side, path) == (items[r]["side"], items[r]["path"])
        smp = getattr(tl, side)
        cut = smp.cutting[:-1] & smp.cutting[1:] & (smp.path[:-1] == path) & (smp.path[1:] == path)
        v = ((smp.tips[1:] - smp.tips[:-1]) ** 2).sum(axis=1) ** 0.5 / dt
        assert float(table.item(r, 4).text()) == pytest.approx(dt[cut & (v < min_feed)].sum() / 1000.0, abs=0.06)
        table.cellClicked.emit(r, 0)
        qtbot.waitUntil(lambda r=r: abs(w.state.cursor_time - 1000.0 * items[r]["first_at_s"]) < 1.0)
        k = min(int(np.searchsorted(tl.t, w.state.cursor_time)), len(tl.t) - 2)
        assert smp.path[k] == path and smp.cutting[k]


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


def test_a_long_slow_paths_list_fills_without_freezing_the_window(planned, qtbot):
    """A plan with a thousand paths below the minimum feed (the BladeX mesh has about that many): the
    list fills in one pass, its columns measured once, while the whole window is shown. The bound is
    generous (a loaded machine cannot trip it); measuring each column again for every row took minutes
    behind a relayout of the window per row."""
    import time

    w = planned
    w.show()
    items = [{"side": ("left", "right")[i % 2], "path": i, "step": 5, "first_at_s": 10.0 * i,
              "below_s": 1.0 + i % 7, "lowest_mm_min": 12.5 * (i % 13), "reason": "axes"} for i in range(1000)]
    t0 = time.perf_counter()
    w.job_panel.slow.show_rows({"job": {"below_min_feed": items}})
    qtbot.wait(0)
    assert time.perf_counter() - t0 < 5.0
    assert w.job_panel.slow.rowCount() == 1000
    assert w.job_panel.slow.item(999, 1).text() == "999"
    assert w.job_panel.slow.columnWidth(6) > 0

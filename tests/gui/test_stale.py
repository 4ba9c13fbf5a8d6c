"""Nothing stale: while another blade plans, every panel shows that blade (or nothing), never the
previous blade's plan; an empty plot draws no h_safe of its own."""

import shutil

import pytest

from .conftest import wait_plan

pytestmark = pytest.mark.gui


def snapshot(w) -> dict:
    """What the panels show, read as an operator reads them."""
    sp = w.share_panel
    x, _ = w.spacing_plot.spacing_curve.getData()
    return {
        "title": w.windowTitle(),
        "collab_tab": w.share_dock.windowTitle(),
        "collab_cells": {c.text() for c in sp.cells.values()},
        "collab_reasons": sp.reasons.text(),
        "collab_headline": sp.headline.text(),
        "collab_points": len(sp.plot.points()[0]),
        "k_line": sp.plot.k_line.isVisible(),
        "spacing_points": 0 if x is None else len(x),
        "h_line": w.spacing_plot.h_line.isVisible(),
        "feed_line": w.feed_plot.feed_line.isVisible(),
        "key_figures": {k: v.text() for k, v in w.key_figures.labels.items()},
        "figures": w.figures.text(),
        "violations": w.violation_list.model.rowCount(),
        "job_tab": w.job_dock.windowTitle(),
        "timeline": w.timeline.isEnabled(),
        "bands": len(w.timeline.bar.bands),
        "cutters": any(a.GetVisibility() for a in w.viewport.cutters.actors.values()),
    }


def test_nothing_of_the_previous_blade_while_another_plans(planned, qtbot, tmp_path):
    from core.blade.source import sample_table_path

    w = planned
    before = snapshot(w)
    assert before["collab_reasons"] and before["spacing_points"] and before["h_line"]
    other = tmp_path / "other blade.csv"
    shutil.copy(sample_table_path(), other)
    seen = []

    def on_plan(data):  # (connected after the panels: they have shown this plan already)
        if data.result is None:
            seen.append((data.blade.blade.info()["name"], snapshot(w)))

    w.state.regions_changed.connect(on_plan)  # (the last signal of a plan shown)
    data = wait_plan(qtbot, w, lambda: w.files.open_blade(str(other)))
    assert seen, "the new blade was shown before its plan"
    _, loading = seen[0]
    assert loading["title"].startswith("other blade.csv") and loading["title"] != before["title"]
    assert loading["collab_tab"] == "Collab." and loading["collab_cells"] == {"–"}
    assert loading["collab_reasons"] == "" and loading["collab_headline"] == "planning…"
    assert loading["collab_points"] == 0 and not loading["k_line"]
    assert loading["spacing_points"] == 0 and not loading["h_line"] and not loading["feed_line"]
    assert loading["key_figures"]["verdict"] == "planning…"
    assert {loading["key_figures"][k] for k in ("total", "spacing", "clearance")} == {"–"}
    assert loading["figures"].endswith("blade loaded, planning…")
    assert loading["violations"] == 0 and loading["job_tab"] == "Job"
    assert not loading["timeline"] and loading["bands"] == 0 and not loading["cutters"]
    # and the new plan fills them again
    after = snapshot(w)
    assert data.blade.source == str(other) and after["spacing_points"] and after["h_line"]
    # the lines' labels name the plan's own values
    h, k = data.result.plan.params.h_safe, data.result.plan.params.k_max
    assert w.spacing_plot.h_line.label.textItem.toPlainText() == f"h_safe {h:.3f} mm"
    assert w.share_panel.plot.k_line.label.textItem.toPlainText() == f"K_max {k:.3g}: tip region above"
    assert after["collab_reasons"] and after["key_figures"]["verdict"] == "SAFE"


def test_an_empty_plot_draws_no_h_safe(window):
    """Before any plan: no h_safe line (it would read 'h_safe 0.000 mm'), no feed line, no K_max line."""
    w = window
    assert w.state.plan is None or not w.state.plan.has_schedule
    assert not w.spacing_plot.h_line.isVisible() and not w.feed_plot.feed_line.isVisible()
    assert not w.share_panel.plot.k_line.isVisible()
    w.controller.cancel()

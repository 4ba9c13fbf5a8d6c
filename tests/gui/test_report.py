"""The job report: an HTML file with the blade, tool, machine, parameters, the plan's figures, its
warnings and a picture of the 3D view, each read back from the file against the plan shown."""

import base64
import re
from dataclasses import fields

import numpy as np
import pytest

from bladecam_gui.style import STEPS

pytestmark = pytest.mark.gui


def test_the_report_file(planned, qtbot, tmp_path):
    from PySide6.QtGui import QImage

    w = planned
    data = w.state.plan
    res, fig, p = data.result, data.result.figures, data.result.plan.params
    out = w.report.save(tmp_path / "job.html")
    text = out.read_text(encoding="utf-8")
    info = data.blade.blade.info()
    assert f"Job report: {info['name']}" in text
    assert "<span class='ok'>SAFE</span>" in text and res.safe
    # blade, tool, machine
    assert f"<td>tip radius</td><td>{info['tip_radius_mm']:g} mm</td>" in text
    assert f"<td>ball-nose radius r</td><td>{p.tool_radius:g} mm</td>" in text
    assert f"<td>base radius</td><td>{res.machine.base_radius}</td>" in text
    # every parameter
    for f in fields(p):
        assert f"<td>{f.name}</td><td>{getattr(p, f.name)}</td>" in text, f.name
    # the figures, as the status bar and the Job tab give them
    assert f"<td>total time</td><td>{fig['total_time_s'] / 60:.2f} min</td>" in text
    assert f"{fig['min_tip_spacing_mm']:.3f} mm (h_safe {p.h_safe:g} mm)" in text
    assert f"<td>minimum tool clearance</td><td>{fig['min_capsule_clearance_mm']:.3f} mm</td>" in text
    rows = w.job_panel.cycle.texts()
    assert len(rows) == len(STEPS) + 1
    for name, time_text, feed_text, share in rows:
        assert f"<td>{name}</td><td>{time_text}</td><td>{feed_text}</td><td>{share}</td>" in text
    assert w.job_panel.summary.text() and f"<p>{w.job_panel.summary.text()}</p>" in text
    for warning in [*p.warnings(), *res.plan.warnings]:
        assert f"<li>{warning}</li>" in text
    # the picture: a PNG of the 3D view, the size it is on screen, the blade's colours in it
    png = base64.b64decode(re.search(r"data:image/png;base64,([A-Za-z0-9+/=]+)", text).group(1))
    img = QImage.fromData(png)
    shot = w.viewport.screenshot()
    assert (img.width(), img.height()) == (shot.shape[1], shot.shape[0])
    px = np.array([[img.pixelColor(x, y).getRgb()[:3] for x in range(0, img.width(), 7)]
                   for y in range(0, img.height(), 7)])
    assert len(np.unique(px.reshape(-1, 3), axis=0)) > 20  # a picture, not a blank
    assert not list(tmp_path.glob(".*tmp*"))  # no temporary file left


def test_no_report_without_a_plan(window, tmp_path, dialogs):
    w = window  # (a new window plans nothing until a blade is opened)
    assert w.state.plan is None
    assert w.report.save(tmp_path / "job.html") is None
    assert dialogs["warning"][-1][0] == "Cannot save the report"
    assert "no plan to report yet" in dialogs["warning"][-1][1]
    assert not (tmp_path / "job.html").exists()


def test_a_report_that_cannot_be_written(planned, tmp_path, dialogs):
    target = tmp_path / "no such folder" / "job.html"
    assert planned.report.save(target) is None
    title, text = dialogs["warning"][-1]
    assert title == "Cannot save the report" and f"cannot write the report {target}" in text
    assert not target.parent.exists()

"""A written plan folder opened read-only for review (File > Open plan folder…, ``bladecam gui FOLDER``):
the tables as the files hold them, both machines' rows at the cursor, verify's findings; the folder is
never written and the workbench's own plan stays as it is. A folder that is not a plan folder is a
message naming what is missing, not an empty window."""

from __future__ import annotations

import hashlib
import subprocess
import sys

import numpy as np
import pytest

from ..conftest import REPO
from .conftest import PLAN_TIMEOUT

VERIFY_TIMEOUT = 600_000  # ms: verify of a coarse plan takes seconds; generous for a loaded machine


@pytest.fixture(scope="module")
def plan_folder(coarse_plan):
    return coarse_plan.folder  # (the sample's coarse plan with its axis tables, once per session)


def _digests(folder) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def _csv(path) -> tuple[list[str], list[list[str]]]:
    lines = path.read_text().splitlines()
    return lines[0].split(","), [ln.split(",") for ln in lines[1:]]


def test_open_plan_folder_shows_the_tables_machines_and_findings(window, qtbot, plan_folder, monkeypatch):
    from PySide6.QtCore import Qt
    from PySide6.QtWidgets import QMessageBox

    from core.verify.check import verify

    warnings = []
    monkeypatch.setattr(QMessageBox, "warning", lambda *a, **k: warnings.append(a))
    before = _digests(plan_folder)
    shown_plan, job = window.state.plan, window.state.job()
    titles = [a.text() for a in window.menuBar().actions()[0].menu().actions()]
    assert "Open plan &folder…" in titles
    review = window.files.open_plan_folder(plan_folder)
    assert not warnings and review is not None and review.isVisible()
    with qtbot.waitSignal(review.verified, timeout=VERIFY_TIMEOUT) as got:
        pass
    report = got.args[0]
    expected = verify(plan_folder)
    assert report.summary() == expected.summary() == review.verify_label.text().split("</b>: ")[1].split("<br>")[0]
    assert [review.findings.item(i).text() for i in range(review.findings.count())] == (
        [f"{k}: {line}" for k, line in zip(expected.kinds, expected.findings, strict=True)]
        or ["no findings: the tables keep every rule verify checks"])
    # the tables as written: every tab's cells are the file's text
    for name in ("left_cl.csv", "right_cl.csv", "left_axes.csv", "right_axes.csv"):
        head, rows = _csv(plan_folder / name)
        model = review.views[name].model()
        assert model.rowCount() == len(rows) and model.columnCount() == len(head)
        assert [model.headerData(c, Qt.Orientation.Horizontal) for c in range(len(head))] == head
        for i in (0, len(rows) // 3, len(rows) - 1):
            assert [model.data(model.index(i, c)) for c in range(len(head))] == rows[i]
    # the machines at the cursor: their axis rows and their cutters' rows at that time
    i = len(_csv(plan_folder / "left_cl.csv")[1]) // 2
    review.slider.setValue(i)
    assert review.cursor == i
    for r, side in enumerate(("left", "right")):
        axes = np.array(_csv(plan_folder / f"{side}_axes.csv")[1][i], float)
        cl = _csv(plan_folder / f"{side}_cl.csv")[1][i]
        cells = [review.machines.item(r, c).text() for c in range(review.machines.columnCount())]
        np.testing.assert_allclose([float(v) for v in cells[:6]], axes[1:7], atol=5e-5)
        assert cells[6:10] == [cl[1], cl[2], cl[3], "yes" if cl[4] == "1" else "no"]
        np.testing.assert_allclose([float(v) for v in cells[10:13]], np.array(cl[5:8], float), atol=5e-5)
    tips = [np.array(_csv(plan_folder / f"{s}_cl.csv")[1][i][5:8], float) for s in ("left", "right")]
    shown = float(review.cursor_label.text().split("tip spacing ")[1].split(" mm")[0])
    assert shown == pytest.approx(np.linalg.norm(tips[0] - tips[1]), abs=1e-4)
    # read-only: what the window says, the folder untouched, the workbench's plan and inputs as they were
    assert "Read-only review" in review.header.text() and "blade.stl" in review.header.text()
    review.close()
    assert _digests(plan_folder) == before
    assert window.state.plan is shown_plan and window.state.job() == job


def test_a_folder_that_is_not_a_plan_is_a_message(window, tmp_path, monkeypatch):
    from PySide6.QtWidgets import QMessageBox

    warnings = []
    monkeypatch.setattr(QMessageBox, "warning", lambda *a, **k: warnings.append(a))
    (tmp_path / "notes.txt").write_text("not a plan")
    assert window.files.open_plan_folder(tmp_path) is None
    assert len(warnings) == 1 and "no plan.json" in warnings[0][2]
    assert window.files.review_windows == []


def test_gui_on_a_plan_folder_opens_the_review_and_its_picture(plan_folder, tmp_path):
    """``bladecam gui FOLDER --screenshot PNG`` (a fresh process under the test's X server): the review
    window alone, pictured once verify has reported; a folder without a plan is one line, status 2."""
    png = tmp_path / "review.png"
    done = subprocess.run([sys.executable, "-m", "bladecam_gui", str(plan_folder), "--screenshot", str(png)],
                          cwd=REPO, capture_output=True, text=True, timeout=PLAN_TIMEOUT / 1000 * 10)
    assert done.returncode == 0, done.stderr
    assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    bad = subprocess.run([sys.executable, "-m", "bladecam_gui", str(tmp_path)], cwd=REPO, capture_output=True,
                         text=True, timeout=PLAN_TIMEOUT / 1000 * 10)
    assert bad.returncode == 2 and "no plan.json" in bad.stderr and "Traceback" not in bad.stderr

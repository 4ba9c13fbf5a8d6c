"""Export through the (patched) folder dialog: the plan shown written as it is (nothing planned again),
the same files as ``bladecam plan``; verification findings refuse the export unless the operator
overrides; nothing is ever half-written."""

import json
import subprocess
import sys

import numpy as np
import pytest
from PySide6.QtWidgets import QFileDialog, QMessageBox

from bladecam_gui.widgets.step_bar import clock
from core.planner import Planner
from tests.conftest import REPO

from .conftest import COARSE, PLAN_TIMEOUT, wait_plan

pytestmark = pytest.mark.gui
EXPORT_TIMEOUT = 120_000  # write + bladecam verify of a coarse plan


@pytest.fixture
def folder_dialog(monkeypatch):
    answer = {"folder": ""}
    monkeypatch.setattr(QFileDialog, "getExistingDirectory", lambda *a, **k: answer["folder"])
    return answer


def export(qtbot, window, folder_dialog, dest):
    folder_dialog["folder"] = str(dest)
    action = [a for a in window.menuBar().actions()[0].menu().actions() if a.text().startswith("&Export")][0]
    with qtbot.waitSignal(window.exporter.busy_changed, timeout=EXPORT_TIMEOUT,
                          check_params_cb=lambda busy: not busy):
        action.trigger()


def cli_plan(out, *extra) -> subprocess.Popen:
    """Start ``bladecam plan`` with the coarse test parameters (runs while the window exports)."""
    args = [sys.executable, "-m", "core", "plan", "--dr", str(COARSE["dr"]), "--dd", str(COARSE["dd"]),
            *extra, "--out", str(out)]
    return subprocess.Popen(args, cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_export_matches_the_cli(planned, qtbot, folder_dialog, dialogs, tmp_path):
    w = planned
    dialogs["answers"]["question"] = QMessageBox.StandardButton.Yes  # override findings, if any
    gui_out = tmp_path / "gui"
    gui_out.mkdir()
    cli_out = tmp_path / "cli"
    cli = cli_plan(cli_out, "--period-ms", repr(w.state.plan.result.period))
    export(qtbot, w, folder_dialog, gui_out)
    _, err = cli.communicate(timeout=300)
    assert cli.returncode == 0, err
    assert not dialogs["warning"], dialogs["warning"]
    report = w.exporter.last_report
    # findings are shown to the operator before anything is written, and only then
    assert len(dialogs["question"]) == (1 if report.findings else 0)
    if report.findings:
        assert report.findings[0] in dialogs["question"][0][1]
    names = sorted(p.name for p in cli_out.iterdir())
    assert sorted(p.name for p in gui_out.iterdir()) == names
    assert {"pairs.csv", "left_cl.csv", "right_cl.csv", "plan.json", "left_axes.csv", "right_axes.csv",
            "machine.toml"} <= set(names)
    assert "verified" in w.statusBar().currentMessage() or "override" in w.statusBar().currentMessage()
    for name in names:  # every table (CL, pairs, and the axis tables when core writes them)
        if name != "plan.json":
            same = (gui_out / name).read_bytes() == (cli_out / name).read_bytes()
            assert same, f"{name} differs from the CLI's"
    gui_json, cli_json = (json.loads((d / "plan.json").read_text()) for d in (gui_out, cli_out))
    assert gui_json["inputs"] == cli_json["inputs"]
    assert gui_json["schedule"] == cli_json["schedule"] and gui_json["period_ms"] == cli_json["period_ms"]
    assert gui_json["paths"] == cli_json["paths"]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")], "staging folders left behind"


def test_unverified_plan_is_refused_unless_overridden(planned, qtbot, folder_dialog, dialogs, tmp_path):
    w = planned
    wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText("symmetric"))
    dest = tmp_path / "sym"
    dialogs["answers"]["question"] = QMessageBox.StandardButton.No
    export(qtbot, w, folder_dialog, dest)
    title, text = dialogs["question"][-1]
    assert title == "The plan fails verification" and "tip spacing" in text and "anyway" in text
    assert not dest.exists() and not list(tmp_path.iterdir()), "a refused export must write nothing"
    assert "refused" in w.statusBar().currentMessage()
    # the operator overrides
    dialogs["answers"]["question"] = QMessageBox.StandardButton.Yes
    export(qtbot, w, folder_dialog, dest)
    assert (dest / "left_cl.csv").is_file() and (dest / "plan.json").is_file()
    assert json.loads((dest / "plan.json").read_text())["inputs"]["mode"] == "symmetric"
    assert "override" in w.statusBar().currentMessage()


def test_export_refuses_a_folder_that_is_not_a_plan(planned, qtbot, folder_dialog, dialogs, tmp_path):
    w = planned
    dest = tmp_path / "documents"
    dest.mkdir()
    (dest / "letter.txt").write_text("keep me")
    folder_dialog["folder"] = str(dest)
    w.files.export_dialog()
    title, text = dialogs["warning"][-1]
    assert title == "Cannot export the plan" and "not a bladecam plan folder" in text
    assert "letter.txt" in text and "ever deleted" in text
    assert [p.name for p in dest.iterdir()] == ["letter.txt"] and not w.exporter.busy
    # a folder a plan.json alone does not make a plan folder: refused the same way
    (dest / "plan.json").write_text("{}")
    w.files.export_dialog()
    assert "no bladecam_version" in dialogs["warning"][-1][1] and not w.exporter.busy
    assert sorted(p.name for p in dest.iterdir()) == ["letter.txt", "plan.json"]
    # a folder that cannot be written: refused before anything is planned or written, by the rule
    # bladecam plan applies (core.output.files.check_destination)
    blocker = tmp_path / "a_file"
    blocker.write_text("not a folder")
    folder_dialog["folder"] = str(blocker / "plan")
    w.files.export_dialog()
    title, text = dialogs["warning"][-1]
    assert title == "Cannot export the plan" and "cannot write" in text and "another folder" in text
    assert blocker.read_text() == "not a folder" and not w.exporter.busy
    # while a re-plan is pending the shown plan is out of date: refused with a message
    w.params_panel.spins["k_max"].setValue(0.17)
    w.files.export_dialog()
    assert "out of date" in dialogs["warning"][-1][1]
    qtbot.waitUntil(lambda: not w.controller.running, timeout=PLAN_TIMEOUT)


def test_export_writes_the_plan_shown(planned, qtbot, folder_dialog, dialogs, tmp_path, monkeypatch):
    """The export writes the result shown, planning nothing: the job time in the status bar and the
    timeline is plan.json's, and the CL and axis tables have the shown plan's rows."""
    w = planned
    dialogs["answers"]["question"] = QMessageBox.StandardButton.Yes  # override findings, if any
    data = w.state.plan
    planned_again = []
    monkeypatch.setattr(Planner, "plan", lambda *a, **k: planned_again.append(a))
    dest = tmp_path / "shown"
    export(qtbot, w, folder_dialog, dest)
    assert not planned_again and not dialogs["warning"], dialogs["warning"]
    summary = json.loads((dest / "plan.json").read_text())
    total_s = summary["schedule"]["total_time_s"]
    assert total_s == data.result.figures["total_time_s"] == round(float(data.timeline.t[-1]) / 1000.0, 3)
    assert f"total {total_s / 60:.1f} min" in w.figures.text()
    assert f" / {clock(total_s * 1000.0)} · " in w.timeline.readout.text()
    for side in ("left", "right"):  # the time column of every table is the shown plan's
        for name, t in ((f"{side}_cl.csv", data.timeline.t), (f"{side}_axes.csv", data.result.axes[side].t)):
            written = np.loadtxt(dest / name, delimiter=",", skiprows=1, usecols=0)
            np.testing.assert_allclose(written, t, rtol=0, atol=1e-6, err_msg=name)


def test_cancel_stops_the_export_before_it_moves_into_place(planned, qtbot, folder_dialog, dialogs, tmp_path,
                                                    monkeypatch):
    """Cancel while the plan is written and verified: nothing is moved into place, the staging folder
    goes, and the window can export again."""
    import threading

    import bladecam_gui.export as export_module

    w = planned
    release = threading.Event()
    real_verify = export_module.verify

    def held_verify(*args, **kwargs):  # the worker verifies, then waits for the test's cancel
        out = real_verify(*args, **kwargs)
        release.wait(EXPORT_TIMEOUT / 1000.0)
        return out

    monkeypatch.setattr(export_module, "verify", held_verify)
    dest = tmp_path / "cancelled"
    folder_dialog["folder"] = str(dest)
    progress = []
    w.exporter.progress.connect(lambda f, m: progress.append(m))
    w.files.export_dialog()
    assert w.exporter.busy
    qtbot.waitUntil(lambda: any(m.startswith("verifying") for m in progress), timeout=EXPORT_TIMEOUT)
    with qtbot.waitSignal(w.exporter._runner.failed, timeout=EXPORT_TIMEOUT) as stopped:  # the worker stops
        w.exporter.cancel()
        assert not w.exporter.busy and "cancelled" in w.statusBar().currentMessage()
        release.set()
    assert type(stopped.args[1]).__name__ == "Cancelled"
    assert not list(tmp_path.iterdir())
    assert not dialogs["warning"]
    monkeypatch.setattr(export_module, "verify", real_verify)
    dialogs["answers"]["question"] = QMessageBox.StandardButton.Yes  # override findings, if any
    export(qtbot, w, folder_dialog, tmp_path / "again")
    assert (tmp_path / "again" / "left_axes.csv").is_file()

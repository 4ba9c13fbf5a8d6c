"""Export through the (patched) folder dialog: the same files as ``bladecam plan``; verification
findings refuse the export unless the operator overrides; nothing is ever half-written."""

import json
import subprocess
import sys

import pytest
from PySide6.QtWidgets import QFileDialog, QMessageBox

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
    # the shown plan has no axis tables (planned while editing without them): the export plans them
    assert w.state.plan.result.axes is None
    assert {"pairs.csv", "left_cl.csv", "right_cl.csv", "plan.json", "left_axes.csv", "right_axes.csv",
            "machine.toml"} <= set(names)
    assert "feed override" in w.statusBar().currentMessage()
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
    # a folder a plan.json alone does not make a plan folder (issue 23): refused the same way
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


def test_cancel_stops_the_export_while_it_plans_the_axis_tables(planned, qtbot, folder_dialog, dialogs,
                                                                  tmp_path):
    """Cancel during the planning for the machines: the planning stops at its next step, nothing is
    written, the staging folder goes, and the window can export again."""
    w = planned
    dest = tmp_path / "cancelled"
    folder_dialog["folder"] = str(dest)
    progress = []
    w.exporter.progress.connect(lambda f, m: progress.append(m))
    w.files.export_dialog()
    assert w.exporter.busy
    qtbot.waitUntil(lambda: any(m.startswith("axis tables") for m in progress), timeout=EXPORT_TIMEOUT)
    with qtbot.waitSignal(w.exporter._runner.failed, timeout=EXPORT_TIMEOUT) as stopped:  # the worker stops
        w.exporter.cancel()
        assert not w.exporter.busy and "cancelled" in w.statusBar().currentMessage()
    assert type(stopped.args[1]).__name__ == "Cancelled"
    assert not any(m.startswith("writing") for m in progress)  # stopped before writing anything
    assert not list(tmp_path.iterdir())
    assert not dialogs["warning"]
    export(qtbot, w, folder_dialog, tmp_path / "again")
    assert (tmp_path / "again" / "left_axes.csv").is_file()

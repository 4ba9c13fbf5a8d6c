"""Files: open each blade source through the (patched) dialogs, a bad file, projects, recent files,
window layout."""

import shutil

import numpy as np
import pytest
from PySide6.QtWidgets import QFileDialog, QInputDialog

from core.blade.source import sample_table_path

from .conftest import PLAN_TIMEOUT, wait_plan

pytestmark = pytest.mark.gui


@pytest.fixture
def pick(monkeypatch):
    """Answer the next file dialogs: pick['files'] (open blades), pick['axis'], pick['open'], pick['save']."""
    answers = {"files": [], "axis": "z", "open": "", "save": "", "asked_axis": 0}
    monkeypatch.setattr(QFileDialog, "getOpenFileNames", lambda *a, **k: (list(answers["files"]), ""))
    monkeypatch.setattr(QFileDialog, "getOpenFileName", lambda *a, **k: (answers["open"], ""))
    monkeypatch.setattr(QFileDialog, "getSaveFileName", lambda *a, **k: (answers["save"], ""))

    def get_item(parent, title, label, items, current=0, editable=False, *a, **k):
        answers["asked_axis"] += 1
        assert list(items) == ["x", "y", "z"]
        return answers["axis"], True

    monkeypatch.setattr(QInputDialog, "getItem", get_item)
    return answers


def menu_action(window, menu: str, text: str):
    m = [a for a in window.menuBar().actions() if a.text() == menu][0].menu()
    return [a for a in m.actions() if a.text().startswith(text)][0]


def test_open_two_meshes_with_axis(planned, qtbot, pick, bladex_dir):
    w = planned
    pick["files"] = [str(bladex_dir / "upper.stl"), str(bladex_dir / "lower.stl")]
    pick["axis"] = "x"
    data = wait_plan(qtbot, w, menu_action(w, "&File", "Open &blade").trigger)
    assert pick["asked_axis"] == 1
    assert data.blade.source == ",".join(pick["files"]) and data.blade.axis == "x"
    assert data.result.source == data.blade.source and data.has_schedule
    assert data.blade.blade.tip_radius == pytest.approx(125.0, abs=0.01)
    bounds = w.viewport.blade.bounds()
    drawn_x = max(data.blade.face[..., 0].max(), data.blade.back[..., 0].max())
    assert bounds[1][0] == pytest.approx(drawn_x, abs=1e-3)  # the new blade is drawn
    assert w.viewport.paths.counts()["tip"] > 0
    assert "upper.stl" in w.state.source and w.state.axis == "x"


def test_open_a_geometry_table(planned, qtbot, pick, tmp_path):
    w = planned
    sample = w.state.plan
    table = tmp_path / "my_blade.csv"
    shutil.copy(sample_table_path(), table)
    pick["files"] = [str(table)]
    data = wait_plan(qtbot, w, w.files.open_blade_dialog)
    assert pick["asked_axis"] == 0  # tables need no axis
    assert data.blade.source == str(table)
    # the same geometry as the built-in sample: the same plan
    assert data.result.plan.region_counts() == sample.result.plan.region_counts()
    assert data.result.figures["total_time_s"] == sample.result.figures["total_time_s"]
    np.testing.assert_allclose(data.timeline.left.tips, sample.timeline.left.tips)
    # and back to the sample from the menu
    data = wait_plan(qtbot, w, menu_action(w, "&File", "Open the &sample").trigger)
    assert data.blade.source == "sample"


def test_bad_file_gives_a_dialog_and_the_window_stays_usable(planned, qtbot, pick, dialogs, tmp_path):
    w = planned
    before = w.state.plan
    bad = tmp_path / "broken.stl"
    bad.write_text("this is not a mesh")
    pick["files"] = [str(bad)]
    # (the file is read when the dialog asks whether it is a whole propeller: refused there, before
    # anything is planned, or else by the worker's load)
    w.files.open_blade_dialog()
    qtbot.waitUntil(lambda: bool(dialogs["warning"]) and not w.controller.running, timeout=PLAN_TIMEOUT)
    title, text = dialogs["warning"][-1]
    assert title == "Cannot open the blade" and "broken.stl" in text
    assert w.state.plan is before and w.state.source == "sample" and not w.state.stale
    assert set(w.viewport.blade.actors) == {"face", "back"}
    # three files, or a table with a mesh: refused before loading anything
    pick["files"] = [str(bad), str(bad), str(bad)]
    w.files.open_blade_dialog()
    assert "three" in dialogs["warning"][-1][1] or "3 files" in dialogs["warning"][-1][1]
    # still usable: an edit plans the sample again
    data = wait_plan(qtbot, w, lambda: w.params_panel.spins["k_max"].setValue(0.18))
    assert data.blade.source == "sample" and data.result.plan.params.k_max == 0.18


def test_save_and_reopen_a_project_gives_the_same_plan(planned, qtbot, pick, tmp_path, dialogs):
    w = planned
    first = wait_plan(qtbot, w, lambda: w.params_panel.spins["h_safe"].setValue(2.0))
    pick["save"] = str(tmp_path / "job")  # the suffix is added
    menu_action(w, "&File", "Save project").trigger()
    saved = tmp_path / "job.toml"
    assert saved.is_file() and "h_safe = 2.0" in saved.read_text()
    wait_plan(qtbot, w, lambda: w.params_panel.combos["mode"].setCurrentText("single"))
    wait_plan(qtbot, w, lambda: w.params_panel.spins["k_max"].setValue(0.12))
    assert w.state.plan.result.figures["mode"] == "single"
    pick["open"] = str(saved)
    again = wait_plan(qtbot, w, menu_action(w, "&File", "Open &project").trigger)
    assert again.job == first.job
    assert w.params_panel.spins["h_safe"].value() == 2.0 and w.params_panel.combos["mode"].currentText() == \
        "collaborative"
    a, b = first.result, again.result
    assert b.plan.region_counts() == a.plan.region_counts()
    for pa, pb in zip(a.plan.pairs, b.plan.pairs, strict=True):
        np.testing.assert_array_equal(pa.left_tip, pb.left_tip)
        np.testing.assert_array_equal(pa.right_axis, pb.right_axis)
    np.testing.assert_array_equal(a.timeline.t, b.timeline.t)
    np.testing.assert_array_equal(a.timeline.right.tips, b.timeline.right.tips)
    assert {k: v for k, v in a.figures.items() if k != "stages"} == \
        {k: v for k, v in b.figures.items() if k != "stages"}
    assert not w.undo_action.isEnabled()  # a project starts a new edit history
    # a project's axes key is no input of the workbench (its plans always have the axis tables): one
    # written with the former "Machine timing while editing" box off opens on the same job
    assert "axes = true" in saved.read_text()
    saved.write_text(saved.read_text().replace("axes = true", "axes = false"))
    again = wait_plan(qtbot, w, menu_action(w, "&File", "Open &project").trigger)
    assert again.job == first.job and again.result.axes is not None
    # a broken project: a dialog naming the key; nothing changes
    saved.write_text(saved.read_text().replace('mode = "collaborative"', 'mode = "both"'))
    menu_action(w, "&File", "Open &project").trigger()
    assert dialogs["warning"][-1][0] == "Cannot open the project" and "mode" in dialogs["warning"][-1][1]
    assert w.state.plan is again


def test_recent_files_and_layout_are_remembered(planned, qtbot, pick, tmp_path):
    from bladecam_gui.main_window import MainWindow

    w = planned
    pick["save"] = str(tmp_path / "a.toml")
    w.files.save_project_dialog()
    table = tmp_path / "t.csv"
    shutil.copy(sample_table_path(), table)
    pick["files"] = [str(table)]
    wait_plan(qtbot, w, w.files.open_blade_dialog)
    w.plots_dock.hide()
    w.close()  # saves the layout
    w2 = MainWindow(restore=True)
    qtbot.addWidget(w2)
    try:
        assert not w2.plots_dock.isVisibleTo(w2) and w2.params_dock.isVisibleTo(w2)
        recent = w2.menuBar().actions()[0].menu().actions()
        blades_menu = [a for a in recent if a.text() == "Recent blades"][0].menu()
        projects_menu = [a for a in recent if a.text() == "Recent projects"][0].menu()
        blades_menu.aboutToShow.emit()
        projects_menu.aboutToShow.emit()
        assert any(str(table) in a.text() for a in blades_menu.actions())
        assert any(str(tmp_path / "a.toml") in a.text() for a in projects_menu.actions())
    finally:
        w2.close()


def test_open_a_whole_propeller_asks_which_blade(planned, qtbot, pick, dialogs, monkeypatch, tmp_path):
    """A CAD file of a whole propeller (4 blades of the sample table on a hub): the dialog shows the count
    and the blades, the blade and the hub cut picked there are opened; cancelled, nothing is."""
    pytest.importorskip("OCP")
    from bladecam_gui.propeller_dialog import PropellerDialog
    from core.blade.source import load_blade
    from tests.core.blade.cad_blades import propeller, write

    table = load_blade("sample")
    hub = table.hub_radius + 3.0
    path = write(propeller(table, 4, hub), tmp_path / "propeller.step")
    shown, answer = [], {"blade": 3, "r_min": None, "accept": False}

    def exec_(dialog):
        shown.append({"count": dialog.count.text(), "max": dialog.blade.maximum(), "found": dialog.found.isChecked(),
                      "r_min": dialog.r_min.value(), "editable": dialog.r_min.isEnabled()})
        dialog.blade.setValue(answer["blade"])
        if answer["r_min"] is not None:
            dialog.found.setChecked(False)
            dialog.r_min.setValue(answer["r_min"])
        return 1 if answer["accept"] else 0

    monkeypatch.setattr(PropellerDialog, "exec", exec_)
    w = planned
    pick["files"], pick["axis"] = [str(path)], "z"
    w.files.open_blade_dialog()
    assert dialogs["warning"] == []
    assert len(shown) == 1 and w.state.source == "sample" and not w.controller.running
    assert shown[0]["count"] == "propeller.step is a whole propeller of 4 blades. Which blade is to be machined?"
    assert shown[0]["max"] == 4 and shown[0]["found"] and not shown[0]["editable"]
    # the hub cut found: just outside the hub cylinder (one of the hub's bands, tip / 200, and the margin)
    tip = table.tip_radius
    assert hub < shown[0]["r_min"] < hub + tip / 200 + 0.02 * tip
    answer.update(accept=True, r_min=60.0)
    data = wait_plan(qtbot, w, w.files.open_blade_dialog)
    assert dialogs["warning"] == []
    assert data.blade.source == f"{path}?blade=3&r_min=60" and w.state.source == data.blade.source
    blade = data.blade.blade
    assert blade.blade_index == 3 and blade.hub_radius == pytest.approx(60.0, abs=1e-6) and blade.warnings == []
    # a geometry table is opened without the question
    pick["files"] = [str(sample_table_path())]
    wait_plan(qtbot, w, w.files.open_blade_dialog)
    assert len(shown) == 2

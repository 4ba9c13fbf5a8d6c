"""Waiting with something to see: a splash screen at once, and a progress that names the stage, moves
every second (its time counts up while a stage reports nothing) and estimates the time left."""

import pytest

from bladecam_gui.widgets.status import ProgressBox, progress_text

from .conftest import wait_plan

pytestmark = pytest.mark.gui


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_progress_names_the_stage_counts_up_and_estimates(qtbot):
    clock = Clock()
    box = ProgressBox(clock=clock)
    qtbot.addWidget(box)
    box.set_busy(True)
    box.set_progress(0.0, "loading the blade")
    assert box.text() == "loading the blade 0 % · 0 s"
    clock.now += 4.0  # a mesh that loads for a while, reporting nothing
    with qtbot.waitSignal(box.ticker.timeout, timeout=5000):
        pass
    assert box.text() == "loading the blade 0 % · 4 s in this stage · 4 s"
    assert box.bar.format() == box.text()
    clock.now += 6.0
    box.set_progress(0.25, "planning the paths")  # a quarter done in 10 s: about 30 s left
    assert box.text() == "planning the paths 25 % · about 30 s left"
    clock.now += 95.0
    box.set_progress(0.7, "schedule: safety rounds")
    clock.now += 10.0
    box.refresh()
    # 0.7 done in 115 s: 0.3 / 0.7 * 115 = 49.3 s left
    assert box.text() == "schedule: safety rounds 70 % · 10 s in this stage · about 49 s left"
    assert progress_text("verifying", -1, 75.0, 75.0) == "verifying · 1:15 min"
    box.set_busy(False)
    assert not box.ticker.isActive()


def test_a_splash_screen_at_once(qapp, qtbot):
    from bladecam_gui.app import show_splash

    splash = show_splash(qapp)
    qtbot.addWidget(splash)
    assert splash.isVisible() and "loading the 3D view" in splash.message()
    splash.close()


def test_the_workbench_names_the_stages_as_it_plans(planned, qtbot):
    w = planned
    seen = []
    w.state.progress_changed.connect(lambda f, m: seen.append((f, w.progress.text())))
    wait_plan(qtbot, w, lambda: w.params_panel.spins["dd"].setValue(0.45))  # new paths
    stages = [text for f, text in seen if 0 <= f < 1]
    assert stages and all(" %" in t for t in stages)
    assert any(t.startswith(("paths", "planning", "schedule", "machine timing")) for t in stages), stages

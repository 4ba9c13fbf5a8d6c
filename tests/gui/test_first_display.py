"""A plan shows what it has as soon as it has it: the blade at once, then the paths (core's
PlanListener.paths_ready, as the planner has them), then the whole plan; each drawn in the 3D view
when it arrives."""

import pytest

from .conftest import wait_plan

pytestmark = pytest.mark.gui


def test_the_blade_then_the_paths_then_the_plan(window, qtbot):
    w = window
    vp = w.viewport
    seen = []

    def on_plan(data):  # (the last signal of a plan shown: the 3D view has drawn this stage)
        stage = "blade" if data.result is None else ("plan" if data.has_schedule else "paths")
        seen.append((stage, set(vp.blade.actors), vp.paths.actor is not None,
                     vp.paths.lines is data.lines, w.state.busy))

    w.state.regions_changed.connect(on_plan)
    data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
    assert [s[0] for s in seen] == ["blade", "paths", "plan"]
    blade, paths, plan = seen
    assert blade[1] == {"face", "back"} and not blade[2] and blade[4]  # the blade, no paths, planning
    assert paths[2] and paths[3] and paths[4]  # the paths drawn while the schedule is computed
    assert plan[2] and plan[3] and data.has_schedule
    assert vp.paths.counts() and sum(vp.paths.counts().values()) == len(data.lines.cells) // 3

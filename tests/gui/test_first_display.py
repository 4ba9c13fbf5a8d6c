"""A plan shows what it has as soon as it has it: the blade at once, then the paths chunk by chunk as
the planner's workers plan them (core's PlanListener.paths_chunk), then all of them (paths_ready),
then the whole plan; each drawn in the 3D view when it arrives."""

import numpy as np
import pytest

from .conftest import wait_plan

pytestmark = pytest.mark.gui


def test_the_blade_then_the_paths_then_the_plan(window, qtbot):
    w = window
    vp = w.viewport
    seen = []

    def on_plan(data):  # (the last signal of a plan shown: the 3D view has drawn this stage)
        stage = "blade" if data.result is None else ("plan" if data.has_schedule else "paths")
        if stage == "blade" and data.lines is not None:
            stage = "chunks"
        seen.append((stage, set(vp.blade.actors), vp.paths.actor is not None,
                     vp.paths.lines is data.lines, w.state.busy))

    w.state.regions_changed.connect(on_plan)
    data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
    stages = [s[0] for s in seen]
    assert stages[0] == "blade" and stages[-2:] == ["paths", "plan"] and set(stages[1:-2]) <= {"chunks"}
    assert all(s[2] and s[3] and s[4] for s in seen[1:-2])  # each chunk drawn while planning
    blade, paths, plan = seen[0], seen[-2], seen[-1]
    assert blade[1] == {"face", "back"} and not blade[2] and blade[4]  # the blade, no paths, planning
    assert paths[2] and paths[3] and paths[4]  # the paths drawn while the schedule is computed
    assert plan[2] and plan[3] and data.has_schedule
    assert vp.paths.counts() and sum(vp.paths.counts().values()) == len(data.lines.cells) // 3


def test_the_paths_show_chunk_by_chunk_before_the_paths_stage_ends(window, qtbot, monkeypatch):
    """The 3D view holds some of the paths before all exist: each chunk's paths (a worker process's,
    or core.paths.planning.CHUNK paths in one process) are drawn as the planner collects them, the
    drawn ones growing, each of them as the whole plan draws it. (The planner waits here for each
    chunk to be drawn: on a busy GUI thread chunks arriving together are drawn once, the latest.)"""
    import threading

    from bladecam_gui import plan_data

    w = window
    vp = w.viewport
    drawn = []  # the paths drawn at each chunk, before the paths stage ends
    chunks = []  # the pairs of each chunk, as the planner gave them
    shown = threading.Semaphore(0)
    paths_chunk = plan_data._Views.paths_chunk

    def waiting(self, pairs, regions):  # (in the planning thread)
        paths_chunk(self, pairs, regions)
        if pairs:
            chunks.append(len(pairs))
            shown.acquire(timeout=60)  # the GUI has drawn it

    monkeypatch.setattr(plan_data._Views, "paths_chunk", waiting)

    def on_regions(data):
        if data.result is None and data.lines is not None:
            drawn.append((vp.paths.lines is data.lines and w.state.busy, np.asarray(data.lines.points)))
            shown.release()

    w.state.regions_changed.connect(on_regions)
    data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
    assert len(drawn) == len(chunks) >= 2 and all(ok for ok, _ in drawn)
    assert sum(chunks) == len(data.result.plan.pairs)
    sizes = [len(points) for _, points in drawn]
    assert sizes == sorted(sizes) and sizes[0] < len(data.lines.points)
    assert np.array_equal(drawn[-1][1], data.lines.points)  # the last chunk: every path, drawn alike
    planned = {tuple(p) for pair in data.result.plan.pairs for tip in (pair.left_tip, pair.right_tip)
               for p in np.round(tip, 9)}
    for _, points in drawn:  # each drawn point is a point of the plan's paths
        assert {tuple(p) for p in np.round(points, 9)} <= planned

"""Paths started at launch (app.start_sample_paths -> plan_data.EarlyPaths): the first job takes them
when it is the same job and shows the plan a fresh job would; a different first job, a cancelled or
replaced one, or a window closed before planning stops their worker processes; a project on the
command line starts none."""

from dataclasses import replace

import numpy as np
import pytest

from bladecam_gui.app import start_sample_paths
from bladecam_gui.plan_data import new_planner, prepare
from core.records import PlanParameters

from .conftest import _CACHE, COARSE, PLAN_TIMEOUT, wait_plan

pytestmark = pytest.mark.gui


@pytest.fixture
def make_window(qtbot):
    """make(early, params) -> a shown MainWindow given ``early``; closed (and checked) at teardown."""
    from pyvista.plotting import plotter as pv_plotter

    from bladecam_gui.main_window import MainWindow

    before = set(pv_plotter._ALL_PLOTTERS)
    made = []

    def make(early, params=COARSE):
        w = MainWindow(params=PlanParameters(**params), debounce_ms=50, restore=False, early=early)
        qtbot.addWidget(w)
        w.resize(1400, 900)
        with qtbot.waitExposed(w):
            w.show()
        made.append(w)
        return w

    yield make
    for w in made:
        w.close()
        assert w.viewport.plotter._closed
    assert not set(pv_plotter._ALL_PLOTTERS) - before


@pytest.fixture
def path_plans(monkeypatch):
    """The paths the workbench's planner starts itself (core.paths.planning.PathsJob made by the
    planner after launch)."""
    import core.planner as planner

    calls = []

    class Spy(planner.PathsJob):
        def __init__(self, *args, **kwargs):
            calls.append(args)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(planner, "PathsJob", Spy)
    return calls


def workers_of(early) -> tuple:
    """(the started paths, their worker processes)."""
    started = early.paths if early is not None else None
    assert started is not None and started._pool is not None  # started, forked
    return started, started.worker_processes()


def stopped(handle) -> bool:
    started, workers = handle
    return started._pool is None and started._scratch is None and not any(p.is_alive() for p in workers)


def test_first_job_takes_the_early_paths_and_shows_the_same_plan(make_window, path_plans, qtbot):
    early = start_sample_paths(PlanParameters(**COARSE))
    workers = workers_of(early)
    path_plans.clear()  # (the early start's own)
    w = make_window(early)
    data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
    assert path_plans == []  # the paths came from the early workers
    assert stopped(workers)
    assert data.job == early.job == w.state.job() and data.blade is early.blade
    fresh = _CACHE.get("sample") or prepare(early.job, None, new_planner())
    assert fresh.job == data.job
    a, b = data.result.plan, fresh.result.plan
    assert len(a.pairs) == len(b.pairs) and a.warnings == b.warnings
    for pa, pb, ra, rb in zip(a.pairs, b.pairs, a.regions, b.regions, strict=True):
        assert np.array_equal(pa.left_tip, pb.left_tip) and np.array_equal(pa.right_axis, pb.right_axis)
        assert np.array_equal(ra.labels, rb.labels)
    assert np.array_equal(data.timeline.t, fresh.timeline.t)
    assert np.array_equal(data.timeline.right.tips, fresh.timeline.right.tips)
    assert data.result.figures == fresh.result.figures
    for name in ("spacing", "clearance", "danger", "speed_left", "speed_right", "step", "bands"):
        assert np.array_equal(getattr(data, name), getattr(fresh, name)), name
    assert np.array_equal(data.lines.points, fresh.lines.points)
    # the early paths keep their fitted curves: an h_safe change reuses them
    changed = wait_plan(qtbot, w, lambda: w.params_panel.spins["h_safe"].setValue(2.2))
    assert changed.reused == "regions" and changed.result.plan.params.h_safe == 2.2


def test_a_different_first_job_cancels_them(make_window, path_plans, qtbot):
    early = start_sample_paths(PlanParameters(**dict(COARSE, k_max=0.12)))
    workers = workers_of(early)
    path_plans.clear()  # (the early start's own)
    w = make_window(early)  # the window's inputs: COARSE, k_max 0.15
    data = wait_plan(qtbot, w, lambda: w.open_blade_source("sample"))
    assert stopped(workers)
    assert len(path_plans) == 1  # planned afresh, for the window's inputs
    assert data.result.plan.params.k_max == 0.15 and data.blade is not early.blade


def test_cancelled_first_job_stops_them_and_replanning_works(make_window, path_plans, qtbot):
    early = start_sample_paths(PlanParameters(**COARSE))
    workers = workers_of(early)
    path_plans.clear()  # (the early start's own)
    w = make_window(early)
    w.open_blade_source("sample")
    w.cancel()
    qtbot.waitUntil(lambda: not w.controller.running and not w.state.busy, timeout=PLAN_TIMEOUT)
    assert stopped(workers)
    assert w.state.plan is None or not w.state.plan.has_schedule
    # the cancel may come before the early paths are complete (the re-plan plans them once) or, on a
    # loaded machine, after (the planner kept them and the re-plan reuses them)
    kept = w.controller._runner.planner.reuse(w.state.job()) != "none"
    data = wait_plan(qtbot, w, lambda: w.controller.request(immediate=True))
    assert data.has_schedule and len(path_plans) == (0 if kept else 1)


def test_replaced_first_job_shows_the_new_inputs(make_window, qtbot):
    early = start_sample_paths(PlanParameters(**COARSE))
    workers = workers_of(early)
    w = make_window(early)
    seen = []
    w.controller.finished.connect(seen.append)
    w.open_blade_source("sample")
    w.params_panel.spins["h_safe"].setValue(2.2)  # while the first job runs
    qtbot.waitUntil(lambda: bool(seen) and not w.controller.running, timeout=PLAN_TIMEOUT)
    assert stopped(workers)
    data = w.state.plan
    assert data.result.plan.params.h_safe == 2.2 and data.job == w.state.job() and not w.state.stale
    assert data.job.params == replace(early.job.params, h_safe=2.2)


def test_window_closed_before_planning_stops_them(make_window):
    early = start_sample_paths(PlanParameters(**COARSE))
    workers = workers_of(early)
    w = make_window(early)
    w.close()
    assert stopped(workers)


@pytest.mark.parametrize("with_project", [False, True])
def test_launch_starts_the_sample_paths_only_without_a_project(with_project, monkeypatch, qtbot, tmp_path):
    from PySide6.QtWidgets import QApplication

    import bladecam_gui.app as app
    import bladecam_gui.main_window as mw
    from core.output.project import Project, save_project

    started, made = [], []
    monkeypatch.setattr(app, "start_sample_paths", lambda params=None: started.append(params))

    class Recorded(mw.MainWindow):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append((self, kwargs.get("early", "not given")))

    monkeypatch.setattr(mw, "MainWindow", Recorded)
    monkeypatch.setattr(QApplication, "exec", lambda self: 0)
    argv = []
    if with_project:
        argv = [str(save_project(Project(params=PlanParameters(**COARSE)), tmp_path / "p.toml"))]
    assert app.main(argv) == 0
    (w, early), = made
    qtbot.addWidget(w)
    try:
        assert started == ([] if with_project else [None]) and early is None
        assert w.state.source == "sample" and w.state.params.dr == (4.0 if with_project else 0.375)
    finally:
        w.close()

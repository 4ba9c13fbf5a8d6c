"""Workbench benchmark (not part of make test): cold start, re-plan with reused paths, timeline drag.

    .venv/bin/python tests/benchmarks/bench_gui.py            # under xvfb-run when there is no DISPLAY
    .venv/bin/python tests/benchmarks/bench_gui.py --coarse   # dR 3 mm, dd 0.5 mm (quick look)

Targets: cold start to a shown window with the sample plan <= 5 s; re-plan after an h_safe
change (paths reused) <= 0.5 s; a timeline drag updates the view in <= 30 ms per frame. The cold start
is measured from launching a fresh process (interpreter, imports, window) to each stage shown: blade,
paths, full plan (schedule, time column, plots). The process starts as bladecam_gui.app.main does:
allocator tuned, the sample's paths started in worker processes, then Qt, the splash screen, the
libraries and the window.
"""

from __future__ import annotations

import json
import os
import sys
import time

from common import REPO, calib, child_result, drag_frames, frame_figures, gui_child, open_window


def child(coarse: bool) -> None:
    """Runs inside the fresh process: prints one JSON line of stage times (s since launch)."""
    t_launch = float(os.environ["BENCH_T0"])
    stamps: dict[str, float] = {}

    def stamp(name: str) -> None:
        stamps.setdefault(name, time.time() - t_launch)

    sys.path.insert(0, str(REPO))
    from core.util.memory import tune_allocator

    tune_allocator(trim=512 << 20)  # as bladecam_gui.app.main
    from bladecam_gui.app import before_qt
    from core.records import PlanParameters

    params = PlanParameters(dr=3.0, dd=0.5) if coarse else None
    early = before_qt(sample=True, params=params)  # as bladecam_gui.app.main: before Qt loads
    stamp("paths_started")
    from PySide6.QtCore import QEventLoop, QTimer
    from PySide6.QtWidgets import QApplication

    app = QApplication([sys.argv[0]])
    stamp("qt_ready")
    from bladecam_gui.app import show_splash

    splash = show_splash(app)  # as bladecam_gui.app.main
    stamp("splash_shown")
    _, w = open_window(coarse, early=early)
    splash.finish(w)
    app.processEvents()
    stamp("window_shown")
    result: dict = {}

    def on_plan(data) -> None:
        if data.result is None:
            stamp("blade_shown")
        elif not data.has_schedule:
            stamp("paths_shown")
        else:
            stamp("plan_shown")

    w.state.plan_changed.connect(on_plan)
    loop = QEventLoop()
    w.controller.idle.connect(loop.quit)
    w.open_blade_source("sample")
    loop.exec()  # idle event loop, as in the application (no polling competing for the GIL)
    for _ in range(5):
        app.processEvents()
    w.viewport.plotter.render()
    data = w.state.plan
    result["samples"] = len(data.timeline.t)
    result["paths"] = len(data.result.plan.pairs)
    result["plan_timings_s"] = {k: round(v, 3) for k, v in data.timings.items()}

    # re-plan after an h_safe change: the paths are reused (core.paths.planning.replan_regions)
    replans = []
    for h in (2.0, 1.7, 2.2):
        done, regions = [], []
        w.controller.finished.connect(done.append)
        w.state.regions_changed.connect(lambda d, seen=regions: seen.append(time.perf_counter()))
        t0 = time.perf_counter()
        w.params_panel.spins["h_safe"].setValue(h)
        loop.exec()
        app.processEvents()  # the view repainted
        replans.append((regions[0] - t0 if regions else float("nan"), time.perf_counter() - t0))
        w.controller.finished.disconnect(done.append)
        w.state.regions_changed.disconnect()
        assert done[0].reused == "regions", done[0].reused
        result.setdefault("replan_timings_s", []).append({k: round(v, 3) for k, v in done[0].timings.items()})
    result["replan_regions_s"] = [round(x[0], 3) for x in replans]
    result["replan_s"] = [round(x[1], 3) for x in replans]
    # undo back to a plan planned before (kept by the controller: shown without planning)
    undos = []
    for _ in range(2):  # (h_safe 2.2 -> 1.7 -> 2.0: each re-plan above is its own undo step)
        if not w.undo_action.isEnabled():
            break
        done = []
        w.controller.finished.connect(done.append)
        jobs = w.controller._next_id
        t0 = time.perf_counter()
        w.undo_action.trigger()
        while not done and time.perf_counter() - t0 < 60:
            app.processEvents(QEventLoop.ProcessEventsFlag.WaitForMoreEvents, 50)
        app.processEvents()  # the views repainted
        undos.append((round(time.perf_counter() - t0, 3), w.controller._next_id > jobs))
        w.controller.finished.disconnect(done.append)
    result["undo_s"] = undos

    # timeline drag: mouse moves with the button held over the step bar, each one painted
    result["drag_frame_ms"] = frame_figures(drag_frames(app, w))
    result["stages_s"] = {k: round(v, 3) for k, v in stamps.items()}
    print("BENCH " + json.dumps(result), flush=True)
    QTimer.singleShot(0, w.close)
    app.processEvents()
    w.close()


def main() -> int:
    coarse = "--coarse" in sys.argv
    if "--child" in sys.argv:
        child(coarse)
        return 0
    launch = gui_child(__file__, coarse)
    if launch is None:
        print("no DISPLAY and no xvfb-run: cannot run the workbench benchmark")
        return 2
    c0 = calib()
    launch[1]["BENCH_T0"] = repr(time.time())
    r = child_result(launch, 900)
    c1 = calib()
    if r is None:
        return 1
    st = r["stages_s"]
    print(f"workbench benchmark ({'coarse dR 3 mm, dd 0.5 mm' if coarse else 'defaults'}): "
          f"{r['paths']} paths, {r['samples']} time samples; calib.py {c0:.3f} s before, {c1:.3f} s after")
    nan = float("nan")
    print(f"  cold start: paths started {st['paths_started']:.2f} s, splash {st.get('splash_shown', nan):.2f} s, "
          f"window {st['window_shown']:.2f} s, "
          f"blade {st.get('blade_shown', nan):.2f} s, paths {st.get('paths_shown', nan):.2f} s, "
          f"full plan {st['plan_shown']:.2f} s (target 5 s)")
    print(f"    in the worker: {r['plan_timings_s']}")
    print(f"  re-plan after an h_safe change (paths reused): new regions shown after "
          f"{r['replan_regions_s']} s (target 0.5 s); full plan (schedule, time column, plots) after "
          f"{r['replan_s']} s")
    print(f"    in the worker: {r['replan_timings_s'][-1]}")
    undos = ", ".join(f"{u:.3f} s" + (" (planned again: no longer kept)" if planned else " (kept)")
                      for u, planned in r["undo_s"])
    print(f"  undo back to a plan planned before: shown after {undos}")
    d = r["drag_frame_ms"]
    print(f"  timeline drag: {d['median']} ms per frame median, p90 {d['p90']} ms, max {d['max']} ms "
          "(target 30 ms)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

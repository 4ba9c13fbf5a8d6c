"""Workbench benchmark (not part of make test): how long the GUI thread stalls while a plan runs.

    .venv/bin/python tests/benchmarks/bench_gui_stalls.py            # under xvfb-run when there is no DISPLAY
    .venv/bin/python tests/benchmarks/bench_gui_stalls.py --coarse   # dR 3 mm, dd 0.5 mm (quick look)
    .venv/bin/python tests/benchmarks/bench_gui_stalls.py --stacks   # and where every thread was

With --stacks, each heartbeat re-arms faulthandler (its watchdog is a C thread: it needs no Python
lock), so that a stall longer than STACK_AFTER_S writes every thread's stack to a file: the GUI
thread busy in a view, or waiting for the Python lock that another thread holds in a long C call.

A QTimer heartbeat every HEARTBEAT_MS on the GUI thread records the gaps between its ticks while the
workbench plans the sample blade from scratch (blade, paths, schedule) and then re-plans it after an
h_safe change (paths reused). A gap beyond the heartbeat is time the window could not answer the
operator. Each plan's arrival on the GUI thread (the state's set_plan / set_regions_preview, which
the views draw from) is timed as well, to say which stalls the results' drawing causes. Every stall
is printed beside calib.py's time measured in the same run (before and after the child; the lower).
"""

from __future__ import annotations

import json
import os
import sys
import tempfile

from common import calib, child_result, gui_child, open_window

HEARTBEAT_MS = 10
STACK_AFTER_S = 0.3


def child(coarse: bool, stacks: str | None) -> None:
    from PySide6.QtCore import QElapsedTimer, QEventLoop, QTimer

    from bladecam_gui.state import WorkbenchState

    arrivals: list[tuple[str, float, float]] = []  # (what, start s, duration s) on the GUI thread
    clock = QElapsedTimer()
    clock.start()

    def timed(name, fn):
        def wrapper(self, data):
            t0 = clock.nsecsElapsed() / 1e9
            fn(self, data)
            what = "blade" if data.result is None else ("plan" if data.has_schedule else "paths")
            arrivals.append((f"{name}:{what}", t0, clock.nsecsElapsed() / 1e9 - t0))
        return wrapper

    WorkbenchState.set_plan = timed("set_plan", WorkbenchState.set_plan)
    WorkbenchState.set_regions_preview = timed("preview", WorkbenchState.set_regions_preview)

    app, w = open_window(coarse)
    for _ in range(5):
        app.processEvents()

    ticks: list[float] = []
    beat = QTimer()
    beat.setInterval(HEARTBEAT_MS)
    beat.timeout.connect(lambda: ticks.append(clock.nsecsElapsed() / 1e9))
    if stacks:
        import faulthandler

        dump = open(stacks, "w")  # (open for the whole run: the watchdog writes to it)

        def rearm() -> None:
            faulthandler.cancel_dump_traceback_later()
            faulthandler.dump_traceback_later(STACK_AFTER_S, repeat=False, file=dump)

        beat.timeout.connect(rearm)
    loop = QEventLoop()
    w.controller.idle.connect(loop.quit)

    def measured(action) -> dict:
        ticks.clear()
        arrivals.clear()
        beat.start()
        t0 = clock.nsecsElapsed() / 1e9
        ticks.append(t0)
        action()
        loop.exec()
        for _ in range(3):
            app.processEvents()
        ticks.append(clock.nsecsElapsed() / 1e9)
        beat.stop()
        gaps = [(b - a, a) for a, b in zip(ticks, ticks[1:], strict=False)]
        gaps.sort(reverse=True)
        worst = [{"ms": round(1000 * g, 1), "at_s": round(a - t0, 3),
                  "during": [n for n, s, d in arrivals if s < a + g and s + d > a]} for g, a in gaps[:5]]
        return {"plan_s": round(ticks[-1] - t0, 3), "ticks": len(ticks),
                "worst": worst,
                "arrivals_ms": [(n, round(s - t0, 3), round(1000 * d, 1)) for n, s, d in arrivals]}

    result = {"from_scratch": measured(lambda: w.open_blade_source("sample"))}
    result["h_safe_change"] = measured(lambda: w.params_panel.spins["h_safe"].setValue(2.0))
    if stacks:
        faulthandler.cancel_dump_traceback_later()
        dump.close()
    result["samples"] = len(w.state.plan.timeline.t)
    print("BENCH " + json.dumps(result), flush=True)
    w.close()


def main() -> int:
    coarse = "--coarse" in sys.argv
    if "--child" in sys.argv:
        child(coarse, os.environ.get("BENCH_STACKS"))
        return 0
    launch = gui_child(__file__, coarse)
    if launch is None:
        print("no DISPLAY and no xvfb-run: cannot run the workbench benchmark")
        return 2
    stacks = None
    if "--stacks" in sys.argv:
        stacks = launch[1]["BENCH_STACKS"] = os.path.join(tempfile.mkdtemp(prefix="bladecam-stalls-"), "stacks.txt")
    c0 = calib()
    r = child_result(launch, 900)
    c1 = calib()
    if r is None:
        return 1
    c = min(c0, c1)
    print(f"GUI-thread stalls while planning ({'coarse dR 3 mm, dd 0.5 mm' if coarse else 'defaults'}), "
          f"heartbeat {HEARTBEAT_MS} ms; calib.py {c:.3f} s (before {c0:.3f}, after {c1:.3f})")
    for name in ("from_scratch", "h_safe_change"):
        m = r[name]
        top = m["worst"][0]
        print(f"  {name}: plan {m['plan_s']:.2f} s; longest stall {top['ms']} ms "
              f"= {top['ms'] / 1000 / c:.2f} x calib")
        for g in m["worst"]:
            print(f"    {g['ms']:8.1f} ms at {g['at_s']:7.3f} s  {', '.join(g['during']) or '(planner / other)'}")
        for n, s, d in m["arrivals_ms"]:
            print(f"    arrival {n:24s} at {s:7.3f} s took {d:8.1f} ms")
    if stacks:
        print(f"  every thread's stack at each stall over {1000 * STACK_AFTER_S:.0f} ms: {stacks}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

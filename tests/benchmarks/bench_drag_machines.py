"""Timeline drag with both XYZ-3RPS machines drawn: frame time of a drag over the step bar,
the plan planned with machine timing on (the machines posed from its axis tables), paired in the same
run with the reference workload ../shared/bench/calib.py (see its README).

    .venv/bin/python tests/benchmarks/bench_drag_machines.py            # under xvfb-run when no DISPLAY
    .venv/bin/python tests/benchmarks/bench_drag_machines.py --coarse   # dR 3 mm, dd 0.5 mm

Target: a drag frame with both machines drawn <= 20 ms at the 90th percentile. Measured in one
window: without the machines, with them (the Plots dock in front, as the window opens), and with them
and the Machine axes plot in front.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

from common import REPO, calib, drag_frames, frame_figures, gui_child

FRAMES = 120
REPEATS = 3


def child(coarse: bool) -> None:
    """Runs inside the X server: prints one JSON line of drag frame times (ms)."""
    os.environ.setdefault("QT_API", "pyside6")
    sys.path.insert(0, str(REPO))
    from PySide6.QtCore import QEventLoop, QSettings
    from PySide6.QtWidgets import QApplication

    from core.records import PlanParameters

    QSettings.setPath(QSettings.Format.IniFormat, QSettings.Scope.UserScope, tempfile.mkdtemp())
    app = QApplication([sys.argv[0]])
    from bladecam_gui.main_window import MainWindow

    params = PlanParameters(dr=3.0, dd=0.5) if coarse else None
    w = MainWindow(params=params, restore=False, debounce_ms=0)
    w.resize(1500, 940)
    w.show()
    app.processEvents()
    loop = QEventLoop()
    w.controller.idle.connect(loop.quit)
    w.open_blade_source("sample")
    loop.exec()
    for _ in range(5):
        app.processEvents()
    data = w.state.plan
    assert data.result.axes is not None, "the plan has no axis tables"

    cursors: set[int] = set()
    w.state.cursor_changed.connect(cursors.add)

    def drag() -> dict:
        cursors.clear()
        return {**frame_figures(drag_frames(app, w, FRAMES)), "cursors": len(cursors)}

    result = {"samples": len(data.timeline.t), "paths": len(data.result.plan.pairs)}
    boxes = w.view_options.boxes

    def condition(machines: bool, axes_plot: bool) -> None:
        boxes["machines"].setChecked(machines)
        (w.axes_dock if axes_plot else w.plots_dock).raise_()
        w.viewport.view("iso")
        app.processEvents()
        drag()  # warm-up (first renders, caches, the plots' ranges)

    # the conditions interleaved, REPEATS drags each: on a shared host another process's burst then
    # falls on one drag of one condition, not on every drag of it; the best drag and all are reported
    for _ in range(REPEATS):
        for key, machines, axes_plot in (("without", False, False), ("machines", True, False),
                                         ("machines_axes_plot", True, True)):
            condition(machines, axes_plot)
            result.setdefault(key, []).append(drag())
    print("BENCH " + json.dumps(result), flush=True)
    w.close()
    app.processEvents()


def main() -> int:
    coarse = "--coarse" in sys.argv
    if "--child" in sys.argv:
        child(coarse)
        return 0
    launch = gui_child(__file__, coarse)
    if launch is None:
        print("no DISPLAY and no xvfb-run: cannot run the workbench benchmark")
        return 2
    cmd, env = launch
    c0 = calib()
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=1800)
    c1 = calib()
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("BENCH ")]
    if not lines:
        print(out.stdout[-3000:], out.stderr[-3000:])
        return 1
    r = json.loads(lines[-1][6:])
    c = min(c0, c1)  # (the host at its quietest: the ratio then errs on the high side)
    print(f"timeline drag with both machines ({'coarse dR 3 mm, dd 0.5 mm' if coarse else 'defaults'}, "
          f"machine timing on): {r['paths']} paths, {r['samples']} time samples; "
          f"calib.py {c0:.3f} s before, {c1:.3f} s after")
    best = {}
    for key, label in (("without", "machines hidden"), ("machines", "both machines drawn"),
                       ("machines_axes_plot", "both machines, Machine axes plot in front")):
        runs = r[key]
        d = best[key] = min(runs, key=lambda x: x["p90"])
        print(f"  {label}: best of {len(runs)} drags: median {d['median']} ms, p90 {d['p90']} ms "
              f"({d['p90'] / 1000 / c:.4f}x calib), max {d['max']} ms over {d['cursors']} cursor positions; "
              f"p90 of each drag {[x['p90'] for x in runs]} ms")
    p90 = best["machines"]["p90"]
    verdict = "met" if p90 <= 20.0 else "NOT met"
    print(f"  target: p90 <= 20 ms with both machines drawn: {verdict} ({p90} ms, best drag)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

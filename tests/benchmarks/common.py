"""What the benchmarks share: the reference workload run in the same benchmark run
(../shared/bench/calib.py, its README), a background load, and for the workbench benchmarks: the
window a child opens, a timeline drag over its step bar, and running the child under an X server."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
#: ../shared/bench/calib.py beside the checkout (or beside a folder holding it, as a git worktree's is)
CALIB = next((p / "shared" / "bench" / "calib.py" for p in REPO.parents
              if (p / "shared" / "bench" / "calib.py").is_file()), REPO.parent / "shared" / "bench" / "calib.py")
if str(REPO) not in sys.path:  # (the checkout's packages, for a benchmark run as a script)
    sys.path.insert(0, str(REPO))


def calib() -> float:
    """calib.py's time in this run, s (its last printed line)."""
    out = subprocess.run([sys.executable, str(CALIB)], check=True, capture_output=True, text=True, timeout=600)
    return float(out.stdout.strip().splitlines()[-1].split()[0])


_BUSY = "import numpy as np\na = np.random.rand(400, 400)\nwhile True:\n    a = np.sin(a @ a.T) / 400\n"


@contextmanager
def background_load(processes: int):
    """``processes`` busy processes (a numpy loop each) for the duration of the block: the host as
    loaded as an engineer's machine running a plan beside the workbench."""
    procs = [subprocess.Popen([sys.executable, "-c", _BUSY], env={**os.environ, "OMP_NUM_THREADS": "1",
                                                                   "OPENBLAS_NUM_THREADS": "1"})
             for _ in range(processes)]
    try:
        yield
    finally:
        for p in procs:
            p.kill()
            p.wait()


def open_window(coarse: bool, **kwargs):
    """(app, window) in a benchmark's child: a QApplication and a shown 1500 x 940 MainWindow on the
    sample's inputs (``coarse``: dR 3 mm, dd 0.5 mm), its settings in a fresh folder; ``kwargs`` go
    to MainWindow."""
    os.environ.setdefault("QT_API", "pyside6")
    import tempfile

    from PySide6.QtCore import QSettings
    from PySide6.QtWidgets import QApplication

    from core.records import PlanParameters

    QSettings.setPath(QSettings.Format.IniFormat, QSettings.Scope.UserScope, tempfile.mkdtemp())
    app = QApplication.instance() or QApplication([sys.argv[0]])
    from bladecam_gui.main_window import MainWindow

    params = PlanParameters(dr=3.0, dd=0.5) if coarse else None
    w = MainWindow(params=params, restore=False, debounce_ms=0, **kwargs)
    w.resize(1500, 940)
    w.show()
    return app, w


def drag_frames(app, window, frames: int = 120) -> list[float]:
    """Seconds per frame of a drag over the window's step bar, left to right, as an operator's: the
    left button pressed, then each frame a mouse move sent to the bar and the event loop run until
    the 3D view, the plots and the timeline have painted; the button released after the last."""
    from PySide6.QtCore import QEvent, QPointF, Qt
    from PySide6.QtGui import QMouseEvent
    from PySide6.QtWidgets import QApplication

    bar = window.timeline.bar
    y = bar.height() / 3
    left, none = Qt.MouseButton.LeftButton, Qt.MouseButton.NoButton

    def send(kind, x: float, button, buttons) -> None:
        pos = QPointF(bar.width() * x, y)
        QApplication.sendEvent(bar, QMouseEvent(kind, pos, bar.mapToGlobal(pos), button, buttons,
                                                Qt.KeyboardModifier.NoModifier))

    send(QEvent.Type.MouseButtonPress, 0.05, left, left)
    app.processEvents()
    out = []
    for k in range(frames):
        x = 0.05 + 0.9 * k / (frames - 1)
        t0 = time.perf_counter()
        send(QEvent.Type.MouseMove, x, none, left)
        app.processEvents()
        out.append(time.perf_counter() - t0)
    send(QEvent.Type.MouseButtonRelease, 0.95, left, none)
    app.processEvents()
    return out


def release_frame(app, window) -> float:
    """Seconds from the button's release on the step bar to the 3D view's full-detail frame painted
    (the frame at rest after a drag)."""
    from PySide6.QtCore import QEvent, QPointF, Qt
    from PySide6.QtGui import QMouseEvent
    from PySide6.QtWidgets import QApplication

    bar = window.timeline.bar
    left = Qt.MouseButton.LeftButton
    for kind, x, button, buttons in ((QEvent.Type.MouseButtonPress, 0.45, left, left),
                                     (QEvent.Type.MouseMove, 0.5, Qt.MouseButton.NoButton, left)):
        pos = QPointF(bar.width() * x, bar.height() / 3)
        QApplication.sendEvent(bar, QMouseEvent(kind, pos, bar.mapToGlobal(pos), button, buttons,
                                                Qt.KeyboardModifier.NoModifier))
        app.processEvents()  # (the press jumps in full, the move draws light)
    t0 = time.perf_counter()
    QApplication.sendEvent(bar, QMouseEvent(QEvent.Type.MouseButtonRelease, pos, bar.mapToGlobal(pos), left,
                                            Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier))
    app.processEvents()
    return time.perf_counter() - t0


def frame_figures(seconds: list[float]) -> dict:
    """median, p90 and max of frame times, ms."""
    ms = sorted(1000.0 * s for s in seconds)
    return {"median": round(ms[len(ms) // 2], 1), "p90": round(ms[int(len(ms) * 0.9)], 1), "max": round(ms[-1], 1)}


def gui_child(script: str, coarse: bool) -> tuple[list[str], dict] | None:
    """(command, environment) running ``script --child`` on this display, or under xvfb-run when there
    is none; None when there is neither."""
    cmd = [sys.executable, script, "--child"] + (["--coarse"] if coarse else [])
    if not os.environ.get("DISPLAY"):
        if not shutil.which("xvfb-run"):
            return None
        cmd = ["xvfb-run", "-a", "-s", "-screen 0 1600x1000x24"] + cmd
    env = dict(os.environ)
    env.pop("QT_QPA_PLATFORM", None)
    return cmd, env


def child_result(command: tuple[list[str], dict], timeout: float) -> dict | None:
    """Run a workbench benchmark's child (``gui_child``'s command and environment) and return the
    JSON of its last ``BENCH `` line; None (its output's ends printed) when it printed none."""
    import json

    cmd, env = command
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("BENCH ")]
    if not lines:
        print(out.stdout[-3000:], out.stderr[-3000:])
        return None
    return json.loads(lines[-1][6:])

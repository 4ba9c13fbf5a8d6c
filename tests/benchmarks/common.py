"""What the benchmarks share: the reference workload run in the same benchmark run
(../shared/bench/calib.py, its README), a timeline drag over the workbench's step bar, and the
command that runs a workbench benchmark's child under an X server."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
#: ../shared/bench/calib.py beside the checkout (or beside a folder holding it, as a git worktree's is)
CALIB = next((p / "shared" / "bench" / "calib.py" for p in REPO.parents
              if (p / "shared" / "bench" / "calib.py").is_file()), REPO.parent / "shared" / "bench" / "calib.py")


def calib() -> float:
    """calib.py's time in this run, s (its last printed line)."""
    out = subprocess.run([sys.executable, str(CALIB)], check=True, capture_output=True, text=True, timeout=600)
    return float(out.stdout.strip().splitlines()[-1].split()[0])


def drag_frames(app, window, frames: int = 120) -> list[float]:
    """Seconds per frame of a drag over the window's step bar, left to right: each a mouse move sent
    to the bar and the event loop run until the 3D view, the plots and the timeline have painted."""
    from PySide6.QtCore import QEvent, QPointF, Qt
    from PySide6.QtGui import QMouseEvent
    from PySide6.QtWidgets import QApplication

    bar = window.timeline.bar
    y = bar.height() / 3
    out = []
    for k in range(frames):
        pos = QPointF(bar.width() * (0.05 + 0.9 * k / (frames - 1)), y)
        t0 = time.perf_counter()
        QApplication.sendEvent(bar, QMouseEvent(QEvent.Type.MouseMove, pos, bar.mapToGlobal(pos),
                                                Qt.MouseButton.NoButton, Qt.MouseButton.LeftButton,
                                                Qt.KeyboardModifier.NoModifier))
        app.processEvents()
        out.append(time.perf_counter() - t0)
    return out


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

"""Take the README's screenshot from the real program: the whole workbench with the sample blade's
plan shown (run under a display or xvfb-run):

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python docs/make_screenshots.py [--coarse]

--coarse plans with dR 3 mm (quicker, for trying the layout); the README's image uses the defaults.
"""

import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("QT_API", "pyside6")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402
from PySide6.QtCore import QEventLoop, QSettings  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

OUT = Path(__file__).parent / "img" / "workbench.png"
SYMMETRIC = Path(__file__).parent / "img" / "symmetric.png"


def main() -> None:
    QSettings.setPath(QSettings.Format.IniFormat, QSettings.Scope.UserScope, tempfile.mkdtemp())
    app = QApplication.instance() or QApplication(sys.argv)
    from bladecam_gui.main_window import MainWindow
    from core.pipeline import PlanParameters

    params = PlanParameters(dr=3.0) if "--coarse" in sys.argv else None
    w = MainWindow(params=params, restore=False)
    w.resize(1500, 920)
    w.show()
    loop = QEventLoop()
    w.controller.idle.connect(loop.quit)
    w.open_blade_source("sample")
    loop.exec()
    data = w.state.plan
    if data is None or not data.has_schedule:
        raise SystemExit("the sample plan did not complete")
    # an instant of the collaborative part: both cutters cutting, past the middle of the job
    tl = data.timeline
    both = np.nonzero(tl.left.cutting & tl.right.cutting & (data.step >= 4))[0]
    w.state.set_cursor(int(both[int(len(both) * 0.45)]) if len(both) else len(tl.t) // 2)
    # from the trailing-edge side and a little above: both cutters (one each side, +-Z_W) in sight
    w.viewport.plotter.view_vector((0.45, 1.0, 0.35), viewup=(0.0, 0.0, 1.0), render=False)
    w.viewport.plotter.reset_camera(render=False)
    w.viewport.plotter.camera.zoom(1.35)
    for _ in range(10):
        app.processEvents()
    w.viewport.plotter.render()
    app.processEvents()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    w.grab().save(str(OUT))
    print(f"wrote {OUT} ({w.figures.text()})")
    w.close()
    symmetric_shot(app)


def symmetric_shot(app) -> None:
    """The operator's guide's second picture: symmetric mode (dR 2 mm), the cursor on a collision
    at an edge while both cut symmetrically: red cutters, the violations marked on the spacing plot."""
    from bladecam_gui.main_window import MainWindow
    from core.pipeline import PlanParameters

    w = MainWindow(params=PlanParameters(dr=2.0, mode="symmetric"), restore=False)
    w.resize(1500, 920)
    w.show()
    loop = QEventLoop()
    w.controller.idle.connect(loop.quit)
    w.open_blade_source("sample")
    loop.exec()
    data = w.state.plan
    if data is None or not data.has_schedule:
        raise SystemExit("the symmetric plan did not complete")
    tl = data.timeline
    cands = np.nonzero(data.danger & (data.step >= 4) & tl.left.cutting & tl.right.cutting)[0]
    w.state.set_cursor(int(cands[len(cands) // 2]) if len(cands) else int(np.argmin(data.spacing)))
    w.viewport.plotter.view_vector((0.45, 1.0, 0.35), viewup=(0.0, 0.0, 1.0), render=False)
    w.viewport.plotter.reset_camera(render=False)
    w.viewport.plotter.camera.zoom(1.35)
    for _ in range(10):
        app.processEvents()
    w.viewport.plotter.render()
    app.processEvents()
    w.grab().save(str(SYMMETRIC))
    print(f"wrote {SYMMETRIC} ({w.figures.text()})")
    w.close()


if __name__ == "__main__":
    main()

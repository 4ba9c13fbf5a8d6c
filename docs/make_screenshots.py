"""Take the README's and the guide's screenshots from the real program: the whole workbench with the
sample blade's plan shown at 1600x1000, 1280x800 and 1024x700 (workbench-<width>.png), and the
symmetric mode's collisions, and the inspection tools (inspect.png; run under a display or xvfb-run):

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python docs/make_screenshots.py [--coarse] [--out DIR]

--coarse plans with dR 3 mm (quicker, for trying the layout); the README's images use the defaults.
--out writes the images to DIR instead of docs/img.
"""

import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("QT_API", "pyside6")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from core.util.process import configure_process  # noqa: E402

configure_process()  # (first: one BLAS thread, as in the application)
import numpy as np  # noqa: E402
from PySide6.QtCore import QEventLoop, QSettings, QTimer  # noqa: E402
from PySide6.QtWidgets import QApplication  # noqa: E402

IMG = Path(__file__).parent / "img"
SIZES = ((1600, 1000), (1280, 800), (1024, 700))


def _planned_window(params):
    """The workbench planning the sample blade with ``params`` (None: defaults), once the plan is in."""
    from bladecam_gui.main_window import MainWindow

    w = MainWindow(params=params, restore=False)
    w.resize(1280, 800)
    w.show()
    loop = QEventLoop()
    w.controller.idle.connect(loop.quit)
    w.open_blade_source("sample")
    loop.exec()
    if w.state.plan is None or not w.state.plan.has_schedule:
        raise SystemExit("the sample plan did not complete")
    return w


def _wait(ms: int) -> None:
    loop = QEventLoop()
    QTimer.singleShot(ms, loop.quit)
    loop.exec()


def _shoot(app, w, cursor: int, out: Path, size=(1280, 800), close: bool = True) -> None:
    """Cursor at sample ``cursor``, the window at ``size``, the view from the trailing-edge side and a
    little above (both cutters, one each side of the blade, in sight), the whole window saved to
    ``out``."""
    w.resize(*size)
    _wait(200)  # (the docks give way on the next turns of the event loop)
    w.state.set_cursor(cursor)
    w.viewport.plotter.view_vector((0.45, 1.0, 0.35), viewup=(0.0, 0.0, 1.0), render=False)
    w.viewport.plotter.reset_camera(render=False)
    w.viewport.plotter.camera.zoom(1.35)
    _wait(500)  # (the read-out and the plots follow the cursor a few times a second, on a timer)
    w.viewport.plotter.render()
    app.processEvents()
    out.parent.mkdir(parents=True, exist_ok=True)
    w.grab().save(str(out))
    print(f"wrote {out} ({w.figures.text()})")
    if close:
        w.close()


def _shoot_inspect(app, w, out: Path) -> None:
    """The inspection tools at 1280x800: the blade coloured by the scallop height, cut at the cursor's
    contour, a distance measured across the section between two picked points, seen from the tip."""
    from vtkmodules.vtkRenderingCore import vtkCoordinate

    w.resize(1280, 800)
    w.view_dock.raise_()
    _wait(200)
    tl = w.state.plan.timeline
    opts, vp = w.view_options, w.viewport
    for key in ("paths", "left", "right"):
        opts.boxes[key].setChecked(False)
    cutting = np.nonzero(tl.left.cutting & (tl.left.path >= 0))[0]
    w.state.set_cursor(int(cutting[len(cutting) // 2]))
    opts.inspect["scallop"].setChecked(True)
    opts.inspect["section"].setChecked(True)
    vp.plotter.view_vector((1.0, 0.55, 0.6), viewup=(0.0, 0.0, 1.0), render=False)
    vp.plotter.reset_camera(render=False)
    vp.plotter.camera.zoom(1.3)
    vp.plotter.render()
    opts.inspect["measure"].setChecked(True)
    section = vp.blade.blade.blade.section(vp.blade.section_r)
    frame = vp.blade.blade.frame
    ends = frame.points(np.array([section.face[len(section.face) // 4], section.face[3 * len(section.face) // 4]]))
    width, height = vp.plotter.ren_win.GetSize()
    for point in ends:  # (the section's face, a quarter from each end: picked where it is drawn)
        c = vtkCoordinate()
        c.SetCoordinateSystemToWorld()
        c.SetValue(*map(float, point))
        x, y = c.GetComputedDoubleDisplayValue(vp.plotter.renderer)
        vp.measure_at(x * vp.widget.width() / width, (height - 1 - y) * vp.widget.height() / height)
    _wait(300)
    vp.plotter.render()
    app.processEvents()
    out.parent.mkdir(parents=True, exist_ok=True)
    w.grab().save(str(out))
    print(f"wrote {out} (measured {vp.measure.text or 'nothing'})")
    w.close()


def main() -> None:
    QSettings.setPath(QSettings.Format.IniFormat, QSettings.Scope.UserScope, tempfile.mkdtemp())
    app = QApplication.instance() or QApplication(sys.argv)
    from core.records import PlanParameters

    img = Path(sys.argv[sys.argv.index("--out") + 1]) if "--out" in sys.argv else IMG
    w = _planned_window(PlanParameters(dr=3.0) if "--coarse" in sys.argv else None)
    data, tl = w.state.plan, w.state.plan.timeline
    # an instant of the collaborative part: both cutters cutting, past the middle of the job
    both = np.nonzero(tl.left.cutting & tl.right.cutting & (data.step >= 4))[0]
    at = int(both[int(len(both) * 0.45)]) if len(both) else len(tl.t) // 2
    for size in SIZES:
        _shoot(app, w, at, img / f"workbench-{size[0]}.png", size, close=False)
    _shoot_inspect(app, w, img / "inspect.png")
    # the guide's second picture: symmetric mode (dR 2 mm), the cursor on a collision at an edge
    # while both cut symmetrically: red cutters, the violations marked on the spacing plot
    w = _planned_window(PlanParameters(dr=2.0, mode="symmetric"))
    data, tl = w.state.plan, w.state.plan.timeline
    hits = np.nonzero(data.danger & (data.step >= 4) & tl.left.cutting & tl.right.cutting)[0]
    _shoot(app, w, int(hits[len(hits) // 2]) if len(hits) else int(np.argmin(data.spacing)),
           img / "symmetric.png")


if __name__ == "__main__":
    main()

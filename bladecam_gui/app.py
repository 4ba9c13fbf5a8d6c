"""Start-up of the workbench: QApplication, the main window, the sample blade (or a project) planned."""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path


def before_qt(sample: bool, params=None):
    """What the workbench does before Qt loads: with ``sample`` (no project given), start the sample
    blade's paths (start_sample_paths; returned, else None), forked before Qt starts any thread."""
    return start_sample_paths(params) if sample else None


def show_splash(app):
    """A splash screen at once, while the 3D libraries load and the window is built (seconds on a
    loaded machine): the program's name and what it is doing. Returned; ``splash.finish(window)``
    closes it when the window shows."""
    from PySide6.QtCore import Qt
    from PySide6.QtGui import QColor, QPixmap
    from PySide6.QtWidgets import QSplashScreen

    from .style import BACKGROUND

    pixmap = QPixmap(460, 150)
    pixmap.fill(QColor(BACKGROUND[0]))
    splash = QSplashScreen(pixmap)
    font = splash.font()
    font.setPointSizeF(font.pointSizeF() * 1.3)
    splash.setFont(font)
    splash.show()
    splash.showMessage("bladecam workbench\n\nloading the 3D view and the plots…",
                       Qt.AlignmentFlag.AlignCenter, QColor("white"))
    app.processEvents()
    return splash


def start_sample_paths(params=None):
    """The sample blade loaded and its paths' worker processes forked (plan_data.EarlyPaths), before
    Qt and VTK load: the paths (about 2 s of two cores) are planned while the libraries load and the
    window is built, and the first job picks them up (if it is the sample's job; else it cancels
    them). Forking before Qt starts any thread is also the safe order. None if that fails."""
    from .plan_data import sample_job, start_early_paths

    return start_early_paths(sample_job(params))


def no_display() -> str | None:
    """Why Qt has no display to open a window on (None: it has one, or is told which platform to
    use): on Linux without DISPLAY or WAYLAND_DISPLAY, Qt's xcb plugin aborts the process (status 134)
    with a message about a missing library."""
    if not sys.platform.startswith("linux") or os.environ.get("QT_QPA_PLATFORM"):
        return None
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
        return None
    return ("no display to open the workbench on (neither DISPLAY nor WAYLAND_DISPLAY is set): run it in a "
            "desktop session or under a virtual X server (xvfb-run bladecam gui), or plan from the command "
            "line (bladecam plan); make run does the latter, with a picture of the workbench")


def screenshot_when_planned(window, app, path: str) -> None:
    """Save a PNG of ``window`` at ``path`` once its first plan is shown, print where, and quit
    (``make run`` without a display); a planning failure prints its message and quits with status 2."""
    def shown() -> None:
        if window.controller.running or window.state.plan is None or not window.state.plan.has_schedule:
            return
        app.processEvents()
        target = Path(path).resolve()
        target.parent.mkdir(parents=True, exist_ok=True)
        if not window.grab().save(str(target), "PNG"):
            print(f"bladecam gui: error: cannot write the picture {target}", file=sys.stderr)
            window.close()
            app.exit(2)
            return
        print(f"picture of the workbench: {target}")
        window.close()  # (ends the planner's thread before the application)
        app.exit(0)

    def failed(title: str, message: str) -> None:
        print(f"bladecam gui: error: {title}: {message}", file=sys.stderr)
        window.close()
        app.exit(2)

    window.controller.failed.disconnect(window._on_failed)  # (no dialog: nobody is there to close it)
    window.controller.failed.connect(failed)
    window.controller.idle.connect(shown)  # (after the plan is shown and the job has ended)


def review_folder(app, folder: str, screenshot: str | None) -> int:
    """``bladecam gui FOLDER``: the plan folder's read-only review window alone (plan_folder); a folder
    that is not a plan folder is one line and status 2. With ``screenshot``: its PNG once verify has
    reported, then quit."""
    from core.errors import BladecamError

    from .plan_folder import PlanFolder, PlanFolderWindow

    try:
        data = PlanFolder.read(folder)
    except BladecamError as exc:
        print(f"bladecam gui: error: {exc}", file=sys.stderr)
        return 2
    window = PlanFolderWindow(data)
    if screenshot:
        def shoot(_report) -> None:
            app.processEvents()
            target = Path(screenshot).resolve()
            target.parent.mkdir(parents=True, exist_ok=True)
            ok = window.grab().save(str(target), "PNG")
            print(f"picture of the plan folder's review: {target}" if ok else
                  f"bladecam gui: error: cannot write the picture {target}", file=sys.stdout if ok else sys.stderr)
            window.close()
            app.exit(0 if ok else 2)

        window.verified.connect(shoot)
    window.show()
    return app.exec()


def main(argv: list[str] | None = None) -> int:
    os.environ.setdefault("QT_API", "pyside6")
    parser = argparse.ArgumentParser(prog="bladecam gui", description="the bladecam workbench")
    parser.add_argument("project", nargs="?",
                        help="a project file (.toml) to open instead of the sample blade, or a written plan "
                             "folder to review (read-only: its tables, the machines at the cursor, verify's "
                             "findings)")
    parser.add_argument("--screenshot", metavar="PNG",
                        help="save a picture of the workbench once its plan is shown, then quit")
    args, qt_args = parser.parse_known_args(sys.argv[1:] if argv is None else argv)
    why = no_display()
    if why is not None:
        print(f"bladecam gui: error: {why}", file=sys.stderr)
        return 2
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    from core.util.memory import tune_allocator

    tune_allocator(trim=512 << 20)  # freed plan arrays reused; at most 512 MiB kept beyond the live data
    folder = args.project if args.project and Path(args.project).is_dir() else None
    early = before_qt(sample=not args.project)

    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication([sys.argv[0], *qt_args])
    app.setApplicationName("bladecam")
    app.setOrganizationName("bladecam")
    app.setDesktopFileName("bladecam")
    from PySide6.QtGui import QIcon

    from core.util.resources import resources_dir

    icon = resources_dir() / "bladecam.png"
    if icon.is_file():
        app.setWindowIcon(QIcon(str(icon)))

    if folder is not None:
        return review_folder(app, folder, args.screenshot)
    splash = show_splash(app)  # (the libraries below load behind it: PySide6's import hook reads
    # their source, about 0.1 s more than before Qt, for something on screen at once)
    import pyvista.plotting  # noqa: F401

    from .main_window import MainWindow

    window = MainWindow(early=early, restore=not args.screenshot)
    if args.screenshot:
        window.resize(1600, 1000)
        screenshot_when_planned(window, app, args.screenshot)
    window.show()
    splash.finish(window)
    if args.project:
        window.files.open_project(args.project)
    else:
        window.open_blade_source("sample")
    return app.exec()

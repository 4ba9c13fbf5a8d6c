"""Start-up of the workbench: QApplication, the main window, the sample blade (or a project) planned."""

from __future__ import annotations

import argparse
import logging
import os
import sys


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


def main(argv: list[str] | None = None) -> int:
    os.environ.setdefault("QT_API", "pyside6")
    parser = argparse.ArgumentParser(prog="bladecam gui", description="the bladecam workbench")
    parser.add_argument("project", nargs="?",
                        help="a project file (.toml) to open instead of the sample blade")
    args, qt_args = parser.parse_known_args(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    from core.util.memory import tune_allocator

    tune_allocator(trim=512 << 20)  # freed plan arrays reused; at most 512 MiB kept beyond the live data
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

    splash = show_splash(app)  # (the libraries below load behind it: PySide6's import hook reads
    # their source, about 0.1 s more than before Qt, for something on screen at once)
    import pyvista.plotting  # noqa: F401

    from .main_window import MainWindow

    window = MainWindow(early=early)
    window.show()
    splash.finish(window)
    if args.project:
        window.files.open_project(args.project)
    else:
        window.open_blade_source("sample")
    return app.exec()

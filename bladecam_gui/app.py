"""Start-up of the workbench: QApplication, the main window, the sample blade (or a project) planned."""

from __future__ import annotations

import argparse
import logging
import os
import sys


def main(argv: list[str] | None = None) -> int:
    os.environ.setdefault("QT_API", "pyside6")
    parser = argparse.ArgumentParser(prog="bladecam gui", description="the bladecam workbench")
    parser.add_argument("project", nargs="?",
                        help="a project file (.toml) to open instead of the sample blade")
    args, qt_args = parser.parse_known_args(sys.argv[1:] if argv is None else argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    from core.memory import tune_allocator

    tune_allocator(trim=512 << 20)  # freed plan arrays reused; at most 512 MiB kept beyond the live data

    from PySide6.QtWidgets import QApplication

    app = QApplication.instance() or QApplication([sys.argv[0], *qt_args])
    app.setApplicationName("bladecam")
    app.setOrganizationName("bladecam")
    app.setDesktopFileName("bladecam")
    from PySide6.QtGui import QIcon

    from core.blade_source import resources_dir

    icon = resources_dir() / "bladecam.png"
    if icon.is_file():
        app.setWindowIcon(QIcon(str(icon)))

    from .main_window import MainWindow

    window = MainWindow()
    window.show()
    if args.project:
        window.files.open_project(args.project)
    else:
        window.open_blade_source("sample")
    return app.exec()

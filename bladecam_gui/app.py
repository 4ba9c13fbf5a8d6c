"""Start-up of the workbench: QApplication, the main window, the sample blade."""

from __future__ import annotations

import os
import sys


def main(argv: list[str] | None = None) -> int:
    os.environ.setdefault("QT_API", "pyside6")
    from PySide6.QtWidgets import QApplication

    from .main_window import MainWindow

    argv = list(sys.argv[1:] if argv is None else argv)
    app = QApplication.instance() or QApplication([sys.argv[0], *argv])
    app.setApplicationName("bladecam")
    app.setOrganizationName("bladecam")
    window = MainWindow()
    window.show()
    window.load_blade_source("sample")
    return app.exec()

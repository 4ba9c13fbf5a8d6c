"""Take the README's screenshots from the real program (run under a display or xvfb-run):

    xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python docs/make_screenshots.py
"""

import os
import sys
from pathlib import Path

os.environ.setdefault("QT_API", "pyside6")
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from PySide6.QtWidgets import QApplication  # noqa: E402

from bladecam_gui.main_window import MainWindow  # noqa: E402


def main() -> None:
    app = QApplication.instance() or QApplication(sys.argv)
    w = MainWindow()
    w.resize(1280, 800)
    w.show()
    w.load_blade_source("sample")
    w.plotter.view_isometric()
    w.plotter.reset_camera()
    for _ in range(5):
        app.processEvents()
    w.plotter.render()
    out = Path(__file__).parent / "img" / "workbench.png"
    w.grab().save(str(out))
    print(f"wrote {out}")
    w.close()


if __name__ == "__main__":
    main()

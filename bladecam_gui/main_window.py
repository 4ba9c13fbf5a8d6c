"""The main window: assembles the 3D view and the menus, and wires them to the state."""

from __future__ import annotations

import logging

from PySide6.QtWidgets import QFileDialog, QMainWindow, QMessageBox
from pyvistaqt import QtInteractor

from core.blade_source import load_blade
from core.errors import BladecamError

from .render.blade_view import BladeView
from .state import WorkbenchState

log = logging.getLogger(__name__)


class MainWindow(QMainWindow):
    def __init__(self, state: WorkbenchState | None = None):
        super().__init__()
        self.setWindowTitle("bladecam")
        self.resize(1280, 820)
        self.state = state or WorkbenchState(self)
        self.plotter = QtInteractor(self)
        self.plotter.set_background("#20242c", top="#3b4252")
        self.plotter.add_axes()
        self.setCentralWidget(self.plotter.interactor)
        self.blade_view = BladeView(self.plotter)
        self.state.blade_changed.connect(self._on_blade_changed)
        self._build_menus()
        self.statusBar().showMessage("ready")

    def _build_menus(self) -> None:
        file_menu = self.menuBar().addMenu("&File")
        file_menu.addAction("Open &blade...", self._on_open_blade)
        file_menu.addSeparator()
        file_menu.addAction("&Quit", self.close)

    def load_blade_source(self, source: str, axis: str = "z") -> bool:
        """Load a blade; on a bad source show a message box and keep the previous blade."""
        try:
            blade = load_blade(source, axis=axis)
        except BladecamError as exc:
            QMessageBox.warning(self, "Cannot open the blade", str(exc))
            return False
        self.state.set_blade(blade, source, axis)
        return True

    def _on_open_blade(self) -> None:
        try:
            path, _ = QFileDialog.getOpenFileName(
                self, "Open blade", "", "Blades (*.csv *.txt *.stl *.obj *.ply);;All files (*)")
            if path:
                self.load_blade_source(path)
        except Exception as exc:  # slots never raise
            log.exception("open blade failed")
            QMessageBox.critical(self, "Error", str(exc))

    def _on_blade_changed(self, blade) -> None:
        try:
            self.blade_view.show(blade)
            self.plotter.reset_camera()
            info = blade.info()
            self.statusBar().showMessage(
                f"{info['name']}: tip radius {info['tip_radius_mm']:.2f} mm, "
                f"hub radius {info['hub_radius_mm']:.2f} mm")
        except Exception as exc:  # slots never raise
            log.exception("showing the blade failed")
            QMessageBox.critical(self, "Error", str(exc))

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        self.plotter.close()
        super().closeEvent(event)

"""The main window: assembles the 3D view, the docks, menus, toolbar and status bar, and wires them."""

from __future__ import annotations

import logging
from pathlib import Path

from PySide6.QtCore import Qt, Slot
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import QDockWidget, QMainWindow, QScrollArea, QSplitter, QWidget

from core.records import PlanParameters

from .about import show_about
from .commands import InputEditor
from .export import ExportController
from .files import FileActions
from .guard import show_error
from .plan_data import EarlyPaths
from .render.viewport import Viewport
from .report import ReportAction
from .settings import restore_layout, save_layout
from .state import WorkbenchState
from .widgets.axes_plot import AxesPlot
from .widgets.clearance_panel import ClearancePanel
from .widgets.dock_layout import DockBalancer, PanelsToggle
from .widgets.edit_keys import REDO_EXTRA, WindowUndoKeys
from .widgets.job_panel import JobPanel
from .widgets.params_panel import ParamsPanel
from .widgets.plots import FeedPlot, SpacingPlot
from .widgets.share_panel import SharePanel
from .widgets.shortcuts import build_go_menu, show_shortcuts
from .widgets.status import FiguresLabel, KeyFigures, ProgressBox
from .widgets.timeline import TimelinePanel
from .widgets.view_options import ViewOptionsPanel
from .worker import PlanController

log = logging.getLogger(__name__)


class MainWindow(QMainWindow):
    """state, controller (planning), editor (undo), viewport (3D), params, timeline, plots, files.
    ``early``: the first job's paths started ahead (app.main), used if that job is the same."""

    def __init__(self, params: PlanParameters | None = None, debounce_ms: int = 350,
                 restore: bool = True, early: EarlyPaths | None = None):
        super().__init__()
        self.setWindowTitle("bladecam workbench")
        self.setObjectName("bladecam-main")
        self.resize(1500, 940)
        self.state = WorkbenchState(self, params=params.resolved() if params is not None else None)
        self.controller = PlanController(self.state, debounce_ms, self, early=early)
        self.editor = InputEditor(self.state, self)
        self.viewport = Viewport(self.state, self)
        self.setCentralWidget(self.viewport.container)
        self.exporter = ExportController(self.state, self)
        self.files = FileActions(self, self.state, self.editor, self.exporter)
        self.params_panel = ParamsPanel(self.state, self.editor)
        self.timeline = TimelinePanel(self.state)
        # the 3D view light while the timeline's cursor is dragged, in full once it rests or is let go
        self.timeline.bar.drag_started.connect(self.viewport.drag.begin)
        self.timeline.bar.drag_finished.connect(self.viewport.drag.end)
        self.spacing_plot = SpacingPlot(self.state)
        self.feed_plot = FeedPlot(self.state)
        self.view_options = ViewOptionsPanel(self.state, self.viewport)
        self.axes_plot = AxesPlot(self.state)
        self.share_panel = SharePanel(self.state)
        self.job_panel = JobPanel(self.state)
        self.violation_list = self.job_panel.violations
        self._build_docks()
        self.view_dock = self._dock("3D view", "dock-view", self.view_options,
                                    Qt.DockWidgetArea.LeftDockWidgetArea)
        # one column of tabs on the left: Parameters gets the column's whole height
        self.tabifyDockWidget(self.params_dock, self.view_dock)
        self.params_dock.raise_()
        self.axes_dock = self._dock("Axes", "dock-axes", self.axes_plot,
                                    Qt.DockWidgetArea.RightDockWidgetArea)
        self.tabifyDockWidget(self.plots_dock, self.axes_dock)
        self.axes_dock.visibilityChanged.connect(self.axes_plot.set_on_screen)
        self.share_dock = self._dock("Collab.", "dock-share", self.share_panel,
                                     Qt.DockWidgetArea.RightDockWidgetArea)
        self.tabifyDockWidget(self.plots_dock, self.share_dock)
        self.clearance_dock = self._dock("Clearance", "dock-clearance", ClearancePanel(self.state),
                                         Qt.DockWidgetArea.RightDockWidgetArea)
        self.tabifyDockWidget(self.plots_dock, self.clearance_dock)
        self.share_panel.summary_changed.connect(self.share_dock.setWindowTitle)
        self.job_dock = self._dock("Job", "dock-job", self.job_panel, Qt.DockWidgetArea.LeftDockWidgetArea)
        self.tabifyDockWidget(self.params_dock, self.job_dock)
        self.params_dock.raise_()
        self.job_panel.title_changed.connect(self.job_dock.setWindowTitle)
        self.plots_dock.raise_()
        self._build_status()
        self._build_actions()
        self.balancer = DockBalancer(self)
        self.state.blade_changed.connect(self._on_blade_changed)
        self.controller.failed.connect(self._on_failed)
        self.exporter.failed.connect(self._on_failed)
        self.exporter.status.connect(lambda text: self.statusBar().showMessage(text, 15000))
        self.statusBar().messageChanged.connect(self.job_panel.on_status_message)  # kept in the log
        self.controller.failed.connect(self.job_panel.on_failed)
        self.exporter.failed.connect(self.job_panel.on_failed)
        if restore:
            restore_layout(self)

    # -- assembly --------------------------------------------------------------------------------
    def _dock(self, title: str, name: str, widget: QWidget, area) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(name)
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        return dock

    def _build_docks(self) -> None:
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setWidget(self.params_panel)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        scroll.setMinimumWidth(self.params_panel.minimumSizeHint().width()
                               + scroll.verticalScrollBar().sizeHint().width() + 4)
        self.params_dock = self._dock("Parameters", "dock-params", scroll,
                                      Qt.DockWidgetArea.LeftDockWidgetArea)
        self.timeline_dock = self._dock("Timeline", "dock-timeline", self.timeline,
                                        Qt.DockWidgetArea.BottomDockWidgetArea)
        plots = QSplitter(Qt.Orientation.Vertical)
        plots.addWidget(self.spacing_plot)
        plots.addWidget(self.feed_plot)
        plots.setMinimumWidth(220)
        self.plots_dock = self._dock("Plots", "dock-plots", plots, Qt.DockWidgetArea.RightDockWidgetArea)
        self.resizeDocks([self.params_dock, self.plots_dock], [max(scroll.minimumWidth(), 310), 430],
                         Qt.Orientation.Horizontal)

    def _build_status(self) -> None:
        self.figures = FiguresLabel(self.state)
        self.key_figures = KeyFigures(self.state)
        self.progress = ProgressBox()
        self.statusBar().addWidget(self.figures, 1)
        self.statusBar().addPermanentWidget(self.key_figures)
        self.statusBar().addPermanentWidget(self.progress)
        self.state.progress_changed.connect(self.progress.set_progress)
        self.exporter.progress.connect(self.progress.set_progress)
        self.state.busy_changed.connect(self._on_busy_changed)
        self.exporter.busy_changed.connect(self._on_busy_changed)
        self.progress.cancel_button.clicked.connect(self.cancel)

    def _action(self, menu, text: str, slot, shortcut=None, tip: str = "") -> QAction:
        action = QAction(text, self)
        if shortcut is not None:
            action.setShortcut(QKeySequence(shortcut))
        action.setStatusTip(tip)
        action.triggered.connect(lambda checked=False: slot())
        menu.addAction(action)
        return action

    def _build_actions(self) -> None:
        f = self.files
        file_menu = self.menuBar().addMenu("&File")
        self._action(file_menu, "Open &blade…", f.open_blade_dialog, QKeySequence.StandardKey.Open,
                     "a geometry table, a mesh, or face and back meshes")
        self._action(file_menu, "Open the &sample blade", lambda: f.open_blade("sample", "z"))
        recent_blades = file_menu.addMenu("Recent blades")
        recent_blades.aboutToShow.connect(lambda: f.fill_recent_blades(recent_blades))
        self._action(file_menu, "&Tool file…", f.open_tool_dialog, None,
                     "the tool assembly (tool.toml: ball, flutes, neck, shank, holder, spindle nose)")
        file_menu.addSeparator()
        self._action(file_menu, "Open &project…", f.open_project_dialog, "Ctrl+Shift+O")
        self._action(file_menu, "Open plan &folder…", f.open_plan_folder_dialog, None,
                     "a written plan folder, read-only: its tables, the machines at the cursor, verify's findings")
        self._action(file_menu, "Save project &as…", f.save_project_dialog, QKeySequence.StandardKey.Save)
        recent_projects = file_menu.addMenu("Recent projects")
        recent_projects.aboutToShow.connect(lambda: f.fill_recent_projects(recent_projects))
        file_menu.addSeparator()
        self.export_action = self._action(file_menu, "&Export plan to folder…", f.export_dialog, "Ctrl+E",
                                          "write the CL (and axis) tables, verified first")
        self.report = ReportAction(self)
        self._action(file_menu, "Save job &report…", self.report.dialog, "Ctrl+Shift+R",
                     "an HTML page of the plan shown: blade, tool, machine, parameters, figures, warnings "
                     "and a picture")
        file_menu.addSeparator()
        self._action(file_menu, "&Quit", self.close, QKeySequence.StandardKey.Quit)

        edit_menu = self.menuBar().addMenu("&Edit")
        self.undo_action = self.editor.stack.createUndoAction(self, "&Undo")
        self.undo_action.setShortcut(QKeySequence.StandardKey.Undo)
        self.redo_action = self.editor.stack.createRedoAction(self, "&Redo")
        # the platform's redo key and Ctrl+Y, wherever the focus is (spin boxes included: edit_keys)
        redo_keys = [k for k in QKeySequence.keyBindings(QKeySequence.StandardKey.Redo)]
        redo_keys += [QKeySequence(REDO_EXTRA)] if QKeySequence(REDO_EXTRA) not in redo_keys else []
        self.redo_action.setShortcuts(redo_keys)
        for action in (self.undo_action, self.redo_action):
            action.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
            self.addAction(action)
        self.undo_keys = WindowUndoKeys(self)
        self.undo_keys.install(self)
        edit_menu.addAction(self.undo_action)
        edit_menu.addAction(self.redo_action)

        view_menu = self.menuBar().addMenu("&View")
        toolbar = self.addToolBar("View")
        toolbar.setObjectName("toolbar-view")
        for name, key in (("front", "Ctrl+1"), ("side", "Ctrl+2"), ("iso", "Ctrl+3"), ("fit", "Ctrl+0")):
            action = self._action(view_menu, name.capitalize(), lambda n=name: self.viewport.view(n), key)
            toolbar.addAction(action)
        self.view_options.add_actions(view_menu, toolbar)
        toolbar.addSeparator()
        toolbar.addAction(self.undo_action)
        toolbar.addAction(self.redo_action)
        view_menu.addSeparator()
        for dock in (self.params_dock, self.timeline_dock, self.plots_dock):
            view_menu.addAction(dock.toggleViewAction())
        for dock in (self.view_dock, self.axes_dock, self.share_dock, self.job_dock):
            view_menu.addAction(dock.toggleViewAction())

        self.panels_action = PanelsToggle(self, [d for d in self.findChildren(QDockWidget)
                                                 if d is not self.timeline_dock])
        view_menu.addAction(self.panels_action)
        self.go_menu = build_go_menu(self, self.timeline)
        self.menuBar().addMenu(self.go_menu)

        plan_menu = self.menuBar().addMenu("&Plan")
        self._action(plan_menu, "&Re-plan now", lambda: self.controller.request(immediate=True, fresh=True),
                     "F5")
        self._action(plan_menu, "&Cancel planning", self.cancel, "Esc")
        help_menu = self.menuBar().addMenu("&Help")
        self._action(help_menu, "&About bladecam", lambda: show_about(self, self.viewport.kind))
        self._action(help_menu, "&Keyboard shortcuts", lambda: show_shortcuts(self), "F1")

    # -- operations ------------------------------------------------------------------------------
    def open_blade_source(self, source: str, axis: str = "z") -> None:
        """Load and plan a blade (asynchronously: wait for state.plan_changed or controller.finished)."""
        self.files.open_blade(source, axis)

    def cancel(self) -> None:
        self.controller.cancel()
        self.exporter.cancel()

    @Slot(object)
    def _on_blade_changed(self, blade) -> None:
        try:
            # the file (two meshes: "face,back"), or the built-in sample's name
            name = (blade.blade.info()["name"] if blade.source == "sample"
                    else " + ".join(Path(p).name for p in blade.source.split(",")))
            self.setWindowTitle(f"{name} · bladecam workbench")
        except Exception:  # slots never raise
            log.exception("naming the window failed")

    @Slot(bool)
    def _on_busy_changed(self, _busy: bool) -> None:
        self.progress.set_busy(self.state.busy or self.exporter.busy)

    @Slot(str, str)
    def _on_failed(self, title: str, message: str) -> None:
        try:
            self.statusBar().showMessage(f"{title}: {message.splitlines()[0]}", 15000)
            show_error(self, title, message)
        except Exception:  # slots never raise
            log.exception("showing an error failed")

    def closeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        try:
            save_layout(self)
            self.timeline.play_button.setChecked(False)
            self.hide()  # gone at once, while a running schedule step finishes (it cannot be interrupted)
            self.controller.shutdown()
            self.exporter.shutdown()
        finally:
            self.viewport.close()
            super().closeEvent(event)

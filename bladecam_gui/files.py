"""File actions: open a blade (table, mesh, or face and back meshes, with the axis; of a whole
propeller, the blade), open and save a project (core.output.project), open a written plan folder for
review (read-only), export the plan to a folder, and the recent-files menus.

A project's ``axes`` key is not an input of the workbench, whose plans always carry the machines' axis
tables: it is ignored on reading (older projects say false) and written true."""

from __future__ import annotations

import logging
from dataclasses import replace
from pathlib import Path

from PySide6.QtCore import QObject, Qt
from PySide6.QtWidgets import QApplication, QFileDialog, QInputDialog, QMenu, QWidget

from core.blade.source import (
    AXES,
    CAD_SUFFIXES,
    MESH_SUFFIXES,
    SAMPLE,
    TABLE_SUFFIXES,
    merged_options,
    source_parts,
    whole_propeller,
)
from core.errors import BladeInputError
from core.machine.tool import load_tool, resolve_tool
from core.output.project import Project, load_project, save_project

from .commands import InputEditor
from .export import ExportController
from .guard import guarded
from .propeller_dialog import PropellerDialog
from .settings import add_recent, recent, settings
from .state import WorkbenchState

BLADE_FILTER = ("Blades (*.csv *.txt *.stl *.obj *.ply *.step *.stp *.igs *.iges)"
                ";;Geometry tables (*.csv *.txt);;"
                "Meshes (*.stl *.obj *.ply);;CAD surfaces (*.step *.stp *.igs *.iges);;All files (*)")
PROJECT_FILTER = "bladecam projects (*.toml);;All files (*)"
log = logging.getLogger(__name__)


def blade_source_from_files(files: list[str]) -> tuple[str, bool]:
    """(SOURCE string, is a mesh) for the files picked: one table, one mesh, or face and back meshes."""
    if not files:
        raise BladeInputError("no file chosen")
    suffixes = {Path(f).suffix.lower() for f in files}
    if len(files) == 1 and suffixes <= set(TABLE_SUFFIXES):
        return files[0], False
    if len(files) <= 2 and (suffixes <= set(MESH_SUFFIXES) or suffixes <= set(CAD_SUFFIXES)):
        return ",".join(files), True
    raise BladeInputError(f"choose one geometry table (.csv), one closed blade mesh or CAD solid, or two mesh "
                          f"or CAD files (face and back), not {len(files)} files of types "
                          f"{', '.join(sorted(suffixes))}")


class FileActions(QObject):
    """The File menu's actions; dialogs are parented to ``parent_widget``."""

    def __init__(self, parent_widget: QWidget, state: WorkbenchState, editor: InputEditor,
                 exporter: ExportController):
        super().__init__(parent_widget)
        self.parent_widget, self.state, self.editor, self.exporter = parent_widget, state, editor, exporter
        self.project_path: Path | None = None
        self._opening: tuple[str, str] | None = None
        self.review_windows: list = []  # (the plan folders open for review)
        state.blade_changed.connect(self._on_blade_changed)

    def _last_dir(self, key: str) -> str:
        return str(settings().value(f"dirs/{key}", ""))

    def _remember_dir(self, key: str, path: str) -> None:
        settings().setValue(f"dirs/{key}", str(Path(path).parent))

    # -- blades ----------------------------------------------------------------------------------
    @guarded("Cannot open the blade")
    def open_blade_dialog(self) -> None:
        files, _ = QFileDialog.getOpenFileNames(
            self.parent_widget, "Open blade: a geometry table, a mesh, or the face and back meshes",
            self._last_dir("blades"), BLADE_FILTER)
        if not files:
            return
        source, is_mesh = blade_source_from_files(list(files))
        axis = "z"
        if is_mesh:
            last = str(settings().value("blade/axis", "z"))
            axis, ok = QInputDialog.getItem(
                self.parent_widget, "Propeller axis", "The propeller axis of the mesh (x, y or z):",
                list(AXES), AXES.index(last) if last in AXES else 2, False)
            if not ok:
                return
            settings().setValue("blade/axis", axis)
            source = self._pick_propeller_blade(source, axis)
            if source is None:
                return
        self._remember_dir("blades", files[0])
        self.open_blade(source, axis)

    def _pick_propeller_blade(self, source: str, axis: str) -> str | None:
        """The SOURCE string with the blade (and hub cut) the operator picks when ``source`` is a whole
        propeller about ``axis`` (PropellerDialog); ``source`` itself when it is not; None when the
        operator cancels. BladeInputError for a file that cannot be read."""
        QApplication.setOverrideCursor(Qt.CursorShape.WaitCursor)
        try:
            prop = whole_propeller(source, axis)
        finally:
            QApplication.restoreOverrideCursor()
        if prop is None:
            return source
        dialog = PropellerDialog(prop, Path(source_parts(source)[0]).name, self.parent_widget)
        if not dialog.exec():
            return None
        index, r_min = dialog.choice()
        return merged_options(source, index, r_min)

    @guarded("Cannot open the blade")
    def open_blade(self, source: str, axis: str = "z") -> None:
        """Load a blade and plan it (in the worker; a bad file brings a message, the old plan stays)."""
        self._opening = (source, axis)
        self.state.set_blade_source(source, axis)

    def _on_blade_changed(self, blade) -> None:
        """A blade is shown: the one being opened goes to Recent blades (one that failed never does)."""
        try:
            if self._opening == (blade.source, blade.axis) and blade.source != SAMPLE:
                add_recent("blades", f"{blade.axis}|{blade.source}")
            self._opening = None
        except Exception:  # slots never raise
            log.exception("remembering the blade failed")

    # -- projects --------------------------------------------------------------------------------
    @guarded("Cannot open the project")
    def open_project_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self.parent_widget, "Open project", self._last_dir("projects"),
                                              PROJECT_FILTER)
        if path:
            self.open_project(path)

    def open_tool_dialog(self) -> None:
        path, _ = QFileDialog.getOpenFileName(self.parent_widget, "Tool file: the tool assembly (tool.toml)",
                                              self._last_dir("tools"), "Tool files (*.toml);;All files (*)")
        if path:
            self.open_tool(path)

    @guarded("Cannot use the tool file")
    def open_tool(self, path: str | Path) -> None:
        """Plan with the tool assembly of ``path``: its ball radius and stick-out become the tool radius
        and length (core.machine.tool.resolve_tool)."""
        tool = load_tool(path)
        self.state.tool = str(Path(path).resolve())
        self._remember_dir("tools", str(path))
        params = replace(self.state.params, tool_radius=tool.ball_radius, tool_length=tool.stick_out)
        if params == self.state.params:  # (the same radius and stick-out: the tool alone is new)
            self.state.inputs_changed.emit("params")
        else:
            self.state.set_params(params)

    @guarded("Cannot open the project")
    def open_project(self, path: str | Path) -> None:
        proj = load_project(path)
        params = proj.params.resolved()  # 'auto' values written out for the panels
        if proj.tool is not None:  # (the tool file's radius and stick-out are the parameters')
            resolve_tool(proj.tool, params.tool_radius, params.tool_length)
        self.editor.stack.clear()
        self.state.tool = proj.tool
        self.state.set_project(proj.source, proj.axis, params, proj.profile, proj.period)
        self.project_path = Path(path)
        self._remember_dir("projects", str(path))
        add_recent("projects", str(Path(path).resolve()))

    @guarded("Cannot save the project")
    def save_project_dialog(self) -> None:
        start = str(self.project_path) if self.project_path else self._last_dir("projects")
        path, _ = QFileDialog.getSaveFileName(self.parent_widget, "Save project", start, PROJECT_FILTER)
        if path:
            if not Path(path).suffix:
                path += ".toml"
            self.save_project(path)

    @guarded("Cannot save the project")
    def save_project(self, path: str | Path) -> None:
        s = self.state
        save_project(Project(s.source, s.axis, s.params, s.profile, s.period, axes=True, tool=s.tool), path)
        self.project_path = Path(path)
        self._remember_dir("projects", str(path))
        add_recent("projects", str(Path(path).resolve()))

    # -- plan folders ----------------------------------------------------------------------------
    @guarded("Cannot open the plan folder")
    def open_plan_folder_dialog(self) -> None:
        folder = QFileDialog.getExistingDirectory(self.parent_widget, "Open a plan folder (read-only review)",
                                                  self._last_dir("plans"))
        if folder:
            self.open_plan_folder(folder)

    @guarded("Cannot open the plan folder")
    def open_plan_folder(self, folder: str | Path):
        """A written plan folder in a read-only review window of its own (plan_folder.PlanFolderWindow:
        the tables as written, the machines at the cursor, verify's findings); the workbench's plan
        stays as it is. Returns the window."""
        from .plan_folder import PlanFolder, PlanFolderWindow

        window = PlanFolderWindow(PlanFolder.read(folder))
        window.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        self.review_windows.append(window)
        window.destroyed.connect(lambda _=None, w=window: self.review_windows.remove(w)
                                 if w in self.review_windows else None)
        settings().setValue("dirs/plans", str(Path(folder).resolve().parent))
        window.show()
        return window

    # -- export ----------------------------------------------------------------------------------
    @guarded("Cannot export the plan")
    def export_dialog(self) -> None:
        folder = QFileDialog.getExistingDirectory(
            self.parent_widget, "Export the plan to a folder (empty, new, or a previous plan folder)",
            self._last_dir("exports"))
        if folder:
            settings().setValue("dirs/exports", folder)
            self.exporter.export_to(folder)

    # -- recent files ----------------------------------------------------------------------------
    def fill_recent_blades(self, menu: QMenu) -> None:
        menu.clear()
        for entry in recent("blades"):
            axis, _, source = entry.partition("|")
            menu.addAction(f"{source}  (axis {axis})", lambda a=axis, s=source: self.open_blade(s, a))
        if menu.isEmpty():
            menu.addAction("(none yet)").setEnabled(False)

    def fill_recent_projects(self, menu: QMenu) -> None:
        menu.clear()
        for path in recent("projects"):
            menu.addAction(path, lambda p=path: self.open_project(p))
        if menu.isEmpty():
            menu.addAction("(none yet)").setEnabled(False)

"""The 3D view's options: what is drawn (blade and its opacity, paths, each cutter, the two machines),
which paths (one face, the current contour emphasised), and a camera that follows a cutter. The
extra views (bottom, top) go to the View menu and the toolbar through ``add_actions``.

Everything is applied by the viewport's render adapters (bladecam_gui.render); this panel holds no
geometry."""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt, Slot
from PySide6.QtGui import QAction, QKeySequence
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QFormLayout,
    QLabel,
    QSlider,
    QVBoxLayout,
    QWidget,
)

from ..render.viewport import Viewport
from ..state import WorkbenchState

log = logging.getLogger(__name__)

FACE_CHOICES = (("both", "both faces"), ("left", "left cutter's face (back, -Z_W)"),
                ("right", "right cutter's face (face, +Z_W)"))
FOLLOW_CHOICES = (("off", "free"), ("left", "follows the left cutter"),
                  ("right", "follows the right cutter"), ("midpoint", "follows the pair's midpoint"))
EXTRA_VIEWS = (("bottom", "Bottom (from -Z_W)", "Ctrl+4", "onto the back, where the left cutter works"),
               ("top", "Top (from the blade tip)", "Ctrl+5", "down the span from +X_W, Z_W up: the "
                "section with a cutter either side"))


def _slider(value: int) -> QSlider:
    s = QSlider(Qt.Orientation.Horizontal)
    s.setRange(0, 100)
    s.setValue(value)
    s.setSingleStep(5)
    s.setPageStep(10)
    return s


class ViewOptionsPanel(QWidget):
    """Check boxes, sliders and combos bound to the viewport's adapters (``viewport``)."""

    def __init__(self, state: WorkbenchState, viewport: Viewport, parent=None):
        super().__init__(parent)
        self.state = state
        self.viewport = viewport
        form = QFormLayout()
        form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
        form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)  # a narrow dock: labels above
        self.boxes: dict[str, QCheckBox] = {}
        for key, text, on in (("blade", "blade", True), ("paths", "paths", True),
                              ("left", "left cutter", True), ("right", "right cutter", True),
                              ("machines", "both machines (XYZ-3RPS)", False)):
            box = QCheckBox(text)
            box.setObjectName(f"show-{key}")
            box.setChecked(on)
            box.toggled.connect(lambda checked, k=key: self._on_shown_changed(k, checked))
            self.boxes[key] = box
        self.blade_opacity = _slider(100)
        self.blade_opacity.setToolTip("see the cutter behind the blade")
        self.blade_opacity.valueChanged.connect(self._on_blade_opacity_changed)
        self.machine_opacity = _slider(100)
        self.machine_opacity.valueChanged.connect(self._on_machine_opacity_changed)
        self.face = QComboBox()
        for key, text in FACE_CHOICES:
            self.face.addItem(text, key)
        self.face.currentIndexChanged.connect(self._on_face_changed)
        self.emphasis = QCheckBox("emphasise the current contour")
        self.emphasis.setToolTip("the contour being machined at the cursor and its neighbours drawn thick, "
                                 "the others dimmed")
        self.emphasis.toggled.connect(self._on_emphasis_changed)
        self.follow = QComboBox()
        for key, text in FOLLOW_CHOICES:
            self.follow.addItem(text, key)
        self.follow.currentIndexChanged.connect(self._on_follow_changed)
        for combo in (self.face, self.follow):  # narrow: the long choices show whole in the list
            combo.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
            combo.setMinimumContentsLength(10)
        self.inspect: dict[str, QCheckBox] = {}
        for key, text, tip in (
                ("scallop", "colour by scallop height",
                 "each part of the blade coloured by the largest scallop height left between the contour "
                 "paths crossing it (red: a strip left uncut; grey: outside the paths)"),
                ("section", "section at the cursor's contour",
                 "the blade cut by the cylinder of the contour machined at the cursor (the tip side "
                 "removed), its outline drawn; follows the cursor"),
                ("measure", "measure (click two points)",
                 "click two points on the blade: the distance between them is drawn; a third click starts "
                 "again; the view still turns on a drag")):
            box = QCheckBox(text)
            box.setObjectName(f"inspect-{key}")
            box.setToolTip(tip)
            box.toggled.connect(lambda checked, k=key: self._on_inspect_changed(k, checked))
            self.inspect[key] = box
        self.note = QLabel()
        self.note.setWordWrap(True)
        self.note.setStyleSheet("color: #9aa4b4;")
        row = QVBoxLayout()
        for key in ("blade", "paths", "left", "right"):
            row.addWidget(self.boxes[key])
        form.addRow("Show", row)
        form.addRow("Blade opacity", self.blade_opacity)
        form.addRow("Paths of", self.face)
        form.addRow("", self.emphasis)
        form.addRow("Camera", self.follow)
        inspect = QVBoxLayout()
        for box in self.inspect.values():
            inspect.addWidget(box)
        form.addRow("Inspect", inspect)
        form.addRow("Machines", self.boxes["machines"])
        form.addRow("Machine opacity", self.machine_opacity)
        form.addRow("", self.note)
        outer = QVBoxLayout(self)
        outer.addLayout(form)
        outer.addStretch(1)
        self.view_actions: dict[str, QAction] = {}
        state.plan_changed.connect(self._on_plan_changed)
        state.cursor_changed.connect(self._on_cursor_changed)
        self._update_note()

    def add_actions(self, menu, toolbar) -> None:
        """The extra views (bottom, top) in the View menu and the toolbar."""
        for name, text, key, tip in EXTRA_VIEWS:
            action = QAction(text, self)
            action.setShortcut(QKeySequence(key))
            action.setStatusTip(tip)
            action.triggered.connect(lambda checked=False, n=name: self._on_view(n))
            menu.addAction(action)
            toolbar.addAction(action)
            self.view_actions[name] = action

    # -- operator --------------------------------------------------------------------------------
    def _on_view(self, name: str) -> None:
        try:
            self.viewport.view(name)
        except Exception:  # slots never raise
            log.exception("turning the view failed")

    def _on_inspect_changed(self, key: str, on: bool) -> None:
        try:
            vp = self.viewport
            {"scallop": vp.set_scallop_shown, "section": vp.set_section_shown,
             "measure": vp.set_measuring}[key](on)
        except Exception:  # slots never raise
            log.exception("turning %s on or off failed", key)

    def _on_shown_changed(self, key: str, shown: bool) -> None:
        try:
            vp = self.viewport
            if key == "blade":
                vp.blade.set_visible(shown)
            elif key == "paths":
                vp.paths.set_visible(shown)
            elif key in ("left", "right"):
                vp.cutters.set_shown(key, shown)
            else:
                vp.set_machines_shown(shown)
                self._update_note()
            vp.render()
        except Exception:  # slots never raise
            log.exception("showing or hiding %s failed", key)

    @Slot(int)
    def _on_blade_opacity_changed(self, value: int) -> None:
        try:
            self.viewport.blade.set_opacity(value / 100.0)
            self.viewport.render()
        except Exception:  # slots never raise
            log.exception("setting the blade's opacity failed")

    @Slot(int)
    def _on_machine_opacity_changed(self, value: int) -> None:
        try:
            self.viewport.machines.set_opacity(value / 100.0)
            self.viewport.render()
        except Exception:  # slots never raise
            log.exception("setting the machines' opacity failed")

    @Slot(int)
    def _on_face_changed(self, _index: int) -> None:
        try:
            self.viewport.paths.set_face(self.face.currentData())
            self.viewport.render()
        except Exception:  # slots never raise
            log.exception("choosing the paths' face failed")

    @Slot(bool)
    def _on_emphasis_changed(self, on: bool) -> None:
        try:
            self.viewport.paths.set_emphasis(on)
            self.viewport.render()
        except Exception:  # slots never raise
            log.exception("emphasising the current contour failed")

    @Slot(int)
    def _on_follow_changed(self, _index: int) -> None:
        try:
            self.viewport.set_follow(self.follow.currentData())
        except Exception:  # slots never raise
            log.exception("setting the camera failed")

    # -- state -----------------------------------------------------------------------------------
    @Slot(object)
    def _on_plan_changed(self, _data) -> None:
        try:
            self._update_note()
        except Exception:  # slots never raise
            log.exception("updating the view options failed")

    @Slot(int)
    def _on_cursor_changed(self, _index: int) -> None:
        try:
            if self.boxes["machines"].isChecked():
                self._update_note()
        except Exception:  # slots never raise
            log.exception("updating the machines' note failed")

    def _update_note(self) -> None:
        if not self.boxes["machines"].isChecked():
            text = "machines hidden"
        else:
            text = self.viewport.machines.note or "no plan yet"
        if text != self.note.text():
            self.note.setText(text)

"""The list of the shown plan's violations: one row per run of consecutive time samples that break the
safety rule (widgets.navigation.violation_list; the timeline's red marks, the status bar's count),
with its time, step, both cutters' paths, kind and depth below the rule. A click (or Enter) on a row
moves the timeline to the violation's first sample."""

from __future__ import annotations

import logging

import numpy as np
from PySide6.QtCore import QAbstractTableModel, QModelIndex, Qt, Signal, Slot
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QLabel, QTableView, QVBoxLayout, QWidget

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import step_name
from . import navigation as nav
from .step_bar import clock

log = logging.getLogger(__name__)

NO_PARENT = QModelIndex()
COLUMNS = ("#", "time", "step", "paths L / R", "kind", "depth mm")


def depth_text(row: dict, i: int) -> str:
    """How far past the rule: mm below h_safe (tip spacing, at or between samples) and mm of overlap of
    the tool capsules."""
    parts = []
    if row["spacing_n"][i]:
        parts.append(f"{row['depth_spacing'][i]:.3f}")
    if row["clearance_n"][i]:
        parts.append(f"{row['depth_clearance'][i]:.3f}")
    return " / ".join(parts)


class ViolationModel(QAbstractTableModel):
    def __init__(self, parent=None):
        super().__init__(parent)
        self.rows: dict[str, np.ndarray] = {}
        self.n = 0

    def set_rows(self, rows: dict[str, np.ndarray]) -> None:
        self.beginResetModel()
        self.rows, self.n = rows, len(rows.get("start", ()))
        self.endResetModel()

    def rowCount(self, parent=NO_PARENT) -> int:  # noqa: N802 (Qt name)
        return 0 if parent.isValid() else self.n

    def columnCount(self, parent=NO_PARENT) -> int:  # noqa: N802 (Qt name)
        return 0 if parent.isValid() else len(COLUMNS)

    def headerData(self, section, orientation, role=Qt.ItemDataRole.DisplayRole):  # noqa: N802 (Qt name)
        if role == Qt.ItemDataRole.DisplayRole and orientation == Qt.Orientation.Horizontal:
            return COLUMNS[section]
        return None

    def text(self, i: int, column: int) -> str:
        r = self.rows
        if column == 0:
            return str(i + 1)
        if column == 1:
            return clock(r["t0"][i])
        if column == 2:
            return str(int(r["step"][i]))
        if column == 3:
            return f"{int(r['left'][i])} / {int(r['right'][i])}"
        if column == 4:
            return str(r["kind"][i])
        return depth_text(r, i)

    def data(self, index, role=Qt.ItemDataRole.DisplayRole):
        if not index.isValid():
            return None
        i, column = index.row(), index.column()
        if role == Qt.ItemDataRole.DisplayRole:
            return self.text(i, column)
        if role == Qt.ItemDataRole.ToolTipRole:
            r = self.rows
            return (f"violation {i + 1}: {clock(r['t0'][i])} to {clock(r['t1'][i])} (samples {r['start'][i]}"
                    f"–{r['end'][i]}), step {int(r['step'][i])} {step_name(r['step'][i])}\n"
                    f"tip spacing: {r['spacing_n'][i]} samples or intervals below h_safe, minimum "
                    f"{r['min_spacing'][i]:.3f} mm\ntool clearance: {r['clearance_n'][i]} samples touching, "
                    f"minimum {r['min_clearance'][i]:.3f} mm")
        return None


class ViolationList(QWidget):
    """A count line and the table; ``count_changed(int)`` the number of violations (for the tab)."""

    count_changed = Signal(int)

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__(parent)
        self.state = state
        self.summary = QLabel("no plan yet")
        self.summary.setWordWrap(True)
        self.model = ViolationModel(self)
        self.table = QTableView(self)
        self.table.setModel(self.model)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.verticalHeader().setVisible(False)
        self.table.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.setMinimumWidth(160)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.summary)
        layout.addWidget(self.table, 1)
        self.table.clicked.connect(self._on_row_chosen)
        self.table.activated.connect(self._on_row_chosen)
        state.plan_changed.connect(self._on_plan_changed)

    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            if not data.has_schedule:
                self.model.set_rows({})
                self.summary.setText("planning…")
                self.count_changed.emit(0)
                return
            rows = nav.violation_list(data)
            self.model.set_rows(rows)
            n = self.model.n
            h = data.result.plan.params.h_safe
            self.summary.setText(
                f"<b>{n} violation{'s' if n != 1 else ''}</b>: runs of consecutive time samples that break "
                f"the safety rule (tip spacing ≥ h_safe {h:g} mm at and between samples, the tool capsules "
                f"apart). Depth: mm below h_safe / mm of capsule overlap. Click a row to go there."
                if n else "no violation: the tip spacing keeps h_safe and the tools stay apart throughout")
            self.count_changed.emit(n)
        except Exception:  # slots never raise
            log.exception("listing the violations failed")

    def _on_row_chosen(self, index) -> None:
        try:
            if index.isValid() and self.model.n:
                self.state.set_cursor(int(self.model.rows["start"][index.row()]))
        except Exception:  # slots never raise
            log.exception("jumping to the violation failed")

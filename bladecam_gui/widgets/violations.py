"""The list of the shown plan's violations: one row per run of consecutive time samples that break the
safety rule or where a part collides (verdict.Violations; the timeline's red marks, the verdict's
count), with its time, step, both cutters' paths, its kinds (tip spacing, tool clearance, part against
the blade, the clamp or the other assembly), their depths and the parts; above it the count by kind
and what to change. A click (or Enter) on a row moves the timeline to the violation's first sample."""

from __future__ import annotations

import logging

import numpy as np
from PySide6.QtCore import QAbstractTableModel, QModelIndex, Qt, Signal, Slot
from PySide6.QtWidgets import QAbstractItemView, QHeaderView, QLabel, QTableView, QVBoxLayout, QWidget

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import step_name
from ..verdict import DEPTH_OF, KINDS, item_text
from . import navigation as nav
from .step_bar import clock

log = logging.getLogger(__name__)

NO_PARENT = QModelIndex()
#: 'depth mm' and 'part' list the run's items in the same order (verdict.Violations.rows)
COLUMNS = ("#", "time", "step", "paths L / R", "kind", "depth mm", "part")


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
        if column == 5:
            return str(r["depths"][i])
        return str(r["part"][i])

    def tooltip(self, i: int) -> str:
        """The run's span and each of its items with its depth, and where the deepest lies."""
        r = self.rows
        lines = [f"violation {i + 1}: {clock(r['t0'][i])} to {clock(r['t1'][i])} (samples {r['start'][i]}"
                 f"–{r['end'][i]}), step {int(r['step'][i])} {step_name(r['step'][i])}"]
        for kind, part, depth, row in r["items"][i]:
            where = f" at sample {row}" if row != r["start"][i] else ""
            lines.append(f"{kind}: {item_text(kind, part, depth)}{where}")
        if r["spacing_n"][i]:
            lines.append(f"tip spacing: {r['spacing_n'][i]} samples or intervals below h_safe, minimum "
                         f"{r['min_spacing'][i]:.3f} mm")
        if r["clearance_n"][i]:
            lines.append(f"tool clearance: {r['clearance_n'][i]} samples touching, minimum "
                         f"{r['min_clearance'][i]:.3f} mm")
        return "\n".join(lines)

    def data(self, index, role=Qt.ItemDataRole.DisplayRole):
        if not index.isValid():
            return None
        i, column = index.row(), index.column()
        if role == Qt.ItemDataRole.DisplayRole:
            return self.text(i, column)
        if role == Qt.ItemDataRole.ToolTipRole:
            return self.tooltip(i)
        return None


def summary_html(found) -> str:
    """The list's heading (verdict.Violations): the count by kind with the deepest of each, and what to
    change; what a violation is and what each depth measures are in its tooltip."""
    if not found.n:
        return ("no violation: the tip spacing keeps h_safe, the tools stay apart and no part of the tool "
                "assemblies or heads touches the blade, the clamp or the other side throughout")
    advice = " ".join(f"{a[0].upper()}{a[1:]}." for a in found.advice())
    return (f"<b>{found.n} violation{'s' if found.n != 1 else ''}</b>: runs of consecutive unsafe samples, "
            f"{found.kinds_text()}. <b>What to change:</b> {advice}")


def summary_tooltip(found) -> str:
    kinds = "\n".join(f"depth of {k}: {DEPTH_OF[k]}" for k in KINDS if found.kinds.get(k))
    return f"{found.tooltip()}\n{kinds}\nclick a row to go there" if found.n else found.tooltip()


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
        self.table.verticalHeader().setDefaultSectionSize(self.fontMetrics().lineSpacing() + 4)
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

    def wanted_height(self, rows: int) -> int:
        """px this list needs to show its heading and ``rows`` rows at its width."""
        t = self.table
        table = (t.horizontalHeader().sizeHint().height() + rows * t.verticalHeader().defaultSectionSize()
                 + t.horizontalScrollBar().sizeHint().height() + 2 * t.frameWidth())
        margins = self.layout().contentsMargins()
        heading = self.summary.heightForWidth(max(self.width(), 200))
        return heading + self.layout().spacing() + table + margins.top() + margins.bottom()

    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            if not data.has_schedule:
                self.model.set_rows({})
                self.summary.setText("planning…")
                self.count_changed.emit(0)
                return
            found = nav.violations_of(data)
            self.model.set_rows(found.rows)
            self.summary.setText(summary_html(found))
            self.summary.setToolTip(summary_tooltip(found))
            self.count_changed.emit(found.n)
        except Exception:  # slots never raise
            log.exception("listing the violations failed")

    def _on_row_chosen(self, index) -> None:
        try:
            if index.isValid() and self.model.n:
                self.state.set_cursor(int(self.model.rows["start"][index.row()]))
        except Exception:  # slots never raise
            log.exception("jumping to the violation failed")

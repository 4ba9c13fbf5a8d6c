"""Plot of both machines' six axes (x, y, z, d1, d2, d3) over the job's time, against machine.toml's
limits (pyqtgraph, as bladecam_gui.widgets.plots): the stroke, the speed or the acceleration of each
axis, one row per axis, the left machine in the left cutter's colour and the right in the right's,
the limits as dashed lines, and the cursor. A click, or dragging a cursor line, moves the timeline.

The figures are the plan's axis tables (core.machine.tables.AxisTable: values, velocities and
accelerations), the ones an export writes; until a plan with them is shown (a blade loaded, its paths
being planned) a note stands in for the plots."""

from __future__ import annotations

import logging

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, Slot
from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QVBoxLayout, QWidget

from core.machine.model import AXES, SIDES

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import BACKGROUND, LEFT_COLOUR, RIGHT_COLOUR
from .plots import MS, cursor_dragged, time_clicked
from .throttle import Throttle

log = logging.getLogger(__name__)

#: quantity -> (label, unit, factor from the table's mm, mm/ms or mm/ms^2)
QUANTITIES = {"position": ("stroke", "mm", 1.0), "speed": ("speed", "mm/s", 1e3),
              "accel": ("acceleration", "mm/s²", 1e6)}
LIMIT_PEN = pg.mkPen("#ffb020", width=1, style=Qt.PenStyle.DashLine)
NO_TABLES = "The machines' axes appear here once the plan is complete."


class AxesPlot(QWidget):
    """Six stacked plots sharing the time axis (min), a quantity chooser and a note."""

    CURSOR_INTERVAL_MS = 200
    CURSOR_PHASE_MS = 150

    def __init__(self, state: WorkbenchState, parent=None):
        super().__init__(parent)
        self.state = state
        self.quantity = QComboBox()
        for key, (label, unit, _) in QUANTITIES.items():
            self.quantity.addItem(f"{label} ({unit})", key)
        self.quantity.currentIndexChanged.connect(self._on_quantity_changed)
        self.note = QLabel(NO_TABLES)
        self.note.setWordWrap(True)
        self.graphics = pg.GraphicsLayoutWidget()
        self.graphics.setBackground(BACKGROUND[0])
        top = QHBoxLayout()
        top.addWidget(QLabel("Machine axes:"))
        top.addWidget(self.quantity, 1)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addLayout(top)
        layout.addWidget(self.note)
        layout.addWidget(self.graphics, 1)
        self.plots: dict[str, pg.PlotItem] = {}
        self.curves: dict[tuple[str, str], pg.PlotDataItem] = {}
        self.limits: dict[str, list[pg.InfiniteLine]] = {}
        self.cursors: list[pg.InfiniteLine] = []
        first = None
        for row, axis in enumerate(AXES):
            item = self.graphics.addPlot(row=row, col=0)
            item.setLabel("left", axis)
            item.showGrid(x=True, y=True, alpha=0.2)
            item.setClipToView(True)
            item.setDownsampling(auto=True, mode="peak")
            item.setMenuEnabled(False)
            item.getAxis("left").setWidth(48)
            if first is None:
                first = item
            else:
                item.setXLink(first)
            if row < len(AXES) - 1:
                item.getAxis("bottom").setStyle(showValues=False)
            else:
                item.setLabel("bottom", "time (min)")
            for side, colour in (("left", LEFT_COLOUR), ("right", RIGHT_COLOUR)):
                self.curves[(axis, side)] = item.plot(pen=pg.mkPen(colour, width=1), name=f"{side} machine")
            self.limits[axis] = [pg.InfiniteLine(angle=0, movable=False, pen=LIMIT_PEN) for _ in range(2)]
            for line in self.limits[axis]:
                item.addItem(line, ignoreBounds=True)
            cursor = pg.InfiniteLine(angle=90, movable=True, pen=pg.mkPen("w", width=1))
            cursor.setZValue(10)
            cursor.sigPositionChanged.connect(self._on_cursor_dragged)
            item.addItem(cursor, ignoreBounds=True)
            self.cursors.append(cursor)
            self.plots[axis] = item
        self.graphics.scene().sigMouseClicked.connect(self._on_clicked)
        self._throttle = Throttle(self._move_cursor, self.CURSOR_INTERVAL_MS, parent=self,
                                  phase_ms=self.CURSOR_PHASE_MS)
        self.on_screen = True  # (set_on_screen)
        self._pending = False  # a plan arrived while off screen: drawn when shown
        state.plan_changed.connect(self._on_plan_changed)
        state.cursor_changed.connect(self._throttle.request)
        self._show(None)

    # -- state -----------------------------------------------------------------------------------
    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        # a hidden plot (its tab behind another) draws when shown: a plan's twelve curves of half a
        # million rows each hold the GUI thread for a third of a second as the plan arrives
        try:
            if self.on_screen:
                self._show(data)
            else:
                self._pending = True
                shown = self.tables(data) is not None
                self.note.setVisible(not shown)
                self.graphics.setVisible(shown)
        except Exception:  # slots never raise
            log.exception("the machine axes plot failed")

    @Slot(bool)
    def set_on_screen(self, shown: bool) -> None:
        """Whether the plot is on screen (its dock's visibilityChanged: a tab behind another is
        'visible' to Qt); a plan that arrived meanwhile is drawn now."""
        self.on_screen = bool(shown)
        if self.on_screen and self._pending:
            self._pending = False
            try:
                self._show(self.state.plan)
            except Exception:  # slots never raise
                log.exception("the machine axes plot failed")

    @Slot(int)
    def _on_quantity_changed(self, _index: int) -> None:
        self._on_plan_changed(self.state.plan)

    def tables(self, data: PlanData | None) -> dict | None:
        """The shown plan's axis tables (side -> AxisTable), or None."""
        if data is None or data.result is None or not data.result.axes or data.result.machine is None:
            return None
        return data.result.axes

    def series(self, table, axis: str) -> tuple[np.ndarray, np.ndarray]:
        """(t min, value in the quantity's unit) of one axis of one table."""
        k = AXES.index(axis)
        key = self.quantity.currentData()
        factor = QUANTITIES[key][2]
        if key == "position":
            return table.t / MS, table.values[:, k]
        if key == "speed":
            return table.t / MS, table.velocities[:, k] * factor
        mid = 0.5 * (table.t[1:] + table.t[:-1])  # (accelerations are between rows)
        return mid / MS, table.accelerations()[:, k] * factor

    def limit_values(self, machine, axis: str) -> tuple[float, float]:
        """The two limit lines of an axis for the chosen quantity (machine.toml's units)."""
        lim = machine.limits.axis(axis)
        key = self.quantity.currentData()
        if key == "position":
            return lim.min_mm, lim.max_mm
        v = lim.max_speed_mm_s if key == "speed" else lim.max_accel_mm_s2
        return -v, v

    def _show(self, data: PlanData | None) -> None:
        tables = self.tables(data)
        self.note.setVisible(tables is None)
        self.graphics.setVisible(tables is not None)
        for curve in self.curves.values():
            curve.setData([], [])
        if tables is None:
            return
        machine = data.result.machine
        t_end = float(data.timeline.t[-1]) / MS if data.has_schedule else float(tables["left"].t[-1]) / MS
        self.plots[AXES[0]].setXRange(0.0, t_end, padding=0.01)
        for axis in AXES:
            lo, hi = self.limit_values(machine, axis)
            for line, v in zip(self.limits[axis], (lo, hi), strict=True):
                line.setValue(v)
            span = hi - lo
            self.plots[axis].setYRange(lo - 0.08 * span, hi + 0.08 * span, padding=0.0)
            for side in SIDES:
                self.curves[(axis, side)].setData(*self.series(tables[side], axis))
        self._move_cursor(self.state.cursor)

    def _move_cursor(self, _index) -> None:
        try:
            if self.tables(self.state.plan) is None:
                return
            x = self.state.cursor_time / MS
            for line in self.cursors:
                line.blockSignals(True)
                line.setValue(x)
                line.blockSignals(False)
        except Exception:  # slots never raise
            log.exception("moving the machine axes plot's cursor failed")

    # -- operator --------------------------------------------------------------------------------
    def _on_cursor_dragged(self, line) -> None:
        cursor_dragged(self.state, line)

    def _on_clicked(self, event) -> None:
        time_clicked(self.state, event, [item.getViewBox() for item in self.plots.values()])

"""Plots over the job's time (pyqtgraph): tip spacing with the h_safe line and the violations, and
both cutters' feed (the sigmoid stages show as the dips). A click, or dragging the cursor line, moves
the timeline there."""

from __future__ import annotations

import logging

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, Slot
from PySide6.QtWidgets import QGraphicsItem

from core.machine.tables import SLOWED_FOR

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import BACKGROUND, DANGER_COLOUR, LEFT_COLOUR, RIGHT_COLOUR
from .throttle import Throttle

log = logging.getLogger(__name__)
MAX_MARKERS = 2000
MS = 60000.0  # ms per plotted time unit (minutes, as on the timeline)
#: the feed plot's top, and the height of its strip where the machine clock slows the job, as shares of
#: the feed (the legend, in two columns, above the strip)
FEED_PLOT_TOP = 1.45
SLOWED_STRIP = 1.07
SLOWED_AXES_COLOUR, SLOWED_CHORD_COLOUR = "#e06c75", "#e5c07b"


class TimePlot(pg.PlotWidget):
    """A plot over the job time (min) with a cursor line bound to the state's cursor."""

    CURSOR_PHASE_MS = 50
    CURSOR_INTERVAL_MS = 150

    def __init__(self, state: WorkbenchState, title: str, y_label: str, parent=None):
        super().__init__(parent=parent, background=BACKGROUND[0])
        self.state = state
        item = self.getPlotItem()
        item.setTitle(title, size="9pt")
        item.setLabel("bottom", "time (min)")
        item.setLabel("left", y_label)
        item.showGrid(x=True, y=True, alpha=0.25)
        # room right of the last tick label (else clipped by the widget's edge)
        item.layout.setContentsMargins(2, 2, 16, 2)
        for name in ("left", "bottom"):
            # plain numbers: never a scale factor such as "(x0.001)" in the label
            item.getAxis(name).enableAutoSIPrefix(False)
            # the axes draw the grid across the whole view, so every move of the cursor line repainted
            # them (1.3 ms each, six per plot update of a timeline drag): from a pixmap cache instead,
            # redrawn only when the axis itself changes
            item.getAxis(name).setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
        item.setClipToView(True)
        item.setDownsampling(auto=True, mode="peak")
        item.setMenuEnabled(False)
        self.legend = item.addLegend(offset=(5, 5), labelTextSize="8pt", brush=pg.mkBrush(38, 42, 51, 210))
        self.cursor = pg.InfiniteLine(angle=90, movable=True, pen=pg.mkPen("w", width=1))
        self.cursor.setZValue(10)
        item.addItem(self.cursor, ignoreBounds=True)
        self.cursor.sigPositionChanged.connect(self._on_cursor_dragged)
        self.scene().sigMouseClicked.connect(self._on_clicked)
        # the read-out follows the cursor at once, the plots 50 and 100 ms later: in a drag each frame
        # repaints at most one of them (all three in one frame made it 10 ms slower)
        self._cursor_throttle = Throttle(self._move_cursor, self.CURSOR_INTERVAL_MS, parent=self,
                                         phase_ms=self.CURSOR_PHASE_MS)
        state.plan_changed.connect(self._on_plan_changed)
        state.cursor_changed.connect(self._cursor_throttle.request)

    def cached(self, item: pg.PlotDataItem) -> pg.PlotDataItem:
        """Draw a curve from a pixmap cache, so that moving the cursor line does not redraw it."""
        item.curve.setCacheMode(QGraphicsItem.CacheMode.DeviceCoordinateCache)
        return item

    @property
    def view_box(self) -> pg.ViewBox:
        return self.getPlotItem().getViewBox()

    # -- state -----------------------------------------------------------------------------------
    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            # the ranges first, on empty curves: pyqtgraph clips and downsamples every curve again
            # whenever a range changes (5 curves of 600k samples: ~27 passes, 0.2 s, if set after)
            self.clear_plan()
            if data.has_schedule:
                self.set_ranges(data)
                self.show_plan(data)
            self._move_cursor(self.state.cursor)
        except Exception:  # slots never raise
            log.exception("plot update failed")

    def _move_cursor(self, _index) -> None:
        """Put the cursor line at the state's cursor (throttled while dragging)."""
        try:
            data = self.state.plan
            if data is None or not data.has_schedule:
                return
            self.cursor.blockSignals(True)
            self.cursor.setValue(self.state.cursor_time / MS)
            self.cursor.blockSignals(False)
        except Exception:  # slots never raise
            log.exception("moving the plot cursor failed")

    # -- operator --------------------------------------------------------------------------------
    def _on_cursor_dragged(self, line) -> None:
        cursor_dragged(self.state, line)

    def _on_clicked(self, event) -> None:
        time_clicked(self.state, event, [self.view_box])

    def set_ranges(self, data: PlanData) -> None:
        """The view's ranges for a plan (before its curves are set): the whole job in x."""
        self.view_box.setXRange(0.0, float(data.timeline.t[-1]) / MS, padding=0.01)

    def show_plan(self, data: PlanData) -> None:
        raise NotImplementedError

    def clear_plan(self) -> None:
        raise NotImplementedError


class SpacingPlot(TimePlot):
    """Tip spacing (and capsule clearance) over time, the h_safe line, violations in red."""

    def __init__(self, state: WorkbenchState, parent=None):
        super().__init__(state, "Tip spacing, clearance", "mm", parent)
        item = self.getPlotItem()
        self.spacing_curve = self.cached(item.plot(pen=pg.mkPen("#e8e8e8", width=1), name="tip spacing"))
        dashed = pg.mkPen("#8090a0", width=1, style=Qt.PenStyle.DashLine)
        self.clearance_curve = self.cached(item.plot(pen=dashed,
                                         name="capsule clearance"))
        self.violation_curve = self.cached(item.plot(pen=pg.mkPen(DANGER_COLOUR, width=3), connect="finite",
                                         name="violation"))
        self.markers = pg.ScatterPlotItem(size=7, pen=None, brush=pg.mkBrush(DANGER_COLOUR), symbol="t")
        item.addItem(self.markers)
        self.h_line = pg.InfiniteLine(angle=0, movable=False,
                                      pen=pg.mkPen("#ffb020", width=1, style=Qt.PenStyle.DashLine),
                                      label="h_safe {value:.3f} mm",
                                      labelOpts={"position": 0.03, "color": "#ffb020",
                                                 "anchors": [(0, 1), (0, 1)]})  # right of its place
        item.addItem(self.h_line, ignoreBounds=True)
        self.h_line.setVisible(False)  # (until a plan gives its h_safe)
        self.violation_times = np.zeros(0)

    def set_ranges(self, data: PlanData) -> None:
        super().set_ranges(data)
        h = data.result.plan.params.h_safe
        low = float(data.clearance.min()) if len(data.clearance) else 0.0
        self.view_box.setYRange(min(-0.1 * h, low), 8.0 * h, padding=0.02)

    def show_plan(self, data: PlanData) -> None:
        t = data.timeline.t / MS
        h = data.result.plan.params.h_safe
        self.spacing_curve.setData(t, data.spacing)
        self.clearance_curve.setData(t, data.clearance)
        y = np.where(data.danger, data.spacing, np.nan)
        self.violation_curve.setData(t, y, connect="finite")
        starts = np.nonzero(data.danger & ~np.concatenate([[False], data.danger[:-1]]))[0]
        self.violation_times = t[starts]
        shown = starts[:MAX_MARKERS]
        self.markers.setData(t[shown], np.zeros(len(shown)))
        self.h_line.setVisible(True)  # (first: a hidden line's label does not follow its value)
        self.h_line.setValue(h)
        self.h_line.label.valueChanged()

    def clear_plan(self) -> None:
        for c in (self.spacing_curve, self.clearance_curve, self.violation_curve):
            c.setData([], [])
        self.markers.setData([], [])
        self.h_line.setVisible(False)  # (no plan, no h_safe of its own)
        self.violation_times = np.zeros(0)


class FeedPlot(TimePlot):
    """Both cutters' tip speed along their paths while cutting (mm/min), with the programmed feed, in a
    window of ``WINDOW_MIN`` minutes that follows the cursor: at the scale of a whole job the speed
    stages of hundreds of paths merge, around the cursor the sigmoid stages of the current paths show.
    ``follow`` off keeps the range the operator zoomed to."""

    WINDOW_MIN = 1.0
    CURSOR_PHASE_MS = 100
    #: its window moves with the cursor, which redraws its time axis and re-clips both curves (~10 ms
    #: of a frame): in a drag at most every 0.4 s, which is as often as anyone can read it
    CURSOR_INTERVAL_MS = 400

    def __init__(self, state: WorkbenchState, parent=None):
        super().__init__(state, "Feed round the cursor", "mm/min", parent)
        item = self.getPlotItem()
        self.left_curve = self.cached(item.plot(pen=pg.mkPen(LEFT_COLOUR, width=1), name="left cutter",
                                                connect="finite"))
        self.right_curve = self.cached(item.plot(pen=pg.mkPen(RIGHT_COLOUR, width=1), name="right cutter",
                                                 connect="finite"))
        self.feed_line = pg.InfiniteLine(angle=0, movable=False,
                                         pen=pg.mkPen("#ffb020", width=1, style=Qt.PenStyle.DashLine))
        item.addItem(self.feed_line, ignoreBounds=True)
        self.feed_line.setVisible(False)
        # the minimum cutting feed: the plan reports where and why a cutter cuts below it (Job tab)
        self.min_feed_line = pg.InfiniteLine(angle=0, movable=False, label="min. feed",
                                             labelOpts={"position": 0.98, "color": "#d03030"},
                                             pen=pg.mkPen("#d03030", width=1, style=Qt.PenStyle.DotLine))
        item.addItem(self.min_feed_line, ignoreBounds=True)
        self.min_feed_line.setVisible(False)
        # a strip above the feed line where the machine clock slows both machines, by what sets it
        self.slowed = {code: self.cached(item.plot(pen=pg.mkPen(colour, width=5), name=f"slowed: {name}",
                                                   connect="finite"))
                       for code, name, colour in ((SLOWED_FOR.index("axes"), "axes", SLOWED_AXES_COLOUR),
                                                  (SLOWED_FOR.index("chord"), "chord", SLOWED_CHORD_COLOUR))}
        self.legend.setColumnCount(2)
        self.setToolTip("both cutters' feed while they cut; the strip above the feed line marks where the "
                        "machine clock slows both machines, and for what: an axis's speed or acceleration "
                        "limit, or the chord tolerance (plan.json: schedule.machine); the dotted line is the "
                        "minimum cutting feed (the Job tab says where and why a cutter cuts below it)")
        self.follow = True

    def window(self, t: float, end: float) -> tuple[float, float]:
        """The window (min) round the time t (min), kept inside the job [0, end] (min)."""
        lo = min(max(t - self.WINDOW_MIN / 2, 0.0), max(end - self.WINDOW_MIN, 0.0))
        return lo, lo + self.WINDOW_MIN

    def set_ranges(self, data: PlanData) -> None:
        if self.follow:  # a window (the cursor moves it next): its curves are clipped to it
            end = float(data.timeline.t[-1]) / MS
            self.view_box.setXRange(*self.window(self.state.cursor_time / MS, end), padding=0.0)
        else:
            super().set_ranges(data)
        self.view_box.setYRange(0.0, FEED_PLOT_TOP * data.result.plan.params.feed, padding=0.0)

    def show_plan(self, data: PlanData) -> None:
        tl = data.timeline
        t = tl.t / MS
        self.left_curve.setData(t, np.where(tl.left.cutting, data.speed_left, np.nan), connect="finite")
        self.right_curve.setData(t, np.where(tl.right.cutting, data.speed_right, np.nan), connect="finite")
        self.feed_line.setVisible(True)
        feed = data.result.plan.params.feed
        self.feed_line.setValue(feed)
        job = data.result.figures.get("job") if data.result.figures else None
        self.min_feed_line.setVisible(job is not None)
        if job is not None:
            self.min_feed_line.setValue(job["min_feed_mm_min"])
        why = data.result.warp.slowed_for if data.result.warp is not None else None
        for code, curve in self.slowed.items():
            if why is None:
                curve.setData([], [])
            else:
                curve.setData(t, np.where(why == code, SLOWED_STRIP * feed, np.nan), connect="finite")

    def _move_cursor(self, index) -> None:
        super()._move_cursor(index)
        data = self.state.plan
        if self.follow and data is not None and data.has_schedule:
            end = float(data.timeline.t[-1]) / MS
            self.view_box.setXRange(*self.window(self.state.cursor_time / MS, end), padding=0.0)

    def clear_plan(self) -> None:
        self.left_curve.setData([], [])
        self.right_curve.setData([], [])
        for curve in self.slowed.values():
            curve.setData([], [])
        self.feed_line.setVisible(False)
        self.min_feed_line.setVisible(False)


def cursor_dragged(state: WorkbenchState, line) -> None:
    """A plot's cursor line dragged (x in minutes): the state's cursor follows (never raises)."""
    try:
        state.set_cursor_time(float(line.value()) * MS)
    except Exception:  # slots never raise
        log.exception("moving the cursor failed")


def time_clicked(state: WorkbenchState, event, boxes) -> None:
    """A left click in one of the view boxes (x in minutes) moves the state's cursor to that time
    (never raises)."""
    try:
        if event.button() != Qt.MouseButton.LeftButton:
            return
        pos = event.scenePos()
        for box in boxes:
            if box.sceneBoundingRect().contains(pos):
                state.set_cursor_time(float(box.mapSceneToView(pos).x()) * MS)
                return
    except Exception:  # slots never raise
        log.exception("jumping to the clicked time failed")

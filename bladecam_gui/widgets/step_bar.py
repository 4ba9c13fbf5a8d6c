"""The timeline's bar: the seven steps as seven coloured bands, one lane each (steps 4-6 repeat per
contour and interleave: in lanes of their own each stays readable at every zoom), the violations as
red marks above them, each cutter's contour numbers where its path changes, a time scale, and the
cursor. It zooms and pans over
the job: the wheel zooms round the mouse, shift + wheel (or a horizontal wheel) and a middle- or
right-button drag pan, ``fit`` shows the whole job; a press or a drag with the left button moves the
cursor. The labels thin out to what fits at every zoom."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import QPoint, QRect, QSize, Qt, Signal
from PySide6.QtGui import QColor, QFont, QPainter, QPen, QPixmap
from PySide6.QtWidgets import QSizePolicy, QToolTip, QWidget

from ..plan_data import PlanData
from ..style import DANGER_COLOUR, LEFT_COLOUR, RIGHT_COLOUR, STEPS, step_name

#: the smallest span shown (ms), and the steps of the time scale (s)
MIN_SPAN_MS = 200.0
TICKS_S = (0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800, 3600, 7200, 1e9)
ZOOM_STEP = 1.25


def clock(t_ms: float) -> str:
    s = t_ms / 1000.0
    return f"{int(s // 60)}:{s % 60:04.1f}"


def runs(flags: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(starts, ends) sample indices of the runs of True in flags (n,) bool (ends inclusive)."""
    f = np.concatenate([[False], np.asarray(flags, bool), [False]])
    d = np.diff(f.astype(np.int8))
    return np.nonzero(d == 1)[0], np.nonzero(d == -1)[0] - 1


def path_starts(path: np.ndarray) -> np.ndarray:
    """Sample indices where a cutter's path (n,) int changes to a contour (>= 0)."""
    change = np.nonzero(np.diff(path))[0] + 1
    if len(path) and path[0] >= 0:
        change = np.concatenate([[0], change])
    return change[path[change] >= 0]


def lane_texts(data: PlanData) -> dict[int, str]:
    """step -> its lane's label: the step's short name and, for a step that machines several
    contours, how many (the contours either cutter cuts during the step)."""
    tl = data.timeline
    out = {}
    for k in np.unique(data.step):
        k = int(k)
        during = data.step == k
        paths = np.union1d(tl.left.path[during & tl.left.cutting], tl.right.path[during & tl.right.cutting])
        n = int(np.count_nonzero(paths >= 0))
        out[k] = step_name(k) + (f" · {n} contours" if n > 1 else "")
    return out


class StepBar(QWidget):
    """Bands, violations, contour numbers and a cursor over a zoomable view [view0, view1] ms."""

    time_requested = Signal(float)
    view_changed = Signal(float, float)
    drag_started = Signal()  # the left button pressed: the cursor follows the mouse until
    drag_finished = Signal()  # the left button released
    MARGIN = 8
    GUTTER = 12     # left of the lanes: each lane's step number
    MARK_H = 5      # the violation marks
    LANE_H = 8      # each step's lane
    CONTOUR_H = 13  # the contour numbers' row
    SCALE_H = 14    # the time scale's row

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.bands = np.zeros((0, 3))
        self.duration = 0.0
        self.time = 0.0
        self.view0, self.view1 = 0.0, 0.0
        self.violations = np.zeros((0, 2))            # (k, 2) t0, t1 ms
        self.contours: dict[str, tuple[np.ndarray, np.ndarray]] = {}  # side -> (t ms, contour)
        self.lane_texts: dict[int, str] = {}  # step -> its lane's label
        self._background: QPixmap | None = None
        self._pan_from: tuple[float, float, float] | None = None
        self.setMinimumHeight(self.MARK_H + 1 + len(STEPS) * self.LANE_H + self.CONTOUR_H + self.SCALE_H)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self.setMouseTracking(True)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)  # paints every pixel: no parent repaints
        self.setToolTip("")

    def sizeHint(self) -> QSize:  # noqa: N802 (Qt name)
        return QSize(600, self.minimumHeight())

    # -- data ------------------------------------------------------------------------------------
    def set_plan(self, data: PlanData | None) -> None:
        """Show a plan's bands, violations and contours (None: nothing); the view fits the job, or
        keeps its span when the new job is as long (a re-plan of the same blade)."""
        if data is None or not data.has_schedule:
            self.set_bands(None, 0.0)
            self.violations, self.contours, self.lane_texts = np.zeros((0, 2)), {}, {}
            return
        tl = data.timeline
        self.lane_texts = lane_texts(data)
        s, e = runs(data.danger)
        self.violations = np.column_stack([tl.t[s], tl.t[e]]) if len(s) else np.zeros((0, 2))
        self.contours = {side: (tl.t[i], getattr(tl, side).path[i])
                         for side in ("left", "right") for i in [path_starts(getattr(tl, side).path)]}
        self.set_bands(data.bands, float(tl.t[-1]))

    def set_bands(self, bands: np.ndarray | None, duration: float) -> None:
        self.bands = np.zeros((0, 3)) if bands is None else bands
        zoomed = self.duration > 0 and (self.view0 > 0 or self.view1 < self.duration)
        self.duration = float(duration)
        if zoomed and self.view1 <= self.duration:
            self._invalidate()
        else:
            self.fit()

    def set_time(self, t: float) -> None:
        old = int(self.x_of(self.time))
        self.time = float(t)
        if not self.view0 <= self.time <= self.view1:  # follow the cursor out of the view
            span = self.span
            self.set_view(self.time - 0.5 * span, self.time + 0.5 * span)
            return
        new = int(self.x_of(self.time))
        if new != old:  # repaint the two strips only
            self.update(QRect(min(old, new) - 3, 0, abs(new - old) + 7, self.height()))

    # -- the view --------------------------------------------------------------------------------
    @property
    def span(self) -> float:
        return self.view1 - self.view0

    def set_view(self, t0: float, t1: float) -> None:
        """Show [t0, t1] ms (kept inside the job, at least MIN_SPAN_MS wide)."""
        if self.duration <= 0:
            t0, t1 = 0.0, 0.0
        else:
            span = float(np.clip(t1 - t0, min(MIN_SPAN_MS, self.duration), self.duration))
            t0 = float(np.clip(t0, 0.0, self.duration - span))
            t1 = t0 + span
        if (t0, t1) != (self.view0, self.view1):
            self.view0, self.view1 = t0, t1
            self._invalidate()
            self.view_changed.emit(t0, t1)

    def fit(self) -> None:
        self.set_view(0.0, self.duration)
        self._invalidate()

    def zoom(self, factor: float, about: float | None = None) -> None:
        """Zoom by ``factor`` (> 1: in) round the time ``about`` ms (default: the cursor if shown)."""
        if about is None:
            about = self.time if self.view0 <= self.time <= self.view1 else 0.5 * (self.view0 + self.view1)
        frac = (about - self.view0) / self.span if self.span > 0 else 0.5
        span = self.span / factor
        self.set_view(about - frac * span, about - frac * span + span)

    def pan(self, fraction: float) -> None:
        """Move the view by ``fraction`` of its span (> 0: later)."""
        self.set_view(self.view0 + fraction * self.span, self.view1 + fraction * self.span)

    # -- geometry --------------------------------------------------------------------------------
    @property
    def left(self) -> int:
        return self.MARGIN + self.GUTTER

    def x_of(self, t: float) -> float:
        w = self.width() - self.left - self.MARGIN
        return self.left + ((t - self.view0) / self.span * w if self.span > 0 else 0.0)

    def t_of(self, x: float) -> float:
        w = max(self.width() - self.left - self.MARGIN, 1)
        return float(self.view0 + np.clip((x - self.left) / w, 0.0, 1.0) * self.span)

    def lane_rect(self, step: int) -> QRect:
        """The lane of step ``step`` (1-7) across the bar."""
        top, band_h = self._band_rect()
        lane = band_h / len(STEPS)
        y0, y1 = top + int(round((step - 1) * lane)), top + int(round(step * lane))
        return QRect(self.left, y0, self.width() - self.left - self.MARGIN, y1 - y0)

    def lane_at(self, y: float) -> int:
        """The step (1-7) whose lane is at height y (0: above or below the lanes)."""
        top, band_h = self._band_rect()
        k = int(np.floor((y - top) / (band_h / len(STEPS)))) + 1
        return k if 1 <= k <= len(STEPS) else 0

    def step_at(self, t: float) -> int:
        if not len(self.bands):
            return 0
        i = int(np.clip(np.searchsorted(self.bands[:, 0], t, side="right") - 1, 0, len(self.bands) - 1))
        return int(self.bands[i, 2])

    def _band_rect(self) -> tuple[int, int]:
        """(top, height) of the bands."""
        top = self.MARK_H + 1
        return top, self.height() - top - self.CONTOUR_H - self.SCALE_H

    # -- painting --------------------------------------------------------------------------------
    def _invalidate(self) -> None:
        self._background = None
        self.update()

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        self._background = None
        super().resizeEvent(event)

    def _visible(self, t0: np.ndarray, t1: np.ndarray) -> np.ndarray:
        return (t1 >= self.view0) & (t0 <= self.view1)

    def _paint_background(self) -> QPixmap:
        """Bands, marks, labels and the scale, drawn once per plan, view and size."""
        pix = QPixmap(self.size())
        pix.fill(QColor("#2a2e36"))
        p = QPainter(pix)
        try:
            font = QFont(self.font())
            font.setPointSizeF(max(font.pointSizeF() * 0.85, 6.0))
            p.setFont(font)
            top, band_h = self._band_rect()
            p.save()
            self._paint_lanes(p)
            p.restore()
            if len(self.violations):
                v = self.violations[self._visible(self.violations[:, 0], self.violations[:, 1])]
                for t0, t1 in v:
                    x0, x1 = self.x_of(max(t0, self.view0)), self.x_of(min(t1, self.view1))
                    p.fillRect(QRect(int(x0) - 1, 0, max(int(np.ceil(x1 - x0)), 1) + 2, self.MARK_H),
                               QColor(DANGER_COLOUR))
            self._paint_contours(p, top + band_h)
            self._paint_scale(p, self.height() - self.SCALE_H)
        finally:
            p.end()
        return pix

    def _paint_lanes(self, p: QPainter) -> None:
        """Each step's lane: its number in the gutter, its runs in its colour, and its label (the
        step's name and how many contours it machines) in the first run wide enough to hold it."""
        font = QFont(p.font())
        font.setPixelSize(max(self.lane_rect(1).height(), 6))
        p.setFont(font)
        m = p.fontMetrics()
        for k, (_, _, colour) in STEPS.items():
            lane = self.lane_rect(k)
            p.fillRect(lane, QColor("#323741" if k % 2 else "#2c3038"))
            p.setPen(QColor(colour).lighter(140))
            p.drawText(QRect(self.MARGIN - 4, lane.y(), self.GUTTER, lane.height()),
                       Qt.AlignmentFlag.AlignCenter, str(k))
        if not len(self.bands):
            return
        shown = self.bands[self._visible(self.bands[:, 0], self.bands[:, 1])]
        labelled: set[int] = set()
        for t0, t1, step in shown:
            k = int(step)
            if k not in STEPS:
                continue
            lane = self.lane_rect(k)
            x0, x1 = self.x_of(max(t0, self.view0)), self.x_of(min(t1, self.view1))
            rect = QRect(int(x0), lane.y(), max(int(np.ceil(x1 - x0)), 1), lane.height())
            p.fillRect(rect, QColor(STEPS[k][2]))
            text = self.lane_texts.get(k, step_name(k))
            if k not in labelled and rect.width() > m.horizontalAdvance(text) + 6:
                p.setPen(QColor("white"))
                p.drawText(rect.adjusted(3, 0, 0, 0),
                           Qt.AlignmentFlag.AlignVCenter | Qt.AlignmentFlag.AlignLeft, text)
                labelled.add(k)

    def _paint_contours(self, p: QPainter, y: int) -> None:
        """Each cutter's contour number where its path starts (left magenta, right cyan), thinned to
        the labels that fit (the earlier wins)."""
        m = p.fontMetrics()
        marks = []
        for side, colour in (("left", LEFT_COLOUR), ("right", RIGHT_COLOUR)):
            if side in self.contours:
                t, n = self.contours[side]
                keep = (t >= self.view0) & (t <= self.view1)
                marks += [(ti, int(ni), colour) for ti, ni in zip(t[keep], n[keep], strict=True)]
        free = -1e9
        for ti, ni, colour in sorted(marks, key=lambda mk: mk[0]):
            x = int(self.x_of(ti))
            text = str(ni)
            if x < free:
                continue
            p.setPen(QColor(colour))
            p.drawLine(x, y, x, y + 3)
            p.drawText(QPoint(x + 2, y + self.CONTOUR_H - 2), text)
            free = x + m.horizontalAdvance(text) + 6

    def _paint_scale(self, p: QPainter, y: int) -> None:
        p.setPen(QColor("#b0b8c4"))
        if self.span <= 0:
            return
        m = p.fontMetrics()
        width = max(self.width() - 2 * self.MARGIN, 1)
        label_px = m.horizontalAdvance("00:00.0") + 12
        span_s = self.span / 1000.0
        tick = next(s for s in TICKS_S if span_s / s <= width / label_px)
        first = np.ceil(self.view0 / 1000.0 / tick) * tick
        for s in np.arange(first, self.view1 / 1000.0 + 1e-9, tick):
            x = int(self.x_of(s * 1000.0))
            p.drawLine(x, y, x, y + 3)
            text = (clock(s * 1000.0) if tick < 1 else f"{int(s // 60)}:{int(round(s % 60)):02d}" if tick < 60
                    else f"{s / 60:g} min")
            if x + m.horizontalAdvance(text) + 2 <= self.width():
                p.drawText(QPoint(x + 2, y + self.SCALE_H - 2), text)

    def paintEvent(self, event) -> None:  # noqa: N802 (Qt name)
        if self._background is None or self._background.size() != self.size():
            self._background = self._paint_background()
        p = QPainter(self)
        try:
            p.drawPixmap(0, 0, self._background)
            if self.view0 <= self.time <= self.view1 and self.span > 0:
                top, band_h = self._band_rect()
                x = int(self.x_of(self.time))
                p.setPen(QPen(QColor("white"), 3))
                p.drawLine(x, 0, x, top + band_h + 4)
                p.setPen(QPen(QColor(DANGER_COLOUR), 1))
                p.drawLine(x, 0, x, top + band_h + 4)
        finally:
            p.end()

    # -- input -----------------------------------------------------------------------------------
    def mousePressEvent(self, event) -> None:  # noqa: N802 (Qt name)
        x = event.position().x()
        if event.button() == Qt.MouseButton.LeftButton:
            self.time_requested.emit(self.t_of(x))  # (a click's jump: drawn in full)
            self.drag_started.emit()
        elif event.button() in (Qt.MouseButton.MiddleButton, Qt.MouseButton.RightButton):
            self._pan_from = (x, self.view0, self.view1)
            self.setCursor(Qt.CursorShape.ClosedHandCursor)

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802 (Qt name)
        if event.button() == Qt.MouseButton.LeftButton:
            self.drag_finished.emit()
        if self._pan_from is not None and not event.buttons() & (Qt.MouseButton.MiddleButton
                                                                 | Qt.MouseButton.RightButton):
            self._pan_from = None
            self.unsetCursor()

    def mouseMoveEvent(self, event) -> None:  # noqa: N802 (Qt name)
        x = event.position().x()
        if event.buttons() & Qt.MouseButton.LeftButton:
            self.time_requested.emit(self.t_of(x))
        elif self._pan_from is not None:
            x0, v0, v1 = self._pan_from
            dt = (x - x0) / max(self.width() - self.left - self.MARGIN, 1) * (v1 - v0)
            self.set_view(v0 - dt, v1 - dt)
        elif len(self.bands):
            t = self.t_of(x)
            step = self.step_at(t)
            lane = self.lane_at(event.position().y())
            lane_text = (f"\nlane {lane}: {self.lane_texts.get(lane, step_name(lane))}"
                         if lane and lane != step else "")
            QToolTip.showText(event.globalPosition().toPoint(),
                              f"{clock(t)}  step {step}: {STEPS.get(step, ('', '?'))[1]}{lane_text}\n"
                              "wheel: zoom · shift+wheel or right-drag: pan", self)

    def wheelEvent(self, event) -> None:  # noqa: N802 (Qt name)
        d = event.angleDelta()
        if d.x() and not d.y():
            self.pan(-d.x() / 120.0 * 0.1)
        elif event.modifiers() & Qt.KeyboardModifier.ShiftModifier:
            self.pan(-(d.y() or d.x()) / 120.0 * 0.1)
        elif d.y():
            self.zoom(ZOOM_STEP ** (d.y() / 120.0), self.t_of(event.position().x()))
        event.accept()

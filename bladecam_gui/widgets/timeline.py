"""The timeline scrubber: the seven steps as coloured bands, a draggable cursor, play / pause with a
speed, previous / next step, and a read-out of the instant (step, each cutter's path and region, tip
spacing, clearance)."""

from __future__ import annotations

import logging

import numpy as np
from PySide6.QtCore import QElapsedTimer, QPoint, QRect, QSize, Qt, QTimer, Signal, Slot
from PySide6.QtGui import QColor, QFont, QPainter, QPen, QPixmap
from PySide6.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSizePolicy,
    QToolTip,
    QVBoxLayout,
    QWidget,
)

from core.schedule.motion import REGION_NAMES

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import DANGER_COLOUR, STEPS, step_name
from .throttle import Throttle

log = logging.getLogger(__name__)

SPEEDS = (1, 10, 30, 100, 300, 1000)
FRAME_MS = 33


def clock(t_ms: float) -> str:
    s = t_ms / 1000.0
    return f"{int(s // 60)}:{s % 60:04.1f}"


class StepBar(QWidget):
    """Bands (t0, t1, step) over [0, duration] ms and a cursor; press or drag to move it."""

    time_requested = Signal(float)
    MARGIN = 8

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.bands = np.zeros((0, 3))
        self.duration = 0.0
        self.time = 0.0
        self._background: QPixmap | None = None
        self.setMinimumHeight(46)
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.setFocusPolicy(Qt.FocusPolicy.StrongFocus)
        self.setMouseTracking(True)
        self.setAttribute(Qt.WidgetAttribute.WA_OpaquePaintEvent)  # paints every pixel: no parent repaints

    def sizeHint(self) -> QSize:  # noqa: N802 (Qt name)
        return QSize(600, 46)

    def set_bands(self, bands: np.ndarray | None, duration: float) -> None:
        self.bands = np.zeros((0, 3)) if bands is None else bands
        self.duration = float(duration)
        self._background = None
        self.update()

    def set_time(self, t: float) -> None:
        old = int(self.x_of(self.time))
        self.time = float(t)
        new = int(self.x_of(self.time))
        if new != old:  # repaint the two strips only
            self.update(QRect(min(old, new) - 3, 0, abs(new - old) + 7, self.height()))

    # -- geometry --------------------------------------------------------------------------------
    def x_of(self, t: float) -> float:
        w = self.width() - 2 * self.MARGIN
        return self.MARGIN + (t / self.duration * w if self.duration > 0 else 0.0)

    def t_of(self, x: float) -> float:
        w = max(self.width() - 2 * self.MARGIN, 1)
        return float(np.clip((x - self.MARGIN) / w, 0.0, 1.0) * self.duration)

    def step_at(self, t: float) -> int:
        if not len(self.bands):
            return 0
        i = int(np.clip(np.searchsorted(self.bands[:, 0], t, side="right") - 1, 0, len(self.bands) - 1))
        return int(self.bands[i, 2])

    # -- painting --------------------------------------------------------------------------------
    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        self._background = None
        super().resizeEvent(event)

    def _paint_background(self) -> QPixmap:
        """Bands, names and ticks, drawn once per plan and size (the cursor is drawn over it)."""
        pix = QPixmap(self.size())
        pix.fill(QColor("#2a2e36"))
        p = QPainter(pix)
        try:
            h = self.height()
            band_h = h - 16
            font = QFont(self.font())
            font.setPointSizeF(max(font.pointSizeF() * 0.85, 6.0))
            p.setFont(font)
            metrics = p.fontMetrics()
            for t0, t1, step in self.bands:
                x0, x1 = self.x_of(t0), self.x_of(t1)
                rect = QRect(int(x0), 2, max(int(np.ceil(x1 - x0)), 1), band_h)
                p.fillRect(rect, QColor(STEPS.get(int(step), ("", "", "#888888"))[2]))
                name = step_name(step)
                if rect.width() > metrics.horizontalAdvance(name) + 6:
                    p.setPen(QColor("white"))
                    p.drawText(rect, Qt.AlignmentFlag.AlignCenter, name)
            p.setPen(QColor("#b0b8c4"))
            if self.duration > 0:
                minutes = self.duration / 60000.0
                tick = next(s for s in (0.5, 1, 2, 5, 10, 15, 30, 60, 120, 1e9) if minutes / s <= 12)
                for m in np.arange(0.0, minutes + 1e-9, tick):
                    x = int(self.x_of(m * 60000.0))
                    p.drawLine(x, band_h + 2, x, band_h + 5)
                    p.drawText(QPoint(x + 2, h - 1), f"{m:g} min")
        finally:
            p.end()
        return pix

    def paintEvent(self, event) -> None:  # noqa: N802 (Qt name)
        if self._background is None or self._background.size() != self.size():
            self._background = self._paint_background()
        p = QPainter(self)
        try:
            p.drawPixmap(0, 0, self._background)
            band_h = self.height() - 16
            x = int(self.x_of(self.time))
            p.setPen(QPen(QColor("white"), 3))
            p.drawLine(x, 0, x, band_h + 4)
            p.setPen(QPen(QColor(DANGER_COLOUR), 1))
            p.drawLine(x, 0, x, band_h + 4)
        finally:
            p.end()

    # -- input -----------------------------------------------------------------------------------
    def mousePressEvent(self, event) -> None:  # noqa: N802 (Qt name)
        if event.button() == Qt.MouseButton.LeftButton:
            self.time_requested.emit(self.t_of(event.position().x()))

    def mouseMoveEvent(self, event) -> None:  # noqa: N802 (Qt name)
        t = self.t_of(event.position().x())
        if event.buttons() & Qt.MouseButton.LeftButton:
            self.time_requested.emit(t)
        elif len(self.bands):
            step = self.step_at(t)
            QToolTip.showText(event.globalPosition().toPoint(),
                              f"{clock(t)}  step {step}: {STEPS.get(step, ('', '?'))[1]}", self)

    def keyPressEvent(self, event) -> None:  # noqa: N802 (Qt name)
        jump = {Qt.Key.Key_Left: -0.002, Qt.Key.Key_Right: 0.002, Qt.Key.Key_PageUp: -0.05,
                Qt.Key.Key_PageDown: 0.05}
        if event.key() in jump:
            self.time_requested.emit(self.time + jump[event.key()] * self.duration)
        elif event.key() == Qt.Key.Key_Home:
            self.time_requested.emit(0.0)
        elif event.key() == Qt.Key.Key_End:
            self.time_requested.emit(self.duration)
        else:
            super().keyPressEvent(event)


class TimelinePanel(QWidget):
    """Controls, the step bar, the step legend and the read-out of the instant at the cursor."""

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__(parent)
        self.state = state
        self.bar = StepBar(self)
        self.prev_button = QPushButton("◀◀ step", self)
        self.play_button = QPushButton("▶ play", self)
        self.play_button.setCheckable(True)
        self.next_button = QPushButton("step ▶▶", self)
        self.speed = QComboBox(self)
        self.speed.addItems([f"{s}×" for s in SPEEDS])
        self.speed.setCurrentText("30×")
        self.speed.setToolTip("playback speed (job time per real time)")
        self.readout = QLabel("no plan yet", self)
        self.readout.setTextFormat(Qt.TextFormat.RichText)
        # no re-layout per frame
        self.readout.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)
        legend = " ".join(f"<span style='background:{c}; color:white'>&nbsp;{short}&nbsp;</span>"
                          for short, _, c in STEPS.values())
        self.legend = QLabel(legend, self)
        self.legend.setToolTip("\n".join(f"step {k}: {v[1]}" for k, v in STEPS.items()))
        row = QHBoxLayout()
        for w in (self.prev_button, self.play_button, self.next_button, self.speed):
            row.addWidget(w)
        row.addWidget(self.readout, 1)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 2, 4, 2)
        layout.addLayout(row)
        layout.addWidget(self.bar)
        layout.addWidget(self.legend)
        self._timer = QTimer(self)
        self._timer.setInterval(FRAME_MS)
        self._timer.timeout.connect(self._on_tick)
        self._elapsed = QElapsedTimer()
        self._play_t, self._play_index = 0.0, -1
        self._readout_throttle = Throttle(self._show_readout, parent=self)
        self.bar.time_requested.connect(self._on_time_requested)
        self.play_button.toggled.connect(self._on_play_toggled)
        self.prev_button.clicked.connect(lambda: self.jump_step(-1))
        self.next_button.clicked.connect(lambda: self.jump_step(+1))
        state.plan_changed.connect(self._on_plan_changed)
        state.cursor_changed.connect(self._on_cursor_changed)
        self.setEnabled(False)

    # -- state -----------------------------------------------------------------------------------
    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            ok = data.has_schedule
            self.setEnabled(ok)
            if not ok:
                self.play_button.setChecked(False)
                self.bar.set_bands(None, 0.0)
                self.readout.setText("planning the schedule…" if data.result is not None else "planning…")
                return
            self.bar.set_bands(data.bands, float(data.timeline.t[-1]))
            self._on_cursor_changed(self.state.cursor)
        except Exception:  # slots never raise
            log.exception("timeline update failed")

    @Slot(int)
    def _on_cursor_changed(self, i: int) -> None:
        try:
            data = self.state.plan
            if data is None or not data.has_schedule:
                return
            self.bar.set_time(float(data.timeline.t[i]))
            self._readout_throttle.request(i)
        except Exception:  # slots never raise
            log.exception("timeline update failed")

    def _show_readout(self, _index) -> None:
        try:
            data = self.state.plan
            if data is not None and data.has_schedule:
                self.readout.setText(self.describe(data, self.state.cursor))
        except Exception:  # slots never raise
            log.exception("timeline read-out failed")

    @staticmethod
    def describe(data: PlanData, i: int) -> str:
        tl = data.timeline
        sl, sr = int(tl.left.step[i]), int(tl.right.step[i])
        step = f"step {data.step[i]}: {step_name(data.step[i])}"
        if sl != sr:
            step += f" (left {sl}, right {sr})"
        sides = []
        for name, s in (("left", tl.left), ("right", tl.right)):
            what = f"path {s.path[i]} {REGION_NAMES[s.code[i]]}" + ("" if s.cutting[i] else " (not cutting)")
            sides.append(f"<b>{name}</b> {what}")
        colour = DANGER_COLOUR if data.danger[i] else "#3cb371"
        safety = (f"<span style='color:{colour}'>tip spacing {data.spacing[i]:.3f} mm · "
                  f"clearance {data.clearance[i]:.3f} mm</span>")
        return (f"t {clock(tl.t[i])} / {clock(tl.t[-1])} · {step} · " + " · ".join(sides) + " · " + safety)

    # -- controls --------------------------------------------------------------------------------
    @Slot(float)
    def _on_time_requested(self, t: float) -> None:
        try:
            self.state.set_cursor_time(t)
        except Exception:  # slots never raise
            log.exception("moving the cursor failed")

    def jump_step(self, direction: int) -> None:
        """Move the cursor to the start of the next (+1) or current / previous (-1) step band."""
        try:
            data = self.state.plan
            if data is None or not data.has_schedule or not len(data.bands):
                return
            t, starts = self.state.cursor_time, data.bands[:, 0]
            if direction > 0:
                later = starts[starts > t + 1e-6]
                target = later[0] if len(later) else float(data.timeline.t[-1])
            else:
                earlier = starts[starts < t - 1e-6]
                target = earlier[-1] if len(earlier) else 0.0
            self.state.set_cursor_time(float(target))
        except Exception:  # slots never raise
            log.exception("step jump failed")

    def speed_factor(self) -> float:
        return float(SPEEDS[self.speed.currentIndex()])

    @Slot(bool)
    def _on_play_toggled(self, playing: bool) -> None:
        self.play_button.setText("❚❚ pause" if playing else "▶ play")
        if playing:
            data = self.state.plan
            if data is not None and data.has_schedule and self.state.cursor >= len(data.timeline.t) - 1:
                self.state.set_cursor(0)
            self._play_t, self._play_index = self.state.cursor_time, self.state.cursor
            self._elapsed.start()
            self._timer.start()
        else:
            self._timer.stop()

    def _on_tick(self) -> None:
        try:
            data = self.state.plan
            if data is None or not data.has_schedule:
                self.play_button.setChecked(False)
                return
            dt = self._elapsed.restart() * self.speed_factor()
            if self.state.cursor != self._play_index:  # dragged meanwhile: continue from there
                self._play_t = self.state.cursor_time
            t = self._play_t = self._play_t + dt
            end = float(data.timeline.t[-1])
            self.state.set_cursor_time(min(t, end))
            self._play_index = self.state.cursor
            if t >= end:
                self.play_button.setChecked(False)
        except Exception:  # slots never raise
            log.exception("playing failed")
            self.play_button.setChecked(False)

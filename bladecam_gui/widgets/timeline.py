"""The timeline: the step bar (widgets.step_bar: zoom, pan, violations, contour numbers), play /
pause with a speed, the jumps (step start, contour N, violation, minimum spacing or clearance, see
widgets.navigation), and a read-out of the instant (step, each cutter's path and region, tip
spacing, clearance)."""

from __future__ import annotations

import logging

from PySide6.QtCore import QElapsedTimer, Qt, QTimer, Slot
from PySide6.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QLabel,
    QSizePolicy,
    QSpinBox,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from core.paths.regions import REGION_NAMES

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import DANGER_COLOUR, STEPS, step_name
from ..verdict import collisions_at
from . import navigation as nav
from .step_bar import ZOOM_STEP, StepBar, clock
from .throttle import Throttle

log = logging.getLogger(__name__)

SPEEDS = (1, 10, 30, 100, 300, 1000)
FRAME_MS = 33
#: a nudge of the cursor (arrow keys): this fraction of the span shown, at least one sample
NUDGE = 0.01


def _button(parent: QWidget, text: str, tip: str) -> QToolButton:
    b = QToolButton(parent)
    b.setText(text)
    b.setToolTip(tip)
    b.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
    b.setFocusPolicy(Qt.FocusPolicy.TabFocus)  # a click leaves the keyboard where it was
    return b


#: what a cutting cutter does in the modes that do not use the regions
MODE_WORDS = {"symmetric": "symmetric", "single": "single-sided"}


def breach_text(data: PlanData, i: int) -> str:
    """The tip spacing and clearance at sample i; on a violation whose breach lies between two samples
    (both samples keep the rule, the tips come closer in between), the spacing at the breach too."""
    text = f"tip spacing {data.spacing[i]:.3f} mm · clearance {data.clearance[i]:.3f} mm"
    if not data.danger[i]:
        return text
    between = data.result.safety.between
    near = [between[j] for j in (i - 1, i) if 0 <= j < len(between)]
    h = data.result.plan.params.h_safe
    if near and min(near) < h <= data.spacing[i] and data.clearance[i] >= 0:
        side = "before" if len(near) == 2 and near[0] < near[1] or i == len(between) else "after"
        return f"tip spacing {min(near):.3f} mm between samples ({side} this one; {text})"
    return text


def scallop_text(data: PlanData, contour: int) -> str:
    """' · scallop 0.086 mm': the largest scallop height between the contour and the next one towards
    the hub (plan.json's scallop figures), that a strip is left uncut, or ''."""
    per = (data.result.figures or {}).get("scallop", {}).get("per_path_max_mm", {})
    if str(contour) not in per:
        return ""
    h = per[str(contour)]
    return " · scallop: a strip uncut (stepover ≥ 2 r)" if h is None else f" · scallop {h:.3f} mm"


class StepLegend(QLabel):
    """The seven steps' colours with their short names, or with their numbers alone where the names do
    not fit (every step's description is in the tooltip)."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.setTextFormat(Qt.TextFormat.RichText)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        self.setToolTip("\n".join(f"step {k}: {v[1]}" for k, v in STEPS.items())
                        + "\nunder the bands: the contour each cutter starts (left magenta, right cyan)")
        violation = f"&nbsp; <span style='color:{DANGER_COLOUR}'>▀ violation</span>"
        self.texts = [" ".join(f"<span style='background:{c}; color:white'>&nbsp;{name}&nbsp;</span>"
                               for name, _, c in ((v[0] if full else str(k), v[1], v[2])
                                                  for k, v in STEPS.items())) + violation
                      for full in (True, False)]
        self.setText(self.texts[0])
        self.full_width = self.sizeHint().width()  # (of the names)

    def resizeEvent(self, event) -> None:  # noqa: N802 (Qt name)
        fits = self.full_width <= event.size().width()
        self.setText(self.texts[0] if fits else self.texts[1])
        super().resizeEvent(event)


class TimelinePanel(QWidget):
    """Controls, the step bar, the step legend and the read-out of the instant at the cursor."""

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__(parent)
        self.state = state
        self.bar = StepBar(self)
        self.prev_button = _button(self, "◀◀ step", "the previous of the seven steps' starts (PgUp)")
        self.play_button = _button(self, "▶ play", "play / pause (Space)")
        self.play_button.setCheckable(True)
        self.play_button.setMinimumWidth(self.play_button.fontMetrics().horizontalAdvance("❚❚ pause") + 16)
        self.next_button = _button(self, "step ▶▶", "the next of the seven steps' starts (PgDown)")
        self.speed = QComboBox(self)
        self.speed.addItems([f"{s}×" for s in SPEEDS])
        self.speed.setCurrentText("30×")
        self.speed.setToolTip("playback speed (job time per real time)")
        self.speed.setFocusPolicy(Qt.FocusPolicy.TabFocus)
        self.contour = QSpinBox(self)
        self.contour.setPrefix("contour ")
        self.contour.setKeyboardTracking(False)
        self.contour.setToolTip("jump to the start of contour N (Ctrl+G; Enter jumps)")
        self.contour_button = _button(self, "go", "jump to the start of this contour")
        self.prev_violation = _button(self, "◀ violation", "previous violation (Shift+V)")
        self.next_violation = _button(self, "violation ▶", "next violation (V)")
        self.min_spacing = _button(self, "min spacing", "the sample of the minimum tip spacing (M)")
        self.min_clearance = _button(self, "min clearance", "the sample of the minimum tool clearance "
                                     "(Shift+M)")
        self.zoom_out_button = _button(self, "−", "zoom the timeline out (-)")
        self.zoom_in_button = _button(self, "+", "zoom the timeline in round the cursor (+)")
        self.fit_button = _button(self, "fit", "show the whole job (F)")
        self.readout = QLabel("no plan yet", self)
        self.readout.setTextFormat(Qt.TextFormat.RichText)
        self.readout.setWordWrap(True)
        # two lines, fixed: no re-layout per frame
        self.readout.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)
        self.readout.setFixedHeight(2 * self.readout.fontMetrics().lineSpacing() + 4)
        self.legend = StepLegend(self)
        row = QHBoxLayout()
        row.setSpacing(3)
        for w in (self.prev_button, self.play_button, self.next_button, self.speed, None, self.contour,
                  self.contour_button, None, self.prev_violation, self.next_violation, self.min_spacing,
                  self.min_clearance, None, self.zoom_out_button, self.zoom_in_button, self.fit_button):
            if w is None:
                row.addSpacing(8)
            else:
                row.addWidget(w)
        row.addSpacing(8)
        row.addWidget(self.legend, 1)  # (what of it fits: every step's name is in its tooltip)
        layout = QVBoxLayout(self)
        layout.setContentsMargins(4, 2, 4, 2)
        layout.setSpacing(2)
        layout.addLayout(row)
        layout.addWidget(self.readout)
        layout.addWidget(self.bar)
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
        self.contour_button.clicked.connect(lambda: self.jump_contour(self.contour.value()))
        self.contour.editingFinished.connect(self._on_contour_entered)
        self.prev_violation.clicked.connect(lambda: self.jump_violation(-1))
        self.next_violation.clicked.connect(lambda: self.jump_violation(+1))
        self.min_spacing.clicked.connect(lambda: self.jump_minimum("spacing"))
        self.min_clearance.clicked.connect(lambda: self.jump_minimum("clearance"))
        self.zoom_in_button.clicked.connect(lambda: self.zoom(ZOOM_STEP ** 2))
        self.zoom_out_button.clicked.connect(lambda: self.zoom(ZOOM_STEP ** -2))
        self.fit_button.clicked.connect(self.fit)
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
                self.bar.set_plan(None)
                self.readout.setText("planning the schedule…" if data.result is not None else "planning…")
                return
            self.bar.set_plan(data)
            lo, hi = nav.contour_range(data)
            self.contour.blockSignals(True)
            self.contour.setRange(lo, hi)
            self.contour.blockSignals(False)
            n = len(nav.violation_starts(data))
            for b in (self.prev_violation, self.next_violation):
                b.setEnabled(n > 0)
            self.next_violation.setToolTip(f"next violation (V): {n} in this plan" if n else "no violation")
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
                if not self.contour.hasFocus():
                    self.contour.blockSignals(True)
                    self.contour.setValue(nav.contour_at(data, self.state.cursor))
                    self.contour.blockSignals(False)
        except Exception:  # slots never raise
            log.exception("timeline read-out failed")

    @staticmethod
    def describe(data: PlanData, i: int) -> str:
        """Two lines: the time and step, what collides (on a violation), the tip spacing and clearance;
        each cutter's path and region."""
        tl = data.timeline
        sl, sr = int(tl.left.step[i]), int(tl.right.step[i])
        step = f"step {data.step[i]}: {step_name(data.step[i])}"
        if sl != sr:
            step += f" (left {sl}, right {sr})"
        sides = []
        mode = data.job.params.mode
        for name, s in (("left", tl.left), ("right", tl.right)):
            region = REGION_NAMES[s.code[i]]
            if mode != "collaborative" and s.cutting[i]:  # (the regions are collaborative mode's)
                region = MODE_WORDS.get(mode, region)
            what = f"path {s.path[i]} {region}" + ("" if s.cutting[i] else " (not cutting)")
            sides.append(f"<b>{name}</b> {what}")
        colour = DANGER_COLOUR if data.danger[i] else "#3cb371"
        hits = collisions_at(data.result, i) if data.danger[i] else []
        safety = (f"<span style='color:{colour}'>{'VIOLATION · ' if data.danger[i] else ''}"
                  + "".join(f"<b>{h}</b> · " for h in hits) + f"{breach_text(data, i)}</span>")
        scallop = scallop_text(data, nav.contour_at(data, i))
        return (f"t {clock(tl.t[i])} / {clock(tl.t[-1])} · sample {i} · {step} · {safety}<br>"
                + " · ".join(sides) + scallop)

    # -- controls --------------------------------------------------------------------------------
    @Slot(float)
    def _on_time_requested(self, t: float) -> None:
        try:
            self.state.set_cursor_time(t)
        except Exception:  # slots never raise
            log.exception("moving the cursor failed")

    def _plan(self) -> PlanData | None:
        data = self.state.plan
        return data if data is not None and data.has_schedule else None

    def _go(self, index: int | None) -> None:
        if index is not None:
            self.state.set_cursor(index)

    def jump_step(self, direction: int) -> None:
        """Move the cursor to the next (+1) or previous (-1) of the seven steps' starts."""
        try:
            data = self._plan()
            if data is not None:
                self._go(nav.step_boundary(data, self.state.cursor, direction))
        except Exception:  # slots never raise
            log.exception("step jump failed")

    def jump_to_step(self, step: int) -> None:
        """Move the cursor to the first sample of step ``step`` (1-7)."""
        try:
            data = self._plan()
            if data is not None:
                self._go(nav.step_start(data, step))
        except Exception:  # slots never raise
            log.exception("step jump failed")

    def jump_contour(self, contour: int) -> None:
        try:
            data = self._plan()
            if data is not None:
                self._go(nav.contour_start(data, int(contour)))
        except Exception:  # slots never raise
            log.exception("contour jump failed")

    def _on_contour_entered(self) -> None:
        if self.contour.hasFocus():
            self.jump_contour(self.contour.value())

    def jump_violation(self, direction: int) -> None:
        try:
            data = self._plan()
            if data is not None:
                self._go(nav.violation(data, self.state.cursor, direction))
        except Exception:  # slots never raise
            log.exception("violation jump failed")

    def jump_minimum(self, what: str) -> None:
        """The sample of the minimum 'spacing' or 'clearance'."""
        try:
            data = self._plan()
            if data is not None:
                self._go(nav.minimum(data, what))
        except Exception:  # slots never raise
            log.exception("jump to the minimum failed")

    def nudge(self, direction: int, samples: bool = False) -> None:
        """Move the cursor by NUDGE of the span shown (``samples``: by one time sample)."""
        try:
            data = self._plan()
            if data is None:
                return
            i = self.state.cursor
            if samples:
                self.state.set_cursor(i + direction)
                return
            j = data.index_at(self.state.cursor_time + direction * NUDGE * self.bar.span)
            self.state.set_cursor(j if j != i else i + direction)
        except Exception:  # slots never raise
            log.exception("moving the cursor failed")

    def go_end(self, end: bool) -> None:
        data = self._plan()
        if data is not None:
            self.state.set_cursor(len(data.timeline.t) - 1 if end else 0)

    def zoom(self, factor: float) -> None:
        self.bar.zoom(factor)

    def fit(self) -> None:
        self.bar.fit()

    def toggle_play(self) -> None:
        if self.isEnabled():
            self.play_button.setChecked(not self.play_button.isChecked())

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

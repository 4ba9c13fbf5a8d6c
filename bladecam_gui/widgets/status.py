"""Status bar pieces: the key figures (verdict, total time, minimum tip spacing and tool clearance:
always whole, at every window size), the plan's other figures on one line that elides (all of it in
its tooltip), and the progress of the running job with a cancel button."""

from __future__ import annotations

import logging

from PySide6.QtCore import QSize, Qt, QTimer, Slot
from PySide6.QtGui import QPainter
from PySide6.QtWidgets import QHBoxLayout, QLabel, QProgressBar, QPushButton, QSizePolicy, QWidget

from core.paths.collaboration import collaboration_warning as plan_collaboration_warning

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import DANGER_COLOUR, SAFE_COLOUR
from . import navigation as nav

log = logging.getLogger(__name__)


WARNING_COLOUR = "#b06000"


def collaboration_warning(data: PlanData) -> str:
    """core.paths.collaboration's warning for the shown plan, marked for the status bar ('' when
    most contours are collaborative)."""
    if data.result is None or data.result.plan is None:
        return ""
    text = plan_collaboration_warning(data.result.plan)
    return f"⚠ {text}" if text else ""


def figures_text(data: PlanData) -> str:
    """One line: paths per region, points per region, total time, minimum spacing and clearance."""
    if data.result is None:
        info = data.blade.blade.info()
        return f"{info['name']}: blade loaded, planning…"
    counts = data.result.plan.region_counts()
    pts = counts["points"]
    text = (f"{counts['paths']} paths: {counts['tip_paths']} tip, {counts['collaborative_paths']} "
            f"collaborative "
            f"· points tip {pts['tip']} / internal {pts['internal']} / variable {pts['variable']} / "
            f"edge {pts['edge']}")
    fig = data.result.figures
    if fig is None:
        return text + " · scheduling…"
    text = (text + f" · total {fig['total_time_s'] / 60:.1f} min"
            f" · min spacing {fig['min_tip_spacing_mm']:.3f} mm"
            f" · min clearance {fig['min_capsule_clearance_mm']:.3f} mm · {fig['mode']}")
    # an unsafe verdict or a warning leads (the line elides at its right end)
    found = nav.violations_of(data) if data.has_schedule else None
    warning = collaboration_warning(data)
    verdict = "safe" if found is None or found.safe else found.summary()
    if verdict != "safe" or warning:
        return " · ".join([verdict, *([warning] if warning else []), text])
    return f"{text} · {verdict}"


def unplanned_text(changes: dict) -> str:
    """The inputs edited and not planned (after a cancel): 'h_safe 2 (plan: 1.875)', ..."""
    def show(v) -> str:
        return f"{v:g}" if isinstance(v, float) else ("auto" if v is None else str(v))
    return ", ".join(f"{name} {show(new)} (plan: {show(old)})" for name, (new, old) in changes.items())


class FiguresLabel(QLabel):
    """The plan's figures; marked 'out of date' while the inputs run ahead of the plan shown, naming
    the inputs the plan shown does not have once nothing is planning them (after a cancel). One line
    that takes the room the key figures leave and elides the rest ('…'); ``text()`` and the tooltip
    are the whole line."""

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__("no plan yet", parent)
        self.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        self.setMinimumWidth(40)
        self.state = state
        self.figures = ""
        state.regions_changed.connect(self._on_regions_changed)
        self.warning = False
        state.stale_changed.connect(self._on_stale_changed)
        state.busy_changed.connect(self._on_stale_changed)

    @Slot(object)
    def _on_regions_changed(self, data: PlanData) -> None:
        try:
            self.figures = figures_text(data)
            unsafe = is_unsafe(data)
            self.warning = bool(collaboration_warning(data))
            colour = DANGER_COLOUR if unsafe else WARNING_COLOUR if self.warning else ""
            self.setStyleSheet(f"color: {colour}; font-weight: bold" if colour else "")
            self._show()
        except Exception:  # slots never raise
            log.exception("status update failed")

    @Slot(bool)
    def _on_stale_changed(self, stale: bool) -> None:
        self._show()

    def _show(self) -> None:
        prefix = ""
        if self.state.stale:
            changes = self.state.unplanned()
            if self.state.busy or not changes:
                prefix = "[out of date: planning the new inputs] "
            else:  # cancelled (or failed): say what the plan shown does not have
                prefix = (f"[out of date: not planned: {unplanned_text(changes)}; "
                          "F5 plans them, Ctrl+Z undoes] ")
        self.setText(prefix + self.figures)
        self.setToolTip(self.text())

    def minimumSizeHint(self) -> QSize:  # noqa: N802 (Qt name)
        return QSize(40, super().minimumSizeHint().height())

    def paintEvent(self, event) -> None:  # noqa: N802 (Qt name)
        p = QPainter(self)
        try:
            rect = self.contentsRect()
            text = self.fontMetrics().elidedText(self.text(), Qt.TextElideMode.ElideRight, rect.width())
            p.setPen(self.palette().color(self.foregroundRole()))
            p.drawText(rect, Qt.AlignmentFlag.AlignVCenter | Qt.AlignmentFlag.AlignLeft, text)
        finally:
            p.end()


def is_unsafe(data: PlanData | None) -> bool:
    """Whether a shown plan's verdict is UNSAFE (verdict.Violations; False before its figures exist)."""
    if data is None or data.result is None or data.result.figures is None or not data.has_schedule:
        return False
    return not nav.violations_of(data).safe


def key_figures(data: PlanData | None) -> dict[str, tuple[str, str]]:
    """name -> (text, tooltip) of the key figures of a shown plan: 'verdict', 'total', 'spacing',
    'clearance'. A violation is a run of consecutive time samples that break the safety rule or where a
    part collides (verdict.Violations: the timeline's red marks, the violation list's rows); the
    verdict's tooltip gives the runs per kind and what to change."""
    if data is None:
        return {k: ("–", "no plan yet") for k in KEY_FIGURES}
    if data.result is None or data.result.figures is None:
        what = "planning the paths…" if data.result is None else "scheduling…"
        return {"verdict": ("planning…", what), **{k: ("–", what) for k in KEY_FIGURES[1:]}}
    fig = data.result.figures
    found = nav.violations_of(data)
    return {"verdict": (found.verdict(), found.tooltip()),
            "total": (f"total {fig['total_time_s'] / 60:.1f} min",
                      f"the job's time: {fig['total_time_s']:.1f} s"),
            "spacing": (f"min spacing {fig['min_tip_spacing_mm']:.3f} mm",
                        "the smallest tip spacing over the job, at and between time samples (M jumps there)"),
            "clearance": (f"min clearance {fig['min_capsule_clearance_mm']:.3f} mm",
                          "the smallest distance between the two tool capsules (Shift+M jumps there)")}


KEY_FIGURES = ("verdict", "total", "spacing", "clearance")


class KeyFigures(QWidget):
    """The verdict, total time, minimum tip spacing and minimum tool clearance of the plan shown, each
    a label that is always shown whole; 'out of date' before them while the inputs run ahead of the
    plan. ``labels[name]``."""

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__(parent)
        self.state = state
        self.data: PlanData | None = None
        self.stale_label = QLabel("out of date", self)
        self.stale_label.setStyleSheet(f"color: {WARNING_COLOUR}; font-weight: bold")
        self.stale_label.setToolTip("the inputs differ from the plan shown: these figures are the plan "
                                    "shown's")
        self.stale_label.setVisible(False)
        self.labels = {name: QLabel("–", self) for name in KEY_FIGURES}
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 4, 0)
        layout.setSpacing(10)
        layout.addWidget(self.stale_label)
        for name in KEY_FIGURES:
            self.labels[name].setObjectName(f"key-{name}")
            self.labels[name].setSizePolicy(QSizePolicy.Policy.Fixed, QSizePolicy.Policy.Preferred)
            layout.addWidget(self.labels[name])
        state.plan_changed.connect(self._on_plan_changed)
        state.stale_changed.connect(self._on_stale_changed)
        self._show()

    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            self.data = data
            self._show()
        except Exception:  # slots never raise
            log.exception("showing the key figures failed")

    @Slot(bool)
    def _on_stale_changed(self, _stale: bool) -> None:
        try:
            self._show()
        except Exception:  # slots never raise
            log.exception("showing the key figures failed")

    def _show(self) -> None:
        stale = self.state.stale and self.data is not None
        self.stale_label.setVisible(stale)
        figures = key_figures(self.data)
        for name, (text, tip) in figures.items():
            label = self.labels[name]
            label.setText(text)
            label.setToolTip(("out of date: the plan shown's figure\n" if stale else "") + tip)
            style = "font-weight: bold"
            if name == "verdict" and self.data is not None and self.data.result is not None \
                    and self.data.result.figures is not None:
                colour = DANGER_COLOUR if is_unsafe(self.data) else SAFE_COLOUR
                style += f"; color: white; background: {colour}; padding: 0 6px"
            if stale:
                style += "; font-style: italic"
            label.setStyleSheet(style)
            label.setMinimumWidth(label.sizeHint().width())


def duration_text(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    return f"{seconds} s" if seconds < 60 else f"{seconds // 60}:{seconds % 60:02d} min"


def progress_text(message: str, fraction: float, elapsed: float, stage_elapsed: float) -> str:
    """What the progress bar says: the stage, how far, how long it has run, and the time left
    extrapolated from the share done so far (once there is enough of it to go by)."""
    if fraction < 0:  # unknown length
        return f"{message} · {duration_text(elapsed)}"
    text = f"{message} {int(100 * min(max(fraction, 0.0), 1.0))} %"
    if stage_elapsed >= STAGE_SHOWN_S:
        text += f" · {duration_text(stage_elapsed)} in this stage"
    if MIN_FRACTION <= fraction < 1.0 and elapsed >= 1.0:
        text += f" · about {duration_text(elapsed * (1.0 - fraction) / fraction)} left"
    elif fraction < 1.0:
        text += f" · {duration_text(elapsed)}"
    return text


#: the share done before the time left is estimated, and how long a stage runs before its own time shows
MIN_FRACTION = 0.05
STAGE_SHOWN_S = 3.0


class ProgressBox(QWidget):
    """A progress bar with the job's stage, how far it is, the time it has run and the time left, and
    a cancel button, shown while something runs. The text moves every second, even while a stage
    reports nothing (a large mesh loading, the schedule's safety rounds): its own time counts up.
    ``clock`` (seconds) is time.monotonic unless a test gives its own."""

    def __init__(self, parent: QWidget | None = None, clock=None):
        super().__init__(parent)
        import time

        self.clock = clock or time.monotonic
        self.bar = QProgressBar(self)
        self.bar.setRange(0, 1000)
        self.bar.setFixedWidth(330)
        self.bar.setTextVisible(True)
        self.cancel_button = QPushButton("Cancel", self)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.bar)
        layout.addWidget(self.cancel_button)
        self.setVisible(False)
        self.message, self.fraction = "", 0.0
        self.started = self.stage_started = self.clock()
        self.ticker = QTimer(self)
        self.ticker.setInterval(1000)
        self.ticker.timeout.connect(self.refresh)

    @Slot(float, str)
    def set_progress(self, fraction: float, message: str) -> None:
        if message != self.message:
            self.message, self.stage_started = message, self.clock()
        self.fraction = fraction
        if fraction < 0:  # unknown length (export's verification)
            self.bar.setRange(0, 0)
        else:
            self.bar.setRange(0, 1000)
            self.bar.setValue(int(max(0.0, min(1.0, fraction)) * 1000))
        self.refresh()

    def refresh(self) -> None:
        now = self.clock()
        text = progress_text(self.message, self.fraction, now - self.started, now - self.stage_started)
        self.bar.setFormat(text)  # (no %p, %v or %m in it: shown as it is)
        self.bar.setToolTip(text)

    def text(self) -> str:
        return self.bar.toolTip()

    @Slot(bool)
    def set_busy(self, busy: bool) -> None:
        if busy and not self.isVisible():
            self.started = self.stage_started = self.clock()
            self.message, self.fraction = "", 0.0
        self.setVisible(busy)
        if busy:
            self.ticker.start()
        else:
            self.ticker.stop()
            self.bar.setRange(0, 1000)
            self.bar.setValue(0)

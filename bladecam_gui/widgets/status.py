"""Status bar pieces: the plan's figures, and the progress of the running job with a cancel button."""

from __future__ import annotations

import logging

from PySide6.QtCore import Slot
from PySide6.QtWidgets import QHBoxLayout, QLabel, QProgressBar, QPushButton, QWidget

from core.paths.collaboration import collaboration_warning as plan_collaboration_warning

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import DANGER_COLOUR

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
    verdict = "safe" if data.result.safe else (f"UNSAFE: {fig['spacing_violations']} spacing, "
                                               f"{fig['capsule_violations']} clearance violations")
    text = (text + f" · total {fig['total_time_s'] / 60:.1f} min"
            f" · min spacing {fig['min_tip_spacing_mm']:.3f} mm"
            f" · min clearance {fig['min_capsule_clearance_mm']:.3f} mm · {fig['mode']} · {verdict}")
    warning = collaboration_warning(data)
    return f"{verdict} · {warning} · {text}" if warning else text


def unplanned_text(changes: dict) -> str:
    """The inputs edited and not planned (after a cancel): 'h_safe 2 (plan: 1.875)', ..."""
    def show(v) -> str:
        return f"{v:g}" if isinstance(v, float) else ("auto" if v is None else str(v))
    return ", ".join(f"{name} {show(new)} (plan: {show(old)})" for name, (new, old) in changes.items())


class FiguresLabel(QLabel):
    """The plan's figures; marked 'out of date' while the inputs run ahead of the plan shown, naming
    the inputs the plan shown does not have once nothing is planning them (after a cancel)."""

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__("no plan yet", parent)
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
            unsafe = data.result is not None and data.result.figures is not None and not data.result.safe
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


class ProgressBox(QWidget):
    """A progress bar with the job's message and a cancel button, shown while something runs."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.bar = QProgressBar(self)
        self.bar.setRange(0, 1000)
        self.bar.setFixedWidth(240)
        self.bar.setTextVisible(True)
        self.cancel_button = QPushButton("Cancel", self)
        layout = QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.bar)
        layout.addWidget(self.cancel_button)
        self.setVisible(False)

    @Slot(float, str)
    def set_progress(self, fraction: float, message: str) -> None:
        if fraction < 0:  # unknown length (export's verification)
            self.bar.setRange(0, 0)
        else:
            self.bar.setRange(0, 1000)
            self.bar.setValue(int(max(0.0, min(1.0, fraction)) * 1000))
        self.bar.setFormat(f"{message} %p%" if fraction >= 0 else message)

    @Slot(bool)
    def set_busy(self, busy: bool) -> None:
        self.setVisible(busy)
        if not busy:
            self.bar.setRange(0, 1000)
            self.bar.setValue(0)

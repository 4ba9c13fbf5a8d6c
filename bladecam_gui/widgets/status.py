"""Status bar pieces: the plan's figures, and the progress of the running job with a cancel button."""

from __future__ import annotations

import logging

from PySide6.QtCore import Slot
from PySide6.QtWidgets import QHBoxLayout, QLabel, QProgressBar, QPushButton, QWidget

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import DANGER_COLOUR

log = logging.getLogger(__name__)


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
    return (text + f" · total {fig['total_time_s'] / 60:.1f} min"
            f" · min spacing {fig['min_tip_spacing_mm']:.3f} mm"
            f" · min clearance {fig['min_capsule_clearance_mm']:.3f} mm · {fig['mode']} · {verdict}")


class FiguresLabel(QLabel):
    """The plan's figures; marked 'out of date' while the inputs run ahead of the plan shown."""

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__("no plan yet", parent)
        self.state = state
        self.figures = ""
        state.regions_changed.connect(self._on_regions_changed)
        state.stale_changed.connect(self._on_stale_changed)

    @Slot(object)
    def _on_regions_changed(self, data: PlanData) -> None:
        try:
            self.figures = figures_text(data)
            unsafe = data.result is not None and data.result.figures is not None and not data.result.safe
            self.setStyleSheet(f"color: {DANGER_COLOUR}" if unsafe else "")
            self._show()
        except Exception:  # slots never raise
            log.exception("status update failed")

    @Slot(bool)
    def _on_stale_changed(self, stale: bool) -> None:
        self._show()

    def _show(self) -> None:
        self.setText(("[out of date] " if self.state.stale else "") + self.figures)


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

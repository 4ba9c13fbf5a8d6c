"""The tool assembly's clearances at the cursor: each part of each side's tool and head from the
blade (the plan's collision check, core.machine.collisions.ClearanceProfile: exact below its REFINE,
"at least" above), the heads from the clamp, the two assemblies from each other; and jumps to the
closest approach of a holder to the blade and of head to head. Nothing here is computed: the figures
are core's, as the plan holds them."""

from __future__ import annotations

import logging

from PySide6.QtCore import Qt, Slot
from PySide6.QtWidgets import QGridLayout, QLabel, QPushButton, QVBoxLayout, QWidget

from core.machine.clearance import REFINE, TOLERANCE

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import DANGER_COLOUR

log = logging.getLogger(__name__)


def clearance_text(value: float) -> str:
    """A clearance as the panel shows it: mm to 3 decimals, 'at least' where it is a bound, red below
    -TOLERANCE (a collision)."""
    if value == float("inf"):
        return "–"
    if value < -TOLERANCE:
        return f"<span style='color:{DANGER_COLOUR}'><b>{value:.3f}</b></span>"
    return f"{value:.3f}" if value < REFINE else f"≥ {value:.2f}"


def rows_at(profile, row: int) -> list[tuple[str, str, str]]:
    """(what, left, right) lines of the panel at ``row``: each part from the blade, then the heads
    from the clamp, and the other side's assembly and head (one column)."""
    out = []
    for k, part in enumerate(profile.parts):
        out.append((part, clearance_text(float(profile.blade["left"][row, k])),
                    clearance_text(float(profile.blade["right"][row, k]))))
    clamp = {s: float(profile.clamp[s][row].min(initial=float("inf"))) for s in ("left", "right")}
    out.append(("heads – clamp", clearance_text(clamp["left"]), clearance_text(clamp["right"])))
    out.append(("left – right tool", clearance_text(float(profile.tools[row])), ""))
    out.append(("left – right head", clearance_text(float(profile.heads[row])), ""))
    return out


class ClearancePanel(QWidget):
    """The read-out and the two jumps (module docstring)."""

    def __init__(self, state: WorkbenchState, parent=None):
        super().__init__(parent)
        self.state = state
        self.profile = None
        layout = QVBoxLayout(self)
        self.title = QLabel("no plan", self)
        layout.addWidget(self.title)
        self.grid = QGridLayout()
        layout.addLayout(self.grid)
        self.holder_jump = QPushButton("holder – blade closest", self)
        self.head_jump = QPushButton("head – head closest", self)
        self.holder_jump.clicked.connect(lambda: self.jump("holder"))
        self.head_jump.clicked.connect(lambda: self.jump("heads"))
        layout.addWidget(self.holder_jump)
        layout.addWidget(self.head_jump)
        layout.addStretch(1)
        self.labels: list[tuple[QLabel, QLabel, QLabel]] = []
        state.plan_changed.connect(self.show_plan)
        state.cursor_changed.connect(self.show_row)
        self.show_plan(None)

    @Slot(object)
    def show_plan(self, data: PlanData | None) -> None:
        try:
            res = None if data is None or not data.has_schedule else data.result
            self.profile = getattr(res, "clearance", None)
            for b in (self.holder_jump, self.head_jump):
                b.setEnabled(self.profile is not None)
            if self.profile is None:
                self.title.setText("no collision check (no schedule shown)")
                return
            n = len(self.profile.collisions)
            self.title.setText(f"clearance at the cursor, mm ({n} collision{'s' if n != 1 else ''} in this plan)")
            self.show_row(self.state.cursor)
        except Exception:  # slots never raise
            log.exception("showing the clearances failed")

    @Slot(int)
    def show_row(self, row: int) -> None:
        try:
            if self.profile is None:
                return
            row = max(0, min(int(row), len(self.profile.tools) - 1))
            lines = rows_at(self.profile, row)
            while len(self.labels) < len(lines) + 1:
                k = len(self.labels)
                trio = tuple(QLabel(self) for _ in range(3))
                for c, label in enumerate(trio):
                    label.setTextFormat(Qt.TextFormat.RichText)
                    self.grid.addWidget(label, k, c)
                self.labels.append(trio)
            head = self.labels[0]
            head[0].setText("<b>part</b>")
            head[1].setText("<b>left</b>")
            head[2].setText("<b>right</b>")
            for trio, line in zip(self.labels[1:], lines, strict=False):
                for label, text in zip(trio, line, strict=True):
                    label.setText(text)
        except Exception:  # slots never raise
            log.exception("showing the clearances at the cursor failed")

    def jump(self, what: str) -> None:
        """Put the cursor on the closest approach of ``what`` ('holder' to the blade, 'heads')."""
        try:
            if self.profile is None:
                return
            row, value, which = self.profile.closest(what)
            self.state.set_cursor(row)
            self.holder_jump.setToolTip(which if what == "holder" else self.holder_jump.toolTip())
            self.head_jump.setToolTip(which if what == "heads" else self.head_jump.toolTip())
        except Exception:  # slots never raise
            log.exception("the clearance jump failed")

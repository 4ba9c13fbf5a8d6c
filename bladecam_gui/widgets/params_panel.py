"""The parameter panels: paths (the tool file, tool, dR, dd), regions (h_safe, K_max), schedule (mode,
feed, a_max).

Every field shows its unit and, where the paper gives one, its recommended range (dR <= r/4,
h_safe 1-1.5 r, K_max 0.1-0.2); a value outside it turns the field amber, with core's warning as the
tooltip. Edits go through the InputEditor (undoable); the panel follows the state's signals. The tool
file loaded (File ▸ Tool file…, or the shipped assembly) heads the Paths group, with the assembly's
sizes as the plan shown carries them (core.machine.tool.Tool: what the collision check used).
"""

from __future__ import annotations

import html
import logging
from pathlib import Path

from PySide6.QtCore import Qt, Slot
from PySide6.QtWidgets import (
    QComboBox,
    QDoubleSpinBox,
    QGridLayout,
    QGroupBox,
    QLabel,
    QVBoxLayout,
    QWidget,
)

from ..commands import InputEditor
from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import WARNING_BG

log = logging.getLogger(__name__)

#: name -> (label with unit, minimum, maximum, step, decimals, group)
FIELDS = {
    "tool_radius": ("Tool radius r (mm)", 0.1, 25.0, 0.1, 3, "Paths"),
    "tool_length": ("Tool stick-out d_T (mm)", 1.0, 500.0, 1.0, 1, "Paths"),
    "dr": ("Radius step dR (mm)", 0.01, 50.0, 0.05, 3, "Paths"),
    "dd": ("Interpolation step dd (mm)", 0.01, 10.0, 0.05, 3, "Paths"),
    "h_safe": ("Safe tip spacing h_safe (mm)", 0.01, 250.0, 0.05, 3, "Regions"),
    "k_max": ("Max staggered ratio K_max (-)", 0.01, 0.99, 0.01, 3, "Regions"),
    "feed": ("Feed (mm/min)", 1.0, 60000.0, 50.0, 1, "Schedule"),
    "a_max": ("Max acceleration a_max (mm/s²)", 1.0, 100000.0, 50.0, 1, "Schedule"),
    "min_feed": ("Min. cutting feed (mm/min)", 0.0, 60000.0, 50.0, 1, "Schedule"),
    "period": ("CL time step (ms)", 0.0, 10000.0, 1.0, 3, "Schedule"),
}
#: the fields' tooltips beyond their labels
TIPS = {"period": "CL time step (ms): 0 is auto, the time dd takes at the feed",
        "min_feed": "Min. cutting feed (mm/min), from the tool's minimum chip thickness: the Job tab reports "
                    "where and why a cutter cuts slower. 0 is auto, 30 % of the feed"}
#: fields whose 0 means the default (None)
AUTO = ("period", "min_feed")
MODES = ("collaborative", "symmetric", "single")
#: a field whose value the plan shown does not have (edited, then the planning cancelled)
UNPLANNED_STYLE = "{w} {{ border: 2px dashed #d03030; }}"
PROFILES = ("sigmoid", "smooth")
#: the prefix of core's PlanParameters.warnings() text per field
WARNING_PREFIX = {"dr": "dR =", "h_safe": "h_safe =", "k_max": "k_max ="}


def tool_sizes(tool) -> str:
    """The sizes of a tool assembly (core.machine.tool.Tool) that decide whether it reaches: 'ball r 1.5
    · neck r 3 to 13.5 · shank r 3 · stick-out 40 · holder r 11–14 mm'."""
    holder = sorted({r for _, r in tool.holder})
    radii = f"{holder[0]:g}–{holder[-1]:g}" if len(holder) > 1 else f"{holder[0]:g}" if holder else "–"
    return (f"ball r {tool.ball_radius:g} · neck r {tool.neck_radius:g} to {tool.neck_length:g} · shank r "
            f"{tool.shank_radius:g} · stick-out {tool.stick_out:g} · holder r {radii} mm")


def tool_text(tool_file: str | None, shown: PlanData | None) -> tuple[str, str]:
    """(rich text, tooltip) naming the tool file of the inputs (None: the shipped assembly), with the
    assembly's sizes once a plan of that file is shown."""
    name = "shipped tool.toml" if tool_file is None else Path(tool_file).name
    text = f"Tool file: <b>{html.escape(name)}</b>"
    tip = ("the tool assembly both machines carry: " + (tool_file or "the shipped resources/tool.toml")
           + "\n(File ▸ Tool file… loads another; its ball radius and stick-out set r and d_T)")
    tool = None if shown is None or shown.result is None else shown.result.tool
    if tool is not None and shown.job.tool == tool_file:
        text += f"<br><span style='color:gray'>{html.escape(tool_sizes(tool))}</span>"
    elif tool_file is not None:
        text += "<br><span style='color:gray'>not planned yet</span>"
    return text, tip


class ParamsPanel(QWidget):
    """Spin boxes and combo boxes for every input; ``spins[name]``, ``combos[name]``, ``hints[name]``."""

    def __init__(self, state: WorkbenchState, editor: InputEditor, parent: QWidget | None = None):
        super().__init__(parent)
        self.state, self.editor = state, editor
        self.spins: dict[str, QDoubleSpinBox] = {}
        self.combos: dict[str, QComboBox] = {}
        self.hints: dict[str, QLabel] = {}
        outer = QVBoxLayout(self)
        groups: dict[str, QGridLayout] = {}
        for title in ("Paths", "Regions", "Schedule"):
            box = QGroupBox(title, self)
            groups[title] = QGridLayout(box)
            outer.addWidget(box)
        self.tool_label = QLabel(self)
        self.tool_label.setObjectName("tool-file")
        self.tool_label.setTextFormat(Qt.TextFormat.RichText)
        self.tool_label.setWordWrap(True)
        groups["Paths"].addWidget(self.tool_label, 0, 0, 1, 2)
        for name, (label, lo, hi, step, decimals, group) in FIELDS.items():
            spin = QDoubleSpinBox(self)
            spin.setRange(lo, hi)
            spin.setSingleStep(step)
            spin.setDecimals(decimals)
            spin.setKeyboardTracking(False)  # valueChanged on Enter / focus out / arrows, not per key
            spin.setObjectName(name)
            if name in AUTO:
                spin.setSpecialValueText("auto")
            spin.valueChanged.connect(lambda v, n=name: self._on_spin_edited(n, v))
            self._add_row(groups[group], label, spin, name)
            self.spins[name] = spin
            spin.setToolTip(TIPS.get(name, label))
        for name, label, items in (("mode", "Plan mode", MODES), ("profile", "Speed stages", PROFILES)):
            combo = QComboBox(self)
            combo.addItems(items)
            combo.setObjectName(name)
            combo.currentTextChanged.connect(lambda text, n=name: self._on_combo_edited(n, text))
            self._add_row(groups["Schedule"], label, combo, name)
            self.combos[name] = combo
        outer.addStretch(1)
        self.unplanned: dict[str, tuple] = {}  # name -> (input value, the shown plan's)
        state.params_changed.connect(self._on_params_changed)
        state.inputs_changed.connect(self._on_inputs_changed)
        state.stale_changed.connect(self._on_stale_changed)
        state.busy_changed.connect(self._on_stale_changed)
        state.inputs_changed.connect(self._on_tool_changed)
        state.plan_changed.connect(self._on_tool_changed)
        self._refresh()
        self._on_tool_changed()

    def _add_row(self, grid: QGridLayout, label: str, widget: QWidget, name: str) -> None:
        row = grid.rowCount()
        text = QLabel(label, self)
        text.setWordWrap(True)  # narrow docks wrap the labels rather than push the 3D view aside
        grid.addWidget(text, row, 0)
        widget.setMinimumWidth(widget.fontMetrics().horizontalAdvance("00000.000") + 30)
        grid.addWidget(widget, row, 1)
        hint = QLabel("", self)
        hint.setStyleSheet("color: gray")
        grid.addWidget(hint, row + 1, 0, 1, 2)
        hint.setVisible(False)
        self.hints[name] = hint

    # -- edits -----------------------------------------------------------------------------------
    def _on_spin_edited(self, name: str, value: float) -> None:
        try:
            if name in AUTO:
                self.editor.edit(name, None if value <= 0 else float(value))
            else:
                self.editor.edit(name, float(value))
        except Exception:  # slots never raise
            log.exception("editing %s failed", name)

    def _on_combo_edited(self, name: str, text: str) -> None:
        try:
            self.editor.edit(name, text)
        except Exception:  # slots never raise
            log.exception("editing %s failed", name)

    # -- state -----------------------------------------------------------------------------------
    @Slot(object)
    def _on_params_changed(self, params) -> None:
        self._refresh()

    @Slot(str)
    def _on_inputs_changed(self, what: str) -> None:
        if what in ("schedule", "project"):
            self._refresh()

    def _on_tool_changed(self, *_args) -> None:
        """The tool file of the inputs (a new file or project), with its sizes once a plan of it shows."""
        try:
            text, tip = tool_text(self.state.tool, self.state.plan)
            self.tool_label.setText(text)
            self.tool_label.setToolTip(tip)
        except Exception:  # slots never raise
            log.exception("showing the tool file failed")

    def _refresh(self) -> None:
        p = self.state.params
        for name, spin in self.spins.items():
            value = self.state.period if name == "period" else getattr(p, name)
            spin.blockSignals(True)
            spin.setValue(0.0 if value is None else float(value))
            spin.blockSignals(False)
        for name, combo in self.combos.items():
            combo.blockSignals(True)
            combo.setCurrentText(p.mode if name == "mode" else self.state.profile)
            combo.blockSignals(False)
        r = p.tool_radius
        ranges = {"dr": f"paper: dR ≤ r/4 = {r / 4:.3g} mm",
                  "h_safe": f"paper: 1–1.5 r = {r:.3g}–{1.5 * r:.3g} mm",
                  "k_max": "paper: 0.1–0.2"}
        warnings = p.warnings()
        for name, text in ranges.items():
            hint = self.hints[name]
            hint.setText(text)
            hint.setVisible(True)
            found = [w for w in warnings if w.startswith(WARNING_PREFIX[name])]
            self.set_warning(name, found[0] if found else "")

    def set_warning(self, name: str, text: str) -> None:
        spin = self.spins[name]
        spin.setProperty("warning", bool(text))
        spin.setProperty("warning_text", text)
        self._restyle(name)
        self.hints[name].setStyleSheet("color: #c07000" if text else "color: gray")

    @Slot(bool)
    def _on_stale_changed(self, _flag: bool) -> None:
        """After a cancel (stale, nothing planning): frame the fields the plan shown does not have."""
        try:
            s = self.state
            self.unplanned = s.unplanned() if s.stale and not s.busy else {}
            for name in self.spins:
                self._restyle(name)
            for name, combo in self.combos.items():
                key = "mode" if name == "mode" else "profile"
                combo.setStyleSheet(UNPLANNED_STYLE.format(w="QComboBox") if key in self.unplanned else "")
        except Exception:  # slots never raise
            log.exception("marking the inputs not planned failed")

    def _restyle(self, name: str) -> None:
        spin = self.spins[name]
        text = spin.property("warning_text") or ""
        style = f"QDoubleSpinBox {{ background: {WARNING_BG}; color: black; }}" if text else ""
        tip = text or TIPS.get(name, FIELDS[name][0])
        if name in self.unplanned:
            new, old = self.unplanned[name]
            style += UNPLANNED_STYLE.format(w="QDoubleSpinBox")
            tip = (f"not planned: the plan shown has {old if old is not None else 'auto'} "
                   f"(F5 plans this value, Ctrl+Z undoes the edit)\n{tip}")
        spin.setStyleSheet(style)
        spin.setToolTip(tip)

    def is_unplanned(self, name: str) -> bool:
        return name in self.unplanned

    def is_warning(self, name: str) -> bool:
        return bool(self.spins[name].property("warning"))

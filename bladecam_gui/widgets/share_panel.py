"""How collaborative the shown plan is: core's figures (plan.json's "collaboration", from
core.schedule.figures.collaboration) for contours, cutting length and job time, machined
collaboratively (symmetric + staggered; of it, supported), and single-sided (the tip region); why the
tip paths went there; the status bar's warning when little is collaborative; and a plot of each
contour's staggered ratio against its radius with the K_max line, above which a contour goes to the
tip region. Hovering a point names the contour and, for a tip path, its reason; a click jumps the
timeline to that contour. Nothing here is computed: the figures are core's, as shown."""

from __future__ import annotations

import logging

import numpy as np
import pyqtgraph as pg
from PySide6.QtCore import Qt, Signal, Slot
from PySide6.QtWidgets import QFrame, QGridLayout, QLabel, QScrollArea, QVBoxLayout, QWidget

from core.paths.collaboration import REMEDY

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import BACKGROUND, REGIONS
from . import navigation as nav
from .status import WARNING_COLOUR, collaboration_warning

log = logging.getLogger(__name__)

#: the figures' measures (plan.json keys, shown as the table's columns) and kinds (its rows)
ROWS = (("paths", "contours"), ("cutting_length", "length"), ("job_time", "time"))
COLUMNS = (("collaborative", "collab."), ("supported", "supported"),
           ("single_sided", "single"))
COLLAB_COLOUR = REGIONS["internal"][1]
TIP_COLOUR = REGIONS["tip"][1]
K_MAX_COLOUR = "#ffb020"
MIN_SIZE = (220, 160)  # px: the panel's own minimum (its content scrolls below that)
MODE_NOTES = {
    "symmetric": "<b>symmetric mode</b>: both cutters machine every contour at once, the edges included "
                 "(what collaborative mode avoids).",
    "single": "<b>single mode</b>: every contour is machined single-sided, by the left cutter, then by "
              "the right one.",
}


def _share(value: float) -> str:
    return f"{100.0 * value:.1f} %"


def cell_texts(fig: dict) -> dict[tuple[str, str], str]:
    """(row, column) -> the text of a cell, from plan.json's "collaboration" figures ``fig``."""
    paths = fig["paths"]
    n, n_coll = paths["total"], paths["collaborative"]
    single = 1.0 - paths["collaborative_share"] if n else 0.0
    out = {("paths", "collaborative"): f"{_share(paths['collaborative_share'])}\n{n_coll}/{n}",
           ("paths", "supported"): "–",
           ("paths", "single_sided"): f"{_share(single)}\n{paths['single_sided']}/{n}"}
    for key, _ in COLUMNS:
        mm, s = fig["cutting_length_mm"][key], fig["job_time_s"][key]
        out[("cutting_length", key)] = f"{_share(fig['cutting_length_share'][key])}\n{mm / 1000.0:.2f} m"
        out[("job_time", key)] = f"{_share(fig['job_time_share'][key])}\n{s / 60.0:.2f} min"
    return out


def reasons_text(fig: dict) -> str:
    """The tip paths' reasons, most first, each with the parameter that would change it."""
    lines = []
    for reason, count in sorted(fig["tip_reasons"].items(), key=lambda kv: -kv[1]):
        remedy = next((v for k, v in REMEDY.items() if reason.startswith(k)), "")
        paths = "path" if count == 1 else "paths"
        lines.append(f"{count} {paths}: {reason}" + (f" ({remedy})" if remedy else ""))
    return "\n".join(lines) if lines else "no tip paths: every contour is collaborative"


class RatioPlot(pg.PlotWidget):
    """Each contour's staggered ratio (edge + variable length over the path's) against its radius
    (mm), tip paths marked, and the K_max line: a contour at or above it goes to the tip region."""

    def __init__(self, parent=None):
        super().__init__(parent=parent, background=BACKGROUND[0])
        item = self.getPlotItem()
        item.setTitle("Staggered ratio K", size="9pt")
        item.setLabel("bottom", "contour radius R (mm)")
        item.setLabel("left", "staggered ratio")
        item.showGrid(x=True, y=True, alpha=0.25)
        item.layout.setContentsMargins(2, 2, 16, 2)
        for name in ("left", "bottom"):
            item.getAxis(name).enableAutoSIPrefix(False)
        item.setMenuEnabled(False)
        legend = item.addLegend(offset=(5, 5), labelTextSize="8pt", brush=pg.mkBrush(38, 42, 51, 210))
        self.tip_band = pg.LinearRegionItem(orientation="horizontal", movable=False,
                                            brush=pg.mkBrush(61, 124, 255, 40), pen=pg.mkPen(None))
        item.addItem(self.tip_band, ignoreBounds=True)
        # one item for all the points (two would clear each other's hover text), two samples for the legend
        self.scatter = pg.ScatterPlotItem(hoverable=True, tip=self._tip)
        item.addItem(self.scatter)
        for kind, name in ((False, "collaborative"), (True, "tip region (single-sided)")):
            legend.addItem(pg.ScatterPlotItem(**self._style(kind)), name)
        self.k_line = pg.InfiniteLine(angle=0, movable=False,
                                      pen=pg.mkPen(K_MAX_COLOUR, width=1, style=Qt.PenStyle.DashLine),
                                      label="K_max {value:.3g}: tip region above",
                                      labelOpts={"position": 0.03, "color": K_MAX_COLOUR,
                                                 "anchors": [(0, 1), (0, 1)]})
        item.addItem(self.k_line, ignoreBounds=True)
        self.k_line.setVisible(False)
        self.tip_band.setVisible(False)
        self.texts: dict[int, str] = {}  # contour -> hover text
        self.is_tip = np.zeros(0, bool)

    @property
    def view_box(self) -> pg.ViewBox:
        return self.getPlotItem().getViewBox()

    _styles: dict[bool, dict] = {}

    @classmethod
    def _style(cls, tip: bool) -> dict:
        """The points' style (one pen and brush object per kind, shared by every point of it: pyqtgraph
        then renders each kind's symbol once, not once a point)."""
        if tip not in cls._styles:
            cls._styles[tip] = ({"size": 8, "pen": pg.mkPen(TIP_COLOUR, width=1.5), "brush": pg.mkBrush(None),
                                 "symbol": "x"} if tip else
                                {"size": 6, "pen": pg.mkPen(None), "brush": pg.mkBrush(COLLAB_COLOUR), "symbol": "o"})
        return cls._styles[tip]

    def _tip(self, x: float, y: float, data) -> str:
        return self.texts.get(int(data), f"R {x:.1f} mm, ratio {y:.3f}")

    def show_plan(self, data: PlanData) -> None:
        """The contours of ``data``'s plan: plan.pairs[k].r against plan.regions[k].staggered_ratio."""
        plan = data.result.plan
        k_max = data.job.params.k_max
        r = np.array([p.r for p in plan.pairs], float)
        ratio = np.array([g.staggered_ratio for g in plan.regions], float)
        tip = np.array([g.is_tip for g in plan.regions], bool)
        index = np.array([p.index for p in plan.pairs], int)
        self.texts = {}
        for p, g in zip(plan.pairs, plan.regions, strict=True):
            where = f"contour {p.index}: R {p.r:.2f} mm, staggered ratio {g.staggered_ratio:.3f}"
            self.texts[p.index] = (f"{where}\ntip region (single-sided): {g.reason}" if g.is_tip
                                   else f"{where}\ncollaborative")
        styles = [self._style(bool(t)) for t in tip]
        self.scatter.setData(r, ratio, data=index, **{key: [st[key] for st in styles]
                                                      for key in ("size", "pen", "brush", "symbol")})
        self.is_tip = tip
        top = max(1.05, float(ratio.max(initial=0.0)) + 0.05)
        self.k_line.setVisible(True)  # (first: a hidden line's label does not follow its value)
        self.tip_band.setVisible(True)
        self.tip_band.setRegion((k_max, top))
        self.k_line.setValue(k_max)
        self.k_line.label.valueChanged()
        if len(r):
            self.view_box.setXRange(float(r.min()), float(r.max()), padding=0.03)
        self.view_box.setYRange(0.0, top, padding=0.02)

    def clear_plan(self) -> None:
        self.scatter.setData([], [])
        self.k_line.setVisible(False)
        self.tip_band.setVisible(False)
        self.texts = {}
        self.is_tip = np.zeros(0, bool)

    def points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(r mm, ratio, is tip) of every plotted point, as drawn (for the tests)."""
        x, y = self.scatter.getData()
        symbols = [spot.symbol() for spot in self.scatter.points()]
        return np.asarray(x, float), np.asarray(y, float), np.array([s == "x" for s in symbols], bool)


class SharePanel(QWidget):
    """The figures table, the tip paths' reasons, the warning and the ratio plot. ``summary_changed``
    carries a short title for the panel's tab ('Collaboration 42 %', with a warning sign when the
    status warns)."""

    summary_changed = Signal(str)

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__(parent)
        self.state = state
        self.headline = QLabel("no plan yet")
        self.headline.setWordWrap(True)
        self.warning = QLabel()
        self.warning.setWordWrap(True)
        self.warning.setStyleSheet(f"color: {WARNING_COLOUR}; font-weight: bold")
        self.warning.setVisible(False)
        # a row per kind of machining, a column per measure (kept narrow: the 3D view keeps its room)
        grid = QGridLayout()
        grid.setHorizontalSpacing(6)
        grid.setVerticalSpacing(2)
        for j, (_, title) in enumerate(ROWS):
            grid.addWidget(QLabel(f"<b>{title}</b>"), 0, j + 1)
        self.cells: dict[tuple[str, str], QLabel] = {}
        for i, (col, title) in enumerate(COLUMNS):
            grid.addWidget(QLabel(title), i + 1, 0)
            for j, (row, _) in enumerate(ROWS):
                cell = QLabel("–")
                cell.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
                grid.addWidget(cell, i + 1, j + 1)
                self.cells[(row, col)] = cell
        small = self.font()
        small.setPointSizeF(0.9 * small.pointSizeF())
        for k in range(grid.count()):
            grid.itemAt(k).widget().setFont(small)
        self.reasons = QLabel()
        self.reasons.setWordWrap(True)
        self.reasons.setStyleSheet("color: #9aa4b4;")
        self.plot = RatioPlot(self)
        self.plot.setMinimumSize(160, 160)
        for label in (self.headline, self.warning, self.reasons):
            label.setMinimumWidth(160)  # (wrapped: never what sets the dock's width)
        content = QWidget()
        layout = QVBoxLayout(content)
        layout.addWidget(self.headline)
        layout.addWidget(self.warning)
        layout.addLayout(grid)
        layout.addWidget(self.reasons)
        layout.addWidget(self.plot, 1)
        # scrolled when the window is small: the panel never sets the window's minimum size
        scroll = QScrollArea(self)
        scroll.setWidgetResizable(True)
        scroll.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)  # fits the width
        scroll.setFrameShape(QFrame.Shape.NoFrame)
        scroll.setWidget(content)
        outer = QVBoxLayout(self)
        outer.setContentsMargins(0, 0, 0, 0)
        outer.addWidget(scroll)
        self.setMinimumSize(*MIN_SIZE)
        self.setToolTip("collab. (collaborative): machined by both cutters (symmetric and staggered), "
                        "outside the tip region; supported: of the collaborative, both cutting with their "
                        "axes in line; single (single-sided): the tip region, one cutter at a time. Shares "
                        "of the whole job; length: the cutting length of both cutters; time: the job time.")
        self.plot.scatter.sigClicked.connect(self._on_point_clicked)
        state.regions_changed.connect(self._on_regions_changed)

    # -- state -----------------------------------------------------------------------------------
    @Slot(object)
    def _on_regions_changed(self, data: PlanData) -> None:
        try:
            self.show_plan(data)
        except Exception:  # slots never raise
            log.exception("showing the collaborative share failed")

    def show_plan(self, data: PlanData) -> None:
        res = data.result
        if res is None or res.plan is None:
            self.plot.clear_plan()
            self._set_cells(None)
            self.headline.setText("planning…")
            self.reasons.setText("")
            self.warning.setVisible(False)
            self.summary_changed.emit("Collab.")
            return
        self.plot.show_plan(data)
        mode = data.job.params.mode
        fig = None if res.figures is None else res.figures.get("collaboration")
        self._set_cells(fig)
        warning = collaboration_warning(data)
        self.warning.setText(warning)
        self.warning.setVisible(bool(warning))
        note = MODE_NOTES.get(mode, "")
        if fig is None:
            self.headline.setText("scheduling…" + (f"\n{note}" if note else ""))
            self.reasons.setText("")
            self.summary_changed.emit("Collab.")
            return
        share = fig["paths"]["collaborative_share"]
        time_share = fig["job_time_share"]["collaborative"]
        self.reasons.setText(reasons_text(fig))
        if note:  # (core counts the whole of these modes as symmetrical, or as single-sided)
            self.headline.setText(note)
            self.summary_changed.emit(f"Collab. ({mode})")
            return
        self.headline.setText(f"<b>{_share(share)}</b> of the contours and <b>{_share(time_share)}</b> of "
                              "the job time machined collaboratively")
        self.summary_changed.emit(f"Collab. {100.0 * share:.0f} %" + (" ⚠" if warning else ""))

    def _set_cells(self, fig: dict | None) -> None:
        texts = cell_texts(fig) if fig is not None else {}
        for key, cell in self.cells.items():
            cell.setText(texts.get(key, "–"))

    # -- operator --------------------------------------------------------------------------------
    def _on_point_clicked(self, _scatter, points, _event=None) -> None:
        try:
            data = self.state.plan
            if not len(points) or data is None or not data.has_schedule:
                return
            i = nav.contour_start(data, int(points[0].data()))
            if i is not None:
                self.state.set_cursor(i)
        except Exception:  # slots never raise
            log.exception("jumping to the clicked contour failed")

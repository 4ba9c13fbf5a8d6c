"""The Job tab: the cycle time per step of the plan shown on the machines and at the feed, with how
much of the cutting runs below the minimum feed and on which paths, and why (plan.json's step_time_s
and schedule.job), its violations
(widgets.violations) and the messages log: the planner's warnings for each plan shown, the status
bar's messages and the errors, each with the time it came, kept for the session (the status bar
shows a message for a few seconds only)."""

from __future__ import annotations

import logging
import time

from PySide6.QtCore import Qt, Signal, Slot
from PySide6.QtWidgets import (
    QAbstractItemView,
    QHeaderView,
    QLabel,
    QPlainTextEdit,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from core.machine.job_figures import minutes_by_reason

from ..plan_data import PlanData
from ..state import WorkbenchState
from ..style import STEPS
from .navigation import violations_of
from .violations import ViolationList

log = logging.getLogger(__name__)


COLUMNS = ("step", "time", "at the feed", "share")


def cycle_rows(figures: dict) -> list[tuple[str, str, str, str]]:
    """(step, time on the machines, time at the feed, share of the job) per step, and the total, from
    plan.json's figures (the time at the feed: schedule.job's step_time_at_feed_s, "–" without it)."""
    per = figures["step_time_s"]
    feed = figures.get("job", {}).get("step_time_at_feed_s")
    total = figures["total_time_s"]
    rows = []
    for k, (name, _, _) in STEPS.items():
        s = per[str(k)]
        rows.append((name, minutes(s), minutes(feed[str(k)]) if feed else "–",
                     f"{100.0 * s / total:.1f} %" if total > 0 else "–"))
    rows.append(("total", minutes(total), minutes(sum(feed.values())) if feed else "–", "100 %"))
    return rows


def job_summary(figures: dict) -> str:
    """One line on the job as the machines run it (plan.json's schedule.job): its time against its time
    at the feed, how much of each cutter's cutting runs below the minimum feed, and why; '' without it."""
    job = figures.get("job")
    if not job:
        return ""
    cut = job["cutting"]
    episodes = cut["both"]["episodes_below_5pct_feed"]
    why = minutes_by_reason(job)
    return (f"on the machines {job['time_on_machines_s'] / 60:.1f} min, {job['machines_over_feed']:.2f} x "
            f"the {job['time_at_feed_s'] / 60:.1f} min at the feed; cutting below the minimum feed "
            f"{job['min_feed_mm_min']:g} mm/min: left {100 * cut['left']['share_below_min_feed']:.1f} %, right "
            f"{100 * cut['right']['share_below_min_feed']:.1f} % ({episodes} episodes below 5 % of the feed)"
            + (f"; why: {why}" if why else ""))


def minutes(seconds: float) -> str:
    return f"{int(seconds // 60)}:{seconds % 60:04.1f}"


class CycleTable(QTableWidget):
    """The job's time per step (min:s) and its share."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(len(STEPS) + 1, len(COLUMNS), parent)
        self.setHorizontalHeaderLabels(list(COLUMNS))
        self.verticalHeader().setVisible(False)
        self.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.setSelectionMode(QAbstractItemView.SelectionMode.NoSelection)
        header = self.horizontalHeader()
        header.setSectionResizeMode(0, QHeaderView.ResizeMode.Stretch)
        for c in range(1, len(COLUMNS)):
            header.setSectionResizeMode(c, QHeaderView.ResizeMode.ResizeToContents)
        self.verticalHeader().setDefaultSectionSize(self.fontMetrics().lineSpacing() + 4)
        self.setMinimumWidth(160)
        self.setToolTip("the job's time per step of the seven-step schedule on the machines and at the "
                        "feed (the schedule's own time, before the machines slow it): the job is in a step "
                        "until both cutters have left it (plan.json: schedule.step_time_s, schedule.job)")
        self.show_rows(None)

    def show_rows(self, figures: dict | None) -> None:
        blank = ("–",) * (len(COLUMNS) - 1)
        rows = cycle_rows(figures) if figures is not None else [(STEPS[k][0], *blank) for k in STEPS] + [
            ("total", *blank)]
        for r, row in enumerate(rows):
            for c, text in enumerate(row):
                item = QTableWidgetItem(text)
                if c:
                    item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                self.setItem(r, c, item)

    def texts(self) -> list[tuple[str, ...]]:
        return [tuple(self.item(r, c).text() for c in range(len(COLUMNS))) for r in range(self.rowCount())]


SLOW_COLUMNS = ("cutter", "path", "step", "from (min)", "below (s)", "slowest (mm/min)", "reason")


def slow_rows(figures: dict | None) -> list[tuple[str, ...]]:
    """One row per path on which a cutter cuts below the minimum feed (plan.json's
    schedule.job.below_min_feed, longest first): the texts of SLOW_COLUMNS."""
    job = (figures or {}).get("job") or {}
    return [(item["side"], str(item["path"]), str(item["step"]), minutes(item["first_at_s"]),
             f"{item['below_s']:.1f}", f"{item['lowest_mm_min']:.1f}", item["reason"])
            for item in job.get("below_min_feed", [])]


class SlowList(QTableWidget):
    """The paths on which a cutter cuts below the minimum feed, longest first, with why; a click puts
    the cursor where it first does."""

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__(0, len(SLOW_COLUMNS), parent)
        self.state = state
        self.times: list[float] = []  # ms, where each row's path first runs below the minimum feed
        self.setHorizontalHeaderLabels(list(SLOW_COLUMNS))
        self.verticalHeader().setVisible(False)
        self.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.horizontalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        self.horizontalHeader().setStretchLastSection(True)
        self.verticalHeader().setDefaultSectionSize(self.fontMetrics().lineSpacing() + 4)
        self.setToolTip("the paths on which a cutter cuts below the minimum feed, and why: the method's speed "
                        "stage, a start or stop, this machine's axes or chord tolerance, or the other "
                        "machine (the shared clock); a click jumps there (plan.json: schedule.job.below_min_feed)")
        self.cellClicked.connect(self._on_clicked)

    def show_rows(self, figures: dict | None) -> None:
        rows = slow_rows(figures)
        job = (figures or {}).get("job") or {}
        self.times = [1000.0 * item["first_at_s"] for item in job.get("below_min_feed", [])]
        # (the columns are measured once, after the fill: measured to their contents as each item
        # arrives, a thousand rows took minutes of the GUI thread)
        header = self.horizontalHeader()
        header.setSectionResizeMode(QHeaderView.ResizeMode.Interactive)
        self.setUpdatesEnabled(False)
        try:
            self.setRowCount(len(rows))
            for r, row in enumerate(rows):
                for c, text in enumerate(row):
                    item = QTableWidgetItem(text)
                    if 0 < c < len(SLOW_COLUMNS) - 1:
                        item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                    self.setItem(r, c, item)
        finally:
            header.setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
            self.setUpdatesEnabled(True)

    def _on_clicked(self, row: int, _column: int) -> None:
        try:
            if 0 <= row < len(self.times):
                self.state.set_cursor_time(self.times[row])
        except Exception:  # slots never raise
            log.exception("jumping to a slow path failed")


class MessageLog(QPlainTextEdit):
    """Read-only lines '[hh:mm:ss] kind: text', the newest last."""

    def __init__(self, parent: QWidget | None = None):
        super().__init__(parent)
        self.setReadOnly(True)
        self.setMaximumBlockCount(5000)
        self.setLineWrapMode(QPlainTextEdit.LineWrapMode.WidgetWidth)
        self.setPlaceholderText("the planner's warnings and the window's messages")
        self.entries: list[tuple[str, str]] = []  # (kind, text)

    def add(self, kind: str, text: str) -> None:
        self.entries.append((kind, text))
        self.appendPlainText(f"[{time.strftime('%H:%M:%S')}] {kind}: {text}")


#: the splitter section of the violations, the rows it makes room for when a plan has some, and the
#: least height it leaves the other sections then (px)
VIOLATIONS = 2
VIOLATION_ROWS = 4
SECTION_MIN = 60


class JobPanel(QWidget):
    """Cycle time per step, violations and messages, one above the other. ``title_changed``: the tab's
    title ('Job', 'Job ⚠' when the plan shown has violations)."""

    title_changed = Signal(str)

    def __init__(self, state: WorkbenchState, parent: QWidget | None = None):
        super().__init__(parent)
        self.state = state
        self.cycle = CycleTable(self)
        self.summary = QLabel(self)
        self.summary.setWordWrap(True)
        self.summary.setToolTip("the job's time on the machines against its time at the feed, the share of "
                                "each cutter's cutting time below the minimum feed (a ball-nose mill that slow "
                                "rubs instead of cutting) and why: plan.json's schedule.job")
        self.slow = SlowList(state, self)
        self.violations = ViolationList(state, self)
        self.messages = MessageLog(self)
        splitter = self.splitter = QSplitter(Qt.Orientation.Vertical, self)
        self.headings: list[int] = []  # px of each section's title above its widget
        for title, widget in (("Cycle time per step", self.cycle), ("Below the minimum feed", self.slow),
                              ("Violations", self.violations), ("Messages", self.messages)):
            box = QWidget()
            lay = QVBoxLayout(box)
            lay.setContentsMargins(2, 2, 2, 2)
            lay.setSpacing(1)
            heading = QLabel(f"<b>{title}</b>")
            lay.addWidget(heading)
            lay.addWidget(widget, 1)
            if widget is self.cycle:
                lay.addWidget(self.summary)
            splitter.addWidget(box)
            self.headings.append(heading.sizeHint().height() + lay.spacing() + 4)  # (4: the box's margins)
        splitter.setSizes([220, 120, 120, 120])
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(splitter)
        self.violations.count_changed.connect(self._on_violations_counted)
        state.plan_changed.connect(self._on_plan_changed)

    @Slot(object)
    def _on_plan_changed(self, data: PlanData) -> None:
        try:
            fig = data.result.figures if data.result is not None else None
            self.cycle.show_rows(fig if fig is not None and "step_time_s" in fig else None)
            self.summary.setText(job_summary(fig) if fig is not None else "")
            self.slow.show_rows(fig)
            if data.has_schedule and fig is not None:
                self.log_plan(data)
        except Exception:  # slots never raise
            log.exception("showing the job failed")

    @Slot(int)
    def _on_violations_counted(self, n: int) -> None:
        try:
            self.title_changed.emit("Job ⚠" if n else "Job")
            if n:
                wanted = self.violations.wanted_height(min(n, VIOLATION_ROWS)) + self.headings[VIOLATIONS]
                self.make_room(VIOLATIONS, wanted)
        except Exception:  # slots never raise
            log.exception("showing the violations failed")

    def make_room(self, section: int, wanted: int) -> None:
        """At least ``wanted`` px for splitter section ``section``, taken from the others in proportion to
        what they have above SECTION_MIN (sizes the operator set stay when the section has enough)."""
        sizes = self.splitter.sizes()
        need = wanted - sizes[section]
        spare = [max(h - SECTION_MIN, 0) if k != section else 0 for k, h in enumerate(sizes)]
        if need <= 0 or not sum(spare):
            return
        take = min(need, sum(spare))
        sizes = [h - round(take * f / sum(spare)) for h, f in zip(sizes, spare, strict=True)]
        sizes[section] += take
        self.splitter.setSizes(sizes)

    def log_plan(self, data: PlanData) -> None:
        """A line for the plan shown, then each of its warnings (the paths', the parameters')."""
        fig = data.result.figures
        plan = data.result.plan
        name = data.blade.blade.info()["name"]
        verdict = violations_of(data).summary()
        self.messages.add("plan", f"{name}: {len(plan.pairs)} paths, {fig['mode']}, total "
                                  f"{fig['total_time_s'] / 60:.1f} min, {verdict}")
        for w in dict.fromkeys([*plan.params.warnings(), *plan.warnings]):  # (the paths repeat the parameters')
            self.messages.add("warning", w)

    @Slot(str)
    def on_status_message(self, text: str) -> None:
        if text:
            self.messages.add("status", text)

    @Slot(str, str)
    def on_failed(self, title: str, message: str) -> None:
        self.messages.add("error", f"{title}: {message}")

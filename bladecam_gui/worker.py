"""Re-planning off the GUI thread: a debounced request starts ``plan_data.prepare`` in a QThread.

One job runs at a time. A new request cancels the running job (through the progress callback, which
core checks between paths and steps) and runs once it has stopped; results of superseded jobs are
dropped (one that completes anyway is shown, marked out of date, and its paths are reused). Until a job
succeeds the previous plan stays shown; a failure is reported through ``failed``
(the main window shows it) and, for a blade that does not load, the state goes back to the blade shown.
"""

from __future__ import annotations

import logging
import time
from collections import OrderedDict

from PySide6.QtCore import QObject, QThread, QTimer, Signal, Slot

from core.errors import BladecamError, BladeInputError, Cancelled

from .guard import message_for
from .plan_data import EarlyPaths, PlanData, PlanJob, new_planner, plan_bytes, prepare
from .state import WorkbenchState

log = logging.getLogger(__name__)


class _Runner(QObject):
    """Lives in the worker thread; runs one job per ``run`` call."""

    progress = Signal(int, float, str)
    preview = Signal(int, object)
    done = Signal(int, object)
    failed = Signal(int, object)
    stopped = Signal(int)

    def __init__(self, early: EarlyPaths | None = None):
        super().__init__()
        self.cancel_upto = 0  # jobs with an id <= this stop at their next progress call
        self.early = early  # for the first job only (prepare uses it if it is the same job)
        # plans every job, keeping what the next one may reuse (the one that started the early paths)
        self.planner = early.planner if early is not None else new_planner()

    @Slot(int, object, object)
    def run(self, job_id: int, job: PlanJob, previous: PlanData | None) -> None:
        def cancelled() -> bool:
            return job_id <= self.cancel_upto

        early, self.early = self.early, None
        try:
            data = prepare(job, previous, self.planner, cancelled,
                           progress=lambda f, m: self.progress.emit(job_id, f, m),
                           preview=lambda d: self.preview.emit(job_id, d), early=early)
        except Cancelled:
            self.stopped.emit(job_id)
        except Exception as exc:  # reported to the GUI thread, never raised in the worker
            if not isinstance(exc, BladecamError):
                log.exception("planning failed")
            self.failed.emit(job_id, exc)
        else:
            self.done.emit(job_id, data)


#: plans kept for instant re-use (an undo, a redo, switching back to a mode or a value): the shown
#: one and the ones before it, at most RECENT_PLANS and RECENT_BYTES of arrays together (the newest is
#: always kept; plan_data.plan_bytes): ~320-330 MB a plan at the sample's defaults (its axis tables
#: included), so that an undo at the defaults shows the plan before at once
RECENT_PLANS = 3
RECENT_BYTES = 1 << 30


class PlanController(QObject):
    """Debounced re-planning of the state's inputs.

    failed(str title, str message); finished(PlanData): a job's plan was shown; idle(): nothing runs.
    The last RECENT_PLANS complete plans are kept by job: asking again for one of them (an undo)
    shows it at once, without planning; opening a blade or a project forgets them (the file may
    have changed).
    """

    failed = Signal(str, str)
    finished = Signal(object)
    idle = Signal()
    _start = Signal(int, object, object)

    def __init__(self, state: WorkbenchState, debounce_ms: int = 350, parent: QObject | None = None,
                 early: EarlyPaths | None = None):
        super().__init__(parent)
        self.state = state
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(debounce_ms)
        self._timer.timeout.connect(self._launch)
        self._thread = QThread(self)
        self._thread.setObjectName("bladecam-planner")
        self._runner = _Runner(early)
        self._runner.moveToThread(self._thread)
        self._start.connect(self._runner.run)
        self._runner.progress.connect(self._on_progress)
        self._runner.preview.connect(self._on_preview)
        self._runner.done.connect(self._on_done)
        self._runner.failed.connect(self._on_failed)
        self._runner.stopped.connect(self._on_stopped)
        self._thread.start()
        self._next_id = 0
        self._running: int | None = None
        self._pending = False
        self._started_at = 0.0
        self._last_progress = 0.0
        self._user_cancelled: int | None = None
        self.last_seconds = 0.0
        self._recent: OrderedDict = OrderedDict()  # PlanJob -> PlanData
        # the paths so far (chunk by chunk) arriving together on a busy GUI thread: only the latest drawn
        self._chunks: tuple[int, PlanData] | None = None
        self._chunk_timer = QTimer(self)
        self._chunk_timer.setSingleShot(True)
        self._chunk_timer.setInterval(0)
        self._chunk_timer.timeout.connect(self._show_chunks)
        self.reused_recent = 0  # plans shown from the recent ones (for the tests and the log)
        state.inputs_changed.connect(self._on_inputs_changed)

    # -- requests --------------------------------------------------------------------------------
    @Slot(str)
    def _on_inputs_changed(self, what: str) -> None:
        if what in ("blade", "project"):
            self._recent.clear()
        self.request(immediate=what in ("blade", "project"))

    def request(self, immediate: bool = False, fresh: bool = False) -> None:
        """Re-plan the current inputs: now, or after the debounce interval (restarted on each call).
        ``fresh``: plan them even if a kept plan has the same inputs (Re-plan now: a file read while
        planning, such as machine.toml, may have changed)."""
        if fresh:
            self._recent.pop(self.state.job(), None)
        self.state.set_stale(True)
        if immediate:
            self._timer.stop()
            self._launch()
        else:
            self._timer.start()

    def cancel(self) -> None:
        """The operator's cancel: stop the running job, forget pending requests, keep the plan shown."""
        self._timer.stop()
        self._pending = False
        self._runner.cancel_upto = self._next_id
        self._user_cancelled = self._running  # its result is dropped even if it completes
        if self._running is None:
            self.state.set_busy(False)
        self.state.progress_changed.emit(0.0, "cancelled")

    @property
    def running(self) -> bool:
        return self._running is not None or self._timer.isActive() or self._pending

    def _launch(self) -> None:
        if self._running is not None:
            self._pending = True
            self._runner.cancel_upto = self._running  # stop it; _on_stopped/_on_done launches again
            return
        self._pending = False
        if self._show_recent():
            return
        self._next_id += 1
        self._running = self._next_id
        self._started_at = time.perf_counter()
        self.state.set_busy(True)
        self.state.progress_changed.emit(0.0, "planning")
        self._start.emit(self._running, self.state.job(), self.state.plan)

    def _show_recent(self) -> bool:
        """Show the kept plan of the state's job, if there is one (True)."""
        data = self._recent.get(self.state.job())
        if data is None:
            return False
        self._recent.move_to_end(data.job)
        self.last_seconds = 0.0
        self.reused_recent += 1
        log.info("plan shown from the recent plans (no planning)")
        self.state.set_plan(data)
        self.state.progress_changed.emit(1.0, "plan ready (kept from before)")
        self.state.set_busy(False)
        self.finished.emit(data)
        self.idle.emit()
        return True

    def _keep(self, data: PlanData) -> None:
        if data.has_schedule:
            self._recent[data.job] = data
            self._recent.move_to_end(data.job)
            while len(self._recent) > 1 and (len(self._recent) > RECENT_PLANS or sum(
                    plan_bytes(d) for d in self._recent.values()) > RECENT_BYTES):
                self._recent.popitem(last=False)

    def _finish(self) -> None:
        self._running = None
        if not self._pending:
            self.state.clear_preview()  # a failed or cancelled job: the shown plan's regions again
        if self._pending:
            self._launch()
        else:
            self.state.set_busy(False)
            self.idle.emit()

    # -- results (GUI thread) ----------------------------------------------------------------------
    @Slot(int, float, str)
    def _on_progress(self, job_id: int, fraction: float, message: str) -> None:
        now = time.perf_counter()
        due = now - self._last_progress > 0.25 or fraction >= 1
        if job_id == self._running and not self._pending and due:
            self._last_progress = now  # a few repaints a second: each one holds the GIL the planner needs
            self.state.progress_changed.emit(fraction, message)

    @Slot(int, object)
    def _on_preview(self, job_id: int, data: PlanData) -> None:
        if data.result is None and data.lines is not None:  # the paths so far: the latest one shown
            self._chunks = (job_id, data)
            self._chunk_timer.start()
            return
        self._chunks = None
        self._show_preview(job_id, data)

    def _show_chunks(self) -> None:
        latest, self._chunks = self._chunks, None
        if latest is not None:
            self._show_preview(*latest)

    def _show_preview(self, job_id: int, data: PlanData) -> None:
        try:
            if job_id != self._running or self._pending:
                return
            shown = self.state.plan
            new_blade = shown is None or (shown.blade.source, shown.blade.axis) != (data.blade.source,
                                                                                     data.blade.axis)
            first_paths = shown is not None and shown.blade is data.blade and shown.result is None
            if new_blade or first_paths:
                self.state.set_plan(data)
            elif data.result is not None:  # the previous plan stays; its paths show the new regions
                self.state.set_regions_preview(data)
        except Exception:  # slots never raise
            log.exception("showing a preview failed")

    @Slot(int, object)
    def _on_done(self, job_id: int, data: PlanData) -> None:
        try:
            # a superseded job that still completed is a valid (stale) plan: shown, and the next job
            # reuses its paths
            if job_id == self._running and job_id != self._user_cancelled:
                self.last_seconds = time.perf_counter() - self._started_at
                log.info("plan shown after %.2f s (%s; paths reused: %s)", self.last_seconds,
                         ", ".join(f"{k} {v:.2f}" for k, v in data.timings.items()), data.reused)
                self.state.set_plan(data)
                self._keep(data)
                if not self._pending:
                    self.finished.emit(data)
        except Exception as exc:  # slots never raise
            log.exception("showing the plan failed")
            self.failed.emit("Cannot show the plan", message_for(exc))
        finally:
            self._finish()

    @Slot(int, object)
    def _on_failed(self, job_id: int, exc: Exception) -> None:
        try:
            if job_id == self._running and not self._pending:
                if isinstance(exc, BladeInputError):
                    self.state.revert_blade()
                    shown = self.state.plan
                    self.state.set_stale(shown is not None and shown.job != self.state.job())
                    title = "Cannot open the blade"
                else:
                    title = "Cannot plan"
                self.failed.emit(title, message_for(exc))
        finally:
            self._finish()

    @Slot(int)
    def _on_stopped(self, job_id: int) -> None:
        self._finish()

    def shutdown(self) -> None:
        """Stop the worker thread (waits for the running step to return)."""
        self._timer.stop()
        self._pending = False
        self._runner.cancel_upto = self._next_id + 1
        self._thread.quit()
        self._thread.wait()
        early, self._runner.early = self._runner.early, None
        if early is not None:  # closed before the first job ran
            early.cancel()

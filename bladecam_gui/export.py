"""Export of the shown plan to a folder, through core, verified before it replaces anything.

The result written is the one shown, with its axis tables (the workbench plans every job with them,
timed for the machines as ``bladecam plan`` times it): nothing is planned again, so the files hold the
job time, the rows and the machine figures the workbench shows.
The plan is written (core.output.writer.write_result) to a staging folder next to the destination and
checked there by ``core.verify.check.verify`` in a worker thread, given the rows the plan holds (the
tables are not read back). With findings, a dialog lists the first
ones and refuses unless the operator confirms an override; then the files move into the destination
atomically (core.output.files.atomic_folder: an existing plan folder is replaced only once the new one is
complete, a folder that is not a plan folder bladecam wrote is refused: core.output.files.check_destination,
applied before the export starts too). Nothing is ever half-overwritten.
"""

from __future__ import annotations

import itertools
import logging
import os
import shutil
from pathlib import Path

from PySide6.QtCore import QObject, QThread, Signal, Slot
from PySide6.QtWidgets import QMessageBox, QWidget

from core.errors import BladecamError, Cancelled, OutputError
from core.output.files import atomic_folder, check_destination, scratch_stem
from core.output.writer import write_result
from core.util.scratch import scratch_owner
from core.verify.check import verify
from core.verify.report import KINDS as FINDING_KINDS

from .guard import message_for
from .state import WorkbenchState
from .verdict import BLADE, CLAMP, PAIR, Violations, finding_advice, item_text

log = logging.getLogger(__name__)
SHOWN_FINDINGS = 8
_counter = itertools.count(1)


def move_into_place(staging: Path, dest: Path) -> Path:
    """Move a complete staged plan into dest atomically; the staging folder is removed either way."""
    try:
        with atomic_folder(dest) as tmp:
            for f in staging.iterdir():
                os.replace(f, tmp / f.name)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return dest


def refusal_text(report, found: Violations | None) -> str:
    """The question an export with findings asks: verify's findings (the first SHOWN_FINDINGS), what to
    change for their kinds (verdict.finding_advice: a colliding tool is changed by another tool file,
    not by K_max or the feed), what the job would do if written anyway, and whether to write it."""
    shown = "\n".join(f"• {f}" for f in report.findings[:SHOWN_FINDINGS])
    rest = report.total - min(len(report.findings), SHOWN_FINDINGS)
    more = f"\n… and {rest} more" if rest > 0 else ""
    kinds = [k for k in FINDING_KINDS if report.counts.get(k)]
    advice = "\n".join(f"• {a[0].upper()}{a[1:]}." for a in finding_advice(kinds, found))
    hits = [] if found is None else [item_text(k, *found.deepest[k][:2]) for k in (BLADE, CLAMP, PAIR)
                                     if k in found.deepest]
    risk = f"Written anyway, the job runs with the {' and the '.join(hits)}. " if hits else ""
    return (f"bladecam verify found {report.total} problem(s) in this plan, so the export is refused:\n\n"
            f"{shown}{more}\n\nWhat to change:\n{advice}\n\n{risk}Export anyway, overriding the "
            "verification?")


class _ExportRunner(QObject):
    progress = Signal(float, str)
    done = Signal(int, object, object)
    failed = Signal(int, object)

    def __init__(self):
        super().__init__()
        self.cancelled = 0  # jobs up to this one were cancelled (ids only grow): dropped when they return

    @Slot(int, object, object)
    def run(self, job: int, result, staging: Path) -> None:
        reports: list = []

        def check(folder: Path, given: dict) -> None:
            """bladecam verify on the folder written, given the rows the plan holds (as ``bladecam
            plan`` does: the tables are not read back)."""
            if job <= self.cancelled:  # (cancelled while writing: not verified)
                raise Cancelled()
            self.progress.emit(-1.0, "verifying the plan (bladecam verify)")
            reports.append(verify(folder, given=given))

        try:
            self.progress.emit(-1.0, f"writing {staging.name}")  # (no fraction: a busy bar)
            # (force: the verification decides, with the operator)
            write_result(result, staging, force=True, check=check)
            report = reports[0]
            # what write_result refuses without --force (machine strokes, axis speeds) counts too
            kind = {"stroke": "axis range", "speed": "axis speed", "acceleration": "axis acceleration"}
            for f in getattr(result, "blocking_findings", []):
                report.bad(kind.get(f.kind, "axis range"), f"machine limit: {f}")
            if job <= self.cancelled:  # (cancelled meanwhile, or the window closed: nobody takes it)
                raise Cancelled()
        except Exception as exc:  # reported to the GUI thread
            shutil.rmtree(staging, ignore_errors=True)
            if not isinstance(exc, (BladecamError, Cancelled)):
                log.exception("export failed")
            self.failed.emit(job, exc)
        else:
            self.done.emit(job, staging, report)


class ExportController(QObject):
    """exported(Path); failed(str title, str message); busy_changed(bool); progress(float, str);
    status(str): a one-line outcome for the status bar."""

    exported = Signal(object)
    failed = Signal(str, str)
    busy_changed = Signal(bool)
    progress = Signal(float, str)
    status = Signal(str)
    _start = Signal(int, object, object)

    def __init__(self, state: WorkbenchState, parent_widget: QWidget):
        super().__init__(parent_widget)
        self.state = state
        self.parent_widget = parent_widget
        self._thread = QThread(self)
        self._thread.setObjectName("bladecam-export")
        self._runner = _ExportRunner()
        self._runner.moveToThread(self._thread)
        self._start.connect(self._runner.run)
        self._runner.progress.connect(self.progress)
        self._runner.done.connect(self._on_done)
        self._runner.failed.connect(self._on_failed)
        self._thread.start()
        self._job: int | None = None
        self._dest: Path | None = None
        self._found: Violations | None = None  # the exported plan's violations (for the advice)
        self.last_report = None

    @property
    def busy(self) -> bool:
        return self._job is not None

    def export_to(self, dest: str | Path) -> None:
        """Start exporting the shown plan to ``dest`` (BladecamError when it cannot start)."""
        if self.busy:
            raise OutputError("an export is already running; wait for it or cancel it")
        data = self.state.plan
        if data is None or not data.has_schedule:
            raise OutputError("there is no complete plan to export yet; wait for the planning to finish")
        if self.state.busy or self.state.stale:
            raise OutputError("the plan shown is out of date (re-planning after an edit); wait for the new "
                              "plan, or undo the edit, then export")
        dest = check_destination(dest)  # (refuses early what atomic_folder would refuse at the end)
        staging = dest.parent / f".{scratch_stem(dest.name)}.export-{scratch_owner()}-{next(_counter)}"
        self._job, self._dest, self._found = next(_counter), dest, data.violations
        self.busy_changed.emit(True)
        self._start.emit(self._job, data.result, staging)

    def cancel(self) -> None:
        """Forget the running export (it stops after writing or verifying, whichever runs): its staging
        folder is removed when the worker returns."""
        if self._job is not None:
            self._runner.cancelled = self._job
            self._job = None
            self.busy_changed.emit(False)
            self.status.emit("export cancelled")

    @Slot(int, object, object)
    def _on_done(self, job: int, staging: Path, report) -> None:
        try:
            if job != self._job:
                shutil.rmtree(staging, ignore_errors=True)
                return
            self._job = None
            self.busy_changed.emit(False)
            self.last_report = report
            dest = self._dest
            if report.total and not self.confirm_override(refusal_text(report, self._found)):
                shutil.rmtree(staging, ignore_errors=True)
                self.status.emit(f"export refused: the plan fails verification; {dest} unchanged")
                return
            move_into_place(staging, dest)
            verified = f" (override: {report.total} findings)" if report.total else " (verified)"
            self.status.emit(f"exported to {dest}{verified}")
            self.exported.emit(dest)
        except Exception as exc:  # slots never raise
            shutil.rmtree(staging, ignore_errors=True)
            self.failed.emit("Cannot export the plan", message_for(exc))

    def confirm_override(self, text: str) -> bool:
        """Ask the question ``text`` (refusal_text): export despite verify's findings?"""
        answer = QMessageBox.question(self.parent_widget, "The plan fails verification", text,
                                      QMessageBox.StandardButton.Yes | QMessageBox.StandardButton.No,
                                      QMessageBox.StandardButton.No)
        return answer == QMessageBox.StandardButton.Yes

    @Slot(int, object)
    def _on_failed(self, job: int, exc: Exception) -> None:
        if job != self._job:
            return
        self._job = None
        self.busy_changed.emit(False)
        self.failed.emit("Cannot export the plan", message_for(exc))

    def shutdown(self) -> None:
        if self._job is not None:  # the running export stops (and removes its staging folder)
            self._runner.cancelled = self._job
        self._job = None
        self._thread.quit()
        self._thread.wait()

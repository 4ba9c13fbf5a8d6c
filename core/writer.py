"""Writing a plan's folder (``write_result``): the refusals (an unsafe collaborative plan, a machine
limit broken) unless forced, then every table formatted (in forked helpers when there are workers:
``early_helpers``, started by run_plan as soon as the tables exist) and the folder written
atomically (core.csvio.atomic_folder, through core.export.write_plan)."""

from __future__ import annotations

import shutil
import threading
import time
from pathlib import Path

from .csvio import Helper, spool_folder
from .errors import OutputError, PlanningError
from .export import cl_csv_chunks, pairs_csv, write_plan
from .machine import machine_to_toml
from .pipeline import PlanResult
from .postprocess import axes_csv_chunks


def _table_jobs(timeline, tables: dict | None, side: str) -> list:
    """One side's tables to format (CL, and the axis table when there is one), as core.csvio.Helper
    jobs."""
    samples = getattr(timeline, side)
    jobs = [(f"{side}_cl.csv", cl_csv_chunks, (timeline.t, samples))]
    if tables is not None:
        jobs.append((f"{side}_axes.csv", axes_csv_chunks, (tables[side],)))
    return jobs


def _beside(out_dir: str | Path | None) -> Path | None:
    """The folder that holds ``out_dir`` (where files are written ahead of it), None if it is missing."""
    if out_dir is None:
        return None
    parent = Path(out_dir).resolve().parent
    return parent if parent.is_dir() else None


def early_helpers(timeline, tables: dict | None, workers: int, out_dir: str | Path | None) -> tuple:
    """Two Helpers formatting the right and the left tables in forked processes (workers > 1), each
    writing its files beside ``out_dir`` when that folder's parent exists; else ()."""
    if workers <= 1:
        return ()
    spool_in = _beside(out_dir)
    helpers = []
    try:
        for side in ("right", "left"):
            helpers.append(Helper(_table_jobs(timeline, tables, side), workers, spool_in=spool_in))
    except BaseException:
        close_helpers(helpers)
        raise
    return tuple(helpers)


class EarlyPairs:
    """pairs.csv written beside ``out_dir`` in a thread while the schedule is planned (run_plan's
    ``early_tables``: the paths' rows are formatted already, and the write then costs the command
    line no time of its own). A helper like core.csvio.Helper for write_result: ``results()`` gives
    the file's Path, moved into the plan folder; ``close()`` removes what is left. The spool folder
    carries this process (pid@host) so that the next plan into that folder clears it after a kill."""

    def __init__(self, plan, out_dir: str | Path, parent: Path):
        self.out = Path(out_dir)
        self.spool = spool_folder(parent)
        self.path = self.spool / "pairs.csv"
        self.plan = plan
        self.error: BaseException | None = None
        self.seconds = 0.0
        self.thread = threading.Thread(target=self._write, name="bladecam-pairs", daemon=True)
        try:
            self.thread.start()
        except BaseException:
            shutil.rmtree(self.spool, ignore_errors=True)
            raise

    @classmethod
    def start(cls, plan, out_dir: str | Path | None) -> EarlyPairs | None:
        """One writing ``plan``'s pairs.csv beside out_dir, or None (no folder to write beside)."""
        parent = _beside(out_dir)
        if parent is None:
            return None
        try:
            return cls(plan, out_dir, parent)
        except (OSError, RuntimeError):  # (no spool folder or no thread: write_result writes it itself)
            return None

    def _write(self) -> None:
        t0 = time.perf_counter()
        try:
            self.path.write_bytes(pairs_csv(self.plan))
        except BaseException as exc:  # (reported by results())
            self.error = exc
        self.seconds = time.perf_counter() - t0

    def results(self) -> dict[str, Path]:
        self.thread.join()
        if isinstance(self.error, OSError):  # (as core.csvio.atomic_folder reports a failed write)
            reason = self.error.strerror or self.error
            raise OutputError(f"cannot write the plan to {self.out}: {reason}") from None
        if self.error is not None:
            raise self.error
        self.plan.timings["write_pairs_csv_s"] = self.seconds
        return {"pairs.csv": self.path}

    def close(self) -> None:
        self.thread.join()
        shutil.rmtree(self.spool, ignore_errors=True)


def close_helpers(helpers) -> None:
    for h in helpers:
        h.close()


def write_result(result: PlanResult, out_dir: str | Path, force: bool = False, workers: int = 1) -> Path:
    """Write a plan's files into out_dir atomically (all or nothing; an existing folder is replaced
    only once the new one is complete): pairs.csv and plan.json, plus left_cl.csv and right_cl.csv
    when the plan has a schedule. An unsafe collaborative plan is refused unless ``force``.
    workers > 1 formats the right-hand tables in a forked process meanwhile (the CLI's batch mode),
    unless run_plan's helpers are already at both sides' (``early_tables``)."""
    plan, fig = result.plan, result.figures
    helpers = result.helpers
    object.__setattr__(result, "helpers", ())  # taken: write_result closes them whatever happens
    try:
        if result.timeline is None:
            return write_plan(plan, out_dir, result.source, result.axis)
        if plan.params.mode == "collaborative" and not result.safe and not force:
            raise PlanningError(
                f"the collaborative schedule still breaks the safety rule (minimum tip spacing "
                f"{fig['min_tip_spacing_mm']:.4f} mm at t = {fig['min_tip_spacing_time_ms']:.0f} ms, h_safe = "
                f"{plan.params.h_safe} mm; minimum capsule clearance {fig['min_capsule_clearance_mm']:.4f} mm); "
                "nothing was written. Raise k_max or h_safe, or give --force to write it anyway")
        if result.blocking_findings and not force:
            lines = "\n  ".join(str(f) for f in result.blocking_findings[:6])
            more = len(result.blocking_findings) - 6
            raise PlanningError(
                f"the plan breaks the machine's limits (machine.toml), nothing was written:\n  {lines}"
                + (f"\n  ... and {more} more" if more > 0 else "")
                + "\nLower the feed or a_max, use a machine file with larger limits (--machine), or give --force")
        t0 = time.perf_counter()
        tl = result.timeline
        files = {}
        if not any(isinstance(h, Helper) for h in helpers):  # the right-hand tables in a forked helper
            helpers = (*helpers, Helper(_table_jobs(tl, result.axes, "right"), workers))  # (workers > 1)
            files.update(Helper(_table_jobs(tl, result.axes, "left"), 1).results())
        if result.axes is not None:
            files["machine.toml"] = machine_to_toml(result.machine).encode()
        for h in helpers:
            files.update(h.results())
        plan.timings["write_tables_s"] = time.perf_counter() - t0
        summary = {"schedule": fig, "period_ms": result.period, "profile": result.profile}
        return write_plan(plan, out_dir, result.source, result.axis, extra_files=files, summary_extra=summary)
    finally:
        close_helpers(helpers)

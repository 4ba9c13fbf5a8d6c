"""Writing a plan's folder: ``PlanWriter`` hooks onto the planner (a core.result.PlanListener) so
that pairs.csv is written beside the output folder while the schedule is planned and the tables are
formatted in forked helpers as soon as they exist (with workers), then ``write`` refuses what must not
be written (an unsafe plan in any mode, a machine limit broken) unless forced, and writes the folder
atomically (core.output.files.atomic_folder, through core.output.files.write_plan). ``write_result``
writes a finished plan with no early files."""

from __future__ import annotations

import shutil
import threading
import time
from pathlib import Path

from core.errors import OutputError, PlanningError
from core.machine.collisions import refusal
from core.machine.model import machine_to_toml
from core.machine.tool import tool_to_toml
from core.output.csvio import Helper, spool_folder
from core.output.files import axes_csv_chunks, cl_csv_chunks, pairs_csv, pairs_rows, write_plan
from core.output.stl import stl_bytes
from core.paths.plan import PathPlan
from core.result import PlanListener, PlanResult


def _table_jobs(timeline, tables: dict | None, side: str) -> list:
    """One side's tables to format (CL, and the axis table when there is one), as core.output.csvio.Helper
    jobs."""
    samples = getattr(timeline, side)
    jobs: list[tuple] = [(f"{side}_cl.csv", cl_csv_chunks, (timeline.t, samples))]
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
    """pairs.csv written beside ``out_dir`` in a thread while the schedule is planned (PlanWriter: the
    paths' rows are formatted already, and the write then costs the command line no time of its
    own). A helper like core.output.csvio.Helper for PlanWriter.write: ``results()`` gives
    the file's Path, moved into the plan folder (``seconds``: the time the write took); ``close()``
    removes what is left. The spool folder
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
    def start(cls, plan: PathPlan, out_dir: str | Path | None) -> EarlyPairs | None:
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
        if isinstance(self.error, OSError):  # (as core.output.files.atomic_folder reports a failed write)
            reason = self.error.strerror or self.error
            raise OutputError(f"cannot write the plan to {self.out}: {reason}") from None
        if self.error is not None:
            raise self.error
        return {"pairs.csv": self.path}

    def close(self) -> None:
        self.thread.join()
        shutil.rmtree(self.spool, ignore_errors=True)


def close_helpers(helpers) -> None:
    for h in helpers:
        h.close()


def unsafe_reason(result: PlanResult) -> str | None:
    """What is unsafe about ``result``'s schedule (any mode), one line; None when it keeps the safety
    rule (tip spacing >= h_safe and the tools never touch, at every sample)."""
    if result.safe:
        return None
    plan, fig = result.plan, result.figures or {}
    parts = []
    if fig.get("spacing_violations"):
        parts.append(f"the tips come to {fig['min_tip_spacing_mm']:.4f} mm at "
                     f"t = {fig['min_tip_spacing_time_ms']:.0f} ms, "
                     f"below h_safe = {plan.params.h_safe:g} mm ({fig['spacing_violations']} samples)")
    if fig.get("capsule_violations"):
        parts.append(f"the two tools collide (minimum clearance {fig['min_capsule_clearance_mm']:.4f} mm at t = "
                     f"{fig.get('min_capsule_clearance_time_ms', 0.0):.0f} ms, {fig['capsule_violations']} samples)")
    return f"the {plan.params.mode} schedule is unsafe: " + "; ".join(parts)


#: what to do about an unsafe plan, by mode
_UNSAFE_ADVICE = {
    "collaborative": "Raise k_max or h_safe",
    "symmetric": "The symmetric mode is an unsafe preview (the paper's Fig. 13): plan in the collaborative "
                 "(default) or single mode",
    "single": "Raise h_safe",
}


def _refusal(result: PlanResult) -> str | None:
    """Why ``result`` must not be written without --force (None: it may be)."""
    unsafe = unsafe_reason(result)
    if unsafe is not None:
        advice = _UNSAFE_ADVICE.get(result.plan.params.mode, "Change the parameters")
        return f"{unsafe}; nothing was written. {advice}, or give --force to write it anyway"
    if result.blocking_findings:
        lines = "\n  ".join(str(f) for f in result.blocking_findings[:6])
        more = len(result.blocking_findings) - 6
        if all(f.kind == "stroke" for f in result.blocking_findings):
            advice = ("The blade does not fit the machines' strokes: use a machine file with longer strokes "
                      "(--machine), or give --force")
        else:
            advice = ("Lower the feed or a_max, use a machine file with larger limits (--machine), or give "
                      "--force")
        return (f"the plan breaks the machine's limits (machine.toml), nothing was written:\n  {lines}"
                + (f"\n  ... and {more} more" if more > 0 else "") + "\n" + advice)
    if result.collisions and result.timeline is not None:
        tl = result.timeline
        return refusal(result.clearance, tl.t, tl.left.path, tl.right.path)
    return None


class PlanWriter(PlanListener):
    """Writes a plan into ``out_dir``. Given to core.planner.Planner.plan as its listener (with
    workers > 1), it starts the files early: pairs.csv's rows are formatted in the path workers and
    the file is written beside out_dir while the schedule is planned, and both sides' tables are
    formatted in two forked helpers as soon as the time column exists. ``write(result)`` then
    writes the folder; ``close()`` (also at the end of ``write``) ends the helpers and removes what
    they left. Used as a context manager, it closes on leaving."""

    def __init__(self, out_dir: str | Path, workers: int = 1):
        self.out_dir, self.workers = Path(out_dir), workers
        self.row_formatter = pairs_rows if workers > 1 else None
        self._pairs: EarlyPairs | None = None
        self._helpers: tuple = ()

    def __enter__(self) -> PlanWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def paths_ready(self, plan: PathPlan, reused: str) -> None:
        if self.workers > 1 and self._pairs is None:
            self._pairs = EarlyPairs.start(plan, self.out_dir)

    def timeline_ready(self, timeline, schedule, warp, tables) -> None:
        close_helpers(self._helpers)
        self._helpers = early_helpers(timeline, tables, self.workers, self.out_dir)

    def close(self) -> None:
        helpers = (*self._helpers, *((self._pairs,) if self._pairs is not None else ()))
        self._helpers, self._pairs = (), None
        close_helpers(helpers)

    def write(self, result: PlanResult, force: bool = False) -> Path:
        """Write a plan's files into out_dir atomically (all or nothing; an existing folder is replaced
        only once the new one is complete): pairs.csv and plan.json, plus left_cl.csv and
        right_cl.csv when the plan has a schedule, and with the machines their axis tables and
        machine.toml. A plan that must not be written (an unsafe one, in any mode; a machine limit
        broken) is refused unless ``force`` (PlanningError)."""
        try:
            return self._write(result, force)
        finally:
            self.close()

    def _write(self, result: PlanResult, force: bool) -> Path:
        plan = result.plan
        files: dict = {}
        written: dict[str, float] = {}
        if self._pairs is not None and self._pairs.plan.pairs is plan.pairs:
            files.update(self._pairs.results())
            written["write_pairs_csv_s"] = self._pairs.seconds
        if result.timeline is None:
            return write_plan(plan, self.out_dir, result.source, result.axis, result.timings.plus(**written),
                              extra_files=files)
        reason = _refusal(result)
        if reason is not None and not force:
            raise PlanningError(reason)
        t0 = time.perf_counter()
        tl = result.timeline
        helpers = self._helpers
        if not helpers:  # the right-hand tables in a forked helper (workers > 1), the left ones here
            helpers = self._helpers = (Helper(_table_jobs(tl, result.axes, "right"), self.workers),)
            files.update(Helper(_table_jobs(tl, result.axes, "left"), 1).results())
        if result.axes is not None:
            files["machine.toml"] = machine_to_toml(result.machine).encode()
        if result.clearance is not None and result.tool is not None:  # (what verify checks the tool against)
            files["tool.toml"] = tool_to_toml(result.tool).encode()
            files["blade.stl"] = stl_bytes(result.clearance.index)
        for h in helpers:
            files.update(h.results())
        written["write_tables_s"] = time.perf_counter() - t0
        summary = {"schedule": result.figures, "period_ms": result.period, "profile": result.profile}
        return write_plan(plan, self.out_dir, result.source, result.axis, result.timings.plus(**written),
                          extra_files=files, summary_extra=summary)


def write_result(result: PlanResult, out_dir: str | Path, force: bool = False, workers: int = 1) -> Path:
    """Write a finished plan into out_dir (PlanWriter.write, no early files); workers > 1 formats the
    right-hand tables in a forked process meanwhile."""
    return PlanWriter(out_dir, workers).write(result, force)

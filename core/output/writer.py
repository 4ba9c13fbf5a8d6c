"""Writing a plan's folder: ``PlanWriter`` hooks onto the planner (a core.result.PlanListener) so
that pairs.csv is written beside the output folder while the schedule is planned and the tables are
written beside it, one thread per side, block by block, as soon as they exist; then ``write`` refuses
what must not be written (an unsafe plan in any mode, a machine limit broken) unless forced, and
writes the folder atomically (core.output.files.atomic_folder, through core.output.files.write_plan):
the files written beside are moved in. ``write_result`` writes a finished plan with no early files."""

from __future__ import annotations

import shutil
import threading
import time
from functools import partial
from pathlib import Path

from core.errors import OutputError, PlanningError
from core.machine.collisions import refusal
from core.machine.model import machine_to_toml
from core.machine.tool import tool_to_toml
from core.output.csvio import spool_folder
from core.output.files import axes_csv_chunks, cl_csv_chunks, pairs_chunks, pairs_csv, pairs_rows, write_plan
from core.output.stl import stl_bytes
from core.paths.plan import PathPlan
from core.paths.regions import REGION_CODE
from core.paths.tessellation import export_mesh
from core.result import PlanListener, PlanResult

#: the region names as the tables write them -> their codes (what a reader of the tables makes of them)
REGION_WORDS = {name.encode(): code for name, code in REGION_CODE.items()}


def table_files(timeline, tables: dict | None) -> list:
    """The tables to write, as (file name, core.output.csvio.CsvChunks): each side's CL table, and its
    axis table when there are ``tables``."""
    files = []
    for side in ("left", "right"):
        files.append((f"{side}_cl.csv", cl_csv_chunks(timeline.t, getattr(timeline, side))))
        if tables is not None:
            files.append((f"{side}_axes.csv", axes_csv_chunks(tables[side])))
    return files


def written_rows(plan: PathPlan, files: list) -> dict:
    """File name -> a function giving the table's rows (n, ncols) exactly as a reader of the file gets
    them (core.output.csvio.CsvChunks.as_written), for the check of a plan before it is written
    (``PlanWriter``'s ``check(folder, given)``): each side's tables (``table_files``) and pairs.csv."""
    given: dict = {name: partial(chunks.as_written, REGION_WORDS) for name, chunks in files}
    if plan.pairs:
        given["pairs.csv"] = lambda: pairs_chunks(plan).as_written(REGION_WORDS)
    return given


def _beside(out_dir: str | Path | None) -> Path | None:
    """The folder that holds ``out_dir`` (where files are written ahead of it), None if it is missing."""
    if out_dir is None:
        return None
    parent = Path(out_dir).resolve().parent
    return parent if parent.is_dir() else None


class Spooled:
    """Files of a plan folder written beside it ahead of the folder, in threads: ``jobs`` is a list
    of thread jobs, each a list of (file name, content) written one after the other, the content bytes,
    a CsvChunks (written block by block: the compiled formatter releases the GIL, so two threads use
    two cores) or a function giving either. They go into a scratch folder (core.output.csvio.
    spool_folder, named with this process: the next plan into that folder clears it after a kill).
    ``results()`` waits and gives {name: Path}, moved into the plan folder by core.output.files.
    write_plan (``seconds``: the longest job's time); ``close()`` stops the jobs at their next block and
    removes what is left. OSError when the scratch folder or a thread cannot be made (nothing left)."""

    def __init__(self, jobs: list, out_dir: str | Path, parent: Path):
        self.out = Path(out_dir)
        self.spool = spool_folder(parent)
        self.stopped = threading.Event()
        self.errors: list[BaseException] = []
        self.seconds = 0.0
        self.names = [name for job in jobs for name, _ in job]
        self.threads = [threading.Thread(target=self._run, args=(job,), name="bladecam-write", daemon=True)
                        for job in jobs]
        try:
            for thread in self.threads:
                thread.start()
        except BaseException:
            self.close()
            raise

    def _run(self, job: list) -> None:
        t0 = time.perf_counter()
        try:
            for name, content in job:
                content = content() if callable(content) else content
                with open(self.spool / name, "wb") as f:
                    for part in [content] if isinstance(content, bytes) else content:
                        if self.stopped.is_set():
                            return
                        f.write(part)
        except BaseException as exc:  # (reported by results())
            self.errors.append(exc)
        self.seconds = max(self.seconds, time.perf_counter() - t0)

    def results(self) -> dict[str, Path]:
        for thread in self.threads:
            if thread.ident is not None:
                thread.join()
        for error in self.errors:
            if isinstance(error, OSError):  # (as core.output.files.atomic_folder reports a failed write)
                raise OutputError(f"cannot write the plan to {self.out}: {error.strerror or error}") from None
            raise error
        return {name: self.spool / name for name in self.names}

    def close(self) -> None:
        self.stopped.set()
        for thread in self.threads:
            if thread.ident is not None:
                thread.join()
        shutil.rmtree(self.spool, ignore_errors=True)


class EarlyPairs(Spooled):
    """pairs.csv written beside ``out_dir`` in a thread while the schedule is planned (PlanWriter: the
    paths' rows are formatted already, and the write then costs the command line no time of its own)."""

    def __init__(self, plan: PathPlan, out_dir: str | Path, parent: Path):
        self.plan = plan
        super().__init__([[("pairs.csv", lambda: pairs_csv(plan))]], out_dir, parent)

    @classmethod
    def start(cls, plan: PathPlan, out_dir: str | Path | None) -> EarlyPairs | None:
        """One writing ``plan``'s pairs.csv beside out_dir, or None (no folder to write beside)."""
        parent = _beside(out_dir)
        if parent is None:
            return None
        try:
            return cls(plan, out_dir, parent)
        except (OSError, RuntimeError):  # (no spool folder or no thread: write_plan writes it itself)
            return None


class EarlyTables(Spooled):
    """Both sides' tables (``table_files``) written beside ``out_dir``, one thread per side, while the
    planner computes the figures (PlanWriter), or at once when a plan is written."""

    def __init__(self, timeline, tables: dict | None, out_dir: str | Path, parent: Path):
        self.timeline = timeline
        #: the tables being written (``table_files``), whose rows as written the plan's check is given
        self.files = files = table_files(timeline, tables)
        super().__init__([[f for f in files if f[0].startswith(side)] for side in ("left", "right")],
                         out_dir, parent)

    @classmethod
    def start(cls, timeline, tables: dict | None, out_dir: str | Path | None) -> EarlyTables | None:
        """One writing the tables beside out_dir, or None (no folder to write beside: write_plan
        formats them into the plan folder itself)."""
        parent = _beside(out_dir)
        if parent is None:
            return None
        try:
            return cls(timeline, tables, out_dir, parent)
        except (OSError, RuntimeError):
            return None


def close_all(writers) -> None:
    for w in writers:
        if w is not None:
            w.close()


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


#: a plan whose rows stray from the planned path beyond the chord tolerance by more than this factor
#: (the rows' own rounding to 1e-6 mm) is refused unless forced
CHORD_SLACK = 1.0 + 1e-3


def _refusal(result: PlanResult) -> str | None:
    """Why ``result`` must not be written without --force (None: it may be)."""
    unsafe = unsafe_reason(result)
    if unsafe is not None:
        advice = _UNSAFE_ADVICE.get(result.plan.params.mode, "Change the parameters")
        return f"{unsafe}; nothing was written. {advice}, or give --force to write it anyway"
    chord = ((result.figures or {}).get("machine") or {}).get("chord") or {}
    if chord.get("largest_deviation_mm", 0.0) > chord.get("tolerance_mm", float("inf")) * CHORD_SLACK:
        return (f"a straight line between two rows strays {chord['largest_deviation_mm']:.4g} mm from the "
                f"planned path at t = {chord.get('largest_deviation_at_ms', 0.0):.0f} ms, beyond the chord "
                f"tolerance {chord['tolerance_mm']:g} mm; nothing was written. Lower the period "
                "(--period-ms) or raise --chord-tol, or give --force to write it anyway")
    if result.blocking_findings:
        lines = "\n  ".join(str(f) for f in result.blocking_findings[:6])
        more = len(result.blocking_findings) - 6
        if all(f.kind == "stroke" for f in result.blocking_findings):
            advice = _off_centre(result) or ("The blade does not fit the machines' strokes: use a machine "
                                             "file with longer strokes (--machine), or give --force")
        else:
            advice = ("Lower the feed or a_max, use a machine file with larger limits (--machine), or give "
                      "--force")
        return (f"the plan breaks the machine's limits (machine.toml), nothing was written:\n  {lines}"
                + (f"\n  ... and {more} more" if more > 0 else "") + "\n" + advice)
    if result.collisions and result.timeline is not None:
        tl = result.timeline
        return refusal(result.clearance, tl.t, tl.left.path, tl.right.path)
    return None


def _off_centre(result: PlanResult) -> str | None:
    """The advice for a plan whose strokes are broken although every axis's travel fits its stroke: the
    blade and the machines are not centred on each other (None: some axis needs more travel than its
    stroke has)."""
    used = ((result.figures or {}).get("machine") or {}).get("axes") or {}
    shifts = []
    for f in {(f.side, f.axis) for f in result.blocking_findings}:
        got, lim = used.get(f[0], {}).get(f[1]), result.machine.limits.axis(f[1])
        if got is None or got["max_mm"] - got["min_mm"] > lim.max_mm - lim.min_mm:
            return None
        shifts.append((f"{f[0]} {f[1]}", got["min_mm"], got["max_mm"], lim,
                       0.5 * (lim.min_mm + lim.max_mm - got["min_mm"] - got["max_mm"])))
    if not shifts:
        return None
    name, lo, hi, lim, shift = max(shifts, key=lambda x: abs(x[4]))
    return (f"The blade and the machines are not centred on each other: the {name} axis travels "
            f"{hi - lo:.1f} mm, within its {lim.max_mm - lim.min_mm:g} mm stroke, but from {lo:.1f} to "
            f"{hi:.1f} mm, {abs(shift):.1f} mm off the stroke's middle ({lim.min_mm:g} to {lim.max_mm:g}). "
            "Move the blade (its file's coordinates: a blade is placed with its hub's centre at the origin) "
            "or the machines (origin_mm in the machine file, --machine), or give --force")


class PlanWriter(PlanListener):
    """Writes a plan into ``out_dir``. Given to core.planner.Planner.plan as its listener, it starts the
    files early: with workers > 1 pairs.csv's rows are formatted in the path workers and the file is
    written beside out_dir while the schedule is planned, and both sides' tables are written beside
    it, one thread per side, as soon as the time column exists (EarlyTables). ``write(result)`` then
    writes the folder; ``close()`` (also at the end of ``write``) stops the threads and removes what
    they left. Used as a context manager, it closes on leaving. ``check(folder, given)``, when given,
    runs on the complete folder before it is made visible (the command line's own verify), ``given``
    holding the tables' rows as written (``written_rows``), so that it need not read them again."""

    def __init__(self, out_dir: str | Path, workers: int = 1, check=None):
        self.out_dir, self.workers, self.check = Path(out_dir), workers, check
        self.row_formatter = pairs_rows if workers > 1 else None
        self._pairs: EarlyPairs | None = None
        self._tables: EarlyTables | None = None

    def __enter__(self) -> PlanWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def paths_ready(self, plan: PathPlan, reused: str) -> None:
        if self.workers > 1 and self._pairs is None:
            self._pairs = EarlyPairs.start(plan, self.out_dir)

    def timeline_ready(self, timeline, schedule, warp, tables) -> None:
        close_all([self._tables])
        self._tables = EarlyTables.start(timeline, tables, self.out_dir)

    def close(self) -> None:
        writers, self._tables, self._pairs = (self._tables, self._pairs), None, None
        close_all(writers)

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
                              extra_files=files, check=self._check(plan, []))
        reason = _refusal(result)
        if reason is not None and not force:
            raise PlanningError(reason)
        t0 = time.perf_counter()
        tl = result.timeline
        if self._tables is None or self._tables.timeline is not tl:  # (not started early: now)
            close_all([self._tables])
            self._tables = EarlyTables.start(tl, result.axes, self.out_dir)
        tables = self._tables.files if self._tables is not None else table_files(tl, result.axes)
        if self._tables is not None:
            files.update(self._tables.results())
        else:  # (no folder to write beside: formatted into the plan folder by write_plan)
            files.update(tables)
        if result.axes is not None:
            files["machine.toml"] = machine_to_toml(result.machine).encode()
        if result.clearance is not None and result.tool is not None:  # (what verify checks the tool against)
            files["tool.toml"] = tool_to_toml(result.tool).encode()
            files["blade.stl"] = stl_bytes(export_mesh(plan.blade, plan.frame))
        written["write_tables_s"] = time.perf_counter() - t0
        summary = {"schedule": result.figures, "period_ms": result.period, "profile": result.profile}
        return write_plan(plan, self.out_dir, result.source, result.axis, result.timings.plus(**written),
                          extra_files=files, summary_extra=summary, check=self._check(plan, tables))

    def _check(self, plan: PathPlan, tables: list):
        """The check of the complete folder (``self.check``) with the tables' rows as written."""
        if self.check is None:
            return None
        given = written_rows(plan, tables)
        return lambda folder: self.check(folder, given)


def write_result(result: PlanResult, out_dir: str | Path, force: bool = False, workers: int = 1,
                 check=None) -> Path:
    """Write a finished plan into out_dir (PlanWriter.write, no early files: the tables are written
    one thread per side); ``check(folder, given)`` as PlanWriter's, on the complete folder before it
    is made visible."""
    return PlanWriter(out_dir, workers, check=check).write(result, force)

"""The planning pipeline: blade -> contour paths -> aligned pairs -> regions (-> schedule, axes).

``PlanParameters`` carries every planning input with the project's names and units (mm, mm/min,
mm/s^2 at this boundary); ``plan_paths`` chains the steps of paper sections 2-4 and reports the time
each step took. A Python loop over paths is used; every step inside is vectorised over points.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import pickle
import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from .alignment import AlignedPair, align_single, align_symmetric, sides
from .blade import Blade
from .contour_paths import ContourPath, contour_path, path_radii, side_assignment
from .errors import BladeInputError, Cancelled, PlanningError  # noqa: F401 (Cancelled: public here)
from .frames import WorkpieceFrame, workpiece_frame
from .gouge import facet_guard, push_pair_out
from .regions import Regions, check_region_parameters, divide

Progress = Callable[[float, str], None]

#: machine limits that refuse an export without --force: strokes, and the axis speeds and
#: accelerations that the feed override (core.override) keeps
ENFORCED_LIMITS = ("stroke", "speed", "acceleration")


@dataclass(frozen=True)
class PlanParameters:
    """Planning inputs. None means the default derived from the tool radius.

    tool_radius : mm (ball radius; the paper's 3 mm ball nose mill has 1.5); dr : mm (default r/4);
    dd : mm, interpolation step; h_safe : mm (default 1.25 r); k_max : staggered-ratio limit;
    tool_length : mm, d_T of Eq. 1-2 (tip to tail point, the tool's stick-out);
    feed : mm/min; a_max : mm/s^2; mode : 'collaborative' | 'symmetric' | 'single'
    """

    tool_radius: float = 1.5
    dr: float | None = None
    dd: float = 0.2
    h_safe: float | None = None
    k_max: float = 0.15
    tool_length: float = 40.0
    feed: float = 1000.0
    a_max: float = 500.0
    mode: str = "collaborative"

    def resolved(self) -> PlanParameters:
        """The same parameters with the defaults filled in, validated (PlanningError)."""
        r = self.tool_radius
        if not isinstance(r, (int, float)) or not math.isfinite(r) or r <= 0:
            raise PlanningError(f"tool radius must be a positive number of mm, got {r}")
        p = replace(self, dr=r / 4 if self.dr is None else self.dr,
                    h_safe=1.25 * r if self.h_safe is None else self.h_safe)
        labels = {"dr": "dR (mm)", "dd": "dd (mm)", "tool_length": "tool length (mm)",
                  "feed": "feed (mm/min)", "a_max": "a_max (mm/s^2)"}
        for name, label in labels.items():
            v = getattr(p, name)
            if not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise PlanningError(f"{label} must be a positive number, got {v}")
        check_region_parameters(p.h_safe, p.k_max, r)
        if p.dd > 5 * r:
            raise PlanningError(f"dd = {p.dd} mm is more than 5 tool radii: the path would be too coarse")
        if p.mode not in ("collaborative", "symmetric", "single"):
            raise PlanningError(f"mode must be collaborative, symmetric or single, got {p.mode!r}")
        return p

    def warnings(self) -> list[str]:
        out = []
        if self.dr is not None and self.dr > self.tool_radius / 4 + 1e-12:
            out.append(f"dR = {self.dr} mm is above tool_radius/4 = {self.tool_radius / 4:g} mm "
                       "(paper section 2): expect larger scallops")
        if self.h_safe is not None and not (1.0 - 1e-9 <= self.h_safe / self.tool_radius <= 1.5 + 1e-9):
            out.append(f"h_safe = {self.h_safe} mm is outside the paper's 1-1.5 tool radii")
        if not 0.1 - 1e-12 <= self.k_max <= 0.2 + 1e-12:
            out.append(f"k_max = {self.k_max} is outside the paper's 0.1-0.2")
        return out

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class PathPlan:
    """The geometric plan: aligned pairs with their regions, tip path first, in machining order."""

    blade: Blade
    frame: WorkpieceFrame
    params: PlanParameters
    paths: list[ContourPath]
    pairs: list[AlignedPair]
    regions: list[Regions]
    warnings: list[str] = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    #: pairs.csv rows per path, when plan_paths was asked to format them (in its workers)
    pairs_rows: list[bytes] | None = None
    #: per pair (contour path, fitted sides, symmetric pair, tip pair or None), kept when planned in
    #: this process, so that replan_regions can change h_safe / k_max without redoing the paths
    reuse: list[tuple] | None = field(default=None, repr=False, compare=False)

    def region_counts(self) -> dict:
        """Number of paths in the tip region and number of pair points per region."""
        points = {k: 0 for k in ("tip", "edge", "variable", "internal")}
        for reg in self.regions:
            names, counts = np.unique(reg.labels, return_counts=True)
            for n, c in zip(names, counts, strict=True):
                points[str(n)] += int(c)
        n_tip = sum(r.is_tip for r in self.regions)
        return {"paths": len(self.pairs), "tip_paths": n_tip, "collaborative_paths": len(self.pairs) - n_tip,
                "points": points}

    def fallback_paths(self) -> list[int]:
        """Indices of paths whose template side could not use the paper's y-parametrisation."""
        return [p.index for p in self.pairs if p.mode != "y"]


def check_blade_fits_tool(blade: Blade, params: PlanParameters) -> None:
    span = blade.tip_radius - blade.hub_radius
    if span < 4 * params.tool_radius:
        raise PlanningError(f"blade {blade.name!r} spans only {span:.3f} mm: too small for a tool of radius "
                            f"{params.tool_radius} mm")
    info = blade.info()
    chords = [c for c in info["chord_mm"].values() if c]
    if not chords or max(chords) < 4 * params.tool_radius:
        raise PlanningError(f"blade {blade.name!r} is too small for a tool of radius {params.tool_radius} mm "
                            f"(largest chord {max(chords, default=0):.3f} mm)")


def _plan_one(blade: Blade, frame: WorkpieceFrame, p: PlanParameters, r: float, index: int,
              left_is_back: bool, clock: dict):
    """Contour path, alignment and regions of one radius; None (and a warning) without a section."""
    t0 = time.perf_counter()
    try:
        path = contour_path(blade, frame, r, index, left_is_back)
    except BladeInputError as exc:
        return None, f"no path at r = {r:.3f} mm (path {index}): {exc}"
    t1 = time.perf_counter()
    fitted = sides(path)
    guard = facet_guard(blade, frame)
    pair = push_pair_out(align_symmetric(path, p.dd, p.tool_radius, fitted), guard, p.tool_radius)
    t2 = time.perf_counter()
    tmpl = pair.left_tip if pair.template == "left" else pair.right_tip
    reg = divide(pair.spacing, tmpl, p.h_safe, p.k_max)
    t3 = time.perf_counter()
    sym, tip_pair = pair, None
    if reg.is_tip:
        pair = tip_pair = push_pair_out(align_single(path, p.dd, p.tool_radius, p.tool_length, fitted, symmetric=pair),
                                   guard, p.tool_radius)
        reg = replace(reg, labels=np.full(len(pair.u), "tip"))
    t4 = time.perf_counter()
    clock["contour_paths_s"] += t1 - t0
    clock["interpolation_alignment_s"] += (t2 - t1) + (t4 - t3)
    clock["regions_s"] += t3 - t2
    return (path, pair, reg, (path, fitted, sym, tip_pair)), None


_JOB: tuple | None = None  # the job of a forked worker (set in the worker by _set_job)


def _set_job(job: tuple) -> None:
    """Worker initializer: the job arrives through fork (never pickled)."""
    global _JOB
    _JOB = job


def _plan_chunk_to_file(args: tuple[list[int], str]) -> str:
    """Worker: plan a chunk and pickle the result to a file (pipes are slow for tens of MB here)."""
    chunk, filename = args
    with open(filename, "wb") as fh:
        pickle.dump(_plan_chunk(chunk), fh, protocol=pickle.HIGHEST_PROTOCOL)
    return filename


def _scratch_dir() -> str | None:
    """A RAM-backed folder for worker results when there is one (Linux /dev/shm)."""
    shm = "/dev/shm"
    return shm if os.path.isdir(shm) and os.access(shm, os.W_OK) else None


def _plan_chunk(chunk: list[int]):
    blade, frame, p, radii, left_is_back, formatter, reusable = _JOB
    clock = dict.fromkeys(("contour_paths_s", "interpolation_alignment_s", "regions_s"), 0.0)
    out = []
    for i in chunk:
        res, warn = _plan_one(blade, frame, p, float(radii[i]), i, left_is_back, clock)
        keep = None if res is None else res if reusable else res[:3]  # the fitted curves only if asked
        out.append((i, keep, warn))
    rows = None
    if formatter is not None:
        t0 = time.perf_counter()
        done = [res for _, res, _ in out if res is not None]
        rows = formatter([r[1] for r in done], [r[2] for r in done])
        clock["format_rows_s"] = time.perf_counter() - t0
    return out, clock, rows


def plan_paths(blade: Blade, params: PlanParameters, progress: Progress | None = None,
               workers: int = 1, row_formatter: Callable | None = None, reusable: bool = False) -> PathPlan:
    """Contour paths, double-curve interpolation, alignment and region division of a blade.

    workers > 1 splits the paths over that many forked processes (when the platform forks and there
    are enough paths); ``progress`` is called with a fraction and a message (per path in one process,
    per finished chunk of paths with workers), and returning False cancels.
    Timings are CPU seconds per step, summed over workers, plus the wall time of the whole step.
    row_formatter(pairs, regions) -> list of bytes per path: output rows formatted inside the workers
    (core.export.pairs_rows), kept in ``PathPlan.pairs_rows``. reusable: bring each path's fitted curves
    back from the workers too, so that ``replan_regions`` can reuse the plan (one process keeps them
    anyway). Same as ``PathsJob(...).result(progress)``.
    """
    return PathsJob(blade, params, workers, row_formatter, reusable).result(progress)


class PathsJob:
    """``plan_paths`` in two halves, for a caller that has other work meanwhile: the constructor
    validates the inputs (PlanningError), builds what every path needs and, with workers > 1, forks
    the worker processes, which start planning at once; ``result(progress)`` (once) waits for them and
    returns the PathPlan plan_paths would; ``cancel()`` stops them. The workbench starts the sample
    blade's paths this way at launch, before its GUI libraries load (forking before Qt starts), and
    collects them in its planning thread. Arguments as plan_paths."""

    def __init__(self, blade: Blade, params: PlanParameters, workers: int = 1,
                 row_formatter: Callable | None = None, reusable: bool = False):
        p = params.resolved()
        self._t_start = time.perf_counter()
        check_blade_fits_tool(blade, p)
        frame = workpiece_frame(blade)
        facet_guard(blade, frame)  # built once here, inherited by forked workers
        self.blade, self.params, self.frame, self.workers = blade, p, frame, workers
        self.radii = path_radii(blade, p.dr)
        self.left_is_back = side_assignment(blade, frame)
        self.row_formatter, self.reusable = row_formatter, reusable
        self._pool = self._chunks = self._scratch = None
        n = len(self.radii)
        if workers > 1 and n >= 4 * workers and "fork" in mp.get_all_start_methods():
            job = (blade, frame, p, self.radii, self.left_is_back, row_formatter, reusable)
            self._scratch = tempfile.mkdtemp(prefix="bladecam-", dir=_scratch_dir())
            k = 4 * workers  # interleaved chunks: balanced, and progress as each one finishes
            jobs = [(list(range(j, n, k)), os.path.join(self._scratch, f"chunk{j}.pkl")) for j in range(k)]
            try:
                self._pool = mp.get_context("fork").Pool(workers, initializer=_set_job, initargs=(job,))
                self._chunks = self._pool.imap_unordered(_plan_chunk_to_file, jobs)
            except BaseException:
                self.cancel()
                raise

    def cancel(self) -> None:
        """Stop the worker processes (if any are still running) and remove their files."""
        pool, self._pool = self._pool, None
        if pool is not None:
            pool.terminate()
        if self._scratch is not None:
            shutil.rmtree(self._scratch, ignore_errors=True)
            self._scratch = None

    def _collect(self, progress: Progress | None, clock: dict, results: dict, rows_by_index: dict) -> None:
        """Wait for the workers' chunks (progress per chunk; False cancels)."""
        k = 4 * self.workers
        chunks = []
        for done, fn in enumerate(self._chunks, start=1):
            with open(fn, "rb") as fh:
                chunks.append(pickle.load(fh))
            if progress is not None and progress(done / k, f"{done} of {k} path chunks") is False:
                raise Cancelled()
        for out, c, rows in chunks:
            done = [i for i, res, _ in out if res is not None]
            for i, res, warn in out:
                results[i] = (res, warn)
            if rows is not None:
                rows_by_index.update(zip(done, rows, strict=True))
            for key, v in c.items():
                clock[key] = clock.get(key, 0.0) + v

    def result(self, progress: Progress | None = None) -> PathPlan:
        """The PathPlan (see plan_paths); raises Cancelled when ``progress`` returns False."""
        p, blade, frame, radii = self.params, self.blade, self.frame, self.radii
        clock = dict.fromkeys(("contour_paths_s", "interpolation_alignment_s", "regions_s"), 0.0)
        results: dict[int, tuple] = {}
        rows_by_index: dict[int, bytes] = {}
        warnings = p.warnings()
        n = len(radii)
        try:
            if self._pool is not None:
                self._collect(progress, clock, results, rows_by_index)
            else:
                for i, r in enumerate(radii):
                    if progress is not None and progress(i / n, f"path {i + 1} of {n}") is False:
                        raise Cancelled()
                    results[i] = _plan_one(blade, frame, p, float(r), i, self.left_is_back, clock)
        finally:
            self.cancel()
        paths, pairs, regions, reuse = [], [], [], []
        for i in range(n):
            res, warn = results[i]
            if warn:
                warnings.append(warn)
                continue
            paths.append(res[0])
            pairs.append(res[1])
            regions.append(res[2])
            reuse.append(res[3] if len(res) > 3 else None)
        if not paths:
            raise PlanningError(f"no contour path could be made on blade {blade.name!r} with dR = {p.dr} mm")
        pairs_rows = None
        if self.row_formatter is not None:
            if rows_by_index:
                pairs_rows = [rows_by_index[pair.index] for pair in pairs]
            else:
                t0 = time.perf_counter()
                pairs_rows = self.row_formatter(pairs, regions)
                clock["format_rows_s"] = time.perf_counter() - t0
        timings = dict(clock)
        timings["paths_wall_s"] = time.perf_counter() - self._t_start
        timings["workers"] = self.workers
        if progress is not None:
            progress(1.0, "paths done")
        return PathPlan(blade=blade, frame=frame, params=p, paths=paths, pairs=pairs, regions=regions,
                        warnings=warnings, timings=timings, pairs_rows=pairs_rows,
                        reuse=reuse if all(r is not None for r in reuse) else None)


@dataclass(frozen=True)
class PlanResult:
    """A whole plan: the geometric plan, and (unless paths-only) its schedule, the common time column
    with both cutters sampled on it, and the figures plan.json reports. Built by ``run_plan``; written
    by ``core.writer.write_result``; the CLI and the workbench both go through these two."""

    plan: PathPlan
    source: str
    axis: str
    period: float
    profile: str = "sigmoid"
    schedule: object | None = None   # core.schedule.Schedule (on the machine's reachable axes)
    timeline: object | None = None   # core.timeline.Timeline
    figures: dict | None = None
    machine: object | None = None    # core.machine.Machine
    axes: dict | None = None         # side -> core.postprocess.AxisTable
    limit_findings: list = field(default_factory=list)  # core.postprocess.LimitFinding
    warp: object | None = None       # core.postprocess.TimeWarp: timeline time -> schedule time
    #: core.csvio.Helpers already formatting the tables (run_plan's ``early_tables``): write_result
    #: takes and closes them
    helpers: tuple = field(default=(), compare=False, repr=False)

    @property
    def blocking_findings(self) -> list:
        """The limit findings that stop an export without --force (kinds in ENFORCED_LIMITS)."""
        return [f for f in self.limit_findings if f.kind in ENFORCED_LIMITS]

    def speeds(self, side: str, t: np.ndarray) -> np.ndarray:
        """(m,) mm/ms: a cutter's tip speed along its path at times t (m,) ms of the timeline."""
        from .motion import sample_speeds

        moves = getattr(self.schedule, side)
        if self.warp is None:
            return sample_speeds(moves, t)
        return sample_speeds(moves, self.warp.to_schedule_time(t)) * self.warp.rate(t)

    @property
    def safe(self) -> bool:
        """True unless the figures count a tip-spacing or capsule violation."""
        f = self.figures or {}
        return not (f.get("spacing_violations") or f.get("capsule_violations"))


def default_period(params: PlanParameters) -> float:
    """The CL tables' time step, ms: one interpolation step dd at the feed."""
    p = params.resolved()
    return p.dd / (p.feed / 60000.0)


def run_plan(blade: Blade, params: PlanParameters, source: str = "sample", axis: str = "z",
             period: float | None = None, profile: str = "sigmoid", paths_only: bool = False,
             workers: int = 1, progress: Progress | None = None, row_formatter: Callable | None = None,
             paths: PathPlan | None = None, machine=None, axes: bool = False, reusable: bool = False,
             early_tables: bool = False, on_timeline: Callable | None = None,
             out_dir: str | Path | None = None) -> PlanResult:
    """Plan a blade end to end: paths (plan_paths; or ``paths`` when given, e.g. from
    ``replan_regions``), then the schedule of ``params.mode`` and its time column every ``period`` ms
    (default: dd at the feed). With ``axes`` the plan is made for the two machines
    (core.postprocess: tool axes within the head's tilt, axis tables and their limit check;
    core.override: a feed override that keeps the axes' speed and acceleration limits; ``machine`` is
    a core.machine.Machine, default the shipped machine.toml).
    ``progress(fraction, message)`` returning False cancels (Cancelled). ``workers``, ``row_formatter``
    and ``reusable``: see plan_paths. ``early_tables`` (with workers > 1, for a caller that writes the
    plan next, into ``out_dir`` if given): the tables are formatted in two forked helpers (right,
    left) as soon as they exist, while the figures are computed; the helpers write them beside
    ``out_dir`` (write_result moves them in) or send them back. ``on_timeline(timeline, schedule,
    warp)`` is called as soon as the final time column exists, before the figures (warp: the feed
    override's TimeWarp with ``axes``, else None), for a caller that starts its own work on it
    meanwhile (the workbench's plots)."""
    from .writer import EarlyPairs

    p = params.resolved()
    if period is None:
        period = default_period(p)
    if not (isinstance(period, (int, float)) and math.isfinite(period) and 0 < period < 1e6):
        raise PlanningError(f"the time step must be a positive number of ms, got {period}")

    def sub(lo: float, hi: float) -> Progress | None:
        if progress is None:
            return None
        return lambda f, msg: progress(lo + (hi - lo) * f, msg)

    if paths is None:
        paths = plan_paths(blade, params, progress=sub(0.0, 0.6 if not paths_only else 1.0), workers=workers,
                           row_formatter=row_formatter, reusable=reusable)
    if paths_only:
        return PlanResult(paths, source, axis, float(period), profile)
    # pairs.csv is written beside out_dir meanwhile, by a thread (mostly waiting on the disk)
    pairs = EarlyPairs.start(paths, out_dir) if early_tables and workers > 1 else None
    try:
        return _schedule_and_tables(paths, p, source, axis, float(period), profile, progress, machine, axes,
                                    early_tables, workers, on_timeline, out_dir, pairs)
    except BaseException:
        if pairs is not None:
            pairs.close()
        raise


def _schedule_and_tables(paths, p, source, axis, period, profile, progress, machine, axes, early_tables,
                         workers, on_timeline, out_dir, pairs) -> PlanResult:
    """run_plan after the paths (its arguments; ``pairs``: an EarlyPairs or None, handed to the
    result's helpers)."""
    from .machine import load_machine
    from .override import retime
    from .parallel import per_side
    from .postprocess import check_limits, machine_figures, machine_plan
    from .schedule import build_schedule
    from .timeline import figures, sample
    from .writer import close_helpers, early_helpers

    early = (pairs,) if pairs is not None else ()
    if progress is not None and progress(0.6, "schedule") is False:
        raise Cancelled()
    t0 = time.perf_counter()

    def cancel_at(fraction: float, message: str):
        if progress is None:
            return None
        return lambda: progress(fraction, message) is False

    planned, tilt_limited = paths, None
    if axes:  # tool axes within the heads' reach before anything is timed
        machine = machine if machine is not None else load_machine(None)
        planned, tilt_limited = machine_plan(paths, machine)
    schedule = build_schedule(planned, p.mode, p.feed, p.a_max, profile, period,
                              cancel=cancel_at(0.7, "schedule: safety rounds"))
    if progress is not None and progress(0.8, "time column") is False:
        raise Cancelled()
    timeline = sample(schedule, period, p.tool_radius, cancel=cancel_at(0.85, "time column: refining rows"))
    t1 = time.perf_counter()
    paths.timings["schedule_s"] = t1 - t0
    if not axes:
        if on_timeline is not None:
            on_timeline(timeline, schedule, None)
        helpers = early_helpers(timeline, None, workers if early_tables else 1, out_dir)
        try:
            fig = figures(timeline, planned, schedule)
        except BaseException:
            close_helpers(helpers)
            raise
        if progress is not None:
            progress(1.0, "plan done")
        return PlanResult(paths, source, axis, float(period), profile, schedule, timeline, fig,
                          helpers=helpers + early)
    at_feed_s = float(timeline.t[-1]) / 1000.0
    timeline, warp, tables = retime(machine, schedule, timeline, period, p.a_max / 1e6,
                                    cancel=cancel_at(0.9, "feed override"))
    if on_timeline is not None:
        on_timeline(timeline, schedule, warp)
    helpers = early_helpers(timeline, tables, workers if early_tables else 1, out_dir)
    try:
        fig = figures(timeline, planned, schedule)
        found = per_side(lambda side: check_limits(machine, tables[side]))  # (caches the accelerations)
        findings = found["left"] + found["right"]
        fig["machine"] = machine_figures(machine, warp, tables, findings, tilt_limited, at_feed_s, ENFORCED_LIMITS)
    except BaseException:
        close_helpers(helpers)
        raise
    paths.timings["axes_s"] = time.perf_counter() - t1
    if progress is not None:
        progress(1.0, "plan done")
    return PlanResult(paths, source, axis, float(period), profile, schedule, timeline, fig, machine, tables,
                      findings, warp, helpers=helpers + early)


def replan_regions(previous: PathPlan, params: PlanParameters, progress: Progress | None = None) -> PathPlan:
    """The same paths with new region parameters (h_safe, k_max): symmetric pairs are reused, only the
    region division and the tip-region pairs that change are recomputed. ``params`` must keep the
    previous tool radius, dR, dd and tool length (PlanningError otherwise: plan_paths then)."""
    p = params.resolved()
    q = previous.params
    for name in ("tool_radius", "dr", "dd", "tool_length"):
        if getattr(p, name) != getattr(q, name):
            raise PlanningError(f"{name} changed ({getattr(q, name)} -> {getattr(p, name)}): plan the paths again")
    if previous.reuse is None:
        raise PlanningError("this plan keeps no reusable paths (it was planned by worker processes)")
    t_start = time.perf_counter()
    clock = dict.fromkeys(("contour_paths_s", "interpolation_alignment_s", "regions_s"), 0.0)
    pairs, regions, reuse = [], [], []
    n = len(previous.reuse)
    for k, (path, fitted, sym, tip_pair) in enumerate(previous.reuse):
        if progress is not None and progress(k / n, f"regions of path {k + 1} of {n}") is False:
            raise Cancelled()
        t0 = time.perf_counter()
        tmpl = sym.left_tip if sym.template == "left" else sym.right_tip
        reg = divide(sym.spacing, tmpl, p.h_safe, p.k_max)
        t1 = time.perf_counter()
        pair = sym
        if reg.is_tip:
            if tip_pair is None:
                tip_pair = push_pair_out(align_single(path, p.dd, p.tool_radius, p.tool_length, fitted, symmetric=sym),
                                    facet_guard(previous.blade, previous.frame), p.tool_radius)
            pair = tip_pair
            reg = replace(reg, labels=np.full(len(pair.u), "tip"))
        clock["regions_s"] += t1 - t0
        clock["interpolation_alignment_s"] += time.perf_counter() - t1
        pairs.append(pair)
        regions.append(reg)
        reuse.append((path, fitted, sym, tip_pair))
    timings = dict(clock)
    timings["paths_wall_s"] = time.perf_counter() - t_start
    timings["reused_paths"] = n
    return PathPlan(blade=previous.blade, frame=previous.frame, params=p, paths=previous.paths, pairs=pairs,
                    regions=regions, warnings=p.warnings() + [w for w in previous.warnings if w.startswith("no path")],
                    timings=timings, reuse=reuse)

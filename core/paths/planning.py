"""Planning the paths (paper sections 2-4): one path (contour, alignment, regions: ``_plan_one``), all
of them in forked worker processes or here (``plan_paths``, ``PathsJob``), and a region re-plan that
reuses them (``replan_regions``). A Python loop over paths is used; every step inside is vectorised
over points."""

from __future__ import annotations

import multiprocessing as mp
import os
import pickle
import shutil
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, replace

import numpy as np

from core.blade.frame import WorkpieceFrame, workpiece_frame
from core.blade.model import Blade
from core.errors import BladeInputError, PlanningError
from core.paths.alignment import align_symmetric, sides
from core.paths.contours import contour_path, path_radii, side_assignment
from core.paths.guard import Guard, blade_guard, guard_pair
from core.paths.plan import KeptPath, PathPlan
from core.paths.regions import divide
from core.paths.single_sided import single_sided_pair
from core.paths.stations import contour_stations
from core.records import PlanParameters, Progress, Timings, check_progress
from core.util.scratch import die_with_parent, scratch_dir, scratch_owner, sweep_worker_scratch


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


@dataclass(frozen=True)
class PathInputs:
    """What every path of one blade needs, built once (PathsJob) and inherited by forked workers: the
    blade in its workpiece frame, the resolved parameters, which side machines the back, the gouge
    guard (core.paths.guard) and the chordwise stations (core.paths.stations)."""

    blade: Blade
    frame: WorkpieceFrame
    params: PlanParameters
    left_is_back: bool
    guard: Guard | None
    stations: np.ndarray | None


def _add_times(clock: dict, times: dict) -> None:
    for key, v in times.items():
        clock[key] = clock.get(key, 0.0) + v


def _plan_one(inputs: PathInputs, r: float, index: int) -> tuple[tuple | None, str | None, dict]:
    """Contour path, alignment and regions of one radius, and the seconds of each step; None (and a
    warning) without a section. PlanningError where a ball still cuts into the blade (core.paths.guard)."""
    blade, frame, p, left_is_back = inputs.blade, inputs.frame, inputs.params, inputs.left_is_back
    guard, stations = inputs.guard, inputs.stations
    t0 = time.perf_counter()
    try:
        path = contour_path(blade, frame, r, index, left_is_back, stations)
    except BladeInputError as exc:
        return None, f"no path at r = {r:.3f} mm (path {index}): {exc}", {}
    t1 = time.perf_counter()
    fitted = sides(path)
    sym = guard_pair(align_symmetric(path, p.dd, p.tool_radius, fitted), guard, p.tool_radius)
    t2 = time.perf_counter()
    pair, reg, tip_pair, times = _divided(path, fitted, sym, None, p, guard)
    times["contour_paths_s"] = t1 - t0
    times["interpolation_alignment_s"] += t2 - t1
    return (path, pair, reg, KeptPath(path, fitted, sym, tip_pair)), None, times


def _divided(path, fitted, sym, tip_pair, p: PlanParameters, guard):
    """A symmetrical pair divided into regions (core.paths.regions.divide) and, wholly in the tip
    region, its single-sided pair instead (``tip_pair`` when made already, else made here: the tip
    region's alignment, core.paths.single_sided.single_sided_pair). Returns (the pair, its regions,
    the tip pair or None, the seconds of the division and of the tip pair's alignment)."""
    t0 = time.perf_counter()
    tmpl = sym.left_tip if sym.template == "left" else sym.right_tip
    reg = divide(sym.spacing, tmpl, p.h_safe, p.k_max)
    t1 = time.perf_counter()
    pair = sym
    if reg.is_tip:
        if tip_pair is None:
            tip_pair = single_sided_pair(path, fitted, sym, p, guard)
        pair = tip_pair
        reg = replace(reg, labels=np.full(len(pair.u), "tip"))
    return pair, reg, tip_pair, {"regions_s": t1 - t0, "interpolation_alignment_s": time.perf_counter() - t1}


#: paths per ``on_chunk`` call when one process plans them (PathsJob.result)
CHUNK = 16

_JOB: tuple | None = None  # the job of a forked worker (set in the worker by _set_job)


def _set_job(job: tuple, parent: int) -> None:
    """Worker initializer: the job arrives through fork (never pickled); the worker dies with its
    parent process ``parent`` (die_with_parent)."""
    global _JOB
    die_with_parent(parent)
    _JOB = job


def _as_done(futures: list[Future]):
    """The results of ``futures`` as each finishes; the first failure raises (a worker that died:
    BrokenProcessPool, a RuntimeError that ``core.util.limits`` names)."""
    pending = set(futures)
    while pending:
        done, pending = wait(pending, return_when=FIRST_COMPLETED)
        for f in done:
            yield f.result()


def _stop(pool: ProcessPoolExecutor, finished: bool) -> None:
    """End ``pool``: when its work is ``finished``, as it ends itself; else now, its queued chunks
    dropped and its running workers terminated (Python 3.14's ``terminate_workers``; before it, the
    executor's own process table)."""
    if finished:
        pool.shutdown(wait=True)
        return
    pool.shutdown(wait=False, cancel_futures=True)
    terminate = getattr(pool, "terminate_workers", None)
    if terminate is not None:
        terminate()
    else:
        for proc in list((pool._processes or {}).values()):
            proc.terminate()
    pool.shutdown(wait=True)


def _plan_chunk_to_file(args: tuple[list[int], str]) -> str:
    """Worker: plan a chunk and pickle the result to a file (pipes are slow for tens of MB here): its
    clock and rows first, then each path on its own (``_read_chunk``)."""
    chunk, filename = args
    out, clock, rows = _plan_chunk(chunk)
    with open(filename, "wb") as fh:
        pickle.dump((clock, rows, len(out)), fh, protocol=pickle.HIGHEST_PROTOCOL)
        for item in out:
            pickle.dump(item, fh, protocol=pickle.HIGHEST_PROTOCOL)
    return filename


def _read_chunk(filename: str) -> tuple[list, dict, list | None]:
    """A chunk file of ``_plan_chunk_to_file``, one path at a time, letting other threads run between
    two (unpickling holds the interpreter lock: a whole chunk at once stalled the workbench's window
    for most of a second on a loaded machine)."""
    with open(filename, "rb") as fh:
        clock, rows, n = pickle.load(fh)
        out = []
        for _ in range(n):
            out.append(pickle.load(fh))
            time.sleep(0)
    return out, clock, rows


def _plan_chunk(chunk: list[int]):
    inputs, radii, formatter, reusable = _JOB
    clock = dict.fromkeys(("contour_paths_s", "interpolation_alignment_s", "regions_s"), 0.0)
    out = []
    for i in chunk:
        res, warn, times = _plan_one(inputs, float(radii[i]), i)
        _add_times(clock, times)
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
    (core.output.files.pairs_rows), kept in ``PathPlan.pairs_rows``. reusable: bring each path's fitted curves
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
        # chordwise stations and the gouge guard: built once here, inherited by forked workers
        self.stations = contour_stations(blade, frame, p.tool_radius)
        self.guard = blade_guard(blade, frame, p.tool_radius, self.stations)
        self.blade, self.params, self.frame, self.workers = blade, p, frame, workers
        self.radii = path_radii(blade, p.dr)
        self.left_is_back = side_assignment(blade, frame)
        self.row_formatter, self.reusable = row_formatter, reusable
        self.inputs = PathInputs(blade, frame, p, self.left_is_back, self.guard, self.stations)
        self._pool = self._chunks = self._scratch = None
        n = len(self.radii)
        if workers > 1 and n >= 4 * workers and "fork" in mp.get_all_start_methods():
            job = (self.inputs, self.radii, row_formatter, reusable)
            sweep_worker_scratch()
            self._scratch = tempfile.mkdtemp(prefix=f"bladecam-{scratch_owner()}-", dir=scratch_dir())
            k = 4 * workers  # interleaved chunks: balanced, and progress as each one finishes
            jobs = [(list(range(j, n, k)), os.path.join(self._scratch, f"chunk{j}.pkl")) for j in range(k)]
            try:
                # (an executor, not a multiprocessing Pool: a worker that dies, or a chunk that cannot
                # be sent, raises in ``result`` where a Pool would wait for ever)
                self._pool = ProcessPoolExecutor(workers, mp.get_context("fork"), _set_job, (job, os.getpid()))
                self._chunks = [self._pool.submit(_plan_chunk_to_file, j) for j in jobs]
            except BaseException:
                self.cancel()
                raise

    def worker_processes(self) -> list:
        """The forked worker processes (multiprocessing.Process; none when planning in this process)."""
        return [] if self._pool is None else list(self._pool._processes.values())

    def cancel(self) -> None:
        """Stop the worker processes (if any are still running) and remove their files."""
        pool, self._pool = self._pool, None
        if pool is not None:
            _stop(pool, finished=all(f.done() for f in self._chunks or ()))
        if self._scratch is not None:
            shutil.rmtree(self._scratch, ignore_errors=True)
            self._scratch = None

    def _collect(self, progress: Progress | None, clock: dict, results: dict, rows_by_index: dict,
                 on_chunk: Callable | None) -> None:
        """Wait for the workers' chunks (progress and ``on_chunk`` per chunk; False cancels)."""
        k = 4 * self.workers
        chunks = []
        for n_done, fn in enumerate(_as_done(self._chunks), start=1):
            chunks.append(_read_chunk(fn))
            if on_chunk is not None:
                done = [res for _, res, _ in chunks[-1][0] if res is not None]
                on_chunk([res[1] for res in done], [res[2] for res in done])
            check_progress(progress, n_done / k, f"{n_done} of {k} path chunks")
        for out, c, rows in chunks:
            done = [i for i, res, _ in out if res is not None]
            for i, res, warn in out:
                results[i] = (res, warn)
            if rows is not None:
                rows_by_index.update(zip(done, rows, strict=True))
            _add_times(clock, c)

    def result(self, progress: Progress | None = None, on_chunk: Callable | None = None) -> PathPlan:
        """The PathPlan (see plan_paths); raises Cancelled when ``progress`` returns False.
        ``on_chunk(pairs, regions)``: called with the pairs and region divisions of each chunk of paths
        as it is planned (a worker's chunk, or CHUNK paths in one process), before the plan is whole."""
        p, blade, frame, radii = self.params, self.blade, self.frame, self.radii
        clock = dict.fromkeys(("contour_paths_s", "interpolation_alignment_s", "regions_s"), 0.0)
        results: dict[int, tuple] = {}
        rows_by_index: dict[int, bytes] = {}
        warnings = p.warnings()
        n = len(radii)
        try:
            if self._pool is not None:
                self._collect(progress, clock, results, rows_by_index, on_chunk)
            else:
                chunk = []
                for i, r in enumerate(radii):
                    check_progress(progress, i / n, f"path {i + 1} of {n}")
                    res, warn, times = _plan_one(self.inputs, float(r), i)
                    results[i] = (res, warn)
                    _add_times(clock, times)
                    if res is not None:
                        chunk.append(res)
                    if on_chunk is not None and chunk and (len(chunk) == CHUNK or i == n - 1):
                        on_chunk([c[1] for c in chunk], [c[2] for c in chunk])
                        chunk = []
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
        timings = Timings.of({**clock, "paths_wall_s": time.perf_counter() - self._t_start,
                              "workers": self.workers})
        if progress is not None:
            progress(1.0, "paths done")
        return PathPlan(blade=blade, frame=frame, params=p, paths=paths, pairs=pairs, regions=regions,
                        warnings=warnings, timings=timings, pairs_rows=pairs_rows,
                        reuse=reuse if all(r is not None for r in reuse) else None, guard=self.guard)


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
    guard = previous.guard
    if guard is None:
        guard = blade_guard(previous.blade, previous.frame, p.tool_radius)
    clock = dict.fromkeys(("contour_paths_s", "interpolation_alignment_s", "regions_s"), 0.0)
    pairs, regions, reuse = [], [], []
    n = len(previous.reuse)
    for k, (path, fitted, sym, tip_pair) in enumerate(previous.reuse):
        check_progress(progress, k / n, f"regions of path {k + 1} of {n}")
        pair, reg, tip_pair, times = _divided(path, fitted, sym, tip_pair, p, guard)
        _add_times(clock, times)
        pairs.append(pair)
        regions.append(reg)
        reuse.append(KeptPath(path, fitted, sym, tip_pair))
    timings = Timings.of({**clock, "paths_wall_s": time.perf_counter() - t_start, "reused_paths": n})
    return PathPlan(blade=previous.blade, frame=previous.frame, params=p, paths=previous.paths, pairs=pairs,
                    regions=regions, warnings=p.warnings() + [w for w in previous.warnings if w.startswith("no path")],
                    timings=timings, reuse=reuse, guard=guard)

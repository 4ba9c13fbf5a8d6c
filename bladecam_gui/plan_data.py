"""What the workbench shows of a plan, prepared off the GUI thread from core's results (no Qt here).

``prepare`` loads the blade (or keeps the previous one), plans through ``core.pipeline.run_plan``
(reusing the previous paths when only h_safe / k_max, or only the schedule inputs, changed) and
gathers, per time sample, what the views and plots need: tip spacing and capsule clearance
(core.safety), both cutters' feed (core.pipeline.PlanResult.speeds) and the job's step bands. Nothing
geometric is computed here that core does not compute.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from core.blade import Blade
from core.blade_source import load_blade
from core.frames import WorkpieceFrame, workpiece_frame
from core.pipeline import Cancelled, PathPlan, PathsJob, PlanParameters, PlanResult, replan_regions, run_plan

from .style import REGIONS

log = logging.getLogger(__name__)

#: processes planning the paths (forked from the planner thread; they only compute and return arrays)
PATH_WORKERS = min(os.cpu_count() or 1, 2)
GEOMETRIC = ("tool_radius", "dr", "dd", "tool_length")
REGIONAL = ("h_safe", "k_max")


@dataclass(frozen=True)
class PlanJob:
    """The inputs of one plan: blade source and axis, parameters, speed profile, CL period (ms), and
    whether to plan for the two machines with their axis tables (core's ``axes``)."""

    source: str
    axis: str
    params: PlanParameters
    profile: str = "sigmoid"
    period: float | None = None
    axes: bool = False


@dataclass(frozen=True)
class BladeData:
    """A loaded blade and its surfaces in the workpiece frame W: face, back (n_r, n_c, 3) mm."""

    blade: Blade
    source: str
    axis: str
    frame: WorkpieceFrame
    face: np.ndarray
    back: np.ndarray


@dataclass(frozen=True)
class PathLines:
    """All pair paths of both sides as line segments: points (m, 3) mm in W; cells (3 k,) VTK line
    cells; region (k,) int codes of style.REGIONS per segment."""

    points: np.ndarray
    cells: np.ndarray
    region: np.ndarray


@dataclass(frozen=True)
class PlanData:
    """A plan as shown. ``result`` is None while only the blade is loaded; ``result.timeline`` is None
    for a paths-only preview. Per time sample (n,): spacing and clearance mm, danger bool, speeds
    mm/min, step (the later of the two cutters' steps). bands (b, 3): t0 ms, t1 ms, step."""

    job: PlanJob
    blade: BladeData
    result: PlanResult | None = None
    lines: PathLines | None = None
    spacing: np.ndarray | None = None
    clearance: np.ndarray | None = None
    danger: np.ndarray | None = None
    speed_left: np.ndarray | None = None
    speed_right: np.ndarray | None = None
    step: np.ndarray | None = None
    bands: np.ndarray | None = None
    reused: str = "none"
    timings: dict = field(default_factory=dict)

    @property
    def timeline(self):
        return None if self.result is None else self.result.timeline

    @property
    def has_schedule(self) -> bool:
        return self.timeline is not None

    def index_at(self, t_ms: float) -> int:
        """The time sample nearest to t_ms (np.searchsorted on the time column)."""
        t = self.timeline.t
        i = int(np.searchsorted(t, t_ms))
        if i <= 0:
            return 0
        if i >= len(t):
            return len(t) - 1
        return i - 1 if t_ms - t[i - 1] <= t[i] - t_ms else i


def _nbytes(obj) -> int:
    """Bytes of the numpy arrays in obj (an array, a dataclass, a tuple, list or dict of them)."""
    if obj is None:
        return 0
    if isinstance(obj, np.ndarray):
        return obj.nbytes
    if isinstance(obj, (tuple, list)):
        return sum(_nbytes(v) for v in obj)
    if isinstance(obj, dict):
        return sum(_nbytes(v) for v in obj.values())
    if hasattr(obj, "__dataclass_fields__"):
        cached = [v for k, v in vars(obj).items() if k.startswith("_") and k not in obj.__dataclass_fields__]
        return sum(_nbytes(getattr(obj, name, None)) for name in obj.__dataclass_fields__) + _nbytes(cached)
    return 0


def plan_bytes(data: PlanData) -> int:
    """About how much memory a shown plan holds beyond its blade and paths (which later plans share):
    its time column with both cutters, the axis tables and the feed override, and the views' arrays."""
    total = sum(_nbytes(getattr(data, k)) for k in ("lines", "spacing", "clearance", "danger", "speed_left",
                                                   "speed_right", "step", "bands"))
    res = data.result
    if res is not None:
        total += _nbytes(res.timeline) + _nbytes(res.warp) + _nbytes(res.axes)  # (the timeline's cache too)
        if res.schedule is not None:
            total += _nbytes(res.schedule._times) + _nbytes(res.schedule._samples)
    return total


def load_blade_data(source: str, axis: str) -> BladeData:
    """Load a blade (BladeInputError) and map its surface grids into the workpiece frame."""
    blade = load_blade(source, axis=axis)
    frame = workpiece_frame(blade)
    face, back = blade.surface_grids()
    to_w = [frame.points(g.reshape(-1, 3)).reshape(g.shape) for g in (face, back)]
    return BladeData(blade, source, axis, frame, *to_w)


#: the drawn paths keep the points a chord needs to stay within DISPLAY_TOLERANCE mm of the path (from
#: the curvature: a chord of length L over curvature k strays L^2 k / 8), at least one every
#: DISPLAY_STEP mm, every point where the path turns by more than DISPLAY_TURN_DEG (round the edges),
#: every region change and both ends: a tenth of a pixel at the scale of a blade, while every segment
#: drawn costs frame time in a software-rendered view (the sample's 41 k segments took 8.5 of the 3D
#: view's 14 ms per frame; 24 mm and 4 degrees, with the tolerance kept, draw 27 k)
DISPLAY_TOLERANCE = 0.05
DISPLAY_STEP = 24.0
DISPLAY_TURN_DEG = 4.0


def path_lines(plan: PathPlan, display_step: float = DISPLAY_STEP,
               tolerance: float = DISPLAY_TOLERANCE) -> PathLines:
    """Line segments of every pair path, both sides, with their region codes (thinned for display;
    display_step 0 keeps every point)."""
    polylines, labels = [], []
    for pair, reg in zip(plan.pairs, plan.regions, strict=True):
        polylines += [pair.left_tip, pair.right_tip]
        labels += [reg.labels, reg.labels]
    points = np.concatenate(polylines)
    names = np.concatenate(labels)
    lengths = np.array([len(p) for p in polylines])
    starts = np.cumsum(lengths) - lengths
    within = np.arange(len(points)) - np.repeat(starts, lengths)
    every = max(1, int(round(display_step / plan.params.dd)))
    change = np.zeros(len(points), bool)
    change[1:] = (names[1:] != names[:-1]) & (within[1:] > 0)
    keep = (within % every == 0) | change
    keep[:-1] |= change[1:]
    if every > 1:
        d = np.diff(points, axis=0)
        ds = np.linalg.norm(d, axis=1)
        d /= np.maximum(ds, 1e-12)[:, None]
        turn = np.arccos(np.clip(np.einsum("ij,ij->i", d[:-1], d[1:]), -1.0, 1.0))  # at points 1..m-2
        keep[1:-1] |= turn > np.radians(DISPLAY_TURN_DEG)  # the corners (across two paths: kept anyway)
        # the curvature budget: sum of sqrt(k / (8 tol)) ds over a chord <= 1 keeps it within tol
        h = 0.5 * (ds[:-1] + ds[1:])
        kappa = turn / np.maximum(h, 1e-12)
        budget = np.concatenate([[0.0], np.cumsum(np.sqrt(kappa / (8.0 * tolerance)) * h), [0.0]])
        budget[-1] = budget[-2]
        keep[1:] |= np.floor(budget[1:]) != np.floor(budget[:-1])
    keep[starts + lengths - 1] = True
    codes = np.zeros(len(names), np.int64)
    for name, (code, _) in REGIONS.items():
        codes[names == name] = code
    points, codes = points[keep], codes[keep]
    kept = np.add.reduceat(keep.astype(np.int64), starts)
    last = np.cumsum(kept) - 1
    segment = np.ones(len(points), bool)
    segment[last] = False
    first = np.nonzero(segment)[0]
    cells = np.column_stack([np.full(len(first), 2), first, first + 1]).ravel()
    return PathLines(points, cells, codes[first])


def step_bands(t: np.ndarray, step: np.ndarray) -> np.ndarray:
    """(b, 3): start ms, end ms, step of every run of equal steps on the time column."""
    change = np.nonzero(np.diff(step))[0] + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [len(t) - 1]])
    return np.column_stack([t[starts], t[ends], step[starts]]).astype(float)


def paths_to_reuse(previous: PlanData | None, job: PlanJob, params: PlanParameters, progress=None):
    """(paths or None, kind): the previous plan's paths when the blade and the geometric inputs are the
    same ('schedule': only feed / a_max / mode / profile / period changed; 'regions': h_safe / k_max
    changed, through core's replan_regions)."""
    if previous is None or previous.result is None:
        return None, "none"
    if (previous.blade.source, previous.blade.axis) != (job.source, job.axis):
        return None, "none"
    old = previous.result.plan
    if any(getattr(old.params, k) != getattr(params, k) for k in GEOMETRIC):
        return None, "none"
    if all(getattr(old.params, k) == getattr(params, k) for k in REGIONAL):
        return replace(old, params=params, timings=dict(old.timings)), "schedule"
    if old.reuse is None:
        return None, "none"
    return replan_regions(old, params, progress=progress), "regions"


def timeline_figures(res: PlanResult) -> dict:
    """The per-sample arrays of a result with a time column (PlanData's fields): tip spacing and
    capsule clearance mm, danger, both cutters' feed mm/min (PlanResult.speeds), step and its bands.
    Needs only ``res``'s plan, schedule, timeline and warp (not its figures)."""
    tl, p = res.timeline, res.plan.params
    # (the same arrays as core's figures: computed once, by whichever asks first; core asks for the
    # spacing first, so the clearance first here: the two are computed side by side)
    clear = tl.clearance(p.tool_radius, p.tool_length)
    at, _ = tl.spacing()
    danger = (at < p.h_safe - 1e-9) | (clear <= 0)
    step = np.maximum(tl.left.step, tl.right.step)
    left, right = res.speeds("left", tl.t), res.speeds("right", tl.t)
    return {"spacing": at, "clearance": clear, "danger": danger, "speed_left": left * 60000.0,
            "speed_right": right * 60000.0, "step": step, "bands": step_bands(tl.t, step)}


def schedule_figures(data: PlanData) -> PlanData:
    """Fill the per-sample arrays of a planned result (spacing, clearance, danger, speeds, steps)."""
    return replace(data, **timeline_figures(data.result))


@dataclass
class EarlyPaths:
    """A plan's paths started ahead of its job (at launch, see app.main): the blade loaded and the
    path workers forked (core.path_planning.PathsJob, the arguments ``prepare`` would give
    run_plan). The first job takes it when it is the same job, else cancels it."""

    job: PlanJob
    blade: BladeData
    paths: PathsJob

    def cancel(self) -> None:
        self.paths.cancel()


def sample_job(params: PlanParameters | None = None) -> PlanJob:
    """The job a new window plans first: the sample blade along z, ``params`` (default: core's
    defaults, derived values written out, as WorkbenchState's), sigmoid profile, default period."""
    return PlanJob("sample", "z", (params or PlanParameters()).resolved())


def start_early_paths(job: PlanJob) -> EarlyPaths | None:
    """Load ``job``'s blade and start planning its paths in worker processes; None (logged) when that
    fails: the job then plans as usual and reports the error."""
    try:
        blade = load_blade_data(job.source, job.axis)
        paths = PathsJob(blade.blade, job.params.resolved(), PATH_WORKERS, reusable=True)
    except Exception:
        log.warning("planning the paths at launch failed; the workbench plans them again", exc_info=True)
        return None
    return EarlyPaths(job, blade, paths)


def prepare(job: PlanJob, previous: PlanData | None, cancelled: Callable[[], bool] = lambda: False,
            progress: Callable[[float, str], None] = lambda f, m: None,
            preview: Callable[[PlanData], None] | None = None, early: EarlyPaths | None = None) -> PlanData:
    """Plan ``job`` (see the module docstring). Raises core's BladecamError subclasses, or Cancelled.
    ``preview`` receives the blade alone, then the paths, when they are new (for a first display).
    ``early``: this job's blade and paths started ahead (an EarlyPaths of another job, or with a
    previous plan, is not used); cancelled here unless its paths were taken."""
    try:
        return _prepare(job, previous, cancelled, progress, preview, early)
    finally:
        if early is not None:
            early.cancel()  # a no-op once its paths were taken


def _prepare(job: PlanJob, previous: PlanData | None, cancelled: Callable[[], bool],
             progress: Callable[[float, str], None], preview: Callable[[PlanData], None] | None,
             early: EarlyPaths | None) -> PlanData:
    clock = {}
    t0 = time.perf_counter()

    def report(lo: float, hi: float):
        def cb(f: float, msg: str) -> bool:
            progress(lo + (hi - lo) * f, msg)
            return not cancelled()
        return cb

    params = job.params.resolved()
    if early is not None and (early.job != job or previous is not None):
        early = None
    if early is not None:
        blade = early.blade
        if preview is not None:
            preview(PlanData(job, blade))
    elif previous is not None and (previous.blade.source, previous.blade.axis) == (job.source, job.axis):
        blade = previous.blade
    else:
        progress(0.0, "loading the blade")
        blade = load_blade_data(job.source, job.axis)
        if preview is not None:
            preview(PlanData(job, blade))
    clock["blade_s"] = time.perf_counter() - t0
    if cancelled():
        raise Cancelled()
    paths, reused = paths_to_reuse(previous, job, params, report(0.05, 0.1))
    if early is not None:  # what run_plan(paths_only=True, workers=PATH_WORKERS, reusable=True) returns
        paths = early.paths.result(progress=report(0.05, 0.5))
    elif paths is None:
        paths = run_plan(blade.blade, params, job.source, job.axis, period=job.period, profile=job.profile,
                         paths_only=True, progress=report(0.05, 0.5), workers=PATH_WORKERS,
                         reusable=True).plan
    clock["paths_s"] = time.perf_counter() - t0 - clock["blade_s"]
    if cancelled():
        raise Cancelled()
    t1 = time.perf_counter()
    extra = {"axes": True} if job.axes else {}
    # the drawn paths, then the views' arrays, in a thread beside the schedule (on the other core)
    with ThreadPoolExecutor(1, thread_name_prefix="bladecam-views") as pool:
        def drawn_paths() -> PathLines:
            lines = path_lines(paths)
            if preview is not None and reused != "schedule":  # new paths or regions: shown at once
                preview(PlanData(job, blade, PlanResult(paths, job.source, job.axis, 0.0, job.profile), lines,
                                 reused=reused))
            return lines

        lines = pool.submit(drawn_paths)  # (its preview is sent before the plan, which waits for it)
        views = []

        def start_views(timeline, schedule, warp) -> None:
            """The views' arrays from the final time column, while core computes its figures."""
            part = PlanResult(paths, job.source, job.axis, 0.0, job.profile, schedule, timeline, warp=warp)
            views.append(pool.submit(timeline_figures, part))

        # (a shown plan's time column is the period rows: the rows a written one adds round the edges
        # bound a controller's straight lines, and cost a third of a re-plan; an export plans again)
        res = run_plan(blade.blade, params, job.source, job.axis, period=job.period, profile=job.profile,
                       paths=paths, progress=report(-0.1, 1.0), on_timeline=start_views, refine=False,
                       **extra)  # reports 0.6..1 with paths given
        clock["schedule_s"] = time.perf_counter() - t1
        t2 = time.perf_counter()
        figures = views[0].result() if views else timeline_figures(res)
        lines = lines.result() if res.plan is paths else path_lines(res.plan)  # (run_plan keeps them)
    data = PlanData(job, blade, res, lines, reused=reused, **figures)
    clock["views_s"] = time.perf_counter() - t2  # what the views' work adds after core's figures
    clock["total_s"] = time.perf_counter() - t0
    progress(1.0, "plan ready")
    return replace(data, timings=clock)

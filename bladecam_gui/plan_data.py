"""What the workbench shows of a plan, prepared off the GUI thread from core's results (no Qt here).

``prepare`` plans a job through a core.planner.Planner (which reuses what the last job leaves valid:
the paths when only h_safe / k_max changed, the regions when only the schedule inputs changed) and
gathers, per time sample, what the views and plots need: tip spacing, capsule clearance and the
rows that break the safety rule (the plan's core.schedule.timeline.SafetyProfile), both cutters'
feed (core.planner.cutter_speeds) and the job's step bands. Nothing geometric is computed here that
core does not compute.
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np

from core.blade.frame import WorkpieceFrame, workpiece_frame
from core.blade.model import Blade
from core.errors import Cancelled
from core.paths.plan import PathPlan
from core.planner import Planner, cutter_speeds
from core.records import PlanJob, PlanParameters, sub_progress
from core.result import PlanListener, PlanResult
from core.schedule.step_times import job_step
from core.util.polyline import turn_angles

from .style import REGIONS
from .verdict import Violations, find_violations

log = logging.getLogger(__name__)

#: processes planning the paths (forked from the planner thread; they only compute and return arrays)
PATH_WORKERS = min(os.cpu_count() or 1, 2)


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
    """A plan as shown. ``result`` is None while only the blade is loaded (``lines`` then: the paths
    planned so far, as their chunks arrive, or None); ``result.timeline`` is None for a paths-only
    preview. Per time sample (n,): spacing and clearance mm, danger bool, speeds
    mm/min, step (core.schedule.step_times.job_step: the earlier of the two cutters' steps). bands
    (b, 3): t0 ms, t1 ms, step. violations: the runs of danger with their kinds and the verdict
    (verdict.Violations), found with the plan, off the GUI thread."""

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
    violations: Violations | None = None
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
        return sum(_nbytes(getattr(obj, name, None)) for name in obj.__dataclass_fields__)
    return 0


def plan_bytes(data: PlanData) -> int:
    """About how much memory a shown plan holds beyond its blade and paths (which later plans share):
    its time column with both cutters, the axis tables and the machine clock, and the views' arrays."""
    total = sum(_nbytes(getattr(data, k)) for k in ("lines", "spacing", "clearance", "danger", "speed_left",
                                                   "speed_right", "step", "bands"))
    res = data.result
    if res is not None:
        total += _nbytes(res.timeline) + _nbytes(res.warp) + _nbytes(res.axes) + _nbytes(res.safety)
    return total


def load_blade_data(planner: Planner, source: str, axis: str) -> BladeData:
    """A blade loaded by the planner (BladeInputError) and its surface grids in the workpiece frame."""
    blade = planner.blade(source, axis)
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
    return pair_lines(plan.pairs, plan.regions, plan.params.dd, display_step, tolerance)


def pair_lines(pairs: list, regions: list, dd: float, display_step: float = DISPLAY_STEP,
               tolerance: float = DISPLAY_TOLERANCE) -> PathLines:
    """``path_lines`` of some of a plan's pairs and their region divisions (interpolation step dd mm)."""
    polylines, labels = [], []
    for pair, reg in zip(pairs, regions, strict=True):
        polylines += [pair.left_tip, pair.right_tip]
        labels += [reg.labels, reg.labels]
    points = np.concatenate(polylines)
    names = np.concatenate(labels)
    lengths = np.array([len(p) for p in polylines])
    starts = np.cumsum(lengths) - lengths
    within = np.arange(len(points)) - np.repeat(starts, lengths)
    every = max(1, int(round(display_step / dd)))
    change = np.zeros(len(points), bool)
    change[1:] = (names[1:] != names[:-1]) & (within[1:] > 0)
    keep = (within % every == 0) | change
    keep[:-1] |= change[1:]
    if every > 1:
        d = np.diff(points, axis=0)
        ds = np.linalg.norm(d, axis=1)
        d /= np.maximum(ds, 1e-12)[:, None]
        turn = turn_angles(d)  # at points 1..m-2
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


def motion_figures(res: PlanResult) -> dict:
    """Both cutters' feed mm/min (core.planner.cutter_speeds), the job's step (job_step) and its
    bands, per sample of a result's time column (needs only its schedule, timeline and warp)."""
    tl = res.timeline
    step = job_step(tl.left.step, tl.right.step)
    left, right = cutter_speeds(res, "left", tl.t), cutter_speeds(res, "right", tl.t)
    return {"speed_left": left * 60000.0, "speed_right": right * 60000.0, "step": step,
            "bands": step_bands(tl.t, step)}


def timeline_figures(res: PlanResult) -> dict:
    """The per-sample arrays of a planned result (PlanData's fields): tip spacing, capsule clearance
    and danger (the rows that break the safety rule or collide) from its SafetyProfile and its collision
    check, their violations (verdict.find_violations), and motion_figures."""
    safety, motion, danger = res.safety, motion_figures(res), danger_rows(res)
    return {"spacing": safety.at, "clearance": safety.clearance, "danger": danger,
            "violations": find_violations(res, danger, motion["step"]), **motion}


def danger_rows(res: PlanResult):
    """(n,) bool: the rows marked as violations: those that break the safety rule, and those where the
    tool assembly or a head collides (core.machine.collisions)."""
    if res.clearance is None or not res.clearance.collisions:
        return res.safety.unsafe
    return res.safety.unsafe | res.clearance.rows_colliding()


@dataclass
class EarlyPaths:
    """A plan's paths started ahead of its job (at launch, see app.main): the blade loaded and the
    path workers forked by a Planner (core.planner.Planner.start), which then plans the workbench's
    jobs. The first job takes the paths when it is the same job; the planner cancels them else."""

    job: PlanJob
    blade: BladeData
    planner: Planner

    @property
    def paths(self):
        """The started paths (core.paths.planning.PathsJob), None once taken or cancelled."""
        return self.planner.started

    def cancel(self) -> None:
        self.planner.cancel()


def sample_job(params: PlanParameters | None = None) -> PlanJob:
    """The job a new window plans first (WorkbenchState.job's at launch): the sample blade along z,
    ``params`` (default: core's defaults, derived values written out), sigmoid profile, default
    period, with the axis tables."""
    return PlanJob("sample", "z", (params or PlanParameters()).resolved(), axes=True)


def new_planner() -> Planner:
    """The workbench's planner: the paths in PATH_WORKERS processes, each path's fitted curves kept
    (an h_safe or k_max change re-divides the regions of the same paths)."""
    return Planner(PATH_WORKERS, keep=True)


def start_early_paths(job: PlanJob) -> EarlyPaths | None:
    """Load ``job``'s blade and start planning its paths in worker processes; None (logged) when that
    fails: the job then plans as usual and reports the error."""
    planner = new_planner()
    try:
        blade = load_blade_data(planner, job.source, job.axis)
        planner.start(job)
    except Exception:
        log.warning("planning the paths at launch failed; the workbench plans them again", exc_info=True)
        planner.cancel()
        return None
    return EarlyPaths(job, blade, planner)


class _Views(PlanListener):
    """Hooked onto the planner by ``prepare``: the paths planned so far as each chunk of new paths
    arrives, the drawn paths as soon as the paths exist (shown at once when they are new), and the
    motion figures as soon as the time column exists, each in a thread beside core's work (on the
    other core)."""

    def __init__(self, job: PlanJob, blade: BladeData, preview, pool: ThreadPoolExecutor, clock: dict):
        self.job, self.blade, self.preview, self.pool, self.clock = job, blade, preview, pool, clock
        self.lines = self.motion = None
        self.t0 = time.perf_counter()
        self.chunks: list[tuple] = []  # (pair, region) of the new paths so far, by pair index

    def paths_chunk(self, pairs: list, regions: list) -> None:
        if self.preview is None or not pairs:
            return
        self.chunks = sorted(self.chunks + list(zip(pairs, regions, strict=True)), key=lambda c: c[0].index)
        job, blade, preview, chunks = self.job, self.blade, self.preview, self.chunks

        def drawn_so_far() -> None:  # (the blade with the paths so far: no plan result yet)
            lines = pair_lines([c[0] for c in chunks], [c[1] for c in chunks], job.params.resolved().dd)
            preview(PlanData(job, blade, lines=lines))

        self.pool.submit(drawn_so_far)

    def paths_ready(self, plan: PathPlan, reused: str) -> None:
        self.clock["paths_s"] = time.perf_counter() - self.t0
        job, blade, preview = self.job, self.blade, self.preview

        def drawn_paths() -> PathLines:
            lines = path_lines(plan)
            if preview is not None and reused != "schedule":  # new paths or regions: shown at once
                preview(PlanData(job, blade, PlanResult(plan, job.source, job.axis, 0.0, job.profile), lines,
                                 reused=reused))
            return lines

        self.lines = self.pool.submit(drawn_paths)

    def timeline_ready(self, timeline, schedule, warp, tables) -> None:
        job = self.job
        part = PlanResult(None, job.source, job.axis, 0.0, job.profile, schedule, timeline, warp=warp)
        self.motion = self.pool.submit(motion_figures, part)


def prepare(job: PlanJob, previous: PlanData | None, planner: Planner,
            cancelled: Callable[[], bool] = lambda: False,
            progress: Callable[[float, str], None] = lambda f, m: None,
            preview: Callable[[PlanData], None] | None = None, early: EarlyPaths | None = None) -> PlanData:
    """Plan ``job`` with ``planner`` (see the module docstring). Raises core's BladecamError
    subclasses, or Cancelled. ``preview`` receives the blade alone, then the paths, when they are new
    (for a first display). ``early``: the blade of the job the planner started ahead (used when it
    is this job, with no previous plan); paths started ahead and not taken stop here, whatever
    happens."""
    try:
        return _prepare(job, previous, planner, cancelled, progress, preview, early)
    finally:
        planner.cancel()


def _prepare(job: PlanJob, previous: PlanData | None, planner: Planner, cancelled: Callable[[], bool],
             progress: Callable[[float, str], None], preview: Callable[[PlanData], None] | None,
             early: EarlyPaths | None) -> PlanData:
    clock = {}
    t0 = time.perf_counter()

    def report(lo: float, hi: float):  # (core's protocol: the callback returns False to cancel)
        return sub_progress(lambda f, msg: progress(f, msg) or not cancelled(), lo, hi)

    if early is not None and early.job == job and previous is None:
        blade = early.blade
        if preview is not None:
            preview(PlanData(job, blade))
    elif previous is not None and (previous.blade.source, previous.blade.axis) == (job.source, job.axis):
        blade = previous.blade
    else:
        progress(0.0, "loading the blade")
        blade = load_blade_data(planner, job.source, job.axis)
        if preview is not None:
            preview(PlanData(job, blade))
    clock["blade_s"] = time.perf_counter() - t0
    if cancelled():
        raise Cancelled()
    if previous is not None and previous.result is not None and planner.reuse(job) == "none":
        # the plan shown (kept from before, or planned by another planner) is where the edit starts
        planner.keep(previous.result.plan, previous.job.source, previous.job.axis)
    with ThreadPoolExecutor(1, thread_name_prefix="bladecam-views") as pool:
        views = _Views(job, blade, preview, pool, clock)
        # (the job as an export writes it: timed for the machines, with the axis tables)
        res = planner.plan(job, progress=report(0.05, 1.0), listener=views)
        clock["schedule_s"] = time.perf_counter() - t0 - clock["blade_s"] - clock.get("paths_s", 0.0)
        t2 = time.perf_counter()
        motion = views.motion.result() if views.motion is not None else motion_figures(res)
        lines = views.lines.result()
    safety, danger = res.safety, danger_rows(res)
    data = PlanData(job, blade, res, lines, spacing=safety.at, clearance=safety.clearance, danger=danger,
                    violations=find_violations(res, danger, motion["step"]), reused=res.reused, **motion)
    clock["views_s"] = time.perf_counter() - t2  # what the views' work adds after core's figures
    clock["total_s"] = time.perf_counter() - t0
    progress(1.0, "plan ready")
    return replace(data, timings=clock)

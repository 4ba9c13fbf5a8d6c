"""The planning pipeline: blade -> contour paths -> aligned pairs -> regions (-> schedule, axes).

``PlanParameters`` carries every planning input with the project's names and units (mm, mm/min,
mm/s^2 at this boundary); ``plan_paths`` (core.path_planning, exported here) chains the steps of
paper sections 2-4 and reports the time each step took; ``run_plan`` plans a blade end to end.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from .alignment import AlignedPair
from .blade import Blade
from .contour_paths import ContourPath
from .errors import Cancelled, PlanningError  # noqa: F401 (Cancelled: public here)
from .frames import WorkpieceFrame
from .path_planning import PathsJob, check_blade_fits_tool, plan_paths, replan_regions  # noqa: F401 (public here)
from .regions import Regions, check_region_parameters

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
             out_dir: str | Path | None = None, refine: bool = True) -> PlanResult:
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
                                    early_tables, workers, on_timeline, out_dir, pairs, refine or axes)
    except BaseException:
        if pairs is not None:
            pairs.close()
        raise


def _schedule_and_tables(paths, p, source, axis, period, profile, progress, machine, axes, early_tables,
                         workers, on_timeline, out_dir, pairs, refine=True) -> PlanResult:
    """run_plan after the paths (its arguments; ``pairs``: an EarlyPairs or None, handed to the
    result's helpers)."""
    from .machine import load_machine
    from .override import retime
    from .parallel import per_side
    from .postprocess import check_limits, machine_figures, machine_plan
    from .schedule import build_schedule
    from .timeline import figures, period_rows, sample
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
    if refine:
        timeline = sample(schedule, period, p.tool_radius, cancel=cancel_at(0.85, "time column: refining rows"))
    else:
        timeline = period_rows(schedule, period)
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
        found = per_side(lambda side: check_limits(machine, tables[side]))
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

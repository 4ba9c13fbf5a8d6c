"""The planner: one staged chain from a blade to the machines' tables, used by the command line, the
workbench's re-plan and its export alike.

Stages, in the paper's order: blade (load the source) -> paths (contour paths, double-curve
interpolation, alignment: sections 2-3) -> regions (section 4) -> schedule (the tool axes within the
heads' tilt, the seven steps of section 5, and the job timed for the machines on the controller's
period: core.machine.timing) -> tables (the axis tables and their limit check). The job is the same
whether or not its axis tables are asked for, so the workbench shows what the export writes.
``Planner`` keeps the last blade and the last paths with their regions, and is the one place that
knows what a parameter change invalidates (``STAGE_INPUTS``): an h_safe or k_max change divides the
kept paths into regions again, a change of mode, feed, a_max, profile, period, chord tolerance or
machine reuses the regions, and any other change plans the paths again. A caller hooks onto the
stages with a core.records.PlanListener (the writer's early files, the workbench's first display);
timings come back in the result as a record.
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from core.blade.model import Blade
from core.blade.source import load_blade
from core.budget import check_work
from core.errors import Cancelled, PathScheduleError, PlanningError
from core.machine.model import Machine, load_machine, machine_to_toml
from core.machine.optimum import Limits
from core.machine.postprocess import check_limits, machine_figures, machine_plan
from core.machine.timing import time_for_machines
from core.paths.planning import PathsJob, replan_regions
from core.paths.single_sided import to_single_sided
from core.records import (
    ENFORCED_LIMITS,
    PathPlan,
    PlanJob,
    PlanListener,
    PlanParameters,
    PlanResult,
    Progress,
)
from core.schedule.figures import figures
from core.schedule.safety import transition_paths
from core.schedule.steps import checked_schedule
from core.schedule.timeline import SafetyProfile
from core.util.parallel import per_side

#: the job's inputs each stage depends on (besides the stages before it): the one record of what a
#: change invalidates. 'params.x' names a PlanParameters field.
STAGE_INPUTS = {
    "blade": ("source", "axis"),
    "paths": ("params.tool_radius", "params.dr", "params.dd", "params.tool_length"),
    "regions": ("params.h_safe", "params.k_max"),
    "schedule": ("params.mode", "params.feed", "params.a_max", "params.min_feed", "profile", "period", "chord_tol",
                 "machine"),
}
STAGES = tuple(STAGE_INPUTS)


def _value(job: PlanJob, params: PlanParameters, name: str):
    return getattr(params, name[7:]) if name.startswith("params.") else getattr(job, name)


def stage_key(job: PlanJob, stage: str) -> tuple:
    """The inputs ``stage`` and every stage before it depend on (parameters resolved)."""
    params = job.params.resolved()
    key = []
    for name in STAGES[:STAGES.index(stage) + 1]:
        key += [_value(job, params, n) for n in STAGE_INPUTS[name]]
    return tuple(key)


def _sub(progress: Progress | None, lo: float, hi: float) -> Progress | None:
    if progress is None:
        return None
    return lambda f, msg: progress(lo + (hi - lo) * f, msg)


def _check(progress: Progress | None, fraction: float, message: str) -> None:
    if progress is not None and progress(fraction, message) is False:
        raise Cancelled()


def _cancel_at(progress: Progress | None, fraction: float, message: str):
    if progress is None:
        return None
    return lambda: progress(fraction, message) is False


class Planner:
    """Plans jobs (core.records.PlanJob) stage by stage, keeping what a next job may reuse.

    workers: processes for the path steps (forked; 1 plans them here). keep: keep each path's fitted
    curves (from the workers too), so that a later h_safe / k_max change can reuse the paths (the
    workbench); a one-shot plan (the command line) need not pay for bringing them back.
    safety_rounds: rounds of the collaborative schedule's self-check (core.schedule.steps); a path
    still unsafe after them is machined single-sided (core.paths.single_sided), at most
    single_sided_rounds times, so that a valid job gives a safe plan rather than a refusal.
    One Planner serves one thread at a time."""

    def __init__(self, workers: int = 1, keep: bool = False, safety_rounds: int = 8, single_sided_rounds: int = 4):
        if safety_rounds < 1 or single_sided_rounds < 0:
            raise ValueError("a planner needs at least one safety round")
        self.workers, self.keep_curves = workers, keep
        self.safety_rounds, self.single_sided_rounds = safety_rounds, single_sided_rounds
        self._blade: tuple[tuple, Blade] | None = None
        self._paths: tuple[tuple, PathPlan] | None = None
        self._early: tuple[tuple, PathsJob] | None = None
        #: the pairs turned within the machines' reach, by pair (core.machine.postprocess.machine_plan),
        #: for the machine and the paths' inputs they were made for
        self._reach: tuple[tuple, dict] | None = None

    @classmethod
    def seeded(cls, plan: PathPlan, source: str = "sample", axis: str = "z", workers: int = 1) -> Planner:
        """A planner that knows ``plan``'s blade, paths and regions already (as the inputs source, axis
        and plan.params): the workbench's export plans the shown paths for the machines this way."""
        planner = cls(workers, keep=plan.reuse is not None)
        planner.keep(plan, source, axis)
        return planner

    def keep(self, plan: PathPlan, source: str = "sample", axis: str = "z") -> None:
        """Keep ``plan``'s blade, paths and regions (as the inputs source, axis and plan.params) for
        the next jobs, in place of what was kept: the workbench, after showing a plan kept from
        before (an undo), plans the next edit from it."""
        self.cancel()
        job = PlanJob(source, axis, plan.params)
        self._blade = (stage_key(job, "blade"), plan.blade)
        self._paths = (stage_key(job, "regions"), plan)

    # -- stages ------------------------------------------------------------------------------------
    def blade(self, source: str, axis: str = "z") -> Blade:
        """The blade of ``source`` (kept: the same source is loaded once). BladeInputError."""
        key = (source, axis)
        if self._blade is None or self._blade[0] != key:
            self._blade = (key, load_blade(source, axis=axis))
            self._paths = None
        return self._blade[1]

    def reuse(self, job: PlanJob) -> str:
        """What planning ``job`` would take from the kept stages: 'schedule' (the paths and their
        regions), 'regions' (the paths, divided again) or 'none'."""
        if self._paths is None:
            return "none"
        kept, plan = self._paths
        if kept == stage_key(job, "regions"):
            return "schedule"
        if kept[:len(stage_key(job, "paths"))] == stage_key(job, "paths") and plan.reuse is not None:
            return "regions"
        return "none"

    def start(self, job: PlanJob, listener: PlanListener | None = None) -> None:
        """Load ``job``'s blade and start its paths in the worker processes at once (forked now), for a
        ``plan`` of the same job later: the workbench does this at launch, before Qt starts."""
        self.cancel()
        if self.reuse(job) != "none":
            return
        params = job.params.resolved()
        blade = self.blade(job.source, job.axis)
        formatter = listener.row_formatter if listener is not None else None
        self._early = (stage_key(job, "regions"), PathsJob(blade, params, self.workers, formatter, self.keep_curves))

    @property
    def started(self) -> PathsJob | None:
        """The paths started by ``start`` and not collected yet (None if there are none)."""
        return None if self._early is None else self._early[1]

    def cancel(self) -> None:
        """Stop path workers started by ``start`` and not yet collected."""
        early, self._early = self._early, None
        if early is not None:
            early[1].cancel()

    def paths(self, job: PlanJob, progress: Progress | None = None, listener: PlanListener | None = None
              ) -> tuple[PathPlan, str]:
        """(the paths with their regions for ``job``, what was reused: see ``reuse``)."""
        params = job.params.resolved()
        reused = self.reuse(job)
        if reused == "schedule":
            plan = self._paths[1]
            plan = replace(plan, params=params) if plan.params != params else plan
        elif reused == "regions":
            plan = replan_regions(self._paths[1], params, progress=progress)
        else:
            blade = self.blade(job.source, job.axis)
            early, self._early = self._early, None
            if early is not None and early[0] != stage_key(job, "regions"):
                early[1].cancel()
                early = None
            if early is None:
                formatter = listener.row_formatter if listener is not None else None
                early = (None, PathsJob(blade, params, self.workers, formatter, self.keep_curves))
            plan = early[1].result(progress)
        self._paths = (stage_key(job, "regions"), plan)
        return plan, reused

    # -- the whole chain ---------------------------------------------------------------------------
    def plan(self, job: PlanJob, progress: Progress | None = None, listener: PlanListener | None = None,
             until: str = "tables") -> PlanResult:
        """Plan ``job`` up to stage ``until`` ('paths' stops after the regions; 'tables' is the whole
        plan: the tool axes within the heads' reach, the schedule of params.mode timed for the machines
        on the controller's period (core.machine.timing), and with job.axes the axis tables).
        ``progress(fraction, message)`` returning False cancels (core.errors.Cancelled)."""
        if until not in ("paths", "tables"):
            raise PlanningError(f"a plan runs until 'paths' or 'tables', not {until!r}")
        listener = listener or PlanListener()
        params = job.params.resolved()  # bad inputs are refused before anything is loaded
        period = job.resolved_period()
        machine = load_machine(job.machine) if until == "tables" else None
        check_work(self.blade(job.source, job.axis), job, machine, until)  # (a runaway refused up front)
        paths, reused = self.paths(job, _sub(progress, 0.0, 0.6 if until == "tables" else 1.0), listener)
        listener.paths_ready(paths, reused)
        timings = paths.timings
        if until == "paths":
            return PlanResult(paths, job.source, job.axis, period, job.profile, timings=timings, reused=reused)
        return self._schedule(job, paths, params, period, machine, progress, listener, reused)

    def _prune_reach(self, paths: PathPlan) -> None:
        """Keep the pairs within reach only for the pairs the paths have or may take again (their
        symmetrical and tip-region pairs kept for an h_safe or K_max change)."""
        wanted = {id(p) for p in paths.pairs}
        for entry in paths.reuse or ():
            wanted.update(id(p) for p in entry[2:] if p is not None)
        kept = self._reach[1]
        for key in [k for k in kept if k not in wanted]:
            del kept[key]

    def _schedule(self, job: PlanJob, paths: PathPlan, p: PlanParameters, period: float, machine: Machine,
                  progress: Progress | None, listener: PlanListener, reused: str) -> PlanResult:
        _check(progress, 0.6, "schedule")
        t0 = time.perf_counter()
        chord_tol = job.resolved_chord_tol()
        # every cutting stretch and turn is timed on its own path for these limits (its time-optimal
        # profile); the machine clock then only checks the rows and slows where the rest needs it
        limits = Limits(machine, period, chord_tol, p.tool_radius, p.feed / 60000.0, p.a_max / 1e6)
        timed: dict = {}

        def on_the_machines(schedule) -> set[int]:
            """Time ``schedule`` for the machines and check the safety rule on their rows (at and
            between them): the paths round whose transitions it breaks."""
            _check(progress, 0.8, "machine timing")
            timing = time_for_machines(machine, schedule, period, p.tool_radius, p.a_max / 1e6, chord_tol,
                                       cancel=_cancel_at(progress, 0.85, "machine timing"))
            safety = SafetyProfile.of(timing.timeline, p.tool_radius, p.tool_length, p.h_safe)
            timed.update(schedule=schedule, timing=timing, safety=safety)
            tl = timing.timeline
            return transition_paths(tl.left.path[safety.unsafe], tl.right.path[safety.unsafe])

        key = (stage_key(job, "paths"), machine_to_toml(machine))
        if self._reach is None or self._reach[0] != key:
            self._reach = (key, {})
        for attempt in range(self.single_sided_rounds + 1):
            # tool axes within the heads' reach before anything is timed (the pairs done for an
            # earlier job of these paths and this machine are kept)
            planned, tilt_limited = machine_plan(paths, machine, self._reach[1])
            self._prune_reach(paths)
            try:
                schedule, _, unsafe = checked_schedule(
                    planned, p.mode, p.feed, p.a_max, job.profile, period, max_rounds=self.safety_rounds,
                    cancel=_cancel_at(progress, 0.7, "schedule: safety rounds"), whole_job=on_the_machines,
                    limits=limits)
            except PathScheduleError as exc:
                # a speed stage that cannot keep a_max on its path's variable region: that path is
                # machined single-sided (as the tip region's), and the schedule is built again
                if p.mode != "collaborative" or attempt == self.single_sided_rounds:
                    raise
                paths = to_single_sided(paths, exc.paths, "its speed stage cannot keep a_max (a variable "
                                        "region too short for the feed)")
                continue
            if timed.get("schedule") is not schedule:  # (the other modes: not checked, timed here)
                on_the_machines(schedule)
            if not unsafe or attempt == self.single_sided_rounds or p.mode != "collaborative":
                break
            # a path whose transitions the synchronisation margins cannot make safe is machined
            # single-sided (as the tip region's), and the schedule is built again
            paths = to_single_sided(paths, unsafe, "the collaborative schedule broke the safety rule round it "
                                    f"after {self.safety_rounds} rounds of synchronisation margins")
        timing, safety = timed["timing"], timed["safety"]
        timeline, warp, tables = timing.timeline, timing.warp, timing.tables
        t1 = time.perf_counter()
        listener.timeline_ready(timeline, schedule, warp, tables if job.axes else None)
        fig = figures(timeline, planned, schedule, safety)
        found = per_side(lambda side: check_limits(machine, tables[side]))
        findings = found["left"] + found["right"]
        fig["machine"] = machine_figures(machine, warp, tables, findings, tilt_limited, schedule.duration / 1000.0,
                                         ENFORCED_LIMITS)
        fig["machine"]["chord"] = timing.chord
        if timing.chord["largest_deviation_mm"] > chord_tol:  # (the rounds of the clock's check ran out)
            paths = replace(paths, warnings=[*paths.warnings, (
                f"a straight line between two rows strays {timing.chord['largest_deviation_mm']:.4g} mm from the "
                f"planned path at t = {timing.chord['largest_deviation_at_ms']:.0f} ms, beyond the chord tolerance "
                f"{chord_tol:g} mm: lower the period (--period-ms) or raise --chord-tol")])
        timings = paths.timings.plus(schedule_s=t1 - t0, figures_s=time.perf_counter() - t1)
        if progress is not None:
            progress(1.0, "plan done")
        return PlanResult(plan=paths, source=job.source, axis=job.axis, period=period, profile=job.profile,
                          schedule=schedule, reused=reused, timeline=timeline, figures=fig, machine=machine,
                          axes=tables if job.axes else None, limit_findings=findings, warp=warp, safety=safety,
                          timings=timings)


def cutter_speeds(result: PlanResult, side: str, t: np.ndarray) -> np.ndarray:
    """(m,) mm/ms: a cutter's tip speed along its path at times t (m,) ms of the result's time column
    (the machine clock)."""
    return result.schedule.speeds(side, result.warp.to_schedule_time(t)) * result.warp.rate(t)

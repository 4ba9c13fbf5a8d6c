"""The planner: one staged chain from a blade to the machines' tables, used by the command line, the
workbench's re-plan and its export alike.

Stages, in the paper's order: blade (load the source) -> paths (contour paths, double-curve
interpolation, alignment: sections 2-3) -> regions (section 4) -> schedule (the tool axes within the
heads' tilt, the seven steps of section 5, and the job timed for the machines on the controller's
period: core.machine.timing) -> tables (the axis tables and their limit check). The job is the same
whether or not its axis tables are asked for, so the workbench shows what the export writes.
``Planner`` owns the one cache of a plan's stages (``StageCache``: the last blade, the last paths with
their regions, the pairs within the machines' reach), each kept with the explicit key of the inputs it
was made from, and is the one place that knows what a parameter change invalidates (``STAGE_INPUTS``):
an h_safe or k_max change divides the kept paths into regions again, a change of mode, feed, a_max,
profile, period, chord tolerance or machine reuses the regions, and any other change plans the paths
again. The stage functions it calls are pure: arrays in, results out. A caller hooks onto the
stages with a core.result.PlanListener (the writer's early files, the workbench's first display);
timings come back in the result as a record.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from core.blade.model import Blade
from core.blade.source import load_blade
from core.budget import check_work
from core.errors import PathScheduleError, PlanningError
from core.machine.clearance import least_clearance
from core.machine.collisions import blade_index, plan_collisions
from core.machine.job_figures import job_figures
from core.machine.model import Machine, load_machine, machine_to_toml
from core.machine.reach import within_reach
from core.machine.tables import check_limits, machine_figures
from core.machine.timing import MachineTiming, time_for_machines
from core.machine.tool import Tool, assembly, resolve_tool
from core.paths.plan import PathPlan
from core.paths.planning import PathsJob, replan_regions
from core.paths.single_sided import to_single_sided
from core.paths.tessellation import TriangleIndex
from core.records import (
    ENFORCED_LIMITS,
    PlanJob,
    PlanParameters,
    Progress,
    cancel_at,
    check_progress,
    default_period,
    sub_progress,
)
from core.result import PlanListener, PlanResult
from core.schedule.figures import figures
from core.schedule.safety import transition_paths
from core.schedule.steps import Schedule, ScheduleMemory, ScheduleOptions, checked_schedule
from core.schedule.timeline import SafetyProfile
from core.util.parallel import per_side

#: the job's inputs each stage depends on (besides the stages before it): the one record of what a
#: change invalidates. 'params.x' names a PlanParameters field.
STAGE_INPUTS = {
    "blade": ("source", "axis"),
    "paths": ("params.tool_radius", "params.dr", "params.dd", "params.tool_length"),
    "regions": ("params.h_safe", "params.k_max"),
    "schedule": ("params.mode", "params.feed", "params.a_max", "params.min_feed", "profile", "period", "chord_tol",
                 "machine", "tool"),
}
STAGES = tuple(STAGE_INPUTS)
#: a plan on a period longer than the default warns when its job on the machine clock takes more than
#: this many times the schedule's own time (the feed cut for the rows' sake: 1.4 at --dr 8 on the
#: default period, 56 at --period-ms 100)
SLOW_PERIOD_WARN = 3.0


def _value(job: PlanJob, params: PlanParameters, name: str):
    return getattr(params, name[7:]) if name.startswith("params.") else getattr(job, name)


def stage_key(job: PlanJob, stage: str) -> tuple:
    """The inputs ``stage`` and every stage before it depend on (parameters resolved)."""
    params = job.params.resolved()
    key = []
    for name in STAGES[:STAGES.index(stage) + 1]:
        key += [_value(job, params, n) for n in STAGE_INPUTS[name]]
    return tuple(key)


class StageCache:
    """The planner's one cache: per stage ('blade', 'paths': the paths with their regions, 'reach':
    the pairs within the machines' reach by core.machine.reach.pair_key, 'mesh': the blade's mesh the
    tool assembly is checked against), the last value with the key of the inputs it was made from
    (``stage_key``)."""

    def __init__(self) -> None:
        self._slots: dict[str, tuple[tuple, Any]] = {}  # (a blade, a PathPlan, pairs by key)

    def get(self, stage: str, key: tuple) -> Any:
        """The value kept for ``stage`` if it was made for ``key``, else None."""
        slot = self._slots.get(stage)
        return slot[1] if slot is not None and slot[0] == key else None

    def slot(self, stage: str) -> tuple[tuple, Any] | None:
        """(key, value) kept for ``stage``, whatever its key (None when nothing is kept)."""
        return self._slots.get(stage)

    def put(self, stage: str, key: tuple, value: Any) -> Any:
        self._slots[stage] = (key, value)
        return value

    def drop(self, stage: str) -> None:
        self._slots.pop(stage, None)

    def clear(self) -> None:
        self._slots.clear()


class _MachineCheck:
    """The whole-job check of a schedule on the machines' rows (checked_schedule's ``whole_job``):
    times the schedule for the machines (core.machine.timing) and checks the safety rule at and
    between their rows; keeps the last schedule it timed with its timing and safety profile."""

    def __init__(self, machine: Machine, params: PlanParameters, period: float, chord_tol: float,
                 progress: Progress | None):
        self.machine, self.params, self.period, self.chord_tol = machine, params, period, chord_tol
        self.progress = progress
        self.schedule: Schedule | None = None
        self.timing: MachineTiming | None = None
        self.safety: SafetyProfile | None = None

    def __call__(self, schedule: Schedule) -> set[int]:
        """The paths round whose transitions ``schedule``, timed for the machines, breaks the rule."""
        p = self.params
        check_progress(self.progress, 0.8, "machine timing")
        timing = time_for_machines(self.machine, schedule, self.period, p.tool_radius, p.a_max / 1e6,
                                   self.chord_tol, cancel=cancel_at(self.progress, 0.85, "machine timing"))
        safety = SafetyProfile.of(timing.timeline, p.tool_radius, p.tool_length, p.h_safe)
        self.schedule, self.timing, self.safety = schedule, timing, safety
        tl = timing.timeline
        return transition_paths(tl.left.path[safety.unsafe], tl.right.path[safety.unsafe])


@dataclass(frozen=True)
class ScheduleRound:
    """One round of the planner's schedule step: the paths within the machines' reach and the points
    their tilt limit changed per side, the schedule timed for the machines (None when a speed stage
    failed: ``error``), and the paths that failed with why (they go single-sided next round)."""

    planned: PathPlan
    tilt_limited: dict[str, int]
    schedule: Schedule | None
    failed: set[int]
    reason: str
    error: PathScheduleError | None = None


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
        self.cache = StageCache()
        #: seconds the single-sided axes' clearance callable took (both sides' threads summed), this plan
        self.clearance_s = 0.0
        #: the paths started by ``start`` (forked workers at work, not a cached value), with their key
        self._early: tuple[tuple, PathsJob] | None = None

    @classmethod
    def seeded(cls, plan: PathPlan, source: str = "sample", axis: str = "z", workers: int = 1) -> Planner:
        """A planner that knows ``plan``'s blade, paths and regions already (as the inputs source, axis
        and plan.params)."""
        planner = cls(workers, keep=plan.reuse is not None)
        planner.keep(plan, source, axis)
        return planner

    def keep(self, plan: PathPlan, source: str = "sample", axis: str = "z") -> None:
        """Keep ``plan``'s blade, paths and regions (as the inputs source, axis and plan.params) for
        the next jobs, in place of what was kept: the workbench, after showing a plan kept from
        before (an undo), plans the next edit from it."""
        self.cancel()
        job = PlanJob(source, axis, plan.params)
        self.cache.put("blade", stage_key(job, "blade"), plan.blade)
        self.cache.put("paths", stage_key(job, "regions"), plan)

    def release(self) -> None:
        """Forget every stage kept (the blade, its paths, its index, the pairs within reach), for a
        caller that plans no more: their memory goes to what it does next."""
        self.cache.clear()

    # -- stages ------------------------------------------------------------------------------------
    def blade(self, source: str, axis: str = "z") -> Blade:
        """The blade of ``source`` (kept: the same source is loaded once). BladeInputError."""
        key = (source, axis)
        blade = self.cache.get("blade", key)
        if blade is None:
            self.cache.drop("paths")
            blade = self.cache.put("blade", key, load_blade(source, axis=axis))
        return blade

    def reuse(self, job: PlanJob) -> str:
        """What planning ``job`` would take from the kept stages: 'schedule' (the paths and their
        regions), 'regions' (the paths, divided again) or 'none'."""
        slot = self.cache.slot("paths")
        if slot is None:
            return "none"
        kept, plan = slot
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
        kept = self.cache.slot("paths")
        if reused == "schedule":
            plan = kept[1]
            plan = replace(plan, params=params) if plan.params != params else plan
        elif reused == "regions":
            plan = replan_regions(kept[1], params, progress=progress)
        else:
            blade = self.blade(job.source, job.axis)
            early, self._early = self._early, None
            if early is not None and early[0] != stage_key(job, "regions"):
                early[1].cancel()
                early = None
            if early is None:
                formatter = listener.row_formatter if listener is not None else None
                early = (None, PathsJob(blade, params, self.workers, formatter, self.keep_curves))
            plan = early[1].result(progress, listener.paths_chunk if listener is not None else None)
        self.cache.put("paths", stage_key(job, "regions"), plan)
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
        if machine is not None:  # (a tool file that disagrees or does not fit is refused up front)
            assembly(job_tool(job), machine)
        check_work(self.blade(job.source, job.axis), job, machine, until)  # (a runaway refused up front)
        paths, reused = self.paths(job, sub_progress(progress, 0.0, 0.6 if until == "tables" else 1.0), listener)
        listener.paths_ready(paths, reused)
        timings = paths.timings
        if until == "paths":
            return PlanResult(paths, job.source, job.axis, period, job.profile, timings=timings, reused=reused)
        return self._schedule(job, paths, params, period, machine, progress, listener, reused)

    def _within_reach(self, job: PlanJob, paths: PathPlan, machine: Machine
                      ) -> tuple[PathPlan, dict[str, int]]:
        """``paths`` with the tool axes within the heads' reach (core.machine.reach), the single-sided
        paths' axes turned clear of the blade where the tool assembly above the flutes would touch it
        (its least clearance, core.machine.clearance.least_clearance, both sides alike; the flutes sit
        next to the blade wherever the ball cuts and are the rows' check's), the pairs done for
        an earlier job of these paths' inputs, this machine and this tool taken from the cache."""
        tool = job_tool(job)
        key = (stage_key(job, "paths"), machine_to_toml(machine), tool)
        above = tuple(p for p in assembly(tool, machine) if p.name != "flute")  # (the flutes cut: not turned for)
        least = least_clearance(above, self.blade_mesh(job, paths))

        def timed(centres: np.ndarray, axes: np.ndarray) -> np.ndarray:
            t0 = time.perf_counter()
            try:
                return least(centres, axes)
            finally:
                self.clearance_s += time.perf_counter() - t0

        planned, tilt_limited, reached = within_reach(paths, machine, self.cache.get("reach", key),
                                                      clearance=lambda side: timed)
        self.cache.put("reach", key, reached)
        return planned, tilt_limited

    def blade_mesh(self, job: PlanJob, paths: PathPlan) -> TriangleIndex:
        """The blade index (core.machine.collisions.blade_index): the one the moves in the air, the tool
        axes' clearance and the whole-tool check ask, kept for the blade it was made for (its
        tessellation and its compiled search depend on the blade alone)."""
        key = stage_key(job, "blade")
        index = self.cache.get("mesh", key)
        return index if index is not None else self.cache.put("mesh", key, blade_index(paths))

    def schedule_round(self, job: PlanJob, paths: PathPlan, machine: Machine, options: ScheduleOptions,
                       check: _MachineCheck, memory: ScheduleMemory, progress: Progress | None) -> ScheduleRound:
        """Machine reach, then the schedule, then its timing for the machines and the safety check on
        their rows: the round's schedule and the paths that failed (a speed stage that cannot keep
        a_max on its path's variable region, or transitions the synchronisation margins cannot make
        safe). ``memory``: what the rounds before found (core.schedule.steps.ScheduleMemory: the
        synchronisation margins and per-pair figures, grown in place)."""
        planned, tilt_limited = self._within_reach(job, paths, machine)
        try:
            schedule, _, unsafe = checked_schedule(
                planned, options, whole_job=check, cancel=cancel_at(progress, 0.7, "schedule: safety rounds"),
                memory=memory)
        except PathScheduleError as exc:
            return ScheduleRound(planned, tilt_limited, None, set(exc.paths), "its speed stage cannot keep "
                                 "a_max (a variable region too short for the feed)", exc)
        if check.schedule is not schedule:  # (the other modes: not checked, timed here)
            check(schedule)
        return ScheduleRound(planned, tilt_limited, schedule, set(unsafe), "the collaborative schedule broke "
                             "the safety rule round it with every synchronisation "
                             "margin tried")

    def _schedule(self, job: PlanJob, paths: PathPlan, p: PlanParameters, period: float, machine: Machine,
                  progress: Progress | None, listener: PlanListener, reused: str) -> PlanResult:
        check_progress(progress, 0.6, "schedule")
        t0 = time.perf_counter()
        self.clearance_s = 0.0
        chord_tol = job.resolved_chord_tol()
        check = _MachineCheck(machine, p, period, chord_tol, progress)
        options = ScheduleOptions(p.mode, p.feed, p.a_max, job.profile, period, self.safety_rounds, p.min_feed)
        # (a round after some paths went single-sided starts from the last's)
        memory = ScheduleMemory(index=self.blade_mesh(job, paths))
        for attempt in range(self.single_sided_rounds + 1):
            rnd = self.schedule_round(job, paths, machine, options, check, memory, progress)
            last = attempt == self.single_sided_rounds or p.mode != "collaborative"
            if rnd.error is not None and (last or not rnd.failed):
                raise rnd.error
            if not rnd.failed or last:
                break
            # a path the schedule cannot keep safe, or whose speed stage cannot keep a_max, is machined
            # single-sided (as the tip region's), and the schedule is built again
            paths = to_single_sided(paths, rnd.failed, rnd.reason)
            memory.forget(rnd.failed)
        planned, tilt_limited, schedule = rnd.planned, rnd.tilt_limited, rnd.schedule
        timing, safety = check.timing, check.safety
        timeline, warp, tables = timing.timeline, timing.warp, timing.tables
        t1 = time.perf_counter()
        listener.timeline_ready(timeline, schedule, warp, tables if job.axes else None)
        fig = figures(timeline, planned, schedule, safety)
        found = per_side(lambda side: check_limits(machine, tables[side]))
        findings = found["left"] + found["right"]
        fig["machine"] = machine_figures(machine, warp, tables, findings, tilt_limited, schedule.duration / 1000.0,
                                         ENFORCED_LIMITS)
        fig["machine"]["chord"] = timing.chord
        fig["job"] = job_figures(schedule, timeline, warp, p.min_feed)
        if timing.chord["largest_deviation_mm"] > chord_tol:  # (the rounds of the clock's check ran out)
            paths = replace(paths, warnings=[*paths.warnings, (
                f"a straight line between two rows strays {timing.chord['largest_deviation_mm']:.4g} mm from the "
                f"planned path at t = {timing.chord['largest_deviation_at_ms']:.0f} ms, beyond the chord tolerance "
                f"{chord_tol:g} mm: lower the period (--period-ms) or raise --chord-tol")])
        at_feed, total = schedule.duration / 1000.0, fig["total_time_s"]
        if period > default_period(p) and total > SLOW_PERIOD_WARN * at_feed:  # (a period too long)
            paths = replace(paths, warnings=[*paths.warnings, (
                f"the job takes {total / 60:.1f} min on the machines, {total / at_feed:.0f} times its "
                f"{at_feed / 60:.1f} min at the schedule's speeds: a row every {period:g} ms is too far "
                f"apart for the chord tolerance {chord_tol:g} mm (it alone slows "
                f"{timing.chord['feed_cut_for_it_s'] / 60:.1f} min of it) and the axes' accelerations "
                f"between rows, so the feed is cut. Lower the period (--period-ms; default dd at the feed, "
                f"{default_period(p):.3g} ms) or raise --chord-tol")])
        t2 = time.perf_counter()
        check_progress(progress, 0.95, "collision check")
        tool = job_tool(job)
        clearance = plan_collisions(planned, timeline, tool, machine, self.blade_mesh(job, paths))
        fig["collisions"] = clearance.figures()
        timings = paths.timings.plus(schedule_s=t1 - t0, figures_s=t2 - t1, collisions_s=time.perf_counter() - t2,
                                     axes_clearance_s=self.clearance_s)
        if progress is not None:
            progress(1.0, "plan done")
        return PlanResult(plan=paths, source=job.source, axis=job.axis, period=period, profile=job.profile,
                          schedule=schedule, reused=reused, timeline=timeline, figures=fig, machine=machine,
                          axes=tables if job.axes else None, limit_findings=findings, warp=warp, safety=safety,
                          timings=timings, tool=tool, clearance=clearance)


def job_tool(job: PlanJob) -> Tool:
    """The tool assembly of ``job`` (core.machine.tool.resolve_tool: its tool file, or the shipped
    assembly with the parameters' tool radius and length)."""
    p = job.params.resolved()
    return resolve_tool(job.tool, p.tool_radius, p.tool_length)


def cutter_speeds(result: PlanResult, side: str, t: np.ndarray) -> np.ndarray:
    """(m,) mm/ms: a cutter's tip speed along its path at times t (m,) ms of the result's time column
    (the machine clock)."""
    return result.schedule.speeds(side, result.warp.to_schedule_time(t)) * result.warp.rate(t)

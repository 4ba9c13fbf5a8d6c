"""A whole plan: ``PlanResult`` (made by core.planner.Planner, written by core.output.writer) and the
``PlanListener`` a caller hooks onto a plan's stages (core.output.writer's early files, the workbench's
first display)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from core.paths.plan import PathPlan
from core.records import ENFORCED_LIMITS, Timings

if TYPE_CHECKING:  # (types only: the record never imports the stages that fill it)
    from core.machine.collisions import ClearanceProfile
    from core.machine.model import Machine
    from core.machine.tables import AxisTable, LimitFinding, TimeWarp
    from core.machine.tool import Tool
    from core.schedule.steps import Schedule
    from core.schedule.timeline import SafetyProfile, Timeline


@dataclass(frozen=True)
class PlanResult:
    """A whole plan: the geometric plan, and (unless paths-only) its schedule, the common time column
    with both cutters sampled on it (the machine clock's rows), the figures plan.json reports, the
    machines' limit findings and the clock's time warp, and the axis tables when asked for. Made by
    core.planner.Planner; written by core.output.writer.

    reused: what the planner took from an earlier plan ('none', 'regions': the paths, with new
    regions; 'schedule': the paths and their regions)."""

    plan: PathPlan
    source: str
    axis: str
    period: float
    profile: str = "sigmoid"
    schedule: Schedule | None = None   # on the machine's reachable axes
    timeline: Timeline | None = None
    figures: dict | None = None
    machine: Machine | None = None
    axes: dict[str, AxisTable] | None = None  # by side
    limit_findings: list[LimitFinding] = field(default_factory=list)
    warp: TimeWarp | None = None       # timeline time -> schedule time
    safety: SafetyProfile | None = None  # of the time column
    timings: Timings = field(default_factory=Timings)
    reused: str = "none"
    tool: Tool | None = None           # the tool assembly both machines carry
    clearance: ClearanceProfile | None = None  # the whole-tool collision check of the time column

    @property
    def collisions(self) -> list:
        """The collision stretches of the tool assemblies and heads (empty without a check)."""
        return [] if self.clearance is None else self.clearance.collisions

    @property
    def blocking_findings(self) -> list:
        """The limit findings that stop an export without --force (kinds in ENFORCED_LIMITS)."""
        return [f for f in self.limit_findings if f.kind in ENFORCED_LIMITS]

    @property
    def safe(self) -> bool:
        """True unless the figures count a tip-spacing or capsule violation."""
        f = self.figures or {}
        return not (f.get("spacing_violations") or f.get("capsule_violations"))


class PlanListener:
    """What a caller hooks onto a plan's stages (each hook is called in the planning thread, and does
    nothing here): ``row_formatter(pairs, regions) -> [bytes]`` formats pairs.csv's rows inside the
    path workers when set; ``paths_chunk(pairs, regions)`` as each chunk of newly planned paths
    arrives, with that chunk's pairs and region divisions (some of the plan's paths, in no particular
    order: a first look at them; never called for reused paths); ``paths_ready(plan, reused)`` once
    the paths and their regions exist;
    ``timeline_ready(timeline, schedule, warp, tables)`` as soon as the final time column exists (warp:
    the machine clock's TimeWarp; tables: the axis tables by side, None when the job does not keep
    them), before the figures are computed."""

    row_formatter: Callable[..., list[bytes]] | None = None

    def paths_chunk(self, pairs: list, regions: list) -> None:
        pass

    def paths_ready(self, plan: PathPlan, reused: str) -> None:
        pass

    def timeline_ready(self, timeline: Timeline, schedule: Schedule, warp: TimeWarp,
                       tables: dict[str, AxisTable] | None) -> None:
        pass

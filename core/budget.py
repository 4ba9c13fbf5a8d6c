"""The work budget of a plan: its work estimated before any planning (contour points from a few of the
blade's sections, rows of the time column from the feed, the machines' speed limits and the period),
and a job past the budget refused with the numbers and what to change. core.planner.Planner checks
every job, from the command line and the workbench alike."""

from __future__ import annotations

import math

from core.blade.extent import path_extent
from core.blade.model import Blade
from core.errors import PlanningError
from core.machine.model import Machine
from core.records import PlanJob, default_period

#: the work a plan may take on, from an estimate made before planning (``check_work``): contour points
#: of one side over all paths (the path steps' work, ~272,000 at the defaults, measured 298,000) and
#: rows of the time column (the schedule's and the tables' work, ~544,000 at the defaults, measured
#: 583,000 period rows refined to 754,000: 1.5 GB at the peak, 420 MB of files, 10 s). Both budgets are
#: 7.3 times the defaults' estimate. Measured at --dd 0.05 (2.2 million rows estimated, 2.8 million
#: written): 5.0 GB at the peak, 1.6 GB of files, 60 s; a plan at the budget takes about 9 GB, 3 GB of
#: files and 2 minutes.
POINTS_BUDGET = 2_000_000
ROWS_BUDGET = 4_000_000
#: the estimate's job time is this many times one cutter's cutting length at the feed (the tip region's
#: paths are cut one side after the other; turns and speed stages): 6.5e6 ms at the defaults, measured 7.0e6
TIME_FACTOR = 2.0
#: the default dd (mm) that the message compares with, to name the parameter to change
DEFAULT_DD = 0.2


def _tip_speed(machine: Machine) -> tuple[float, str]:
    """(mm/s, the axis): the speed a tool tip of ``machine`` (core.machine.model.Machine) keeps along its
    paths within the axis speed limits, estimated: a contour path runs along all three stage axes (chord,
    pitch, thickness), so the slowest stage axis holds the tip to about sqrt(3) times its limit; the legs
    tilt the tool through the head's lever (gauge length over the platform radius)."""
    lim = machine.limits
    axis = min(("x", "y", "z"), key=lambda a: lim.axis(a).max_speed_mm_s)
    leg = min(("d1", "d2", "d3"), key=lambda a: lim.axis(a).max_speed_mm_s)
    stage = math.sqrt(3.0) * lim.axis(axis).max_speed_mm_s
    legs = math.sqrt(3.0) * lim.axis(leg).max_speed_mm_s * machine.gauge_length / machine.platform_radius
    return (stage, axis) if stage <= legs else (legs, leg)


def _size_problem(blade: Blade, job: PlanJob, machine: Machine | None, until: str) -> str | None:
    """The first budget the job's estimated work exceeds, as a message that gives the numbers and
    what to change (None: within both budgets)."""
    p = job.params.resolved()
    ext = path_extent(blade, p.dr, p.dd)
    if ext is None:
        return None
    shape = (f"{ext.contours:,.0f} contour paths (dR = {p.dr:g} mm over the blade's {ext.span_mm:.4g} mm span), "
             f"each side about {ext.side_mm:.4g} mm long in steps of dd = {p.dd:g} mm")
    default_dr = p.tool_radius / 4
    if ext.points > POINTS_BUDGET:
        need = ext.points / POINTS_BUDGET
        if default_dr / p.dr >= DEFAULT_DD / p.dd and p.dr < default_dr:
            change = f"raise --dr to at least {p.dr * need:.3g} mm (default {default_dr:g}, a quarter tool radius)"
        elif p.dd < DEFAULT_DD:
            change = f"raise --dd to at least {p.dd * need:.3g} mm (default {DEFAULT_DD:g})"
        else:
            change = (f"the blade is large ({ext.span_mm:.4g} mm span): check its size and units, or raise --dr to "
                      f"{p.dr * need:.3g} mm or --dd to {p.dd * need:.3g} mm")
        return (f"this plan is too big to compute: about {ext.points:,.0f} contour points (budget "
                f"{POINTS_BUDGET:,}) from {shape}. To plan it, {change}")
    if until == "paths":
        return None
    period = job.resolved_period()
    speed = p.feed / 60.0  # mm/s
    v_machine, slowest = _tip_speed(machine) if machine is not None else (math.inf, "")
    v = min(speed, v_machine)
    time_ms = TIME_FACTOR * ext.points * p.dd / v * 1000.0
    rows = time_ms / period
    if rows <= ROWS_BUDGET:
        return None
    need = rows / ROWS_BUDGET
    own = default_period(p)
    if v_machine < speed and speed / v_machine >= own / period:
        slowest_speed = machine.limits.axis(slowest).max_speed_mm_s
        change = (f"the machine's axis speed limits ({slowest} at {slowest_speed:g} mm/s) "
                  f"hold a tool tip to about {v_machine:.3g} mm/s, below the feed ({speed:.3g} mm/s): raise the "
                  f"speed limits in the machine file ({job.machine or 'the default'}) about {need:.3g} times, or "
                  "plan --no-axes")
    elif period < own:
        change = (f"raise --period-ms to at least {period * need:.3g} ms (the default is dd at the feed: "
                  f"{own:.3g} ms)")
    elif p.dr < default_dr:
        change = f"raise --dr to at least {p.dr * need:.3g} mm (default {default_dr:g}, a quarter tool radius)"
    else:
        change = f"raise --period-ms to at least {period * need:.3g} ms, or --dr to {p.dr * need:.3g} mm"
    return (f"this plan is too big to compute: about {rows:,.0f} rows in the time column (budget {ROWS_BUDGET:,}): "
            f"a job of about {time_ms / 3.6e6:.3g} h at {v:.3g} mm/s, sampled every {period:.3g} ms, on {shape}. "
            f"To plan it, {change}")


def check_work(blade: Blade, job: PlanJob, machine: Machine | None = None, until: str = "tables") -> None:
    """Refuse (PlanningError) a job whose estimated work exceeds POINTS_BUDGET contour points or, for a
    whole plan, ROWS_BUDGET rows of the time column, before any planning: the estimate
    (core.blade.extent.path_extent on a few sections, the feed, the speed limits of ``machine``, the
    job's machines, the period) costs milliseconds, the runaway it stops hours and tens of GB."""
    problem = _size_problem(blade, job, machine, until)
    if problem is not None:
        raise PlanningError(problem)

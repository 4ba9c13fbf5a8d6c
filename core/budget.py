"""The work budget of a plan: its work estimated before any planning, and a job past the budget
refused with the numbers and what to change. core.planner.Planner checks every job, from the command
line and the workbench alike, in milliseconds, where the runaway it stops takes hours and tens of GB.

Every dimension of the work is estimated from a few of the blade's sections (core.blade.extent):
- contour points of one side over all paths (the path steps' work): dR, dd and the blade's size;
- the tool against the blade: a ball larger than the blade is thick leaves no path to machine from
  both sides and makes the gouge guard search the whole blade from far off;
- rows of the time column (the schedule's, the machine clock's and the tables' work): the job's
  length at the feed and the machines' speed limits over the period, and at least the rows the chord
  tolerance needs on the blade's curves whatever the period;
- the job's length on the machine clock: where a row may move only a chord's length on the curves
  and the period is long, the feed is cut to a crawl (``JOB_HOURS_BUDGET``);
- the machines' strokes: every section point's tool position within each axis's stroke, from the
  sections' outward normals as tool axes (``stroke_problem``), so that a blade too large for the
  machines, or one not centred on its hub, is refused before the plan, not after it.
What to change stays within the paper's ranges (dR at most a quarter tool radius, section 2); where no
value there fits, the message says so and names what else to change."""

from __future__ import annotations

import math

import numpy as np

from core.blade.extent import PathExtent, path_extent
from core.blade.frame import workpiece_frame
from core.blade.model import Blade
from core.errors import BladeInputError, MachineError, PlanningError
from core.machine.kinematics import inverse_kinematics
from core.machine.model import AXES, SIDES, Machine
from core.machine.reach import limit_tilt, spindle_direction
from core.records import FEED_RANGE, MAX_CHORD_TOL, PlanJob, PlanParameters, default_period

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
#: the rows the chord tolerance needs are TIME_FACTOR * CHORD_FACTOR times one side's estimate
#: (PathExtent.chord_rows, the sections' own curvature: 64,500 at the defaults; the tool axes' turning
#: through the head's lever, the turns and the clock's aim inside the tolerance add the rest): the
#: default plan at --period-ms 100 and 1000 has about 436,000 and 442,000 rows (jobs of 727 and
#: 7,364 min), 6.8 times the estimate. Coarse plans have more per path (--dr 8: 160,000 rows at 100 ms,
#: 8 times more per path), so the estimate stays below them
CHORD_FACTOR = 3.4
#: the longest job on the machine clock the budget allows (h), 11 times the defaults' 133 min: the
#: default plan at --period-ms 1000 (122 h estimated) ran past 500 s and 4 GB, --period-ms 1e5 out of
#: memory; at --period-ms 100 (12 h estimated) it plans
JOB_HOURS_BUDGET = 24.0
#: a ball whose radius is more than this many times the blade's largest section thickness is refused:
#: its h_safe (1-1.5 radii) exceeds every tip spacing, so no path is cut from both sides, and the
#: gouge guard searches the blade's tessellation from a ball centre far off it at every point
TOOL_THICKNESS_RATIO = 1.0
#: the default dd (mm) that the message compares with, to name the parameter to change
DEFAULT_DD = 0.2
#: sections whose points and outward normals estimate the machines' axis values (``stroke_problem``)
STROKE_SECTIONS = 9
#: the share of an axis's stroke an estimated value may pass it by before the job is refused up front:
#: the planned axes differ from the inner sections' normals (tilt limited, smoothed in the tip region):
#: the sample scaled to 600 and 800 mm diameter was estimated 44 and 43 mm beyond the x axis's travel
#: its plan used (253 and 345 mm, planned 209 and 302 mm); the plan's own check of every row refuses
#: what passes here, and names an off-centre blade too (core.output.writer)
STROKE_SLACK = 0.15
#: the share of a section's length at each end (the edges) left out of the estimate: the edges'
#: normals point along the span near the tip, where the planned axes do not
EDGE_SHARE = 0.1


def _tip_speed(machine: Machine) -> tuple[float, str]:
    """(mm/s, the axis): the speed a tool tip of ``machine`` (core.machine.model.Machine) keeps along its
    paths within the axis speed limits, estimated: a contour path runs along all three stage axes (chord,
    pitch, thickness), so the slowest stage axis holds the tip to about sqrt(3) times its limit; the legs
    tilt the tool through the head's lever (gauge length over the platform radius), at most about the
    leg's own speed (the tip moves with the platform where the lever is short)."""
    lim = machine.limits
    axis = min(("x", "y", "z"), key=lambda a: lim.axis(a).max_speed_mm_s)
    leg = min(("d1", "d2", "d3"), key=lambda a: lim.axis(a).max_speed_mm_s)
    stage = math.sqrt(3.0) * lim.axis(axis).max_speed_mm_s
    lever = max(machine.gauge_length / machine.platform_radius, 1.0)
    legs = math.sqrt(3.0) * lim.axis(leg).max_speed_mm_s * lever
    return (stage, axis) if stage <= legs else (legs, leg)


def _shape(p: PlanParameters, ext: PathExtent) -> str:
    return (f"{ext.contours:,.0f} contour paths (dR = {p.dr:g} mm over the blade's {ext.span_mm:.4g} mm "
            f"span), each side about {ext.side_mm:.4g} mm long in steps of dd = {p.dd:g} mm")


def _points_change(p: PlanParameters, ext: PathExtent) -> str:
    """What to change so that the contour points fit POINTS_BUDGET, within the paper's range of dR (at
    most a quarter tool radius) and the planner's of dd (at most 5 tool radii)."""
    need = ext.points / POINTS_BUDGET
    top_dr, top_dd = p.tool_radius / 4, 5 * p.tool_radius
    dr, dd = p.dr * need, p.dd * need
    options = []
    if dr <= top_dr:
        options.append(f"raise --dr to at least {dr:.3g} mm (at most {top_dr:g}, a quarter tool radius: the "
                       "paper's range)")
    if dd <= top_dd:
        options.append(f"raise --dd to at least {dd:.3g} mm (default {DEFAULT_DD:g})")
    if dr > top_dr:
        # the ball whose quarter radius, as dR, makes the points fit at this dd
        radius = 4.0 * ext.points * p.dr / POINTS_BUDGET
        options.append(f"no dR within the paper's range (at most a quarter tool radius, {top_dr:g} mm) "
                       f"fits at dd = {p.dd:g} mm: use a ball of radius at least {radius:.3g} mm "
                       "(--tool-radius) with dR = r/4")
    if dr > top_dr and dd > top_dd:
        options.append(f"the blade is large ({ext.span_mm:.4g} mm span): check its size and units")
    return "; or ".join(options)


def _rows_change(p: PlanParameters, job: PlanJob, rows: tuple[float, float],
                 machine_speed: tuple[float, str] | None) -> str:
    """What to change so that the rows fit ROWS_BUDGET: ``rows`` = (the job's length at the feed in ms,
    the rows the chord tolerance needs)."""
    options = []
    feed_ms, chord_rows = rows
    period, tol = job.resolved_period(), job.resolved_chord_tol()
    chord_bound = chord_rows >= feed_ms / period
    need = max(feed_ms / period, chord_rows) / ROWS_BUDGET
    if chord_bound and tol * need * need <= MAX_CHORD_TOL:
        options.append(f"raise --chord-tol to at least {tol * need * need:.3g} mm (the rows it needs go "
                       "as one over its square root)")
    elif chord_bound:
        options.append(f"no chord tolerance up to {MAX_CHORD_TOL:g} mm (--chord-tol) fits")
    else:
        own = default_period(p)
        if machine_speed is not None and machine_speed[0] < p.feed / 60.0:
            v, slowest = machine_speed
            options.append(f"the machine's axis speed limits ({slowest}) hold a tool tip to about "
                           f"{v:.3g} mm/s, below the feed ({p.feed / 60:.3g} mm/s): raise the speed limits "
                           f"in the machine file ({job.machine or 'the default'}) about {need:.3g} times")
        options.append(f"raise --period-ms to at least {feed_ms / ROWS_BUDGET:.3g} ms (the default is dd at "
                       f"the feed: {own:.3g} ms)")
        if p.feed * need <= FEED_RANGE[1] and (machine_speed is None or machine_speed[0] >= p.feed / 60.0):
            options.append(f"raise --feed to at least {p.feed * need:.4g} mm/min")
    top_dr = p.tool_radius / 4
    if p.dr * need <= top_dr:
        options.append(f"raise --dr to at least {p.dr * need:.3g} mm (at most {top_dr:g}, a quarter tool "
                       "radius)")
    return "; or ".join(options)


def _tool_problem(p: PlanParameters, ext: PathExtent) -> str | None:
    """A ball too large for the blade (TOOL_THICKNESS_RATIO)."""
    if ext.thickness_mm <= 0 or p.tool_radius <= TOOL_THICKNESS_RATIO * ext.thickness_mm:
        return None
    return (f"the ball (radius {p.tool_radius:g} mm) is larger than the blade is thick (at most about "
            f"{ext.thickness_mm:.3g} mm): h_safe = {p.h_safe:g} mm leaves no path to cut from both sides, "
            "and the gouge guard would search the whole blade from far off it. Use a ball of radius at most "
            f"{TOOL_THICKNESS_RATIO * ext.thickness_mm:.3g} mm (--tool-radius; the paper's is 1.5), or check "
            "the blade's size and units")


def _size_problem(blade: Blade, job: PlanJob, machine: Machine | None, until: str) -> str | None:
    """The first budget the job's estimated work exceeds, as a message that gives the numbers and
    what to change (None: within every budget)."""
    p = job.params.resolved()
    ext = path_extent(blade, p.dr, p.dd)
    if ext is None:
        return None
    if ext.points > POINTS_BUDGET:
        return (f"this plan is too big to compute: about {ext.points:,.0f} contour points (budget "
                f"{POINTS_BUDGET:,}) from {_shape(p, ext)}. To plan it, {_points_change(p, ext)}")
    tool = _tool_problem(p, ext)
    if tool is not None:
        return tool
    if until == "paths":
        return None
    period = job.resolved_period()
    tol = job.resolved_chord_tol()
    speed = p.feed / 60.0  # mm/s
    machine_speed = _tip_speed(machine) if machine is not None else None
    v = min(speed, machine_speed[0]) if machine_speed is not None else speed
    feed_ms = TIME_FACTOR * ext.points * p.dd / v * 1000.0
    chord_rows = TIME_FACTOR * CHORD_FACTOR * ext.chord_rows(tol)
    rows = max(feed_ms / period, chord_rows)
    time_ms = max(feed_ms, chord_rows * period)
    if rows > ROWS_BUDGET:
        chord_bound = chord_rows >= feed_ms / period
        why = (f"the chord tolerance {tol:g} mm needs a row every few hundredths of a millimetre on the "
               "blade's curves, whatever the period" if chord_bound else
               f"a job of about {time_ms / 3.6e6:.3g} h at {v:.3g} mm/s, sampled every {period:.3g} ms")
        count = f"about {rows:,.0f}" if rows < 1e15 else "more than 10^15"
        return (f"this plan is too big to compute: {count} rows in the time column (budget "
                f"{ROWS_BUDGET:,}): {why}, on {_shape(p, ext)}. To plan it, "
                f"{_rows_change(p, job, (feed_ms, chord_rows), machine_speed)}")
    if time_ms > JOB_HOURS_BUDGET * 3.6e6:
        step = math.sqrt(8.0 * tol * ext.side_mm)  # (a chord on a gentle curve of the blade's size)
        fits = JOB_HOURS_BUDGET * 3.6e6 / chord_rows
        return (f"this job is too long to time: about {time_ms / 3.6e6:,.0f} h on the machines (budget "
                f"{JOB_HOURS_BUDGET:g} h). A row every {period:.3g} ms may move the tool only as far as the "
                f"chord tolerance {tol:g} mm allows on the blade's curves (about {step:.2g} mm on a gentle "
                f"one, far less at the edges), where the feed moves it {speed * period / 1000:.3g} mm: the "
                f"feed is cut to a crawl. Lower --period-ms to at most {fits:.3g} ms (the default is "
                f"{default_period(p):.3g} ms), or raise --chord-tol")
    return None


def _section_points(blade: Blade, side_of: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(points (n, 3), outward normals (n, 3), radii (n,)) of the sections' face or back, blade frame,
    but for EDGE_SHARE of each section's length at either edge."""
    span = blade.tip_radius - blade.hub_radius
    pts, nrm, rad = [], [], []
    for k in range(STROKE_SECTIONS):
        r = blade.hub_radius + (k + 0.5) * span / STROKE_SECTIONS
        try:
            s = blade.section(float(r))
        except BladeInputError:
            continue
        p, n = (s.face, s.face_normals) if side_of == "face" else (s.back, s.back_normals)
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))]
        inner = (arc >= EDGE_SHARE * arc[-1]) & (arc <= (1 - EDGE_SHARE) * arc[-1])
        pts.append(p[inner])
        nrm.append(n[inner])
        rad.append(np.full(int(inner.sum()), r))
    if not pts:
        return np.empty((0, 3)), np.empty((0, 3)), np.empty(0)
    return np.concatenate(pts), np.concatenate(nrm), np.concatenate(rad)


def stroke_problem(blade: Blade, machine: Machine, tool_radius: float) -> str | None:
    """Why the blade cannot fit the machines' strokes (None: it may), estimated before planning: each
    side's section points (the back for the left machine, the face for the right: core.blade.frame)
    with their outward normals as tool axes, turned within the heads' tilt as the planner does
    (core.machine.postprocess.limit_tilt), through the inverse kinematics; an axis value beyond its
    stroke by more than STROKE_SLACK of it refuses the job. When the values' span fits the stroke but
    not where they lie, the blade is off-centre, and the message says so and by how much."""
    frame = workpiece_frame(blade)
    worst = None
    for side, surface in zip(SIDES, ("back", "face"), strict=True):
        pts, nrm, radii = _section_points(blade, surface)
        ok = np.isfinite(pts).all(axis=1) & np.isfinite(nrm).all(axis=1)
        if not ok.any():
            continue
        tips, axes = frame.points(pts[ok]), frame.vectors(nrm[ok])
        axes = axes / np.linalg.norm(axes, axis=1)[:, None]
        tips, axes, _ = limit_tilt(tips, axes, tool_radius, spindle_direction(machine, side),
                                   machine.max_tilt_deg)
        try:
            values = inverse_kinematics(machine, side, tips, axes)
        except MachineError:
            continue
        for j, name in enumerate(AXES):
            lim = machine.limits.axis(name)
            col = values[:, j]
            lo, hi = float(col.min()), float(col.max())
            excess = max(hi - lim.max_mm, lim.min_mm - lo)
            if excess > STROKE_SLACK * (lim.max_mm - lim.min_mm) and (worst is None or excess > worst[0]):
                far = int(np.argmax(col)) if hi - lim.max_mm >= lim.min_mm - lo else int(np.argmin(col))
                at = radii[ok][far]
                worst = (excess, side, name, lo, hi, lim, float(at))
    if worst is None:
        return None
    excess, side, name, lo, hi, lim, at = worst
    head = (f"the blade does not fit the machines' strokes: the {side} machine's {name} axis would need "
            f"about {lo:.1f} to {hi:.1f} mm (near r = {at:.0f} mm), its stroke is {lim.min_mm:g} to "
            f"{lim.max_mm:g} mm (machine file)")
    if hi - lo <= lim.max_mm - lim.min_mm:
        shift = 0.5 * (lim.min_mm + lim.max_mm - lo - hi)
        where = _where(blade)
        return (f"{head}. That travel fits the stroke, {abs(shift):.1f} mm off its middle: "
                + (f"the blade lies off-centre ({where}). Move the blade (its file's coordinates) or "
                   if where else "the machines are placed for another blade. Move ")
                + "the machines (origin_mm in the machine file, --machine) so that the blade sits in the "
                "middle of the strokes; checked before planning")
    return (f"{head}: {hi - lo:.1f} mm of travel where the stroke has {lim.max_mm - lim.min_mm:g}. Use a "
            "machine file with longer strokes (--machine), or check the blade's size and units; checked "
            "before planning")


def _where(blade: Blade) -> str:
    """Where the blade lies along its propeller axis, when away from the origin by more than half its
    mid-span chord (a mesh modelled off its hub's centre), as a clause; '' otherwise."""
    r = 0.5 * (blade.hub_radius + blade.tip_radius)
    try:
        s = blade.section(float(r))
    except BladeInputError:
        return ""
    z = float(np.mean(np.concatenate([s.face[:, 2], s.back[:, 2]])))
    chord = float(np.linalg.norm(s.face[0] - s.face[-1]))
    if not math.isfinite(z) or abs(z) <= 0.5 * chord:
        return ""
    return (f"its sections lie about {z:.0f} mm along the propeller axis from the origin, where a blade's "
            "hub centre belongs")


def check_work(blade: Blade, job: PlanJob, machine: Machine | None = None, until: str = "tables") -> None:
    """Refuse (PlanningError) a job whose estimated work exceeds a budget (module docstring), or
    whose blade does not fit ``machine``'s strokes, before any planning: the estimate
    (core.blade.extent.path_extent on a few sections, the feed, the speed limits of ``machine``, the
    job's machines, the period, the chord tolerance) costs milliseconds."""
    problem = _size_problem(blade, job, machine, until)
    if problem is None and machine is not None and until == "tables":
        problem = stroke_problem(blade, machine, job.params.resolved().tool_radius)
    if problem is not None:
        raise PlanningError(problem)

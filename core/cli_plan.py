"""``bladecam plan`` and ``bladecam verify``."""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

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


def _plan(args: argparse.Namespace) -> int:
    from core.errors import PlanningError
    from core.output.files import check_destination
    from core.output.writer import PlanWriter, unsafe_reason
    from core.planner import Planner
    from core.records import PlanJob, PlanParameters

    t0 = time.perf_counter()
    params = PlanParameters(tool_radius=args.tool_radius, dr=args.dr, dd=args.dd, h_safe=args.h_safe,
                            k_max=args.k_max, feed=args.feed, a_max=args.a_max, mode=args.mode)
    if args.machine is not None and not args.axes:
        raise PlanningError("--machine is used only for the machines' axis tables; drop --no-axes")
    check_destination(args.out)  # (refused before any planning, as atomic_folder would at the end)
    job = PlanJob(args.blade, args.axis, params, args.profile, args.period_ms, args.axes, args.machine)
    job.params.resolved()  # (bad parameters are refused before anything is loaded)
    job.resolved_period()
    planner = Planner(workers=args.workers)
    blade = planner.blade(job.source, job.axis)  # (kept by the planner: loaded once)
    for w in blade.warnings:
        print(f"warning: {w}", file=sys.stderr)
    check_work(blade, job, until="paths" if args.paths_only else "tables")
    with PlanWriter(args.out, args.workers) as writer:
        result = planner.plan(job, listener=writer, until="paths" if args.paths_only else "tables")
        out = writer.write(result, force=args.force)
    plan, fig = result.plan, result.figures
    counts = plan.region_counts()
    for w in plan.warnings:
        print(f"warning: {w}", file=sys.stderr)
    unsafe = unsafe_reason(result) if fig is not None else None
    if unsafe is not None:  # written only with --force
        print(f"warning: written with --force although {unsafe}", file=sys.stderr)
    if result.limit_findings:  # written only with --force (every kind refuses a plan: ENFORCED_LIMITS)
        kinds = sorted({f"{f.side} {f.axis} {f.kind}" for f in result.limit_findings})
        print(f"warning: written with --force although {len(kinds)} axis limits are exceeded (see plan.json "
              f"schedule.machine): {', '.join(kinds[:6])}{' ...' if len(kinds) > 6 else ''}", file=sys.stderr)
    head = f"planned {counts['paths']} paths ({counts['tip_paths']} in the tip region) on {plan.blade.name!r}; "
    if fig is None:
        print(head + f"wrote pairs.csv and plan.json to {out} in {time.perf_counter() - t0:.2f} s")
    else:
        print(head + f"{job.params.resolved().mode} schedule {fig['total_time_s'] / 60:.1f} min, minimum tip "
              f"spacing {fig['min_tip_spacing_mm']:.3f} mm, minimum clearance "
              f"{fig['min_capsule_clearance_mm']:.3f} mm; wrote {out} in {time.perf_counter() - t0:.2f} s")
    return 0


def _tip_speed(machine) -> tuple[float, str]:
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


def _size_problem(blade, job, until: str) -> str | None:
    """The first budget the job's estimated work exceeds, as a message that gives the numbers and
    what to change (None: within both budgets)."""
    from core.blade.extent import path_extent
    from core.machine.model import load_machine
    from core.records import default_period

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
    machine = load_machine(job.machine) if job.axes else None
    v_machine, slowest = _tip_speed(machine) if machine is not None else (math.inf, "")
    v = min(speed, v_machine)
    time_ms = TIME_FACTOR * ext.points * p.dd / v * 1000.0
    rows = time_ms / period
    if rows <= ROWS_BUDGET:
        return None
    need = rows / ROWS_BUDGET
    own = default_period(p)
    if v_machine < speed and speed / v_machine >= own / period:
        change = (f"the machine's axis speed limits ({slowest} at {machine.limits.axis(slowest).max_speed_mm_s:g} mm/s) "
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


def check_work(blade, job, until: str = "tables") -> None:
    """Refuse (PlanningError) a job whose estimated work exceeds POINTS_BUDGET contour points or, for a
    whole plan, ROWS_BUDGET rows of the time column, before any planning: the estimate
    (core.blade.extent.path_extent on a few sections, the feed, the machine's speed limits, the period)
    costs milliseconds, the runaway it stops hours and tens of GB."""
    from core.errors import PlanningError

    problem = _size_problem(blade, job, until)
    if problem is not None:
        raise PlanningError(problem)


def _verify(args: argparse.Namespace) -> int:
    from core.output.files import restore_plan
    from core.verify import verify

    t0 = time.perf_counter()
    hidden = restore_plan(os.path.abspath(args.dir))
    if hidden is not None:
        print(f"bladecam: restored {args.dir} from {hidden.name} (the previous plan, moved aside by a run "
              "that was killed while it replaced this folder)", file=sys.stderr)
    rep = verify(args.dir)
    for msg in rep.findings:
        print(msg)
    figs = ", ".join(f"{k} {v}" for k, v in rep.figures.items())
    state = "FAIL" if rep.findings else "ok"
    print(f"{state}: {len(rep.findings)} findings; {figs}; checked in {time.perf_counter() - t0:.2f} s")
    return 1 if rep.findings else 0


MAX_WORKERS = 64


def _workers(text: str) -> int:
    """--workers: a whole number from 1 to MAX_WORKERS."""
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number of processes, got {text!r}") from None
    if not 1 <= n <= MAX_WORKERS:
        raise argparse.ArgumentTypeError(f"must be from 1 to {MAX_WORKERS} processes, got {n}")
    return n


def add_commands(sub, add_blade_args) -> None:
    p = sub.add_parser("plan", help="plan the double-sided tool paths and write them to --out DIR")
    add_blade_args(p)
    p.add_argument("--tool-radius", type=float, default=1.5, metavar="MM", help="ball radius (default 1.5)")
    p.add_argument("--dr", type=float, default=None, metavar="MM", help="radius increment dR (default r/4)")
    p.add_argument("--dd", type=float, default=0.2, metavar="MM", help="interpolation step (default 0.2)")
    p.add_argument("--h-safe", type=float, default=None, metavar="MM",
                   help="minimum tip spacing (default 1.25 r)")
    p.add_argument("--k-max", type=float, default=0.15, metavar="X", help="maximum staggered ratio (0.15)")
    p.add_argument("--mode", default="collaborative", choices=("collaborative", "symmetric", "single"),
                   help="collaborative (default, the paper's), symmetric (unsafe preview) or single")
    p.add_argument("--feed", type=float, default=1000.0, metavar="MM_PER_MIN", help="feed (default 1000)")
    p.add_argument("--a-max", type=float, default=500.0, metavar="MM_PER_S2",
                   help="maximum acceleration along the path (default 500)")
    p.add_argument("--profile", default="sigmoid", choices=("sigmoid", "smooth"),
                   help="speed stages: the paper's sigmoid (default) or a jerk-limited smooth profile")
    p.add_argument("--period-ms", type=float, default=None, metavar="MS",
                   help="time step of the CL tables (default dd / feed)")
    p.add_argument("--paths-only", action="store_true",
                   help="stop after the paths: write pairs.csv and plan.json only (no schedule, no CL tables)")
    p.add_argument("--axes", action=argparse.BooleanOptionalAction, default=True,
                   help="plan for the two XYZ-3RPS machines (tool axes within the heads' tilt, feed slowed "
                        "where an axis would exceed its speed or acceleration limit) and write left_axes.csv, "
                        "right_axes.csv and machine.toml (the default); --no-axes: the CL tables only, timed "
                        "at the feed (faster; not for the machines)")
    p.add_argument("--machine", default=None, metavar="FILE",
                   help="machine.toml of the two machines (default: the shipped bench machine)")
    p.add_argument("--force", action="store_true",
                   help="write the plan even if it is unsafe or breaks a machine axis's stroke, speed or "
                        "acceleration limit")
    p.add_argument("--workers", type=_workers, default=min(os.cpu_count() or 1, 2), metavar="N",
                   help="processes for the path steps (default: 2, or 1 on a one-core machine)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (written atomically)")
    p.set_defaults(func=_plan)
    v = sub.add_parser("verify", help="re-check a written plan folder independently (exit 1 on a violation)",
                       description="Re-check a plan folder written by 'bladecam plan' without the planner's code: "
                                   "tip spacing, tool clearance, the cutting balls on the blade's offset surface, "
                                   "speeds and accelerations, and the machines' axis tables. Exit 0: clean; 1: "
                                   "findings (one per line); 2: not a readable plan folder.")
    v.add_argument("dir", metavar="DIR", help="the plan folder: the --out DIR of 'bladecam plan'")
    v.set_defaults(func=_verify)

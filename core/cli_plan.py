"""``bladecam plan`` and ``bladecam verify``."""

from __future__ import annotations

import argparse
import os
import sys
import time


def _plan(args: argparse.Namespace) -> int:
    from core.output.files import check_destination
    from core.output.writer import PlanWriter, unsafe_reason
    from core.planner import Planner
    from core.records import PlanJob, PlanParameters

    t0 = time.perf_counter()
    params = PlanParameters(tool_radius=args.tool_radius, dr=args.dr, dd=args.dd, h_safe=args.h_safe,
                            k_max=args.k_max, feed=args.feed, a_max=args.a_max, mode=args.mode,
                            min_feed=args.min_feed)
    check_destination(args.out)  # (refused before any planning, as atomic_folder would at the end)
    job = PlanJob(absolute_source(args.blade), args.axis, params, args.profile, args.period_ms, args.axes,
                  args.machine, args.chord_tol)
    job.params.resolved()  # (bad parameters are refused before anything is loaded)
    job.resolved_period()
    job.resolved_chord_tol()
    planner = Planner(workers=args.workers)
    blade = planner.blade(job.source, job.axis)  # (kept by the planner: loaded once; its warnings first)
    for w in blade.warnings:
        print(f"warning: {w}", file=sys.stderr)
    with PlanWriter(args.out, args.workers) as writer:
        result = planner.plan(job, progress=terminal_progress(), listener=writer,
                              until="paths" if args.paths_only else "tables")
        if sys.stderr.isatty():
            print("\r\033[K", end="", file=sys.stderr, flush=True)
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


def terminal_progress():
    """A progress callback that shows the stage and its share on one line of a terminal's stderr, at
    most five times a second (None when stderr is not a terminal: batch runs and logs stay clean)."""
    if not sys.stderr.isatty():
        return None
    last = [0.0]

    def show(fraction: float, message: str) -> bool:
        now = time.monotonic()
        if now - last[0] >= 0.2:
            last[0] = now
            print(f"\r\033[K{100 * fraction:3.0f} % {message}", end="", file=sys.stderr, flush=True)
        return True

    return show


def absolute_source(source: str) -> str:
    """--blade SOURCE with each of its files made absolute ('sample' as it is): plan.json records the
    source, and ``bladecam verify`` reloads the blade from it, from whatever folder it is run in."""
    if source.strip().lower() == "sample":
        return source
    return ",".join(os.path.abspath(part.strip()) for part in source.split(",") if part.strip())


def _verify(args: argparse.Namespace) -> int:
    from core.output.files import restore_plan
    from core.verify import verify

    t0 = time.perf_counter()
    hidden = restore_plan(os.path.abspath(args.dir))
    if hidden is not None:
        print(f"bladecam: restored {args.dir} from {hidden.name} (the previous plan, moved aside by a run "
              "that was killed while it replaced this folder)", file=sys.stderr)
    rep = verify(args.dir)
    for line in [*rep.findings, *rep.figure_lines(), rep.trusted]:  # (one finding per line, then figures)
        print(line)
    print(f"{rep.summary()}; checked in {time.perf_counter() - t0:.2f} s")
    return 1 if rep.total else 0


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
    p.add_argument("--min-feed", type=float, default=None, metavar="MM_PER_MIN",
                   help="the slowest a cutting cutter may run (chip thickness); the speed stages keep above it "
                        "and plan.json reports where the machines cannot (default 30 %% of the feed)")
    p.add_argument("--profile", default="sigmoid", choices=("sigmoid", "smooth"),
                   help="speed stages: the paper's sigmoid (default) or a jerk-limited smooth profile")
    p.add_argument("--period-ms", type=float, default=None, metavar="MS",
                   help="the controllers' period: every row of the CL and axis tables lies on t = k * period "
                        "(default dd / feed)")
    p.add_argument("--chord-tol", type=float, default=1e-3, metavar="MM",
                   help="how far the straight line between two rows may stray from the planned path; the feed "
                        "is slowed where the path turns too sharply for it (default 0.001)")
    p.add_argument("--paths-only", action="store_true",
                   help="stop after the paths: write pairs.csv and plan.json only (no schedule, no CL tables)")
    p.add_argument("--axes", action=argparse.BooleanOptionalAction, default=True,
                   help="write the two XYZ-3RPS machines' axis tables left_axes.csv, right_axes.csv and "
                        "machine.toml (the default); --no-axes: the CL tables only. The job is the same either "
                        "way: timed for the machines (tool axes within the heads' tilt, the feed slowed where an "
                        "axis would exceed its speed or acceleration limit)")
    p.add_argument("--machine", default=None, metavar="FILE",
                   help="machine.toml of the two machines the job is timed for (default: the shipped bench "
                        "machine)")
    p.add_argument("--force", action="store_true",
                   help="write the plan even if it is unsafe or breaks a machine axis's stroke, speed or "
                        "acceleration limit")
    p.add_argument("--workers", type=_workers, default=min(os.cpu_count() or 1, 2), metavar="N",
                   help="processes for the path steps (default: 2, or 1 on a one-core machine)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (written atomically)")
    p.set_defaults(func=_plan)
    v = sub.add_parser("verify", help="re-check a written plan folder independently (exit 1 on a violation)",
                       description="Re-check a plan folder written by 'bladecam plan' without the planner's code: "
                                   "its file set, tip spacing, tool clearance, the cutting balls on the blade's "
                                   "offset surface, speeds and accelerations, every pair point of pairs.csv cut by "
                                   "its cutter in order, and the machines' axis tables (forward kinematics, limits, "
                                   "velocities that are the derivative of the positions). plan.json's parameters "
                                   "and machine.toml are trusted as written (the report says so). Exit 0: clean; 1: "
                                   "findings (one per line, a few of each kind, then a summary that counts them "
                                   "all); 2: not a readable plan folder.")
    v.add_argument("dir", metavar="DIR", help="the plan folder: the --out DIR of 'bladecam plan'")
    v.set_defaults(func=_verify)

"""``bladecam plan`` (and later ``bladecam verify``)."""

from __future__ import annotations

import argparse
import os
import sys
import time


def _plan(args: argparse.Namespace) -> int:
    from .blade_source import load_blade
    from .errors import PlanningError
    from .export import cl_csv, pairs_rows, write_plan
    from .pipeline import PlanParameters, plan_paths
    t0 = time.perf_counter()
    params = PlanParameters(tool_radius=args.tool_radius, dr=args.dr, dd=args.dd, h_safe=args.h_safe,
                            k_max=args.k_max, feed=args.feed, a_max=args.a_max, mode=args.mode)
    p = params.resolved()  # refuse bad parameters before loading anything
    period = args.period_ms if args.period_ms is not None else p.dd / (p.feed / 60000.0)
    if not (period > 0 and period < 1e6):
        raise PlanningError(f"--period-ms must be a positive number of ms, got {args.period_ms}")
    blade = load_blade(args.blade, axis=args.axis)
    plan = plan_paths(blade, params, workers=args.workers, row_formatter=pairs_rows)
    if args.paths_only:
        out = write_plan(plan, args.out, args.blade, args.axis)
        counts = plan.region_counts()
        for w in plan.warnings:
            print(f"warning: {w}", file=sys.stderr)
        print(f"planned {counts['paths']} paths ({counts['tip_paths']} in the tip region) on {blade.name!r}; "
              f"wrote pairs.csv and plan.json to {out} in {time.perf_counter() - t0:.2f} s")
        return 0
    t1 = time.perf_counter()
    from .schedule import build_schedule
    from .timeline import figures, sample

    schedule = build_schedule(plan, p.mode, p.feed, p.a_max, args.profile, period)
    timeline = sample(schedule, period, p.tool_radius)
    fig = figures(timeline, plan, schedule)
    t2 = time.perf_counter()
    if p.mode == "collaborative" and (fig["spacing_violations"] or fig["capsule_violations"]) and not args.force:
        raise PlanningError(
            f"the collaborative schedule still breaks the safety rule (minimum tip spacing "
            f"{fig['min_tip_spacing_mm']:.4f} mm at t = {fig['min_tip_spacing_time_ms']:.0f} ms, h_safe = "
            f"{p.h_safe} mm; minimum capsule clearance {fig['min_capsule_clearance_mm']:.4f} mm); nothing "
            "was written. Raise k_max or h_safe, or give --force to write it anyway")
    files = {"left_cl.csv": cl_csv(timeline.t, timeline.left), "right_cl.csv": cl_csv(timeline.t, timeline.right)}
    t3 = time.perf_counter()
    plan.timings.update({"schedule_s": t2 - t1, "write_cl_s": t3 - t2})
    out = write_plan(plan, args.out, args.blade, args.axis, extra_files=files, summary_extra={"schedule": fig})
    counts = plan.region_counts()
    for w in plan.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"planned {counts['paths']} paths ({counts['tip_paths']} in the tip region) on {blade.name!r}; "
          f"{p.mode} schedule {fig['total_time_s'] / 60:.1f} min, minimum tip spacing "
          f"{fig['min_tip_spacing_mm']:.3f} mm, minimum clearance {fig['min_capsule_clearance_mm']:.3f} mm; "
          f"wrote {out} in {time.perf_counter() - t0:.2f} s")
    return 0


def _verify(args: argparse.Namespace) -> int:
    from .verify import verify

    t0 = time.perf_counter()
    rep = verify(args.dir)
    for msg in rep.findings:
        print(msg)
    figs = ", ".join(f"{k} {v}" for k, v in rep.figures.items())
    state = "FAIL" if rep.findings else "ok"
    print(f"{state}: {len(rep.findings)} findings; {figs}; checked in {time.perf_counter() - t0:.2f} s")
    return 1 if rep.findings else 0


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
    p.add_argument("--force", action="store_true", help="write a collaborative plan even if it is unsafe")
    p.add_argument("--workers", type=int, default=min(os.cpu_count() or 1, 2), metavar="N",
                   help="processes for the path steps (default: 2, or 1 on a one-core machine)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (written atomically)")
    p.set_defaults(func=_plan)
    v = sub.add_parser("verify", help="re-check a written plan folder independently (exit 1 on a violation)")
    v.add_argument("dir", metavar="DIR")
    v.set_defaults(func=_verify)

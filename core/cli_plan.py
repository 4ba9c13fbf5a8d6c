"""``bladecam plan`` (and later ``bladecam verify``)."""

from __future__ import annotations

import argparse
import os
import sys
import time


def _plan(args: argparse.Namespace) -> int:
    from .blade_source import load_blade
    from .export import pairs_rows, write_plan
    from .pipeline import PlanParameters, plan_paths

    t0 = time.perf_counter()
    params = PlanParameters(tool_radius=args.tool_radius, dr=args.dr, dd=args.dd, h_safe=args.h_safe,
                            k_max=args.k_max)
    params.resolved()  # refuse bad parameters before loading anything
    blade = load_blade(args.blade, axis=args.axis)
    plan = plan_paths(blade, params, workers=args.workers, row_formatter=pairs_rows)
    out = write_plan(plan, args.out, args.blade, args.axis)
    counts = plan.region_counts()
    for w in plan.warnings:
        print(f"warning: {w}", file=sys.stderr)
    print(f"planned {counts['paths']} paths ({counts['tip_paths']} in the tip region) on {blade.name!r}; "
          f"{sum(counts['points'].values())} pair points; wrote {out} in {time.perf_counter() - t0:.2f} s")
    return 0


def add_commands(sub, add_blade_args) -> None:
    p = sub.add_parser("plan", help="plan the double-sided tool paths and write them to --out DIR")
    add_blade_args(p)
    p.add_argument("--tool-radius", type=float, default=1.5, metavar="MM", help="ball radius (default 1.5)")
    p.add_argument("--dr", type=float, default=None, metavar="MM", help="radius increment dR (default r/4)")
    p.add_argument("--dd", type=float, default=0.2, metavar="MM", help="interpolation step (default 0.2)")
    p.add_argument("--h-safe", type=float, default=None, metavar="MM",
                   help="minimum tip spacing (default 1.25 r)")
    p.add_argument("--k-max", type=float, default=0.15, metavar="X", help="maximum staggered ratio (0.15)")
    p.add_argument("--workers", type=int, default=min(os.cpu_count() or 1, 2), metavar="N",
                   help="processes for the path steps (default: 2, or 1 on a one-core machine)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (written atomically)")
    p.set_defaults(func=_plan)

"""Benchmark: the job the machines run on the sample at the defaults, against the time-optimal job
under the same limits, in total and per kind of stretch; the job against its time at the feed; how
fast the cutters cut (share of cutting time below 30 % of the feed, episodes below 5 %); and the
plan's wall time beside calib.py's time in the same run. The figures are plan.json's
``schedule.job`` (core.machine.job_figures).

Before the jobs were timed on their own profiles (the schedule at the feed, then one clock shared by
both machines scaling it by s <= 1): job 132.6 min, time-optimal 109.6 min, at the feed 93.2 min; 35 %
of the cutting time below 30 % of the feed; 7,939 episodes below 5 %; tip step 1 1.22x the optimum,
tip step 2 1.07, staggered and variable stretches 1.99 and 1.50, symmetric 1.01.

Run: .venv/bin/python tests/benchmarks/bench_job.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from core.planner import Planner  # noqa: E402
from core.records import PlanJob  # noqa: E402
from tests.benchmarks.common import calib  # noqa: E402


def main() -> None:
    ref = calib()
    t0 = time.perf_counter()
    res = Planner(workers=2).plan(PlanJob(axes=False))
    wall = time.perf_counter() - t0
    job = res.figures["job"]
    print(f"calib.py: {ref:.3f} s")
    print(f"plan (sample, defaults, no tables written): {wall:.1f} s wall = {wall / ref:.1f}x calib")
    print(f"job on the machines      {job['time_on_machines_s'] / 60:8.1f} min")
    print(f"time-optimal job         {job['time_optimal_s'] / 60:8.1f} min  (job / optimum "
          f"{job['job_over_optimal']:.3f})")
    print(f"time at the feed         {job['time_at_feed_s'] / 60:8.1f} min  (job / feed time "
          f"{job['time_on_machines_s'] / job['time_at_feed_s']:.3f})")
    for name, k in job["per_kind"].items():
        print(f"  {name:14s} machine {k['machine_s'] / 60:7.1f} min  optimal {k['optimal_s'] / 60:7.1f} min  "
              f"ratio {k['ratio']:.3f}")
    c = job["cutting"]
    print(f"cutting time below 30 % of the feed: {100 * c['share_below_30pct_feed']:.1f} % of "
          f"{c['cutting_time_s'] / 60:.1f} min; episodes below 5 %: {c['episodes_below_5pct_feed']} "
          f"({c['time_below_5pct_feed_s']:.1f} s); stages below the minimum feed: "
          f"{len(job['stages_below_min_feed'])}")


if __name__ == "__main__":
    main()

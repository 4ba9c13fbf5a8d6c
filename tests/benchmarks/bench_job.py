"""Benchmark: the job the machines run on the sample at the defaults, against the time-optimal job for
the same executed tool axes under the same limits (core.machine.optimum through
core.machine.job_figures.optimum), in total and per kind of stretch; the job against its time at the
feed; how fast the cutters cut (share of cutting time below 30 % of the feed, episodes below 5 %);
and the times of the plan, of plan.json's job figures and of the optimum, each beside calib.py's time
measured in the same run (before and after: the load of a shared machine changes).

The job figures are plan.json's ``schedule.job``; the optimum is computed here only (it costs more than
the plan's own machine timing: docs/DECISIONS.md).

Run: .venv/bin/python tests/benchmarks/bench_job.py
"""

from __future__ import annotations

import resource
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from common import calib  # noqa: E402

from core.machine.job_figures import job_figures  # noqa: E402
from core.machine.optimum import Limits  # noqa: E402
from core.planner import Planner  # noqa: E402
from core.records import PlanJob  # noqa: E402

ROWS = ("tip step 1", "tip step 2", "staggered steps 5-6", "variable", "symmetric internal", "other cutting",
        "not cutting")


def _cpu() -> float:
    """CPU seconds of this process (its threads) and of its finished children (the path workers)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def main() -> None:
    ref0 = calib()
    job = PlanJob(axes=False)
    c0, t0 = _cpu(), time.perf_counter()
    res = Planner(workers=2).plan(job)
    t_plan, c_plan = time.perf_counter() - t0, _cpu() - c0
    p = res.plan.params
    c0, t0 = _cpu(), time.perf_counter()
    job_figures(res.schedule, res.timeline, res.warp, p.min_feed)
    t_fig, c_fig = time.perf_counter() - t0, _cpu() - c0
    limits = Limits(res.machine, res.period, job.resolved_chord_tol(), p.tool_radius, p.feed / 60000.0,
                    p.a_max / 1e6)
    c0, t0 = _cpu(), time.perf_counter()
    fig = job_figures(res.schedule, res.timeline, res.warp, p.min_feed, limits)
    t_opt, c_opt = time.perf_counter() - t0 - t_fig, _cpu() - c0 - c_fig
    ref1 = calib()
    ref = 0.5 * (ref0 + ref1)
    print(f"calib.py: {ref0:.3f} s before, {ref1:.3f} s after (mean {ref:.3f} s)")
    print("(wall s = x calib; CPU s of the process and its path workers = x calib)")
    for name, wall, cpu in (("plan (sample, defaults, no tables written)", t_plan, c_plan),
                            ("job figures (plan.json)", t_fig, c_fig), ("time-optimal job (every move)", t_opt, c_opt)):
        print(f"{name:43s} wall {wall:7.2f} s = {wall / ref:6.2f}x   CPU {cpu:7.2f} s = {cpu / ref:6.2f}x")
    print(f"the optimum costs {100 * c_opt / c_plan:.0f} % of the plan's CPU time, the job figures "
          f"{100 * c_fig / c_plan:.1f} %")
    print()
    print(f"job on the machines   {fig['time_on_machines_s'] / 60:7.1f} min")
    print(f"time-optimal job      {fig['time_optimal_s'] / 60:7.1f} min   job / optimum "
          f"{fig['machines_over_optimal']:.3f}")
    print(f"time at the feed      {fig['time_at_feed_s'] / 60:7.1f} min   job / feed time "
          f"{fig['machines_over_feed']:.3f}")
    print()
    print("| stretch kind | machines min | at the feed min | optimum min | machines / optimum |")
    print("|---|---|---|---|---|")
    for name in ROWS:
        k = fig["stretches"].get(name)
        if k is not None:
            print(f"| {name} | {k['machine_s'] / 60:.1f} | {k['at_feed_s'] / 60:.1f} | {k['optimal_s'] / 60:.1f} | "
                  f"{k['machine_over_optimal']:.3f} |")
    print(f"| whole job | {fig['time_on_machines_s'] / 60:.1f} | {fig['time_at_feed_s'] / 60:.1f} | "
          f"{fig['time_optimal_s'] / 60:.1f} | {fig['machines_over_optimal']:.3f} |")
    print()
    for side, c in fig["cutting"].items():
        why = ", ".join(f"{k} {v / 60:.1f}" for k, v in c["below_min_feed_by_reason_s"].items())
        print(f"{side:5s}: cutting {c['cutting_time_s'] / 60:6.1f} min, {100 * c['share_below_min_feed']:5.1f} % "
              f"below the minimum feed {fig['min_feed_mm_min']:g} mm/min (min: {why}), "
              f"{c['episodes_below_5pct_feed']} episodes below 5 % ({c['below_5pct_feed_s'] / 60:.1f} min)")
    print()
    print("| step | machines s | at the feed s |")
    print("|---|---|---|")
    for step, t in fig["step_time_s"].items():
        print(f"| {step} | {t:.1f} | {fig['step_time_at_feed_s'][step]:.1f} |")


if __name__ == "__main__":
    main()

"""Benchmark: the executed tool axes of the single-sided (tip region) paths on the sample blade at the
default parameters: what they cost to choose and how much the heads must swing to follow them.

Run: .venv/bin/python tests/benchmarks/bench_tip_axes.py [--job] [--dr MM] [--tree DIR]
(--tree measures another checkout's axes with the same figures: core is imported from there, and
--job plans with that checkout; default this one.)

Prints, paired with ../shared/bench/calib.py run before and after in the same run:
- the CPU and wall time of core.machine.reach.machine_plan (every pair turned within reach,
  the single-sided pairs' axes chosen);
- per side, over the single-sided paths, from the inverse kinematics of the executed tips and axes:
  the axis travel per mm of tip over the last millimetre of tip at each end of each path (the largest
  axis's travel) and on one segment, the peak axis speed the axes ask for with the tip at the feed,
  per axis, as a share of the axis's limit, and the speed-cap floor: the time the tip paths take at
  the feed capped on every segment by each axis's speed limit (no acceleration, no chord tolerance:
  no timing can be faster on these axes) over their time at the feed;
- the change of axis from one path to the next (degrees: what the turn between them swings);
- with --job: the whole plan at these parameters in this process (core.planner.Planner, without the
  axis tables): the job on the machines and the time at the feed (the schedule's), their ratio, and
  the same per step of the seven (step 1-2: the single-sided paths).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

# isort: off
TREE = Path(__file__).resolve().parents[2]
if "--tree" in sys.argv:
    TREE = Path(sys.argv[sys.argv.index("--tree") + 1])
sys.path.insert(0, str(TREE.resolve()))
from core.util.process import configure_process  # noqa: E402

configure_process()  # (before numpy: one BLAS thread per process, as bladecam plan)
import numpy as np  # noqa: E402
# isort: on

from common import CALIB, calib  # noqa: E402

import core  # noqa: E402
from core.blade.source import load_blade  # noqa: E402
from core.machine.kinematics import inverse_kinematics  # noqa: E402
from core.machine.model import AXES, load_machine  # noqa: E402
from core.machine.reach import machine_plan  # noqa: E402
from core.paths.planning import plan_paths  # noqa: E402
from core.records import PlanParameters  # noqa: E402

#: the stretch at each end of a path over which the axis travel per mm of tip is measured (mm of tip)
END_MM = 1.0


def swing(machine, side: str, pairs: list, feed: float) -> dict:
    """The swing figures of one side's single-sided pairs (module docstring); feed mm/s."""
    v_lim = np.array([machine.limits.axis(a).max_speed_mm_s for a in AXES])
    end_travel, peak, t_feed, t_floor, first, last = [], np.zeros(6), 0.0, 0.0, [], []
    seg_peak = 0.0
    for pair in pairs:
        tips, axes = getattr(pair, f"{side}_tip"), getattr(pair, f"{side}_axis")
        first.append(axes[0])
        last.append(axes[-1])
        q = inverse_kinematics(machine, side, tips, axes)
        dp = np.linalg.norm(np.diff(tips, axis=0), axis=1)
        dq = np.abs(np.diff(q, axis=0))
        moving = dp > 1e-12
        rate = dq[moving] / dp[moving, None]  # mm of axis per mm of tip
        peak = np.maximum(peak, (rate * feed).max(axis=0, initial=0.0))
        seg_peak = max(seg_peak, float(rate.max(initial=0.0)))
        t_feed += dp.sum() / feed
        cap = np.minimum(feed, (v_lim / np.maximum(rate, 1e-300)).min(axis=1))
        t_floor += (dp[moving] / cap).sum()
        s = np.concatenate([[0.0], np.cumsum(dp)])
        for part in (s <= min(END_MM, s[-1]), s >= max(s[-1] - END_MM, 0.0)):
            k = np.flatnonzero(part)
            lo, hi = k[0], k[-1]
            if hi > lo and s[hi] - s[lo] > 1e-9:
                end_travel.append(dq[lo:hi].sum(axis=0).max() / (s[hi] - s[lo]))
    change = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", np.array(last[:-1]), np.array(first[1:])),
                                          -1.0, 1.0)))
    end_travel = np.array(end_travel)
    return {"segment_max": seg_peak, "end_travel_max": end_travel.max(),
            "end_travel_median": np.median(end_travel),
            "peak_speed": peak, "peak_share": peak / v_lim, "t_feed": t_feed, "t_floor": t_floor,
            "turn_median": np.median(change), "turn_max": change.max()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", action="store_true", help="also run the whole bladecam plan")
    ap.add_argument("--dr", type=float, default=None, help="dR (mm); default the parameters' own")
    ap.add_argument("--tree", default=None, help="the checkout whose core is measured")
    args = ap.parse_args()
    repo = Path(core.__file__).resolve().parents[1]
    print(f"core from {repo}")
    c0 = calib() if CALIB.is_file() else float("nan")
    print(f"calib (same run): {c0:.3f} s")
    params = PlanParameters(dr=args.dr)
    plan = plan_paths(load_blade("sample"), params)
    machine = load_machine(None)
    w0, p0 = time.perf_counter(), time.process_time()
    planned, _ = machine_plan(plan, machine)
    wall, cpu = time.perf_counter() - w0, time.process_time() - p0
    print(f"machine_plan: {cpu:.3f} s CPU ({cpu / c0:.3f}x calib), {wall:.3f} s wall "
          f"({wall / c0:.3f}x calib)")
    feed = params.feed / 60.0
    single = [p for p in planned.pairs if p.kind == "single"]
    points = sum(len(p.u) for p in single)
    print(f"{len(single)} single-sided paths, {points} points a side; feed {feed:.2f} mm/s")
    for side in ("left", "right"):
        f = swing(machine, side, single, feed)
        shares = ", ".join(f"{a} {s:.2f}" for a, s in zip(AXES, f["peak_share"], strict=True))
        print(f"{side}: axis travel per mm of tip in the last {END_MM:g} mm at a path's end: max "
              f"{f['end_travel_max']:.2f}, median {f['end_travel_median']:.2f}; on one segment: max "
              f"{f['segment_max']:.2f}")
        print(f"  peak axis speed at the feed / limit: {shares}")
        print(f"  tip paths at the feed {f['t_feed'] / 60:.2f} min; speed-cap floor "
              f"{f['t_floor'] / 60:.2f} min "
              f"({f['t_floor'] / f['t_feed']:.3f}x)")
        print(f"  axis change from one path to the next: median {f['turn_median']:.3f} deg, "
              f"max {f['turn_max']:.3f} deg")
    if args.job:
        from core.planner import Planner
        from core.records import PlanJob

        t0 = time.perf_counter()
        res = Planner(workers=2).plan(PlanJob("sample", "z", params, axes=False))
        wall = time.perf_counter() - t0
        t, tau, step = res.warp.t, res.warp.schedule_t, res.timeline.left.step
        job, at_feed = float(t[-1]) / 1000.0, float(tau[-1]) / 1000.0
        print(f"plan (in process, no axis tables): {wall:.1f} s wall ({wall / c0:.1f}x calib); "
              f"job {job / 60:.2f} min, at the feed {at_feed / 60:.2f} min: job / time at the feed "
              f"{job / at_feed:.3f}")
        dt, dtau = np.diff(t), np.diff(tau)
        for k in np.unique(step):
            sel = step[:-1] == k
            print(f"  step {k}: {dt[sel].sum() / 60000:.2f} min on the machines, "
                  f"{dtau[sel].sum() / 60000:.2f} at the feed "
                  f"({dt[sel].sum() / max(dtau[sel].sum(), 1e-9):.3f}x)")
    c1 = calib() if CALIB.is_file() else float("nan")
    print(f"calib after: {c1:.3f} s")


if __name__ == "__main__":
    main()

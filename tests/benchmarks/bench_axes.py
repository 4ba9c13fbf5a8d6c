"""Benchmark: the whole `bladecam plan` (all files, the axis tables included) for the
sample blade, and the writing of both axis tables alone, at dR 3 mm and (with --default) at the
default dR.

Run: .venv/bin/python tests/benchmarks/bench_axes.py [--default]
Prints the CLI's wall time and its timings, rows and file sizes, peak memory, the time to format
both axis tables (core.output.files.axes_csv) in one process, and the verify result.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def main() -> None:
    sys.path.insert(0, str(REPO))
    dr = [] if "--default" in sys.argv else ["--dr", "3"]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "plan"
        t0 = time.perf_counter()
        res = subprocess.run([sys.executable, "-m", "core", "plan", *dr, "--out", str(out)],
                             capture_output=True, text=True)
        wall = time.perf_counter() - t0
        peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        print(f"bladecam plan {' '.join(dr) or '(default dR)'}: {wall:.2f} s wall, "
              f"exit {res.returncode}, peak {peak:.0f} MiB")
        summary = json.loads((out / "plan.json").read_text())
        for k, v in summary["timings_s"].items():
            print(f"  {k:30s} {v}")
        sch = summary["schedule"]
        print(f"  rows {sch['samples']}, job {sch['total_time_s'] / 60:.1f} min "
              f"(at the feed {sch['machine']['time_at_feed_s'] / 60:.1f} min)")
        for f in sorted(out.iterdir()):
            print(f"  {f.name:16s} {f.stat().st_size / 1e6:8.1f} MB")
        t0 = time.perf_counter()
        v = subprocess.run([sys.executable, "-m", "core", "verify", str(out)], capture_output=True, text=True)
        print(f"bladecam verify: {time.perf_counter() - t0:.2f} s, exit {v.returncode}: {v.stdout.strip()[:160]}")

    # formatting both axis tables alone, in this process
    from core.output.files import axes_csv
    from core.planner import Planner
    from core.records import PlanJob, PlanParameters

    params = PlanParameters() if not dr else PlanParameters(dr=3.0)
    result = Planner(workers=2).plan(PlanJob("sample", "z", params, axes=True))
    best = min(_timed(lambda: [axes_csv(result.axes[s]) for s in ("left", "right")]) for _ in range(3))
    rows = len(result.axes["left"].t)
    print(f"both axis tables formatted: {best:.2f} s best of 3 for {rows} rows each")


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()

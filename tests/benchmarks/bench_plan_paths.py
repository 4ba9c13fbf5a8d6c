"""Benchmark: `bladecam plan --paths-only` (up to pairs.csv) for the sample blade at the defaults.

Run: .venv/bin/python tests/benchmarks/bench_plan_paths.py [--repeat N]
Prints the wall time of the whole command in a fresh Python process (start-up included), the split
per step from plan.json, the size of pairs.csv and the peak memory (max RSS of the child).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    walls = []
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as tmp:
            out = Path(tmp) / "plan"
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "core", "plan", "--paths-only", "--out", str(out)], check=True,
                           capture_output=True)
            walls.append(time.perf_counter() - t0)
            summary = json.loads((out / "plan.json").read_text())
            size = (out / "pairs.csv").stat().st_size
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(f"bladecam plan (sample, defaults): wall {min(walls):.2f} s best of {len(walls)} "
          f"(all: {', '.join(f'{w:.2f}' for w in walls)}); target 3 s")
    for k, v in summary["timings_s"].items():
        print(f"  {k:30s} {v:.3f} s")
    print(f"  paths {summary['paths']['paths']}, tip paths {summary['paths']['tip_paths']}, "
          f"pair points {sum(summary['paths']['points'].values())}")
    print(f"  pairs.csv {size / 1e6:.1f} MB; peak memory (max RSS) {peak:.0f} MiB")


if __name__ == "__main__":
    main()

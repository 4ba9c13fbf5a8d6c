"""Benchmark: `bladecam plan --no-axes` for the sample blade at the defaults (the machine-timed job, its
CL tables only; the default plan with the machines' axis tables is bench_axes.py), and `bladecam
verify` on its output. Fresh Python processes, start-up included.

Run: .venv/bin/python tests/benchmarks/bench_plan_full.py
Prints wall times, the timings plan.json records per step, file sizes and peak memory (max RSS).
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def run(args: list[str]) -> tuple[float, int, str]:
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "core", *args], capture_output=True, text=True)
    return time.perf_counter() - t0, res.returncode, res.stdout.strip().splitlines()[-1] if res.stdout else res.stderr


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "plan"
        wall, rc, msg = run(["plan", "--no-axes", "--out", str(out)])
        peak_plan = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        print(f"bladecam plan --no-axes (sample, defaults, CL written): {wall:.2f} s wall, exit {rc}")
        summary = json.loads((out / "plan.json").read_text())
        for k, v in summary["timings_s"].items():
            print(f"  {k:30s} {v}")
        for f in sorted(out.iterdir()):
            print(f"  {f.name:14s} {f.stat().st_size / 1e6:8.1f} MB")
        print(f"  peak memory (max RSS of a child) {peak_plan:.0f} MiB")
        wall, rc, msg = run(["verify", str(out)])
        print(f"bladecam verify: {wall:.2f} s wall, exit {rc}: {msg[:300]}")


if __name__ == "__main__":
    main()

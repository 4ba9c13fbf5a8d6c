"""Benchmark: what the whole-tool collision check adds to `bladecam plan` at the defaults, paired with
calib.py, against the same plan by a checkout without it.

Run: .venv/bin/python tests/benchmarks/bench_collisions.py --base DIR [plan options]
  --base DIR   a checkout without the check (e.g. of main before it), planned in the same run, with
               the same Python, right before this checkout's plan
Prints calib.py's time before, between and after the two plans; each plan's wall time and its ratio
to the calib beside it; this checkout's plan.json timings of the check (the rows' check:
collisions_s; the single-sided axes' clearance queries: axes_clearance_s) and the collision figures;
the time the `bladecam verify` run inside `bladecam plan` spent on the check is in the plan's wall
time. The target: this checkout's plan within 1.15 times the base's (each as a ratio to its calib).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from common import REPO, calib  # noqa: E402


def plan(tree: Path, out: Path, extra: list[str]) -> float:
    """Wall seconds of `python -m core plan` run from ``tree`` into ``out`` (exit status checked)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "core", "plan", *extra, "--out", str(out)], cwd=tree, env=env,
                         capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if res.returncode:
        raise SystemExit(f"plan from {tree} failed (exit {res.returncode}): {res.stderr[-2000:]}")
    return wall


def main() -> None:
    args = sys.argv[1:]
    if "--base" not in args:
        raise SystemExit(__doc__)
    k = args.index("--base")
    base = Path(args[k + 1]).resolve()
    extra = args[:k] + args[k + 2:]
    with tempfile.TemporaryDirectory() as tmp:
        c0 = calib()
        wall_base = plan(base, Path(tmp) / "base", extra)
        c1 = calib()
        wall = plan(REPO, Path(tmp) / "check", extra)
        c2 = calib()
        summary = json.loads((Path(tmp) / "check" / "plan.json").read_text())
    timings = summary["timings_s"]
    ref_base, ref = 0.5 * (c0 + c1), 0.5 * (c1 + c2)
    print(f"calib.py: {c0:.3f} s, {c1:.3f} s, {c2:.3f} s (before, between, after)")
    print(f"plan {' '.join(extra) or '(defaults)'} without the check ({base}): {wall_base:.1f} s wall, "
          f"{wall_base / ref_base:.1f} calib")
    print(f"plan with the check ({REPO}): {wall:.1f} s wall, {wall / ref:.1f} calib: "
          f"{100 * ((wall / ref) / (wall_base / ref_base) - 1):+.1f} % (target <= +15 %)")
    print(f"  rows' check collisions_s {timings.get('collisions_s', 0):.1f} s, single-sided axes' clearance "
          f"axes_clearance_s {timings.get('axes_clearance_s', 0):.1f} s (both sides' threads summed)")
    print(f"  figures: {json.dumps(summary['schedule'].get('collisions'))}")


if __name__ == "__main__":
    main()

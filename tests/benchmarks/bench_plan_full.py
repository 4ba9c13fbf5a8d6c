"""Benchmark: the whole `bladecam plan` for the sample blade, every file written (CL and axis tables),
at the defaults and at --period-ms 4, each as a multiple of ../shared/bench/calib.py measured in the
same run (before the plans and again after them: the load of a shared machine changes), and `bladecam
verify` on the default plan. Fresh Python processes, start-up included.

Run: .venv/bin/python tests/benchmarks/bench_plan_full.py [--tree DIR] [--no-verify]
  --tree DIR   plan with the checkout in DIR instead of this one (the same Python): to compare a
               change with the code before it in one run (e.g. --tree of a checkout of main)
Prints per plan: wall time and x calib, the peak memory of the process tree (the proportional set
sizes of the command and any processes it starts, summed, sampled every 50 ms) and the largest
single process's max RSS, the timings plan.json records and the file sizes; then the ratios of the
--period-ms 4 plan to the default one. Targets: the default plan <= 6x calib and <= 600 MB; at
--period-ms 4 within 3x the time and 1.5x the memory of the default.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import CALIB, REPO, calib


def _children(pid: int) -> list[int]:
    found = []
    try:
        for task in os.listdir(f"/proc/{pid}/task"):
            with open(f"/proc/{pid}/task/{task}/children") as f:
                found += [int(x) for x in f.read().split()]
    except OSError:
        pass
    return found


def _pss_mib(pid: int) -> float:
    """MiB of memory process ``pid`` holds: its proportional set size (a page shared with a fork counts
    in each by its share), or its resident set where the kernel gives no PSS."""
    for path, key in ((f"/proc/{pid}/smaps_rollup", "Pss:"), (f"/proc/{pid}/status", "VmRSS:")):
        try:
            with open(path) as f:
                for line in f:
                    if line.startswith(key):
                        return int(line.split()[1]) / 1024
        except OSError:
            continue
    return 0.0


def tree_memory(pid: int) -> float:
    """MiB held by process ``pid`` and all its descendants (PSS: forked pages are not counted twice)."""
    total, todo = 0.0, [pid]
    while todo:
        p = todo.pop()
        total += _pss_mib(p)
        todo += _children(p)
    return total


def run(args: list[str], tree: Path) -> dict:
    """Run ``python -m core ARGS`` from ``tree``: wall s, exit code, last line, the process tree's
    sampled peak MiB and the largest process's max RSS MiB."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "core", *args], cwd=tree, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    peak = 0.0
    while proc.poll() is None:
        peak = max(peak, tree_memory(proc.pid))
        time.sleep(0.05)
    wall = time.perf_counter() - t0
    out, err = proc.communicate()
    maxrss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    lines = (out or err).strip().splitlines()
    return {"wall": wall, "rc": proc.returncode, "msg": lines[-1] if lines else "", "peak_tree": peak,
            "max_rss": maxrss / 1024 if maxrss > before else float("nan")}


def report(name: str, got: dict, ref: float, out: Path) -> None:
    print(f"{name}: {got['wall']:.2f} s wall = {got['wall'] / ref:.2f}x calib, exit {got['rc']}, peak "
          f"{got['peak_tree']:.0f} MiB (process tree), max RSS {got['max_rss']:.0f} MiB")
    if got["rc"] != 0:
        print(f"  {got['msg'][:300]}")
        return
    summary = json.loads((out / "plan.json").read_text())
    print(f"  rows {summary['schedule']['samples']}, job {summary['schedule']['total_time_s'] / 60:.1f} min")
    for k, v in summary["timings_s"].items():
        print(f"  {k:30s} {v}")
    for f in sorted(out.iterdir()):
        print(f"  {f.name:16s} {f.stat().st_size / 1e6:8.1f} MB")


def main() -> None:
    tree = REPO
    if "--tree" in sys.argv:
        tree = Path(sys.argv[sys.argv.index("--tree") + 1]).resolve()
    have_calib = CALIB.is_file()
    ref0 = calib() if have_calib else float("nan")
    print(f"calib (same run, before the plans): {ref0:.3f} s; code: {tree}")
    got = {}
    with tempfile.TemporaryDirectory() as tmp:
        outs = {"default": Path(tmp) / "default", "period 4 ms": Path(tmp) / "p4"}
        got["default"] = run(["plan", "--out", str(outs["default"])], tree)
        got["period 4 ms"] = run(["plan", "--period-ms", "4", "--out", str(outs["period 4 ms"])], tree)
        ref1 = calib() if have_calib else float("nan")
        ref = min(ref0, ref1)
        print(f"calib (same run, after the plans): {ref1:.3f} s; the ratios use the smaller, {ref:.3f} s")
        for name, out in outs.items():
            report(f"bladecam plan ({name}, every file)", got[name], ref, out)
        a, b = got["default"], got["period 4 ms"]
        print(f"period 4 ms / default: time {b['wall'] / a['wall']:.2f}x (target <= 3), peak memory "
              f"{b['peak_tree'] / a['peak_tree']:.2f}x (target <= 1.5)")
        print(f"default plan: {a['wall'] / ref:.2f}x calib (target <= 6), {a['peak_tree']:.0f} MiB (target <= 600)")
        if "--no-verify" not in sys.argv and a["rc"] == 0:
            v = run(["verify", str(outs["default"])], tree)
            print(f"bladecam verify (default plan): {v['wall']:.2f} s = {v['wall'] / ref:.2f}x calib, exit "
                  f"{v['rc']}: {v['msg'][:300]}")


if __name__ == "__main__":
    main()

"""Benchmark: what the whole-tool collision check adds to `bladecam plan` at the defaults and to
`bladecam verify`, paired with calib.py.

Run: .venv/bin/python tests/benchmarks/bench_collisions.py [--dr MM]
Prints calib.py's time, the plan's wall time with its collision timings from plan.json (turning the
single-sided axes clear, all rounds: clear_axes_s; the rows' check: collisions_s) and their share of
the rest of the plan, and verify's wall time with its check's (collision_check_s) and share; each time
also as a ratio to calib.py's.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from common import calib  # noqa: E402


def main() -> None:
    extra = sys.argv[1:]
    ref = calib()
    print(f"calib.py: {ref:.3f} s")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "plan"
        t0 = time.perf_counter()
        res = subprocess.run([sys.executable, "-m", "core", "plan", *extra, "--out", str(out)],
                             capture_output=True, text=True)
        wall = time.perf_counter() - t0
        if res.returncode:
            print(res.stderr[-2000:])
            return
        timings = json.loads((out / "plan.json").read_text())["timings_s"]
        check = timings.get("collisions_s", 0.0) + timings.get("clear_axes_s", 0.0)
        print(f"bladecam plan {' '.join(extra) or '(defaults)'}: {wall:.1f} s wall ({wall / ref:.2f} calib); "
              f"turning axes clear {timings.get('clear_axes_s', 0.0):.1f} s, rows' check "
              f"{timings.get('collisions_s', 0.0):.1f} s: {check:.1f} s ({check / ref:.2f} calib), "
              f"{100 * check / max(wall - check, 1e-9):.1f} % of the plan without them")
        t0 = time.perf_counter()
        v = subprocess.run([sys.executable, "-m", "core", "verify", str(out)], capture_output=True, text=True)
        vwall = time.perf_counter() - t0
        m = re.search(r"collision_check_s ([0-9.]+)", v.stdout)
        vcheck = float(m.group(1)) if m else float("nan")
        print(f"bladecam verify: {vwall:.1f} s wall ({vwall / ref:.2f} calib), exit {v.returncode}; its collision "
              f"check {vcheck:.1f} s ({vcheck / ref:.2f} calib), {100 * vcheck / max(vwall - vcheck, 1e-9):.1f} % of "
              f"verify without it")


if __name__ == "__main__":
    main()

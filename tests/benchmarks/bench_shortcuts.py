"""Benchmark: do the two shortcuts that only shave time matter to the whole command? `bladecam plan`
(sample blade, defaults, every file) run as shipped, with core.util.rowwise's column-by-column row
reductions replaced by the plain numpy expressions they stand for (``np.linalg.norm(a, axis=1)``,
``(a * b).sum(1)``, ``a.max(axis=1)``), and ending through Python's own teardown instead of the console
entry point's quick exit (core.cli.run). Fresh processes, interleaved, paired in the same run with
../shared/bench/calib.py.

Run: .venv/bin/python tests/benchmarks/bench_shortcuts.py [--rounds N]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import REPO, calib

#: each variant: code run in a fresh interpreter before the command line ({out}: the output folder)
VARIANTS = {
    "as shipped": "from core.cli import run\nrun(['plan', '--out', {out!r}])",
    "numpy row reductions": (
        "import numpy as np\nimport core.util.rowwise as rw\n"
        "rw.row_norm = lambda a: np.linalg.norm(a, axis=1)\n"
        "rw.row_sum_of_products = lambda a, b=None: (a * (a if b is None else b)).sum(axis=1)\n"
        "rw.row_max = lambda a: a.max(axis=1)\n"
        "from core.cli import run\nrun(['plan', '--out', {out!r}])"),
    "Python's teardown": (
        "import sys\nfrom core.util.process import configure_process\nconfigure_process()\n"
        "from core.cli import main\nsys.exit(main(['plan', '--out', {out!r}]))"),
}


def timed(code: str) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, cwd=REPO)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    times: dict[str, list[float]] = {k: [] for k in VARIANTS}
    cal = [calib()]
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.rounds):
            for name, code in VARIANTS.items():
                times[name].append(timed(code.format(out=str(Path(tmp) / f"plan-{r}"))))
            cal.append(calib())
    c = statistics.median(cal)
    print(f"calib (median of {len(cal)}): {c:.3f} s")
    base = statistics.median(times["as shipped"])
    for name, ts in times.items():
        m = statistics.median(ts)
        print(f"  {name:22s} median {m:6.2f} s = {m / c:5.1f}x calib   ({', '.join(f'{t:.2f}' for t in ts)}); "
              f"{m - base:+.2f} s against as shipped")


if __name__ == "__main__":
    main()

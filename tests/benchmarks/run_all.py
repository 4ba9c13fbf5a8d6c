"""Run every benchmark in turn (`make bench`): paths only, the full plan and verify, kinematics, the
axis tables at dR 3 mm, and the workbench (under xvfb-run when there is no display), each paired with
../shared/bench/calib.py run just before it (the figures are quoted as multiples of calib's time).
The default-dR axis run takes minutes: `bench_axes.py --default` on its own."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from common import CALIB, calib

HERE = Path(__file__).resolve().parent
SCRIPTS = ["bench_plan_paths.py", "bench_plan_full.py", "bench_kinematics.py", "bench_axes.py", "bench_gui.py"]


def main() -> int:
    failed = []
    for name in SCRIPTS:
        print(f"== {name}", flush=True)
        if CALIB.is_file():
            print(f"calib (same run): {calib():.3f} s", flush=True)
        if subprocess.run([sys.executable, str(HERE / name)]).returncode != 0:
            failed.append(name)
    if failed:
        print("failed: " + ", ".join(failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

"""A blade from exact CAD surfaces against the reference workload and the sample table, in one run.

    .venv/bin/python tests/benchmarks/bench_cad.py            # plans at the default parameters
    .venv/bin/python tests/benchmarks/bench_cad.py --dr 2     # quicker plans (coarser contour paths)

Makes the sample table's blade as a STEP face/back pair (tests/core/blade/cad_blades.py), then times,
each in a fresh process: calib.py; reading the pair and its first section (OpenCASCADE's import
included); a plan of the paths and the job (no axis tables) from the STEP pair and from the sample
table. Targets: loading and the first section within 2x calib; the plan from CAD within 1.5x the
table's."""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from common import REPO, calib

LOAD = """
import time, sys
t = time.perf_counter()
from core.blade.source import load_blade
b = load_blade(sys.argv[1])
b.section(0.5 * (b.hub_radius + b.tip_radius))
print(time.perf_counter() - t)
"""

PLAN = """
import time, sys
t = time.perf_counter()
from core.planner import Planner
from core.records import PlanJob, PlanParameters
params = PlanParameters() if sys.argv[2] == "default" else PlanParameters(dr=float(sys.argv[2]))
Planner(workers=2).plan(PlanJob(sys.argv[1], "z", params, axes=False))
print(time.perf_counter() - t)
"""


def timed(code: str, *args: str) -> float:
    """Seconds the code took in a fresh process (RuntimeError with its last error line if it failed)."""
    out = subprocess.run([sys.executable, "-c", code, *args], cwd=REPO, capture_output=True, text=True,
                         timeout=7200)
    if out.returncode != 0:
        raise RuntimeError((out.stderr.strip().splitlines() or ["no output"])[-1])
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dr", default="default", help="the plans' radius increment, mm (default: the planner's)")
    args = ap.parse_args()
    sys.path.insert(0, str(REPO))
    from core.blade.source import load_blade
    from tests.core.blade.cad_blades import side_faces, write

    with tempfile.TemporaryDirectory() as tmp:
        face, back = side_faces(load_blade("sample"), n_r=80, m=241)
        pair = f"{write(face, Path(tmp) / 'face.step')},{write(back, Path(tmp) / 'back.step')}"
        c = calib()
        t0 = time.perf_counter()
        load = timed(LOAD, pair)
        try:
            plan_cad = timed(PLAN, pair, args.dr)
        except RuntimeError as exc:
            print(f"the plan from the STEP pair failed: {exc}")
            plan_cad = float("nan")
        plan_table = timed(PLAN, "sample", args.dr)
        c2 = calib()
    print(f"calib {c:.3f} s (again at the end: {c2:.3f} s)")
    print(f"STEP pair: load and first section {load:.3f} s = {load / c:.2f} x calib (target <= 2)")
    print(f"plan (dR {args.dr}): from the STEP pair {plan_cad:.2f} s, from the sample table {plan_table:.2f} s: "
          f"{plan_cad / plan_table:.2f} x (target <= 1.5); whole run {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()

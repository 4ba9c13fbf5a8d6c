"""One blade of a whole propeller mesh against the reference workload, in one run.

    .venv/bin/python tests/benchmarks/bench_propeller.py

Makes the 5-blade propeller of the BladeX blade (tests/core/blade/propellers.py: 8,917 triangles), then
times, each in a fresh process (best of 3): calib.py; reading the STL, finding its hub and blades,
splitting blade 3 into face and back, and its first section (trimesh's import included); the same for
the BladeX face/back pair it was made of."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

from common import REPO, calib

LOAD = """
import time, sys
t = time.perf_counter()
from core.blade.source import load_blade
b = load_blade(sys.argv[1], axis="x")
b.section(0.5 * (b.hub_radius + b.tip_radius))
print(time.perf_counter() - t)
"""


def timed(source: str) -> float:
    runs = [float(subprocess.run([sys.executable, "-c", LOAD, source], cwd=REPO, check=True, capture_output=True,
                                 text=True, timeout=600).stdout.strip().splitlines()[-1]) for _ in range(3)]
    return min(runs)


def main() -> None:
    sys.path.insert(0, str(REPO))
    from tests.core.blade.propellers import bladex_propeller

    # ../shared/data beside the checkout (or beside a folder holding it, as a git worktree's is)
    bladex = next(p / "shared" / "data" / "bladex-test-blade" for p in REPO.parents
                  if (p / "shared" / "data" / "bladex-test-blade").is_dir())

    with tempfile.TemporaryDirectory() as tmp:
        prop = bladex_propeller(bladex, Path(tmp) / "propeller.stl")
        c = calib()
        t_prop = timed(f"{prop}?blade=3")
        t_pair = timed(f"{bladex / 'lower.stl'},{bladex / 'upper.stl'}")
    print(f"calib.py {c:.3f} s")
    print(f"blade 3 of the propeller, loaded with its first section: {t_prop:.3f} s ({t_prop / c:.2f} x calib)")
    print(f"the BladeX pair, loaded with its first section:          {t_pair:.3f} s ({t_pair / c:.2f} x calib)")


if __name__ == "__main__":
    main()

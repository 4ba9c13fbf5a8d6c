"""Random search for plans that bladecam refuses or that fail its own independent check (not a
benchmark and not part of make test: it takes about 20 s per plan).

    .venv/bin/python tests/benchmarks/search_plans.py [SEED] [N]

Draws N plans (default 20) from seed SEED (default 1): the blade source (the sample, a geometry
table, the BladeX mesh in ../shared when present), plan mode (collaborative or single), speed-stage
profile, tool radius 1-3 mm, dd 0.1-0.5 mm, and dR, h_safe, K_max, a_max and feed in the ranges of
the property test (dR and h_safe scaled with the tool radius). Each is planned as `bladecam plan`
plans it (core.planner.Planner, CL and axis tables written) and checked by `bladecam verify`. One line per
plan; the parameters of every refusal or finding are printed in full, as `bladecam plan` options,
so that the case can be re-run (the 'table' source is resources/sample_blade.csv with its diameter
set to 400 mm, written to a scratch folder that is removed at the end, as is every plan). A refusal
naming the remedy "lower the feed or raise a_max" is expected where the feed is high for the
acceleration (feed / a_max > 3, as in the property test).

Found this way (and fixed, each with a regression test in tests/core/schedule/test_schedule.py): the step-3
meeting, the step-2 back-off, edge stretches passing tight corners at speed, the last path's margins,
short symmetrical stretches from rest.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

# isort: off
from core.util.process import configure_process  # noqa: E402

configure_process()  # (before numpy: one BLAS thread per process, as bladecam plan)
import numpy as np  # noqa: E402
# isort: on

from core.blade.source import sample_table_path  # noqa: E402
from core.errors import BladecamError  # noqa: E402
from core.output.writer import write_result  # noqa: E402
from core.planner import Planner  # noqa: E402
from core.records import PlanJob, PlanParameters  # noqa: E402
from core.verify.check import verify  # noqa: E402

BLADEX = REPO.parent / "shared" / "data" / "bladex-test-blade"


def main() -> int:
    seed = int(sys.argv[1]) if len(sys.argv) > 1 else 1
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 20
    rng = np.random.default_rng(seed)
    with tempfile.TemporaryDirectory(prefix="bladecam-search-") as scratch:
        tmp = Path(scratch)
        table = tmp / "blade.csv"
        sample = sample_table_path().read_text()
        table.write_text(sample.replace("# diameter_mm: 458.72", "# diameter_mm: 400"))
        sources = {"sample": ("sample", "z"), "table": (str(table), "z")}
        if (BLADEX / "upper.stl").is_file():
            sources["bladex"] = (f"{BLADEX / 'upper.stl'},{BLADEX / 'lower.stl'}", "x")
        names = sorted(sources)
        bad = 0
        for k in range(n):
            name = names[int(rng.integers(len(names)))]
            r = float(rng.uniform(1.0, 3.0))
            dd = float(rng.choice([0.1, 0.2, 0.3, 0.5]))
            dr = float(rng.choice([3.0, 4.0, 5.0])) * r / 1.5
            h_safe = r * float(rng.uniform(1.0, 1.5))
            k_max = float(rng.uniform(0.1, 0.2))
            a_max, feed = float(rng.uniform(300, 2000)), float(rng.uniform(500, 2000))
            mode = str(rng.choice(["collaborative", "collaborative", "single"]))
            profile = str(rng.choice(["sigmoid", "smooth"]))
            src, axis = sources[name]
            options = (f"--blade {src} --axis {axis} --mode {mode} --profile {profile} --tool-radius {r!r} "
                       f"--dd {dd} --dr {dr!r} --h-safe {h_safe!r} --k-max {k_max!r} --a-max {a_max!r} "
                       f"--feed {feed!r}")
            t0 = time.perf_counter()
            try:
                params = PlanParameters(tool_radius=r, dd=dd, dr=dr, h_safe=h_safe, k_max=k_max, feed=feed,
                                        a_max=a_max, mode=mode)
                res = Planner(workers=2).plan(PlanJob(src, axis, params, profile, axes=True))  # (as `bladecam plan`)
                out = tmp / f"plan{k}"
                write_result(res, out)
                findings = verify(out).findings
                shutil.rmtree(out)  # ~100-300 MB each: only the options are kept
            except BladecamError as exc:
                msg = str(exc)  # the remedy named, where the feed is high for a_max (as the property test)
                expected = ("a_max" in msg and ("lower the feed" in msg or "cannot change speed" in msg)
                            and feed / a_max > 3.0)
                bad += not expected
                kind = "refused (expected)" if expected else "REFUSED"
                print(f"{k:3d} {name:6s} {kind}: {msg[:160]}\n    bladecam plan {options}", flush=True)
                continue
            if findings:
                bad += 1
                print(f"{k:3d} {name:6s} FINDINGS {len(findings)}: {findings[:2]}\n"
                      f"    bladecam plan {options}", flush=True)
            else:
                print(f"{k:3d} {name:6s} {mode:13s} clean ({time.perf_counter() - t0:.1f} s)", flush=True)
    print(f"{n} plans, {bad} refused or with findings")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

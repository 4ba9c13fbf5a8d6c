"""Shared test helpers: where the repository and the shared folder are."""

import os
from pathlib import Path

import pytest
from hypothesis import settings

from core.util.process import configure_process

configure_process()  # (before numpy: one BLAS thread per process, as in the application)

# the property tests draw the same examples on every run (CI lands a stop only when it passes: a
# failure must be reproducible, not luck); BLADECAM_HYPOTHESIS=random explores new ones locally
settings.register_profile("fixed", derandomize=True)
settings.register_profile("random", derandomize=False)
settings.load_profile(os.environ.get("BLADECAM_HYPOTHESIS", "fixed"))

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"
BLADEX = SHARED / "data" / "bladex-test-blade"
CHECKS = SHARED / "checks"
#: the coarse parameters of a quick plan of the sample blade (about a second of paths), for the tests that
#: need a whole plan but not its detail: as PlanParameters keywords, and as the command line's options
COARSE = {"dr": 4.0, "dd": 0.5}
COARSE_ARGS = ("--dr", "4", "--dd", "0.5")


@pytest.fixture(scope="session")
def bladex_dir() -> Path:
    if not (BLADEX / "upper.stl").is_file():
        pytest.skip("shared BladeX data not present")
    return BLADEX


@pytest.fixture(scope="session")
def sample_paths():
    """``sample_paths(**params)``: the sample blade's paths (a PathPlan) for those PlanParameters
    keywords, planned once per session whichever test asks first (the paths of one dR serve many test
    modules). Planned in two worker processes, with the fitted curves kept (as one process keeps them)."""
    from core.blade.source import load_blade
    from core.paths.planning import plan_paths
    from core.records import PlanParameters

    planned: dict[tuple, object] = {}

    def paths(**params):
        key = tuple(sorted(params.items()))
        if key not in planned:
            planned[key] = plan_paths(load_blade("sample"), PlanParameters(**params), workers=2, reusable=True)
        return planned[key]

    return paths


def bladecam(*args: str, cwd: Path | None = None, env: dict | None = None, timeout: float = 600):
    """``python -m core ARGS`` in a fresh process (the repository's folder unless ``cwd``), its
    output captured (subprocess.CompletedProcess)."""
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "core", *args], cwd=cwd or REPO, capture_output=True,
                          text=True, timeout=timeout, env=env)


def bladecam_process(*args: str, **popen):
    """``python -m core ARGS`` started in a fresh process (subprocess.Popen; ``popen``: its keywords)."""
    import subprocess
    import sys

    popen.setdefault("cwd", REPO)
    return subprocess.Popen([sys.executable, "-m", "core", *args], **popen)


def plan_on(paths, source: str = "sample", axis: str = "z", workers: int = 1, progress=None, listener=None,
            **job):
    """A whole plan (core.planner.Planner) on paths planned already (a PathPlan of ``source``): the
    job's parameters default to the paths' own; the result carries the axis tables with ``axes=True``."""
    from core.planner import Planner
    from core.records import PlanJob

    job.setdefault("params", paths.params)
    job.setdefault("axes", False)
    return Planner.seeded(paths, source, axis, workers).plan(PlanJob(source, axis, **job), progress=progress,
                                                             listener=listener)

"""Shared test helpers: where the repository and the shared folder are, the command line run in-process
(``cli``) or in a fresh process (``bladecam``), the sample's paths and its plan at the defaults, planned
once per session."""

import contextlib
import io
import os
import signal
from pathlib import Path
from typing import NamedTuple

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


@pytest.fixture(scope="session")
def coarse_result(sample_paths):
    """The sample's coarse whole plan in memory (core.planner's result on ``sample_paths(**COARSE)``,
    without the axis tables), planned once per session: read it, never change it."""
    return plan_on(sample_paths(**COARSE))


@pytest.fixture(scope="session")
def sample_plan_dir(tmp_path_factory) -> Path:
    """The sample blade planned at the default parameters (``bladecam plan``: the axis tables, verified;
    about a minute, ~390 MB), once per session, in-process. Read it; a test that edits a plan folder
    copies it first (shutil.copytree)."""
    from core.cli import main

    out = tmp_path_factory.mktemp("sample-defaults") / "plan"
    with _signals_kept():
        assert main(["plan", "--out", str(out)]) == 0
    return out


@contextlib.contextmanager
def _signals_kept():
    """core.cli.main turns SIGTERM and SIGHUP into an interrupt in its process: the test process gets
    its own handlers back afterwards."""
    names = [name for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name)]
    kept = {name: signal.getsignal(getattr(signal, name)) for name in names}
    try:
        yield
    finally:
        for name, handler in kept.items():
            signal.signal(getattr(signal, name), handler)


class Ran(NamedTuple):
    """What ``cli`` ran: named as subprocess.CompletedProcess names them, and a tuple (code, out, err)."""

    returncode: int
    stdout: str
    stderr: str


def cli(capsys, *args) -> Ran:
    """(exit status, stdout, stderr) of ``bladecam ARGS`` run in-process (core.cli.main): the command
    line's own code without a fresh interpreter's start-up. ``capsys``: the test's, or None in a fixture
    of a wider scope (the output is then caught by redirecting sys.stdout and sys.stderr). A test of the
    real process (its exit codes, a kill, stdin or stdout piping, start-up imports) uses ``bladecam``."""
    from core.cli import main

    out, err = io.StringIO(), io.StringIO()
    with _signals_kept(), contextlib.ExitStack() as stack:
        if capsys is None:
            stack.enter_context(contextlib.redirect_stdout(out))
            stack.enter_context(contextlib.redirect_stderr(err))
        try:
            code = main([str(a) for a in args])
        except SystemExit as exc:  # (argparse's own errors and --help)
            code = exc.code if isinstance(exc.code, int) else 2
    if capsys is None:
        return Ran(code, out.getvalue(), err.getvalue())
    return Ran(code, *capsys.readouterr())


class Written(NamedTuple):
    """A plan folder written by ``bladecam plan``, and that run."""

    folder: Path
    run: Ran


@pytest.fixture(scope="session")
def coarse_plan(tmp_path_factory) -> Written:
    """The sample's coarse plan (COARSE_ARGS: the axis tables too, verified) written by ``bladecam plan``
    in-process, once per session for every test that reads a whole plan folder: (its folder, the run).
    Read it; a test that edits a plan folder copies it first (shutil.copytree)."""
    out = tmp_path_factory.mktemp("sample-coarse") / "plan"
    run = cli(None, "plan", *COARSE_ARGS, "--out", out)
    assert run.returncode == 0, run.stderr
    return Written(out, run)


def bladecam(*args: str, cwd: Path | None = None, env: dict | None = None, timeout: float = 600):
    """``python -m core ARGS`` in a fresh process (the repository's folder unless ``cwd``), its
    output captured (subprocess.CompletedProcess). For a test of the process itself; else ``cli``."""
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

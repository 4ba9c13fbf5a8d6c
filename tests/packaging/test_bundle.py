"""The desktop bundle: build dist/bladecam/ with PyInstaller and run it with no Python around.

Slow (the build takes about two minutes on two cores), so not part of ``make test``:

    .venv/bin/python -m pytest -q -m slow tests/packaging

The build is the same command as ``make package`` (into the repository's dist/ and build/). To test an
existing bundle instead, set BLADECAM_BUNDLE=path/to/dist/bladecam.
"""

from __future__ import annotations

import csv
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

import core

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[2]
BUILD_TIMEOUT = 1800  # s
RUN_TIMEOUT = 600  # s


@pytest.fixture(scope="module")
def bundle() -> Path:
    """dist/bladecam/, freshly built (or BLADECAM_BUNDLE)."""
    given = os.environ.get("BLADECAM_BUNDLE")
    if given:
        folder = Path(given).resolve()
    else:
        pytest.importorskip("PyInstaller", reason="the 'package' extras are not installed (make package)")
        cmd = [sys.executable, "-m", "PyInstaller", "--noconfirm", "--clean", "--distpath", "dist",
               "--workpath", "build", "packaging/bladecam.spec"]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=BUILD_TIMEOUT)
        assert proc.returncode == 0, f"PyInstaller failed:\n{proc.stderr[-4000:]}"
        folder = REPO / "dist" / "bladecam"
        size = sum(f.stat().st_size for f in folder.rglob("*") if f.is_file() and not f.is_symlink())
        print(f"\nbundle built in {time.perf_counter() - t0:.0f} s: {folder} {size / 2**20:.0f} MiB")
    assert (folder / "bladecam").is_file() and os.access(folder / "bladecam", os.X_OK)
    return folder


@pytest.fixture
def bare_env(tmp_path) -> dict[str, str]:
    """An environment with no Python on PATH, no PYTHONHOME/PYTHONPATH, no virtualenv, no display."""
    empty = tmp_path / "empty-bin"
    empty.mkdir()
    env = {"PATH": str(empty), "HOME": str(tmp_path / "home"), "LANG": "C.UTF-8",
           "XDG_CONFIG_HOME": str(tmp_path / "config"), "XDG_CACHE_HOME": str(tmp_path / "cache")}
    assert shutil.which("python3", path=env["PATH"]) is None
    assert shutil.which("python", path=env["PATH"]) is None
    return env


def run(bundle: Path, *args: str, env: dict[str, str], cwd: Path, wrap: tuple[str, ...] = (),
        timeout: float = RUN_TIMEOUT) -> subprocess.CompletedProcess:
    return subprocess.run([*wrap, str(bundle / "bladecam"), *args], env=env, cwd=cwd, capture_output=True,
                          text=True, timeout=timeout)


def test_bundle_carries_its_interpreter_and_resources(bundle):
    internal = bundle / "_internal"
    assert list(internal.glob("libpython3*.so*")), "no libpython in the bundle"
    for name in ("sample_blade.csv", "machine.toml", "bladecam.png", "bladecam.svg"):
        assert (internal / "resources" / name).is_file(), f"resources/{name} missing"
    assert not (internal / "tests").exists()
    # the stand-in for `import vtk` (packaging/shims/vtk.py) keeps VTK's unused modules out
    assert not (internal / "vtkmodules" / "vtkIOIOSS.cpython-311-x86_64-linux-gnu.so").exists()
    assert (internal / "vtkmodules" / "vtkRenderingOpenGL2.cpython-311-x86_64-linux-gnu.so").exists()


def test_version(bundle, bare_env, tmp_path):
    proc = run(bundle, "--version", env=bare_env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"bladecam {core.__version__}"


def test_blade_info(bundle, bare_env, tmp_path):
    proc = run(bundle, "blade", "info", "--json", env=bare_env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    info = json.loads(proc.stdout)
    assert info["tip_radius_mm"] > info["hub_radius_mm"] > 0


def test_input_error_is_one_line(bundle, bare_env, tmp_path):
    proc = run(bundle, "blade", "info", "--blade", str(tmp_path / "missing.csv"), env=bare_env, cwd=tmp_path)
    assert proc.returncode == 2
    assert proc.stderr.startswith("bladecam: error:") and "Traceback" not in proc.stderr


def test_plan_and_verify_match_the_source(bundle, bare_env, tmp_path):
    out = tmp_path / "plan"
    proc = run(bundle, "plan", "--dr", "4", "--out", str(out), env=bare_env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("planned ")
    for name in ("pairs.csv", "left_cl.csv", "right_cl.csv", "plan.json"):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, f"{name} missing or empty"
    plan = json.loads((out / "plan.json").read_text())
    assert isinstance(plan, dict) and plan
    with (out / "pairs.csv").open(newline="") as fh:
        assert sum(1 for _ in csv.reader(fh)) > 100

    # the frozen program computes exactly what the source does
    ref = tmp_path / "plan-source"
    src = subprocess.run([sys.executable, "-m", "core", "plan", "--dr", "4", "--out", str(ref)], cwd=REPO,
                         capture_output=True, text=True, timeout=RUN_TIMEOUT)
    assert src.returncode == 0, src.stderr
    for name in ("pairs.csv", "left_cl.csv", "right_cl.csv"):
        assert (out / name).read_bytes() == (ref / name).read_bytes(), f"{name} differs from the source run"

    proc = run(bundle, "verify", str(out), env=bare_env, cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.splitlines()[-1].startswith("ok: 0 findings")


@pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="xvfb-run not installed (make sysdeps)")
def test_workbench_starts_with_no_arguments(bundle, bare_env, tmp_path):
    """No arguments opens the workbench; --smoke-ms (launcher only) waits for the sample plan and quits."""
    env = dict(bare_env, PATH="/usr/bin:/bin")  # for xvfb-run, Xvfb and xauth; the bundle needs none of it
    wrap = ("xvfb-run", "-a", "-s", "-screen 0 1600x1000x24")
    proc = run(bundle, "--smoke-ms", "300000", env=env, cwd=tmp_path, wrap=wrap, timeout=RUN_TIMEOUT)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-4000:]
    line = next(x for x in proc.stdout.splitlines() if x.startswith("smoke:"))
    assert line.startswith("smoke: ok: window 'bladecam"), line
    assert re.search(r"VTK \d+\.\d+", line), line  # the About box's `import vtk` works in the bundle

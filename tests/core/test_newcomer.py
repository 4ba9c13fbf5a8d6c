"""A newcomer's path: the workbench without a display says so in one line, ``make run`` without one
plans the sample and pictures the workbench, ``make`` says what takes its minute, and the tests leave
nothing behind in pytest's temporary folder."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

from tests.conftest import REPO, bladecam


def _headless_env() -> dict:
    env = dict(os.environ)
    for name in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM"):
        env.pop(name, None)
    return env


def test_the_workbench_without_a_display_says_so_in_one_line():
    done = bladecam("gui", env=_headless_env(), timeout=120)
    lines = [ln for ln in done.stderr.splitlines() if ln.strip()]
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1 and "no display" in lines[0] and "DISPLAY" in lines[0], done.stderr
    assert "xcb" not in done.stderr and "Traceback" not in done.stderr


def test_make_run_without_a_display_plans_and_pictures_the_sample():
    # -B: every recipe as on a fresh machine, where the venv does not exist yet
    done = subprocess.run(["make", "-n", "-B", "run"], cwd=REPO, capture_output=True, text=True,
                          env=_headless_env())
    script = done.stdout
    assert done.returncode == 0, done.stderr
    plan = script.index("-m core plan --out out/sample")
    shot = script.index("-m bladecam_gui --screenshot out/sample-workbench.png")
    assert plan < shot and "xvfb-run" in script[plan:shot + 60]
    assert "installing the Python packages (about a minute)" in script


def test_a_passing_session_leaves_no_temporary_folders(tmp_path):
    tests = tmp_path / "t"
    tests.mkdir()
    (tests / "test_big.py").write_text(textwrap.dedent("""
        import pytest

        @pytest.fixture(scope="module")
        def shared(tmp_path_factory):
            d = tmp_path_factory.mktemp("plan")
            (d / "rows.csv").write_bytes(b"0" * 100_000)
            return d

        def test_writes(tmp_path, shared):
            (tmp_path / "rows.csv").write_bytes(b"0" * 100_000)
    """))
    root = tmp_path / "temproot"
    root.mkdir()
    env = {**os.environ, "PYTEST_DEBUG_TEMPROOT": str(root)}
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:xvfb", "-c",
                           str(REPO / "pyproject.toml"), "--rootdir", str(tests), str(tests / "test_big.py")],
                          cwd=tests, capture_output=True, text=True, env=env, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    left = [p for p in root.rglob("*") if p.is_file()]
    assert not left, left

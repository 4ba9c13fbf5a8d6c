"""Files are never lost and nothing is left behind, one test per class:
a folder is replaced only if it is provably a plan folder bladecam wrote; a kill between the two
renames of a plan folder's swap is recovered at once; forked workers die with their parent and the
next run clears the scratch folders of dead processes; plan folders follow the umask; a refused
--out is refused before any planning, by the same rule atomic_folder applies."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from core.errors import OutputError
from core.output.files import LEGACY_FILES, atomic_folder, check_destination, plan_folder_files
from core.util.scratch import _host, die_with_parent, scratch_owner, sweep_worker_scratch

from ...conftest import COARSE_ARGS, REPO, bladecam_process, cli

COARSE = [*COARSE_ARGS, "--no-axes"]
linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux /proc and prctl")


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def _summary(files, **extra) -> str:
    return json.dumps({"bladecam_version": "0.test", "files": sorted(files), **extra})


# -- 1. what a plan folder is -------------------------------------------------------------------------

def _folder(tmp_path: Path, files: dict) -> Path:
    folder = tmp_path / "out"
    folder.mkdir()
    for name, text in files.items():
        if text is None:
            (folder / name).mkdir()
        elif isinstance(text, bytes):
            (folder / name).write_bytes(text)
        else:
            (folder / name).write_text(text)
    return folder


LEGACY_JSON = '{"bladecam_version": "0.1.0", "inputs": {}}'
PLAN_FILES = ["left_cl.csv", "pairs.csv", "plan.json", "right_cl.csv"]


@pytest.mark.parametrize("files", [
    {},
    {name: "x" for name in PLAN_FILES} | {"plan.json": _summary(PLAN_FILES)},
    {"pairs.csv": "x", "plan.json": LEGACY_JSON},  # an earlier version's (no file list), --paths-only
    {name: "x" for name in LEGACY_FILES} | {"plan.json": LEGACY_JSON},
], ids=["empty", "manifest", "legacy-paths-only", "legacy-all"])
def test_a_plan_folder_bladecam_wrote_is_recognised(tmp_path, files):
    folder = _folder(tmp_path, files)
    assert plan_folder_files(folder) == (set(files), "")


@pytest.mark.parametrize("files, why", [
    ({"plan.json": "{}", "thesis.tex": "x"}, "no bladecam_version.*thesis.tex"),
    ({"thesis.tex": "x"}, "no plan.json"),
    ({"plan.json": _summary(["plan.json"]), "thesis.tex": "x"}, "holds thesis.tex"),
    ({"plan.json": _summary(["plan.json", "pairs.csv"])}, "pairs.csv listed in its plan.json missing"),
    ({"plan.json": _summary(["plan.json"]), "data": None}, "holds data"),
    ({"plan.json": LEGACY_JSON, "pairs.csv": "x", "notes.txt": "x"}, "holds notes.txt"),
    ({"plan.json": LEGACY_JSON}, "pairs.csv missing"),
    ({"plan.json": '{"bladecam_version": "1", "files": "plan.json"}'}, "file list is malformed"),
    ({"plan.json": "[1, 2", "pairs.csv": "x"}, "no bladecam_version"),
    ({"plan.json": b"\xff\xfe{}", "pairs.csv": "x"}, "no bladecam_version"),
], ids=["json-without-version", "no-plan-json", "foreign-file", "listed-missing", "subfolder",
        "legacy-foreign", "legacy-no-pairs", "malformed-list", "not-json", "not-utf8"])
def test_anything_else_is_not_a_plan_folder_and_is_never_replaced(tmp_path, files, why):
    import re

    folder = _folder(tmp_path, files)
    found, reason = plan_folder_files(folder)
    assert found is None and re.search(why, reason), reason
    before = {p.name: p.stat().st_mtime_ns for p in folder.iterdir()}
    with pytest.raises(OutputError, match="is ever deleted"):
        with atomic_folder(folder) as tmp:
            (tmp / "plan.json").write_text(_summary(["plan.json"]))
    assert {p.name: p.stat().st_mtime_ns for p in folder.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_a_symlink_in_a_plan_folder_makes_it_foreign(tmp_path):
    folder = _folder(tmp_path, {"plan.json": LEGACY_JSON, "pairs.csv": "x"})
    (tmp_path / "elsewhere.csv").write_text("mine")
    os.symlink(tmp_path / "elsewhere.csv", folder / "left_cl.csv")
    assert plan_folder_files(folder)[0] is None


def test_the_issue_case_keeps_the_thesis_and_plans_nothing(tmp_path, capsys):
    proj = tmp_path / "proj"
    proj.mkdir()
    (proj / "plan.json").write_text("{}\n")
    (proj / "thesis.tex").write_text("x\n")
    res = cli(capsys, "plan", *COARSE, "--out", proj)
    assert res.returncode == 2 and "thesis.tex" in res.stderr and "ever deleted" in res.stderr, res.stderr
    assert "Traceback" not in res.stderr and not res.stdout
    assert (proj / "thesis.tex").read_text() == "x\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["proj"]


def test_a_folder_that_changes_while_the_plan_is_made_is_not_replaced(tmp_path):
    """The rule is applied again just before the swap: a file put into the plan folder meanwhile
    keeps the folder as it is (the new plan is not written)."""
    out = tmp_path / "plan"
    with atomic_folder(out) as tmp:
        (tmp / "plan.json").write_text(_summary(["plan.json"]))
    with pytest.raises(OutputError, match="holds notes.txt"):
        with atomic_folder(out) as tmp:
            (tmp / "plan.json").write_text(_summary(["plan.json"]))
            (out / "notes.txt").write_text("mine")
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "plan.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan"]


# -- 2. the two-rename window ----------------------------------------------------------------------

KILLED_BETWEEN_RENAMES = """
import os, signal, sys
import core.output.files as files
real = os.replace
def replace(src, dst):
    real(src, dst)
    if ".old-" in str(dst):  # (the previous plan moved aside: die before the new one moves in)
        os.kill(os.getpid(), signal.SIGKILL)
os.replace = replace
with files.atomic_folder(sys.argv[1]) as tmp:
    (tmp / "plan.json").write_text('{"bladecam_version": "new", "files": ["plan.json"]}')
"""


@pytest.fixture(scope="module")
def written_plan(coarse_plan) -> Path:
    return coarse_plan.folder  # (the session's: copied before it is replaced)


def _killed_between_renames(plan: Path, tmp_path: Path) -> Path:
    """A copy of ``plan`` in tmp_path, replaced by a process killed between its two renames."""
    out = tmp_path / "plan"
    shutil.copytree(plan, out)
    res = subprocess.run([sys.executable, "-c", KILLED_BETWEEN_RENAMES, str(out)], cwd=REPO)
    assert res.returncode == -signal.SIGKILL
    assert not out.exists() and [p.name for p in tmp_path.glob(".plan.old-*")]
    return out


def test_a_kill_between_the_two_renames_is_recovered_at_once(written_plan, tmp_path, capsys):
    """No plan folder is visible after the kill; the next run, ``bladecam verify`` and the workbench
    (check_destination, then atomic_folder) put the previous plan back at once (no sweep age)."""
    files = sorted(p.name for p in written_plan.iterdir())
    out = _killed_between_renames(written_plan, tmp_path)
    res = cli(capsys, "verify", out)
    assert res.returncode == 0 and "restored" in res.stderr, res.stdout + res.stderr
    assert sorted(p.name for p in out.iterdir()) == files and not list(tmp_path.glob(".plan.old-*"))
    # (verify only puts the plan back: the killed run's unfinished copy goes with the next run)

    shutil.rmtree(out)
    out = _killed_between_renames(written_plan, tmp_path)
    assert check_destination(out) == out.resolve()  # (bladecam plan and the export check first)
    assert sorted(p.name for p in out.iterdir()) == files and [p.name for p in tmp_path.iterdir()] == ["plan"]

    shutil.rmtree(out)
    out = _killed_between_renames(written_plan, tmp_path)
    res = cli(capsys, "plan", *COARSE, "--paths-only", "--out", out)  # the next run replaces it
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in out.iterdir()) == ["pairs.csv", "plan.json"]
    assert [p.name for p in tmp_path.iterdir()] == ["plan"]


def test_a_hidden_plan_of_a_running_process_is_left_alone(tmp_path):
    hidden = tmp_path / f".plan.old-{os.getpid()}@{scratch_owner().split('@', 1)[1]}"
    hidden.mkdir()
    check_destination(tmp_path / "plan")
    assert hidden.is_dir() and not (tmp_path / "plan").exists()


# -- 3. leaks after a kill -----------------------------------------------------------------------

def _children(pid: int) -> set[int]:
    found = set()
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.add(int(entry))
    return found


def _running(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except OSError:
        return False


def _shm(pid: int) -> list[str]:
    if not os.path.isdir("/dev/shm"):
        return []
    return [n for n in os.listdir("/dev/shm") if n.startswith(f"bladecam-{pid}@")]


@linux_only
@pytest.mark.parametrize("moment", ["paths", "tables"])
def test_kill_9_leaves_no_worker_and_the_next_run_sweeps(tmp_path, capsys, monkeypatch, moment):
    """kill -9 of ``python -m core plan`` (the parent alone, not its process group) while its path
    workers plan (moment "paths": their results folder in /dev/shm) or while its table helpers write
    beside the output (moment "tables"): every forked child ends within seconds, and the next run,
    with no sweep age set, leaves only its plan folder (and no /dev/shm folder of the dead run)."""
    out = tmp_path / "plan"
    for _attempt in range(5):
        proc = bladecam_process("plan", *COARSE, "--workers", "2", "--out", str(out), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        kids: set[int] = set()
        while proc.poll() is None:
            kids |= _children(proc.pid)
            if moment == "paths" and len(kids) >= 2 and _shm(proc.pid):
                break
            if moment == "tables" and any(p.name.startswith(".bladecam-spool-") for p in tmp_path.iterdir()):
                kids |= _children(proc.pid)
                break
        else:
            shutil.rmtree(out, ignore_errors=True)
            continue
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=60)
        break
    else:
        pytest.fail(f"never caught the plan at its {moment}")
    assert kids, "no forked child seen"
    deadline = time.monotonic() + 10
    while any(_running(k) for k in kids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [k for k in kids if _running(k)], "forked workers outlived their killed parent"
    left = _shm(proc.pid) if moment == "paths" else [p.name for p in tmp_path.glob(".bladecam-spool-*")]
    assert left, "the killed run left nothing to sweep"
    monkeypatch.delenv("BLADECAM_SWEEP_AGE_S", raising=False)
    res = cli(capsys, "plan", *COARSE, "--workers", "2", "--out", out)  # (the next run: in-process)
    assert res.returncode == 0, res.stderr
    assert [p.name for p in tmp_path.iterdir()] == ["plan"]
    assert not _shm(proc.pid)
    summary = json.loads((out / "plan.json").read_text())
    assert summary["files"] == sorted(p.name for p in out.iterdir())  # (its manifest)


BUSY_WORKERS = """
import sys, time
import core.paths.planning as planning
from core.blade.source import load_blade
from core.output.csvio import Helper
from core.records import PlanParameters

def busy(args):  # (a path chunk that takes a minute: a fine plan's)
    time.sleep(60)

planning._plan_chunk_to_file = busy
job = planning.PathsJob(load_blade("sample"), PlanParameters(dr=4, dd=0.5), workers=2)
helper = Helper([("right_cl.csv", time.sleep, (60,))], 2)
print("busy", flush=True)
time.sleep(60)
"""


@linux_only
def test_busy_workers_and_helpers_die_with_their_killed_parent():
    """Path workers and a table helper in the middle of a minute's work: a kill -9 of their parent
    ends them at once (they do not finish their work first)."""
    proc = subprocess.Popen([sys.executable, "-c", BUSY_WORKERS], cwd=REPO, stdout=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        assert proc.stdout.readline().strip() == "busy"
        kids = _children(proc.pid)
        assert len(kids) >= 3, kids  # (two path workers, one helper)
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(timeout=60)
    deadline = time.monotonic() + 5
    while any(_running(k) for k in kids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not [k for k in kids if _running(k)], "forked workers outlived their killed parent"


@linux_only
def test_a_child_whose_parent_died_before_it_asked_ends(tmp_path):
    """die_with_parent closes the race of a parent dying between the fork and the prctl call: a
    parent other than the one given means it is gone, and the child ends at once."""
    pid = os.fork()
    if pid == 0:
        try:
            die_with_parent(os.getppid() + 1 if os.getppid() > 1 else 2)
            os._exit(0)
        except BaseException:
            os._exit(3)
    assert os.waitpid(pid, 0)[1] >> 8 == 1
    pid = os.fork()
    if pid == 0:
        die_with_parent(os.getppid())
        os._exit(0)
    assert os.waitpid(pid, 0)[1] >> 8 == 0


@linux_only
def test_worker_scratch_of_dead_processes_is_swept(tmp_path):
    if not os.access("/dev/shm", os.W_OK):
        pytest.skip("no writable /dev/shm")
    ours = scratch_owner().split("@", 1)[1]
    dead = _dead_pid()
    made = {key: Path("/dev/shm") / name for key, name in {
        "dead": f"bladecam-{dead}@{ours}-t1", "alive": f"bladecam-{os.getpid()}@{ours}-t2",
        "aged": f"bladecam-{dead}@{_host()}-t3", "remote": f"bladecam-{dead}@elsewhere-t4"}.items()}
    try:
        for path in made.values():
            path.mkdir()
            (path / "chunk0.pkl").write_bytes(b"x")
        done = sweep_worker_scratch()
        assert str(made["dead"]) in done and not made["dead"].exists()
        assert all(made[k].exists() for k in ("alive", "aged", "remote"))
    finally:
        for path in made.values():
            shutil.rmtree(path, ignore_errors=True)


# -- 4. the umask ----------------------------------------------------------------------------------

@pytest.mark.parametrize("umask, mode", [(0o022, 0o755), (0o027, 0o750), (0o002, 0o775)])
def test_a_plan_folder_follows_the_umask(tmp_path, umask, mode):
    old = os.umask(umask)
    try:
        with atomic_folder(tmp_path / "plan") as tmp:
            (tmp / "plan.json").write_text(_summary(["plan.json"]))
    finally:
        os.umask(old)
    assert (tmp_path / "plan").stat().st_mode & 0o777 == mode
    assert (tmp_path / "plan" / "plan.json").stat().st_mode & 0o777 == mode & 0o666


# -- 5. a refused --out is refused first ----------------------------------------------------------

def _refused(tmp_path):
    (tmp_path / "a_file").write_text("x")
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "letter.txt").write_text("x")
    return {"file": (tmp_path / "a_file", "exists and is not a folder"),
            "parent-is-a-file": (tmp_path / "a_file" / "plan", "cannot write into"),
            "not-a-plan-folder": (tmp_path / "docs", "letter.txt")}


@pytest.mark.parametrize("case", ["file", "parent-is-a-file", "not-a-plan-folder"])
def test_a_refused_out_is_refused_before_any_planning(tmp_path, monkeypatch, capsys, case):
    """bladecam plan refuses before it plans anything (the planner is never called), with the very
    message atomic_folder gives (one rule: check_destination)."""
    from core.cli import main
    from core.planner import Planner

    out, why = _refused(tmp_path)[case]

    def never(*args, **kwargs):
        raise AssertionError("planned before the output folder was checked")

    monkeypatch.setattr(Planner, "plan", never)
    assert main(["plan", *COARSE, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert why in err, err
    with pytest.raises(OutputError) as by_atomic:
        with atomic_folder(out):
            pass
    assert f"bladecam: error: {by_atomic.value}" in err


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_an_unwritable_parent_is_refused_first(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    try:
        with pytest.raises(OutputError, match="cannot write into"):
            check_destination(locked / "sub" / "plan")
    finally:
        locked.chmod(0o755)


def test_the_workbench_uses_the_same_rule():
    pytest.importorskip("PySide6")
    import bladecam_gui.export as export

    assert export.check_destination is check_destination

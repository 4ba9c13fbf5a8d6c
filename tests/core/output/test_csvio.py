import csv
import io
from pathlib import Path

import numpy as np
import pytest

from core.errors import OutputError
from core.output.csvio import csv_body, csv_bytes
from core.output.files import atomic_folder


@pytest.mark.parametrize("decimals", [0, 1, 4, 9])
def test_fixed_point_matches_python_formatting(decimals):
    rng = np.random.default_rng(decimals)
    v = np.concatenate([rng.normal(0, 100, 2000), rng.normal(0, 1e-3, 200), [0.0, -0.0, 1.0, -1.0,
                        9.999999999, -9.5, 123456.0, -5e-10, 5e-10, 10.0, 99.99999, -100.0]])
    text = csv_bytes(["v"], [("f", v, decimals)]).decode()
    got = text.splitlines()[1:]
    want = []
    for x in v:
        w = f"{round(x * 10**decimals) / 10**decimals:.{decimals}f}"
        want.append("0" + w[2:] if w.startswith("-0") and float(w) == 0 and False else w)
    for g, w, x in zip(got, want, v):
        assert float(g) == pytest.approx(float(w), abs=10.0 ** -decimals * 0.51), (g, w, x)
        assert "e" not in g and " " not in g


def test_mixed_columns_parse_back():
    n = 500
    rng = np.random.default_rng(1)
    ints = rng.integers(-5, 3000, n)
    strs = rng.choice(["tip", "edge", "variable", "internal"], n)
    f = rng.normal(0, 50, n)
    data = csv_bytes(["a", "b", "c"], [("i", ints, None), ("s", strs, None), ("f", f, 6)])
    rows = list(csv.reader(io.StringIO(data.decode())))
    assert rows[0] == ["a", "b", "c"] and len(rows) == n + 1
    assert [int(r[0]) for r in rows[1:]] == ints.tolist()
    assert [r[1] for r in rows[1:]] == strs.tolist()
    assert np.allclose([float(r[2]) for r in rows[1:]], f, atol=5e-7)


def test_non_finite_refused():
    with pytest.raises(OutputError, match="non-finite"):
        csv_bytes(["x"], [("f", np.array([1.0, np.nan]), 3)])


#: a plan.json as core.output.files.write_plan writes it for a folder of a.csv and plan.json
SUMMARY = '{"bladecam_version": "test", "files": ["a.csv", "plan.json"]}'


def test_atomic_folder_all_or_nothing(tmp_path):
    out = tmp_path / "plan"
    with atomic_folder(out) as tmp:
        (tmp / "plan.json").write_text(SUMMARY)
        (tmp / "a.csv").write_text("1")
    assert sorted(p.name for p in out.iterdir()) == ["a.csv", "plan.json"]
    with pytest.raises(RuntimeError):
        with atomic_folder(out) as tmp:
            (tmp / "plan.json").write_text("{new}")
            raise RuntimeError("crash in the middle")
    assert (out / "plan.json").read_text() == SUMMARY
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan"]
    with atomic_folder(out) as tmp:  # a plan folder bladecam wrote is replaced
        (tmp / "plan.json").write_text(SUMMARY)
        (tmp / "a.csv").write_text("2")
    assert (out / "a.csv").read_text() == "2" and sorted(p.name for p in tmp_path.iterdir()) == ["plan"]


def test_blocks_codes_and_row_ends(monkeypatch):
    """Rows formatted in blocks (a block size that does not divide the rows), a coded string column
    and the row offsets agree with Python's own formatting of every row."""
    import core.output.csvio as csvio

    monkeypatch.setattr(csvio, "BLOCK_ROWS", 97)
    n = 1000
    rng = np.random.default_rng(7)
    f = rng.normal(0, 1e3, n)
    f[::50] *= 1e4  # wider numbers in some blocks only
    codes = rng.integers(0, 3, n)
    names = ["tip", "internal", "edge"]
    ints = rng.integers(-99, 99999, n)
    body, ends = csvio.csv_body([("f", f, 4), ("c", (codes, names), None), ("i", ints, None)])
    want = [f"{x:.4f},{names[c]},{i}\n" for x, c, i in zip(f, codes, ints)]
    assert body.decode() == "".join(want)
    assert ends.tolist() == np.cumsum([len(w) for w in want]).tolist()
    head = b"a,b,c\n"
    assert csvio.csv_bytes(["a", "b", "c"], [("f", f, 4), ("c", (codes, names), None), ("i", ints, None)]) == head + body


def _table():
    return {"t": np.arange(3.0)}


def _refuse():
    from core.errors import PlanningError

    raise PlanningError("right_cl.csv: unexpected header")


@pytest.mark.parametrize("workers", [1, 2])
def test_helper_returns_values_and_raises_bladecam_errors_as_they_are(workers):
    """A forked Helper hands back bytes as they are and other values pickled; a bladecam error in a
    job is raised again in the caller with its own type and message (as without a helper)."""
    from core.errors import PlanningError
    from core.output.csvio import Helper

    helper = Helper([("a", bytes, (b"x,y\n",)), ("b", _table, ())], workers)
    try:
        out = helper.results()
    finally:
        helper.close()
    assert out["a"] == b"x,y\n" and out["b"]["t"].tolist() == [0.0, 1.0, 2.0]
    helper = Helper([("c", _refuse, ())], workers, doing="reading")
    try:
        with pytest.raises(PlanningError, match="^right_cl.csv: unexpected header$"):
            helper.results()
    finally:
        helper.close()


def test_helper_spools_bytes_into_files_and_removes_what_is_left(tmp_path):
    """With spool_in, a forked Helper writes bytes results into a scratch folder of its own there and
    hands back their paths (other values still come back pickled); close() removes the folder and
    what is still in it. A folder it cannot write into means bytes through the pipe, as without."""
    from core.output.csvio import Helper

    helper = Helper([("a.csv", bytes, (b"x,y\n1,2\n",)), ("b", _table, ())], 2, spool_in=tmp_path)
    try:
        out = helper.results()
        assert isinstance(out["a.csv"], Path) and out["a.csv"].parent == helper.spool
        assert out["a.csv"].parent.parent == tmp_path and out["a.csv"].read_bytes() == b"x,y\n1,2\n"
        assert out["b"]["t"].tolist() == [0.0, 1.0, 2.0]
    finally:
        helper.close()
    assert list(tmp_path.iterdir()) == []
    helper = Helper([("a.csv", bytes, (b"x\n",))], 2, spool_in=tmp_path / "missing")
    try:
        assert helper.spool is None and helper.results() == {"a.csv": b"x\n"}
    finally:
        helper.close()


def test_a_helper_that_cannot_start_leaves_no_scratch_folder(tmp_path, monkeypatch):
    """The process cannot be started (too many processes, no memory to fork): the error is raised
    and the helper's scratch folder is gone; tables written beside a plan folder whose second thread
    cannot start stop the first and leave no scratch folder either."""
    import multiprocessing.context
    import threading

    from core.output.csvio import Helper
    from core.output.writer import EarlyTables

    def refuse(self):
        raise OSError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(multiprocessing.context.ForkProcess, "start", refuse)
    with pytest.raises(OSError, match="temporarily unavailable"):
        Helper([("a.csv", bytes, (b"x\n",))], 2, spool_in=tmp_path)
    assert list(tmp_path.iterdir()) == []

    started = []
    real_start = threading.Thread.start

    def second_fails(self):
        if started:
            raise RuntimeError("can't start new thread")
        real_start(self)
        started.append(self)

    monkeypatch.undo()
    monkeypatch.setattr(threading.Thread, "start", second_fails)
    samples = type("S", (), {"step": np.ones(3, int), "code": np.zeros(3, int), "path": np.zeros(3, int),
                             "cutting": np.zeros(3, bool), "tips": np.zeros((3, 3)), "axes": np.zeros((3, 3))})()
    timeline = type("T", (), {"t": np.arange(3.0), "left": samples, "right": samples})()
    assert EarlyTables.start(timeline, None, tmp_path / "plan") is None  # (write_plan writes them itself)
    assert len(started) == 1 and not started[0].is_alive()
    assert list(tmp_path.iterdir()) == []


def test_a_spooling_helper_that_fails_or_dies_leaves_nothing(tmp_path):
    """A job that fails in a spooling helper (its file half-written or not) is an OutputError naming
    the job; a helper killed mid-way is one too; either way close() leaves no scratch folder."""
    import os
    import signal

    from core.errors import OutputError
    from core.output.csvio import Helper

    helper = Helper([("a.csv", bytes, (b"x\n",)), ("b.csv", _broken, ())], 2, spool_in=tmp_path)
    try:
        with pytest.raises(OutputError, match="b.csv"):
            helper.results()
    finally:
        helper.close()
    assert list(tmp_path.iterdir()) == []
    helper = Helper([("c.csv", _slow, ())], 2, spool_in=tmp_path)
    try:
        os.kill(helper.proc.pid, signal.SIGKILL)
        with pytest.raises(OutputError, match="c.csv"):
            helper.results()
    finally:
        helper.close()
    assert list(tmp_path.iterdir()) == []


def _broken():
    raise ValueError("no room left on the device (simulated)")


def _slow():
    import time

    time.sleep(30)
    return b"late\n"


def _dead_pid() -> int:
    """The pid of a process that has ended (and is reaped)."""
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_scratch_left_by_a_killed_run_is_cleared_by_the_next_one(tmp_path, monkeypatch):
    """What a run killed outright left beside its plan folder: its helpers' scratch folders, its
    unfinished copy and a workbench export's staging go; the previous plan it had moved aside comes
    back (the run died between its two renames). A process of this boot and pid namespace that no
    longer runs is known dead: its folders go at once; those named by this host only (an earlier
    version, another pid namespace) wait for the sweep age. A running process's folders, other
    hosts', other plans' and malformed names are left alone."""
    import os

    from core.output.files import sweep_scratch
    from core.util.scratch import _host, scratch_owner

    ours, bare = scratch_owner().split("@", 1)[1], _host()
    assert ours.startswith(bare + "_") and len(ours) == len(bare) + 9  # (Linux: boot and pid namespace)
    dead, alive = _dead_pid(), os.getpid()
    made = {}
    for key, name in {"spool": f".bladecam-spool-{dead}@{ours}-abc", "tmp": f".plan.tmp-{dead}@{ours}-x1",
                      "old": f".plan.old-{dead}@{ours}", "export": f".plan.export-{dead}@{ours}-3",
                      "aged": f".bladecam-spool-{dead}@{bare}-ghi", "aged_tmp": f".plan.tmp-{dead}@{bare}-x4",
                      "live": f".bladecam-spool-{alive}@{ours}-def",
                      "remote": f".plan.tmp-{dead}@elsewhere-x2", "other": f".other.tmp-{dead}@{ours}-x3",
                      "huge": f".bladecam-spool-99999999999999999999@{ours}-x",
                      "big": f".bladecam-spool-9999999999@{ours}-y"}.items():
        made[key] = tmp_path / name
        made[key].mkdir()
        (made[key] / "left_cl.csv").write_text(key)
    (tmp_path / "keep.txt").write_text("mine")
    done = sweep_scratch(tmp_path, "plan")
    gone = ("spool", "tmp", "old", "export")
    assert sorted(p.name for p in done) == sorted(made[k].name for k in gone)
    assert not any(made[k].exists() for k in gone)
    assert (tmp_path / "plan" / "left_cl.csv").read_text() == "old"  # the previous plan is back
    assert all(made[k].exists() for k in made if k not in gone) and (tmp_path / "keep.txt").exists()
    monkeypatch.setenv("BLADECAM_SWEEP_AGE_S", "0")  # (as if they were older than the sweep age)
    done = sweep_scratch(tmp_path, "plan")
    assert sorted(p.name for p in done) == sorted(made[k].name for k in ("aged", "aged_tmp"))
    # with the plan folder there, a stale moved-aside copy is removed (a plan folder: only its own
    # files), not restored over it; one holding a file bladecam did not write stays
    stale = tmp_path / f".plan.old-{dead}@{ours}"
    stale.mkdir()
    (stale / "plan.json").write_text(SUMMARY)
    (stale / "a.csv").write_text("1")
    sweep_scratch(tmp_path, "plan")
    assert not stale.exists() and (tmp_path / "plan" / "left_cl.csv").read_text() == "old"
    stale.mkdir()
    (stale / "notes.txt").write_text("mine")
    sweep_scratch(tmp_path, "plan")
    assert (stale / "notes.txt").read_text() == "mine"


def test_atomic_folder_sweeps_before_writing(tmp_path):
    from core.util.scratch import scratch_owner

    host = scratch_owner().split("@", 1)[1]
    left = tmp_path / f".plan.tmp-{_dead_pid()}@{host}-zz"
    left.mkdir()
    with atomic_folder(tmp_path / "plan") as tmp:
        assert not left.exists()
        (tmp / "plan.json").write_text(SUMMARY)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan"]


def test_csv_chunks_can_be_written_twice_and_refuse_early():
    from core.output.csvio import CsvChunks

    v = np.arange(200000) / 7.0
    chunks = CsvChunks(["v"], [("f", v, 4)])
    first = bytes(chunks)
    assert bytes(chunks) == first == b"".join(chunks) == csv_bytes(["v"], [("f", v, 4)])
    v[123456] = np.nan
    with pytest.raises(OutputError, match="row 123456"):
        CsvChunks(["v"], [("f", v, 4)])


def _fixed_point(x: float, decimals: int) -> str:
    """The fixed-point text of x as the tables write it, by Python's integer formatting: x * 10**decimals
    rounded half to even, '-' only when that is negative, at least one digit before the point."""
    m = int(np.rint(x * 10.0**decimals))
    digits = str(abs(m)).rjust(decimals + 1, "0")
    text = digits[:len(digits) - decimals] + ("." + digits[len(digits) - decimals:] if decimals else "")
    return ("-" if m < 0 else "") + text


@pytest.mark.parametrize("decimals", [0, 1, 6, 9, 10])
def test_compiled_formatter_edge_values(decimals):
    """The compiled formatter on negative zero, rounding ties (half to even, both signs), values a
    hair either side of a tie, the smallest and largest magnitudes it writes, and integers."""
    rng = np.random.default_rng(decimals)
    k = rng.integers(-10**6, 10**6, 3000)
    limit = 2.0**53 / 10.0**decimals
    ties = (k + 0.5) / 10.0**decimals
    v = np.concatenate([
        [0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 1e-300, -1e-300, 5e-324, -5e-324,
         0.5 / 10.0**decimals, -0.5 / 10.0**decimals, 1.5 / 10.0**decimals, -1.5 / 10.0**decimals,
         limit * 0.999, -limit * 0.999, 123456.0, -9.5],
        ties, np.nextafter(ties, np.inf), np.nextafter(ties, -np.inf), k / 10.0**decimals,
        rng.normal(size=3000) * 10.0 ** rng.integers(-12, 6, 3000)])
    v = v[np.abs(v) < limit]
    ints = rng.integers(-10**15, 10**15, len(v))
    body, ends = csv_body([("f", v, decimals), ("i", ints, None), ("c", (np.arange(len(v)) % 2, ["a", "bc"]), None)])
    want = [f"{_fixed_point(x, decimals)},{i},{'bc' if j % 2 else 'a'}\n" for j, (x, i) in enumerate(zip(v, ints))]
    assert body.decode() == "".join(want)
    assert ends.tolist() == np.cumsum([len(w) for w in want]).tolist()


def test_compiled_formatter_refuses_what_it_cannot_write():
    """A number beyond 2**53 once scaled, or a code outside the names, is an OutputError naming the
    row (nothing is written)."""
    from core.output.csvio import format_block

    with pytest.raises(OutputError, match="row 2"):
        format_block([("f", np.array([1.0, 2.0, 1e10]), 6)])
    with pytest.raises(OutputError, match="row 1"):
        format_block([("i", np.array([1, 2**60]), None)])
    with pytest.raises(OutputError, match="row 0: a code outside"):
        format_block([("c", (np.array([2]), ["a", "b"]), None)])
    assert format_block([("f", np.zeros(0), 3)])[0] == b""


def test_without_the_built_formatter_the_error_says_how_to_build_it(monkeypatch):
    import core.output.csvio as csvio

    monkeypatch.setattr(csvio, "_format_rows", None)
    with pytest.raises(OutputError, match=r"not built: run `pip install -e \.`"):
        csvio.csv_bytes(["v"], [("f", np.arange(3.0), 2)])

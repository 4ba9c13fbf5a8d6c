"""bladecam verify against tampering, one test per kind: all four tables cut at
the same row, every row of one path deleted, both axis tables deleted with machine.toml kept, the
velocity columns zeroed, a row's cutting flag flipped and the row moved, pairs.csv missing, and a
relative --blade path verified from another folder. Also: the report's lines and counts, and the
derivative rule on uniform and non-uniform time columns."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from core.blade.source import sample_table_path
from core.verify.axes import derivative_slack
from core.verify.check import verify
from core.verify.report import LINE_MAX, SHOWN_PER_KIND, Report

from ...conftest import COARSE_ARGS, Ran, cli

COARSE = COARSE_ARGS
TABLES = ("left_cl.csv", "right_cl.csv", "left_axes.csv", "right_axes.csv")


@pytest.fixture(scope="module")
def plan(coarse_plan) -> Path:
    """The session's coarse plan (``bladecam plan COARSE``, with the axis tables): copied before an edit."""
    assert coarse_plan.run.returncode == 0, coarse_plan.run.stderr
    return coarse_plan.folder


def _copy(plan: Path, dst: Path) -> Path:
    shutil.copytree(plan, dst)
    return dst


def _rows(path: Path) -> tuple[str, list[str]]:
    head, *rows = path.read_text().splitlines()
    return head, rows


def _write(path: Path, head: str, rows: list[str]) -> None:
    path.write_text("\n".join([head, *rows]) + "\n")


def _keep_rows(folder: Path, keep) -> None:
    """The same rows of all four tables kept (they keep sharing one time column)."""
    for name in TABLES:
        head, rows = _rows(folder / name)
        _write(folder / name, head, [r for r, k in zip(rows, keep, strict=True) if k])


def _cl(folder: Path, side: str = "left") -> dict:
    head, rows = _rows(folder / f"{side}_cl.csv")
    cells = [r.split(",") for r in rows]
    return {"path": np.array([int(c[3]) for c in cells]), "cutting": np.array([c[4] == "1" for c in cells]),
            "region": np.array([c[2] for c in cells])}


def test_the_plan_is_clean_and_its_report_short(plan, capsys):
    res = cli(capsys, "verify", plan)
    assert res.returncode == 0, res.stdout[-2000:]
    lines = res.stdout.splitlines()
    assert lines[-1].startswith("ok: 0 findings")
    assert max(len(x) for x in lines) <= LINE_MAX
    trust = [x for x in lines if x.startswith("trusted as written:")]
    assert len(trust) == 1 and "plan.json" in trust[0] and "machine.toml" in trust[0]


def _summary_adds_up(res: Ran) -> list[str]:
    """The finding lines of a failing verify's output, after checking that the summary's counts add up
    (per kind: shown + more = its count; the kinds' counts = the total; the shown = the lines above)."""
    lines = res.stdout.splitlines()
    assert res.returncode == 1 and max(len(x) for x in lines) <= LINE_MAX
    head = re.match(r"FAIL: (\d+) findings, (\d+) shown above \((.*)\); checked in", lines[-1])
    assert head, lines[-1]
    total, shown = int(head.group(1)), int(head.group(2))
    n_sum = s_sum = 0
    for part in head.group(3).split("; "):
        m = re.fullmatch(r"[a-z ]+ (\d+)(?:: (\d+) shown and (\d+) more)?", part)
        assert m, part
        n = int(m.group(1))
        s = int(m.group(2)) if m.group(2) else n
        assert s <= SHOWN_PER_KIND and (not m.group(2) or s + int(m.group(3)) == n)
        n_sum, s_sum = n_sum + n, s_sum + s
    findings = lines[:lines.index(next(x for x in lines if x.startswith(("figures:", "trusted"))))]
    assert (n_sum, s_sum) == (total, shown) and len(findings) == shown
    return findings


def test_all_four_tables_cut_at_the_same_row(plan, tmp_path, capsys):
    d = _copy(plan, tmp_path / "cut")
    n = len(_rows(d / "left_cl.csv")[1])
    _keep_rows(d, np.arange(n) < n // 2)  # (half the job missing)
    res = cli(capsys, "verify", d)
    findings = _summary_adds_up(res)
    assert any("never cuts path" in f for f in findings), findings
    assert "completeness" in res.stdout.splitlines()[-1]


def test_every_row_of_one_path_deleted(plan, tmp_path):
    d = _copy(plan, tmp_path / "path")
    cl = _cl(d)
    cut = np.unique(cl["path"][cl["cutting"]])
    victim = int(cut[len(cut) // 2])
    _keep_rows(d, cl["path"] != victim)
    rep = verify(d)
    assert f"the left cutter never cuts path {victim} " in " ".join(rep.findings) + " ", rep.findings


def test_both_axis_tables_deleted_while_machine_toml_stays(plan, tmp_path):
    d = _copy(plan, tmp_path / "axes")
    for side in ("left", "right"):
        (d / f"{side}_axes.csv").unlink()
    rep = verify(d)
    assert rep.counts == {"file set": 2}, rep.findings
    assert all("_axes.csv is missing (listed in plan.json)" in f for f in rep.findings)
    # the same with the file list of plan.json edited to match: machine.toml still calls for them
    summary = json.loads((d / "plan.json").read_text())
    summary["files"] = [f for f in summary["files"] if not f.endswith("_axes.csv")]
    (d / "plan.json").write_text(json.dumps(summary))
    rep = verify(d)
    assert sum("_axes.csv is missing" in f for f in rep.findings) == 2, rep.findings
    assert "machine.toml" not in rep.trusted  # (nothing of it was used)


def test_zeroed_velocity_columns(plan, tmp_path):
    d = _copy(plan, tmp_path / "zero")
    for side in ("left", "right"):
        head, rows = _rows(d / f"{side}_axes.csv")
        _write(d / f"{side}_axes.csv", head, [",".join(r.split(",")[:7] + ["0.000000000"] * 6) for r in rows])
    rep = verify(d)
    assert rep.counts.get("axis velocities", 0) > 100 and set(rep.counts) == {"axis velocities", "digest"}, rep.counts
    assert rep.counts["digest"] == 2  # (both axis tables changed after planning)
    assert "is not the derivative of" in rep.findings[rep.kinds.index("axis velocities")]


def _flip(folder: Path, move_mm: float) -> int:
    """A left row in the middle of an internal stretch turned to cutting 0 and moved along x."""
    path = folder / "left_cl.csv"
    head, rows = _rows(path)
    cl = _cl(folder)
    inside = cl["cutting"][:-2] & cl["cutting"][1:-1] & cl["cutting"][2:] & (cl["region"][1:-1] == "internal")
    i = int(np.flatnonzero(inside)[len(np.flatnonzero(inside)) // 2]) + 1
    c = rows[i].split(",")
    c[4] = "0"
    c[5] = f"{float(c[5]) + move_mm:.10f}"
    rows[i] = ",".join(c)
    _write(path, head, rows)
    return i


def test_a_row_flipped_to_not_cutting_and_moved(plan, tmp_path):
    d = _copy(plan, tmp_path / "flip")
    _flip(d, 0.5)
    rep = verify(d)
    cut = [f for f in rep.findings if f.startswith("the left cutter") or "the left cutter's row" in f]
    assert cut and rep.counts.get("completeness", 0) >= 1, rep.findings
    # without the axis tables (whose forward kinematics would find the moved row too) it is found all the same
    for name in ("left_axes.csv", "right_axes.csv", "machine.toml"):
        (d / name).unlink()
    summary = json.loads((d / "plan.json").read_text())
    summary["files"] = [f for f in summary["files"]
                        if f not in ("left_axes.csv", "right_axes.csv", "machine.toml")]
    (d / "plan.json").write_text(json.dumps(summary))
    rep = verify(d)
    assert rep.counts.get("completeness", 0) >= 1 and "file set" not in rep.counts, rep.findings
    # flipped alone (not moved): the flag contradicts the motion
    e = _copy(plan, tmp_path / "flag")
    _flip(e, 0.0)
    assert any("is not cutting between two rows cutting path" in f for f in verify(e).findings)


def test_pairs_csv_missing(plan, tmp_path):
    d = _copy(plan, tmp_path / "nopairs")
    (d / "pairs.csv").unlink()
    rep = verify(d)
    assert rep.counts == {"file set": 1} and "pairs.csv is missing" in rep.findings[0], rep.findings


def test_a_relative_blade_path_is_verified_from_another_folder(tmp_path, capsys, monkeypatch):
    where = tmp_path / "work"
    where.mkdir()
    shutil.copy(sample_table_path(), where / "my_blade.csv")
    monkeypatch.chdir(where)  # (the command line in-process, run from that folder)
    res = cli(capsys, "plan", "--blade", "my_blade.csv", *COARSE, "--no-axes", "--out", "plan")
    assert res.returncode == 0, res.stderr
    source = json.loads((where / "plan" / "plan.json").read_text())["inputs"]["blade_source"]
    assert source == str(where / "my_blade.csv")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    res = cli(capsys, "verify", where / "plan")
    assert res.returncode == 0, res.stdout + res.stderr
    assert res.stdout.splitlines()[-1].startswith("ok: 0 findings")


def test_the_derivative_rule_on_uniform_and_non_uniform_columns():
    rng = np.random.default_rng(5)
    for t in (np.arange(400) * 12.0, np.cumsum(rng.uniform(0.01, 12.0, 400))):
        x = 30.0 * np.sin(t / 900.0)  # mm over ms: peak speed 0.033 mm/ms, peak acceleration 3.7e-5 mm/ms^2
        v = 30.0 / 900.0 * np.cos(t / 900.0)
        assert derivative_slack(t, np.round(x, 6), np.round(v, 9), 3.8e-5).max() == 0.0
        assert derivative_slack(t, x, np.zeros_like(v), 3.8e-5).max() > 0.0  # zeroed velocities
        assert derivative_slack(t, x, v + 0.005, 3.8e-5).max() > 0.0  # (5 mm/s off)


def test_the_report_caps_each_kind_and_counts_every_finding():
    rep = Report()
    rep.many("completeness", np.arange(12), lambda i: f"finding {i} " + "x" * 300)
    other = Report()
    other.bad("file set", "one")
    other.many("completeness", np.arange(3), lambda i: f"more {i}")
    rep.merge(other)
    assert rep.counts == {"completeness": 15, "file set": 1} and rep.total == 16
    assert len(rep.findings) == SHOWN_PER_KIND + 1 and max(map(len, rep.findings)) <= LINE_MAX
    want = "FAIL: 16 findings, 6 shown above (file set 1; completeness 15: 5 shown and 10 more)"
    assert rep.summary() == want


def _line_pairs(n: int = 21, step: float = 0.1) -> dict:
    """pairs.csv's arrays of one straight path 0 along x (tips on z = 0, axes +z): ball centres at z = r."""
    x = np.arange(n) * step
    tips = np.column_stack([x, np.zeros(n), np.zeros(n)])
    axes = np.tile([0.0, 0.0, 1.0], (n, 1))
    return {"path": np.zeros(n, int), "k": np.arange(n), "region": np.full(n, 3), "left_tip": tips,
            "left_axis": axes, "right_tip": tips, "right_axis": axes}


def _line_cl(xs, cutting, lift=()) -> dict:
    """A CL table along the same line: rows at x (mm), cutting or not, those in ``lift`` 5 mm up."""
    xs = np.asarray(xs, float)
    p = np.column_stack([xs, np.zeros(len(xs)), np.zeros(len(xs))])
    p[list(lift), 2] += 5.0
    return {"t": np.arange(len(xs)) * 12.0, "path": np.zeros(len(xs), int),
            "cutting": np.asarray(cutting, bool), "p": p, "w": np.tile([0.0, 0.0, 1.0], (len(xs), 1)),
            "region": np.full(len(xs), 3), "step": np.full(len(xs), 4)}


def test_completeness_and_order_on_one_straight_path():
    from core.verify.coverage import path_checks

    pairs = _line_pairs()
    rows = np.r_[-0.05, np.arange(0.03, 2.0, 0.1), 2.03]  # (rows between the pair points; a cut begins and
    cut = np.r_[False, np.ones(20, bool), False]           # ends between two rows)
    rep = Report()
    figures = path_checks("left", pairs, _line_cl(rows, cut), 1.0, rep)
    assert rep.total == 0 and figures["left_reach_error_mm"] < 1e-9, rep.findings
    # the job cut short: the points past its last row are missed
    rep = Report()
    path_checks("left", pairs, _line_cl(rows[:-8], cut[:-8]), 1.0, rep)
    assert rep.counts == {"completeness": 1} and "(k 13-20)" in rep.findings[0], rep.findings
    # a cutting row moved 0.05 mm sideways: off its path, and the points beside it passed off
    moved = _line_cl(rows, cut)
    moved["p"][10, 1] += 0.05
    rep = Report()
    path_checks("left", pairs, moved, 1.0, rep)
    assert rep.counts.get("off path") == 1 and rep.counts.get("completeness") == 1, rep.findings
    # two runs, the second starting 0.4 mm behind where the first ended: out of order, though complete
    xs = np.r_[-0.05, np.arange(0.03, 1.0, 0.1), 1.03, 1.03, 0.45, np.arange(0.53, 2.0, 0.1), 2.03]
    runs = np.r_[False, np.ones(10, bool), False, False, False, np.ones(15, bool), False]
    rep = Report()
    path_checks("left", pairs, _line_cl(xs, runs, lift=[12]), 1.0, rep)
    assert rep.counts == {"order": 1} and "0.400 mm back along path 0" in rep.findings[0], rep.findings

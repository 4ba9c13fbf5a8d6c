"""bladecam verify: clean on a collaborative plan, failing on a symmetric one, and catching each kind
of defect planted in a written plan (the files are edited by hand here, the way a damaged or foreign
file would reach it)."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from core.verify._tables import parse_rows

from core.errors import OutputError
from core.verify.check import verify
from core.verify.read import CL_HEADER, REGION_CODES, read_cl

from ...conftest import COARSE_ARGS, cli


@pytest.fixture(scope="module")
def plans(tmp_path_factory, coarse_plan):
    """Written plans of the sample (coarse, with the axis tables): the session's collaborative one, and
    a symmetric one (unsafe: written with --force), planned in-process. Tests copy them to edit them."""
    symmetric = tmp_path_factory.mktemp("verify") / "symmetric"
    res = cli(None, "plan", *COARSE_ARGS, "--mode", "symmetric", "--force", "--out", symmetric)
    assert res.returncode == 0, res.stderr
    return {"collaborative": coarse_plan.folder, "symmetric": symmetric}


def _edit(src, dst, side, fn):
    shutil.copytree(src, dst)
    path = dst / f"{side}_cl.csv"
    head, *rows = path.read_text().splitlines()
    rows = fn(rows)
    path.write_text("\n".join([head, *rows]) + "\n")
    return dst


def test_collaborative_is_clean_and_symmetric_fails(plans, capsys):
    rep = verify(plans["collaborative"])
    assert rep.findings == [], rep.findings[:5]
    assert rep.figures["min_tip_spacing_mm"] >= 1.875 - 1e-6
    bad = verify(plans["symmetric"])
    assert any("tip spacing" in f for f in bad.findings)
    run = cli(capsys, "verify", plans["symmetric"])
    assert run.returncode == 1 and "FAIL" in run.stdout
    run = cli(capsys, "verify", plans["collaborative"])
    assert run.returncode == 0 and run.stdout.splitlines()[-1].startswith("ok: 0 findings")


def _cutting_row(rows, after=0):
    for i, r in enumerate(rows):
        if i > after and r.split(",")[4] == "1" and rows[i + 1].split(",")[4] == "1":
            return i
    raise AssertionError("no cutting row")


def test_a_ball_pushed_into_the_blade_is_found(plans, tmp_path):
    def push(rows):
        i = _cutting_row(rows, len(rows) // 3)
        c = rows[i].split(",")
        w = np.array([float(x) for x in c[8:11]])
        p = np.array([float(x) for x in c[5:8]]) - 0.05 * w  # 0.05 mm deeper along the axis
        c[5:8] = [f"{x:.9f}" for x in p]
        rows[i] = ",".join(c)
        return rows

    rep = verify(_edit(plans["collaborative"], tmp_path / "p", "left", push))
    assert any("cuts into the blade" in f for f in rep.findings), rep.findings


def test_time_going_back_and_a_jump_are_found(plans, tmp_path):
    def swap(rows):
        i = len(rows) // 2  # the same row in both tables: they keep sharing one time column
        rows[i], rows[i + 1] = rows[i + 1], rows[i]
        return rows

    d = _edit(plans["collaborative"], tmp_path / "a", "left", swap)
    _edit(plans["collaborative"], tmp_path / "b", "right", swap)
    shutil.copy(tmp_path / "b" / "right_cl.csv", d / "right_cl.csv")
    rep = verify(d)
    assert any("not strictly increasing" in f for f in rep.findings)

    dd = json.loads((plans["collaborative"] / "plan.json").read_text())["inputs"]["dd"]

    def jump(rows):
        i = _cutting_row(rows, len(rows) // 2)
        c = rows[i].split(",")
        c[5] = f"{float(c[5]) + 2.5 * dd:.9f}"  # 2.5 dd off in one sample (0.5 mm at dd 0.2): too fast, off surface
        rows[i] = ",".join(c)
        return rows

    rep = verify(_edit(plans["collaborative"], tmp_path / "c", "right", jump))
    assert any("mm/min > feed" in f for f in rep.findings)
    assert any("accelerates" in f for f in rep.findings)


def test_missing_or_foreign_files_are_refused(plans, tmp_path):
    d = tmp_path / "m"
    shutil.copytree(plans["collaborative"], d)
    (d / "right_cl.csv").unlink()
    rep = verify(d)  # (a file missing: a finding of the file set; a file not bladecam's: refused)
    assert rep.counts == {"file set": 1}, rep.findings
    assert rep.findings[0].startswith("right_cl.csv is missing")
    (d / "right_cl.csv").write_text("time,x\n1,2\n")
    with pytest.raises(OutputError, match="unexpected header"):
        verify(d)
    s = json.loads((plans["collaborative"] / "plan.json").read_text())
    assert s["inputs"]["h_safe"] == 1.875


def test_the_compiled_reader_matches_strtod_exactly(tmp_path):
    rng = np.random.default_rng(3)
    vals = rng.normal(0, 300, (500, 4))
    text = "\n".join(",".join(f"{v:.{d}f}" for v, d in zip(row, (0, 3, 6, 10), strict=True)) for row in vals)
    got, bad = parse_rows(text.encode() + b"\n", 4, {})
    ref = np.array([[float(x) for x in ln.split(",")] for ln in text.splitlines()])
    assert bad == -1
    np.testing.assert_array_equal(got, ref)  # (the digits over 10**d: the double nearest the decimal)
    for body, ncols, row in ((b"1e3,2\n", 2, 0), (b"1,2\n1,,2\n", 3, 0), (b"1,2\n3,4\n5,x\n", 2, 2),
                             (b"1,2\n3\n", 2, 1), (b"1,2\n3,4", 2, 1), (b"1.,2\n", 2, 0)):
        assert parse_rows(body, ncols, {})[1] == row, body
    p = tmp_path / "x_cl.csv"
    p.write_text("t_ms,step,region,path,cutting,x_mm,y_mm,z_mm,i,j,k\n0,1,idle,-1,0,1e-3,0,0,0,0,1\n")
    assert read_cl(p)["p"][0, 0] == pytest.approx(1e-3)  # exponent: general parser
    # every region name maps to its code; a word that is no region is named
    rows = "".join(f"{k}.5,1,{name.decode()},2,1,1,2,3,0,0,1\n" for name, k in REGION_CODES.items())
    p.write_text(CL_HEADER + "\n" + rows)
    assert read_cl(p)["region"].tolist() == list(REGION_CODES.values())
    p.write_text(CL_HEADER + "\n0,1,edges,-1,0,0,0,0,0,0,1\n")
    with pytest.raises(OutputError, match="edges"):
        read_cl(p)

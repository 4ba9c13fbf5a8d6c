"""Every promise kept on new classes of input: the work budget covers every dimension of a plan and
refuses up front with what to change inside the paper's ranges; hostile files and process limits end in
one line naming the limit; inputs that were misread or misreported are read or named for what they are.
Each class runs through the command line in-process (core.cli.main) or in a fresh process where a
process limit is the point."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from core.blade.source import sample_table_path
from core.machine.model import default_machine_path
from tests.conftest import REPO
from tests.core.test_bad_input import _surface_stl, cli, fuzz, refused

SAMPLE = sample_table_path().read_text()
MACHINE = default_machine_path().read_text()
COARSE = ["--dr", "8", "--workers", "1"]


def scaled(tmp_path: Path, diameter: float) -> Path:
    p = tmp_path / f"d{diameter:g}.csv"
    p.write_text(SAMPLE.replace("# diameter_mm: 458.72", f"# diameter_mm: {diameter:g}"))
    return p


def quick_refusal(capsys, tmp_path, *args, words=(), out: Path | None = None) -> str:
    """A plan refused up front: exit 2, one error line holding ``words``, within seconds, nothing written."""
    out = out or tmp_path / "out"
    t0 = time.perf_counter()
    line = refused(*cli(capsys, "plan", "--workers", "1", *args, "--out", out)[::2], *words)
    assert time.perf_counter() - t0 < 20 and not out.exists()
    return line


# ---- the budget: every dimension of the work, up front ----

@pytest.mark.parametrize("args, words", [
    (["--period-ms", "1e5"], ["too long to time", "Lower --period-ms to at most"]),
    (["--period-ms", "999999"], ["too long to time", "budget 24 h"]),
    (["--period-ms", "1000"], ["too long to time"]),
    (["--period-ms", "100", "--chord-tol", "1e-5"], ["rows in the time column",
                                                      "raise --chord-tol to at least"]),
    (["--period-ms", "1e5", "--chord-tol", "1e-5"], ["rows in the time column", "--chord-tol"]),
    (["--tool-radius", "20", "--dr", "3"], ["larger than the blade is thick", "--tool-radius"]),
    (["--tool-radius", "20", "--dr", "3", "--dd", "1"], ["larger than the blade is thick"]),
])
def test_runaways_of_every_dimension_are_refused_up_front(capsys, tmp_path, args, words):
    quick_refusal(capsys, tmp_path, *args, words=words)


def test_the_job_length_budget_names_a_period_that_fits(capsys, tmp_path):
    from core.blade.extent import path_extent
    from core.blade.source import load_blade
    from core.budget import CHORD_FACTOR, JOB_HOURS_BUDGET, TIME_FACTOR

    line = quick_refusal(capsys, tmp_path, "--period-ms", "1e5", words=["too long to time"])
    fits = float(re.search(r"at most ([0-9.e+]+) ms", line).group(1))
    ext = path_extent(load_blade("sample"), 0.375, 0.2)
    rows = TIME_FACTOR * CHORD_FACTOR * ext.contours * ext.bend_mm / math.sqrt(8 * 1e-3)
    assert fits == pytest.approx(JOB_HOURS_BUDGET * 3.6e6 / rows, rel=2e-3)
    hours = float(re.search(r"about ([0-9,]+) h", line).group(1).replace(",", ""))
    assert hours == pytest.approx(rows * 1e5 / 3.6e6, rel=1e-3)


def test_the_chord_rows_estimate_measures_the_sections():
    """PathExtent.bend_mm against its definition on a circle: sum(sqrt(ds * turn)) over a polyline of
    a circle of radius R is 2 pi R / sqrt(R) (n steps of 2 pi R / n turning 2 pi / n each)."""
    from core.blade.extent import _bend

    for radius in (0.5, 20.0):
        t = np.linspace(0, 2 * np.pi, 2001)
        circle = np.column_stack([radius * np.cos(t), radius * np.sin(t), np.zeros_like(t)])
        assert _bend(circle) == pytest.approx(2 * np.pi * math.sqrt(radius), rel=1e-3)


def test_strokes_are_checked_before_planning(capsys, tmp_path):
    line = quick_refusal(capsys, tmp_path, "--blade", scaled(tmp_path, 2000), "--dr", "3",
                         words=["does not fit the machines' strokes", "checked before planning",
                                "-300 to 300"])
    lo, hi = (float(v) for v in re.search(r"need about (-?[0-9.]+) to (-?[0-9.]+) mm", line).groups())
    assert hi - lo > 600 and "longer strokes" in line


def test_a_travel_that_fits_off_the_middle_is_named(capsys, tmp_path):
    line = quick_refusal(capsys, tmp_path, "--blade", scaled(tmp_path, 1000), "--dr", "3",
                         words=["fits the stroke", "off its middle", "origin_mm"])
    lo, hi = (float(v) for v in re.search(r"need about (-?[0-9.]+) to (-?[0-9.]+) mm", line).groups())
    shift = float(re.search(r"fits the stroke, ([0-9.]+) mm off", line).group(1))
    assert hi - lo <= 600 and shift == pytest.approx(abs(lo + hi) / 2, abs=0.11)


def test_an_off_centre_mesh_is_named_off_centre(capsys, tmp_path):
    from core.blade.source import load_blade

    face, back = load_blade("sample").surface_grids(n_radii=14)
    paths = []
    for name, grid in (("face", face), ("back", back)):
        g = grid[:, ::4].copy()
        g[..., 2] += 200.0
        paths.append(tmp_path / f"{name}.stl")
        _surface_stl(g, paths[-1])
    quick_refusal(capsys, tmp_path, "--blade", f"{paths[0]},{paths[1]}", "--dr", "8",
                  words=["off-centre", "200 mm along the propeller axis", "checked before planning"])


def test_a_plan_refused_for_its_strokes_says_when_the_travel_fits():
    from core.machine.model import load_machine
    from core.machine.tables import LimitFinding
    from core.output.writer import _refusal

    class Result:
        safe, machine = True, load_machine()
        blocking_findings = [LimitFinding("left", "z", "stroke", 10.0, -160.0, -150.0, "mm")]
        figures = {"machine": {"axes": {"left": {"z": {"min_mm": -160.0, "max_mm": 40.0}}}}}

    text = _refusal(Result())
    assert "not centred on each other" in text and "travels 200.0 mm" in text and "50.0 mm off" in text
    Result.figures["machine"]["axes"]["left"]["z"]["max_mm"] = 130.5  # (290.5 mm: more than the stroke)
    assert "longer strokes" in _refusal(Result())


@pytest.mark.parametrize("args", [["--blade", "BIG"], ["--dd", "1e-3"], ["--dr", "0.05"]])
def test_suggestions_stay_inside_the_papers_range(capsys, tmp_path, args):
    from core.blade.extent import path_extent
    from core.blade.source import load_blade
    from core.budget import POINTS_BUDGET

    big = scaled(tmp_path, 11000)
    args = [str(big) if a == "BIG" else a for a in args]
    line = quick_refusal(capsys, tmp_path, *args, words=["too big to compute"])
    for dr in re.findall(r"--dr to at least ([0-9.e+-]+) mm", line):
        assert float(dr) <= 1.5 / 4
    ball = re.search(r"ball of radius at least ([0-9.e+-]+) mm", line)
    if ball:  # (dR = r/4 at that radius fits the points budget: measured afresh)
        r = float(ball.group(1))
        dd = float(args[args.index("--dd") + 1]) if "--dd" in args else 0.2
        ext = path_extent(load_blade(str(big) if "--blade" in args else "sample"), r / 4, dd)
        assert ext.points <= POINTS_BUDGET * 1.01
        assert "no dR within the paper's range" in line


@pytest.mark.parametrize("key, old", [("gauge_length_mm", "280.0"), ("platform_radius_mm", "60.0"),
                                      ("base_radius_mm", "100.0")])
def test_a_head_too_small_to_be_one_is_refused_by_name(capsys, tmp_path, key, old):
    m = tmp_path / "tiny.toml"
    m.write_text(MACHINE.replace(f"{key} = {old}", f"{key} = 0.001"))
    line = refused(*cli(capsys, "plan", *COARSE, "--machine", m, "--out", tmp_path / "o")[::2], str(m),
                   f"[head] {key} = 0.001 mm", "below 1 mm")
    assert "speed limits" not in line


def test_rows_beyond_the_chord_tolerance_are_refused_unless_forced():
    from core.output.writer import _refusal

    class Result:
        safe, blocking_findings, collisions = True, [], []
        figures = {"machine": {"chord": {"tolerance_mm": 1e-5, "largest_deviation_mm": 1.2e-5,
                                         "largest_deviation_at_ms": 4.0}}}

    text = _refusal(Result())
    assert "strays 1.2e-05 mm" in text and "chord tolerance 1e-05 mm" in text and "--force" in text
    Result.figures["machine"]["chord"]["largest_deviation_mm"] = 1.000001e-5
    assert _refusal(Result()) is None


def test_a_vanishing_period_gets_finite_numbers(capsys, tmp_path):
    line = quick_refusal(capsys, tmp_path, "--period-ms", "5e-324", words=["more than 10^15 rows"])
    assert "inf" not in line
    assert float(re.search(r"--period-ms to at least ([0-9.e+-]+) ms", line).group(1)) > 1


# ---- hostile files and process limits ----

def _nested(depth: int) -> str:
    return "[" * depth + "]" * depth


def test_deep_nesting_in_a_machine_file_is_a_clear_error(capsys, tmp_path):
    m = tmp_path / "deep.toml"
    m.write_text(MACHINE + f"\nextra = {_nested(5000)}\n")
    refused(*cli(capsys, "plan", *COARSE, "--machine", m, "--out", tmp_path / "o")[::2], str(m),
            "nested too deeply", "recursion limit")


def test_deep_nesting_and_huge_numbers_in_a_project_are_clear_errors(tmp_path):
    from core.errors import ProjectError
    from core.output.project import Project, load_project, project_text

    text = project_text(Project())
    deep = tmp_path / "deep.toml"
    deep.write_text(text.replace('axis = "z"', f'axis = "z"\nx = {{a = {"{a = " * 3000}1{"}" * 3000}}}'))
    with pytest.raises(ProjectError, match="nested too deeply"):
        load_project(deep)
    huge = tmp_path / "huge.toml"
    huge.write_text(text.replace('dr = "auto"', "dr = " + "9" * 400))
    with pytest.raises(ProjectError, match=r"\[parameters\] dr = 9{37}\.\.\. \(400 digits\)"):
        load_project(huge)
    huger = tmp_path / "huger.toml"
    huger.write_text(text.replace('dr = "auto"', "dr = " + "9" * 5000))
    with pytest.raises(ProjectError, match="more than 4300 digits"):
        load_project(huger)


def test_deep_nesting_in_plan_json_is_a_clear_error(capsys, tmp_path):
    folder = tmp_path / "p"
    assert cli(capsys, "plan", *COARSE, "--paths-only", "--out", folder)[0] == 0
    (folder / "plan.json").write_text(_nested(100_000))
    refused(*cli(capsys, "verify", folder)[::2], "plan.json")


@pytest.mark.parametrize("length, words", [(256, ["256 bytes", "limit of 255"]), (4200, ["limit of 4096"])])
def test_names_too_long_for_the_file_system_are_named(capsys, tmp_path, length, words):
    out = tmp_path / ("a" * length if length < 300 else "/".join(["b" * 200] * (length // 200)))
    refused(*cli(capsys, "plan", *COARSE, "--paths-only", "--out", out)[::2], *words)


def test_a_folder_name_near_the_limit_is_planned_and_verified(capsys, whole_plan):
    out = whole_plan  # (planned into a folder named with 250 characters)
    assert len(out.name) == 250
    assert [p.name for p in out.parent.iterdir()] == [out.name]  # (no scratch folder left beside it)
    assert cli(capsys, "verify", out)[0] == 0


def test_a_plan_folder_inside_a_plan_folder_is_refused(capsys, tmp_path):
    outer = tmp_path / "outer"
    assert cli(capsys, "plan", *COARSE, "--paths-only", "--out", outer)[0] == 0
    quick_refusal(capsys, tmp_path, "--paths-only", out=outer / "inner", words=["inside the plan folder"])
    assert sorted(p.name for p in outer.iterdir()) == ["pairs.csv", "plan.json"]


def _limited(limit: str, value: int, *args: str) -> subprocess.CompletedProcess:
    """``bladecam ARGS`` in a fresh process whose resource ``limit`` (RLIMIT_NOFILE, RLIMIT_AS) is
    ``value``."""
    code = (f"import resource, sys; resource.setrlimit(resource.{limit}, ({value}, {value})); "
            "from core.cli import main; sys.exit(main(sys.argv[1:]))")
    return subprocess.run([sys.executable, "-c", code, *args], cwd=REPO, capture_output=True, text=True,
                          timeout=600)


@pytest.mark.parametrize("limit, value, words", [
    ("RLIMIT_NOFILE", 12, ["too many open files", "may open 12", "ulimit -n"]),
    ("RLIMIT_AS", 300 << 20, ["address-space limit", "300 MB", "ulimit -v"]),
])
def test_process_limits_end_in_one_line_naming_them(tmp_path, limit, value, words):
    done = _limited(limit, value, "plan", "--dr", "8", "--workers", "2", "--out", str(tmp_path / "o"))
    lines = [ln for ln in done.stderr.splitlines() if "error:" in ln]
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr[-3000:]
    assert all(w in lines[0] for w in words), lines[0]


def _dying_chunk(args):  # (a path worker killed in the middle of its chunk: the OOM killer's work)
    import os

    os._exit(9)


def test_a_path_worker_that_dies_ends_the_plan_in_one_line(capsys, tmp_path, monkeypatch):
    """A forked path worker that dies is an error naming what happened and what to do, never a wait
    for a chunk that will not come."""
    import core.paths.planning as planning

    monkeypatch.setattr(planning, "_plan_chunk_to_file", _dying_chunk)
    code, _, err = cli(capsys, "plan", "--dr", "8", "--workers", "2", "--out", tmp_path / "o")
    assert code == 2 and "a worker process ended before its work was done" in err, err
    assert "--workers 1" in err and not (tmp_path / "o").exists()


def test_the_limit_messages_name_the_limits():
    import errno
    import resource

    from core.util.limits import limit_message

    soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
    assert f"may open {soft} " in limit_message(OSError(errno.EMFILE, "Too many open files"))
    assert limit_message(MemoryError()).startswith("out of memory")
    assert limit_message(OSError(errno.ENOENT, "No such file")) is None
    assert limit_message(RuntimeError("something else")) is None


# ---- inputs misread or misreported ----

def test_a_blade_path_with_a_comma_survives_a_project_file(tmp_path):
    from core.blade.source import load_blade
    from core.output.project import Project, load_project, save_project

    blade = tmp_path / "blades, v2" / "prop,1.csv"
    blade.parent.mkdir()
    blade.write_text(SAMPLE)
    project = tmp_path / "p.toml"
    save_project(Project(source=str(blade)), project)
    loaded = load_project(project)
    assert loaded.source == str(blade)
    assert load_blade(loaded.source).info()["chord_mm"]["0.5"] == pytest.approx(142.18, rel=0.005)


def test_two_meshes_with_commas_in_their_names_are_split_where_both_exist(tmp_path):
    from core.blade.source import source_parts

    a, b = tmp_path / "face,1.stl", tmp_path / "back,2.stl"
    a.write_text("solid\nendsolid\n")
    b.write_text("solid\nendsolid\n")
    assert source_parts(f"{a},{b}") == [str(a), str(b)]
    assert source_parts("x.stl,y.stl") == ["x.stl", "y.stl"]


def test_a_project_file_may_start_with_a_byte_order_mark(tmp_path):
    from core.output.project import Project, load_project, project_text

    p = tmp_path / "bom.toml"
    p.write_text(project_text(Project()), encoding="utf-8-sig")
    assert load_project(p).params.tool_radius == 1.5


def test_a_utf16_table_is_read(capsys, tmp_path):
    for enc in ("utf-16", "utf-16-be", "utf-16-le"):
        p = tmp_path / f"{enc}.csv"
        p.write_bytes(SAMPLE.encode(enc))
        code, out, err = cli(capsys, "blade", "info", "--json", "--blade", p)
        assert code == 0, err
        assert json.loads(out)["chord_mm"]["0.5"] == pytest.approx(142.18, rel=0.005)


def test_a_non_finite_vertex_and_a_wrong_triangle_count_are_named(capsys, tmp_path):
    import trimesh

    box = trimesh.creation.box()
    text = box.export(file_type="stl_ascii").splitlines()
    at = [i for i, ln in enumerate(text) if ln.strip().startswith("vertex")][4]
    text[at] = "vertex nan 0 0"
    nan = tmp_path / "nan.stl"
    nan.write_text("\n".join(text) + "\n")
    refused(*cli(capsys, "blade", "info", "--blade", nan)[::2], "vertex 5 (facet 2)", "not a finite number")
    raw = box.export(file_type="stl")
    wrong = tmp_path / "count.stl"
    wrong.write_bytes(raw[:80] + (20).to_bytes(4, "little") + raw[84:])
    refused(*cli(capsys, "blade", "info", "--blade", wrong)[::2], "counts 20 triangles",
            f"{len(raw):,} bytes",
            "room for 12.0")


def test_verify_on_a_missing_folder_says_so(capsys, tmp_path):
    refused(*cli(capsys, "verify", tmp_path / "gone")[::2], "does not exist", "--out DIR")


# ---- the fuzz test of the new classes (bounded: about 20 s together) ----


_BLADES: dict = {}


def _blade(diameter: float):
    from core.blade.table import load_table_blade

    if diameter not in _BLADES:
        import tempfile

        with tempfile.TemporaryDirectory() as d:
            p = Path(d) / "b.csv"
            p.write_text(SAMPLE.replace("# diameter_mm: 458.72", f"# diameter_mm: {diameter:g}"))
            _BLADES[diameter] = load_table_blade(p)
    return _BLADES[diameter]


@fuzz(60)
@given(diameter=st.sampled_from([100.0, 458.72, 800.0, 2000.0, 11000.0]),
       radius=st.sampled_from([0.5, 1.5, 3.0, 8.0, 20.0, 60.0]), dr=st.one_of(st.none(), st.floats(0.01, 20)),
       dd=st.floats(0.005, 2.0), period=st.one_of(st.none(), st.floats(5e-324, 999999)),
       tol=st.floats(1e-5, 0.5), feed=st.floats(1.0, 100_000.0))
def test_fuzz_the_budget(diameter, radius, dr, dd, period, tol, feed):
    """Whatever the job, the budget answers in a second: within it, or a refusal whose numbers are
    finite and whose suggestions stay inside the paper's ranges."""
    from core.budget import check_work
    from core.errors import PlanningError
    from core.machine.model import load_machine
    from core.records import PlanJob, PlanParameters

    params = PlanParameters(tool_radius=radius, dr=dr, dd=min(dd, 5 * radius), feed=feed)
    job = PlanJob(params=params, period=period, chord_tol=tol)
    t0 = time.perf_counter()
    try:
        check_work(_blade(diameter), job, load_machine())
    except PlanningError as exc:
        text = str(exc)
        assert not re.search(r"\b(inf|nan)\b", text), text
        for value in re.findall(r"--dr to at least ([0-9.e+-]+) mm", text):
            assert float(value) <= radius / 4 * 1.001, text
        for value in re.findall(r"--chord-tol to at least ([0-9.e+-]+) mm", text):
            assert float(value) <= 0.5, text
    assert time.perf_counter() - t0 < 5


@fuzz(40)
@given(depth=st.integers(1, 20_000), digits=st.integers(1, 6000),
       where=st.sampled_from(["machine", "project"]), kind=st.sampled_from(["array", "table", "integer"]))
def test_fuzz_hostile_toml(tmp_path_factory, depth, digits, where, kind):
    """Nested arrays and inline tables of any depth, integers of any length: a clear error naming the
    file (MachineError, ProjectError) or a file read, never another exception."""
    from core.errors import MachineError, ProjectError
    from core.machine.model import load_machine
    from core.output.project import Project, load_project, project_text

    value = {"array": "[" * depth + "1" + "]" * depth, "table": "{a = " * depth + "1" + "}" * depth,
             "integer": "9" * digits}[kind]
    p = tmp_path_factory.mktemp("hostile") / f"{where}.toml"
    if where == "machine":
        p.write_text(MACHINE.replace("max_tilt_deg = 40.0", f"max_tilt_deg = {value}"))
        load, error = load_machine, MachineError
    else:
        p.write_text(project_text(Project()).replace('dd = 0.2', f"dd = {value}"))
        load, error = load_project, ProjectError
    try:
        load(p)
    except error as exc:
        assert str(p) in str(exc)


# ---- the command line says what the workbench says ----

@pytest.mark.parametrize("k_max", ["0.05", "0.15"])
def test_the_command_line_warns_of_a_plan_that_is_hardly_collaborative(capsys, tmp_path, k_max):
    out = tmp_path / "o"
    code, stdout, err = cli(capsys, "plan", *COARSE, "--k-max", k_max, "--paths-only", "--out", out)
    assert code == 0, err
    paths = json.loads((out / "plan.json").read_text())["paths"]
    n, tips = paths["paths"], len(paths["tip_path_indices"])
    warned = [ln for ln in err.splitlines() if "collaborative" in ln.lower()]
    if n - tips >= n / 2:
        assert not warned, err
    elif tips == n:
        assert warned == [f"warning: NOT COLLABORATIVE: all {n} paths single-sided (tip region); "
                          + warned[0].split("; ", 1)[1]], err
    else:
        assert f"only {n - tips} of {n} paths collaborative ({100 * (n - tips) / n:.0f} %)" in warned[0], err
    assert f"planned {n} paths ({tips} in the tip region)" in stdout


@pytest.mark.parametrize("mode", ["symmetric", "single"])
def test_modes_without_regions_say_nothing_of_a_tip_region(capsys, tmp_path, mode):
    code, stdout, err = cli(capsys, "plan", *COARSE, "--mode", mode, "--paths-only", "--out", tmp_path / "o")
    assert code == 0 and "tip region" not in stdout and "collaborative" not in err, stdout + err


# ---- exit 0 means verified ----

def test_a_plan_its_own_verify_rejects_is_not_written(capsys, tmp_path, monkeypatch):
    import core.verify.check

    real = core.verify.check.verify
    seen = []

    def verify_with_a_finding(folder, *args, **kwargs):
        rep = real(folder, *args, **kwargs)
        seen.append(Path(folder))
        rep.bad("surface", "t = 1.0 ms: left ball cuts into the blade by 0.1800 mm")
        return rep

    monkeypatch.setattr(core.verify.check, "verify", verify_with_a_finding)
    out = tmp_path / "o"
    code, _, err = cli(capsys, "plan", *COARSE, "--paths-only", "--out", out)
    refused(code, err, "fails bladecam verify")
    assert "cuts into the blade by 0.1800 mm" in err and "surface 1" in err
    assert not out.exists() and seen and seen[0] != out and not seen[0].exists()
    code, _, err = cli(capsys, "plan", *COARSE, "--paths-only", "--force", "--out", out)
    assert code == 0 and out.is_dir() and "written with --force although bladecam verify finds FAIL: 1" in err


@pytest.fixture(scope="module")
def whole_plan(tmp_path_factory) -> Path:
    """A coarse whole plan with its CL tables, written by the command line (which verified it), into a
    folder whose name is near the file systems' limit of 255 bytes (250 characters). Tests that edit it
    copy it first."""
    out = tmp_path_factory.mktemp("whole") / ("n" * 250)
    code, _, err = cli(None, "plan", *COARSE, "--dd", "0.5", "--no-axes", "--out", out)
    assert code == 0, err
    return out


def test_a_plan_written_is_one_verify_accepts(capsys, whole_plan):
    code, out, _ = cli(capsys, "verify", whole_plan)
    assert code == 0 and "left_clearance_mm" in out, out


def test_a_move_that_does_not_cut_pushed_into_the_blade_is_found(capsys, tmp_path, whole_plan):
    """The classic crash: a turn's rows moved into the blade (the CL table rewritten to match), each
    row's ball centre put on the tip of the last cutting row before the turn, which lies on the blade
    (a ball one radius deep): every row that does not cut, and every move between rows, is checked."""
    folder = _copy(whole_plan, tmp_path)
    r = 1.5  # (the default tool radius the plan was made with)
    lines = (folder / "left_cl.csv").read_text().splitlines()
    rows = [ln.split(",") for ln in lines[1:]]
    turn = [k for k, row in enumerate(rows) if row[2] == "turn" and row[4] == "0"]
    run = [k for k in turn[len(turn) // 2:len(turn) // 2 + 40] if k - 1 in turn or k + 1 in turn]
    assert run
    last_cut = max(k for k in range(run[0]) if rows[k][4] == "1")
    on_blade = np.array(rows[last_cut][5:8], float)
    for k in run:
        axis = np.array(rows[k][8:11], float)
        rows[k][5:8] = [f"{v:.10f}" for v in on_blade - r * axis]
    (folder / "left_cl.csv").write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    code, out, _ = cli(capsys, "verify", folder)
    assert code == 1 and "not cutting (turn)" in out and "inside the blade" in out, out
    assert "left_cl.csv changed after planning" in out


# ---- verify finds a file changed after planning, whatever changed ----

@pytest.fixture(scope="module")
def digested_plan(tmp_path_factory) -> Path:
    from core.cli import main

    folder = tmp_path_factory.mktemp("digested") / "p"
    blade = folder.parent / "blade.csv"
    blade.write_text(SAMPLE)
    assert main(["plan", *COARSE, "--blade", str(blade), "--paths-only", "--out", str(folder)]) == 0
    return folder


def _copy(folder: Path, tmp_path: Path) -> Path:
    import shutil

    dest = tmp_path / "p"
    shutil.copytree(folder, dest)
    return dest


def test_plan_json_records_the_digests_of_its_files_and_inputs(digested_plan):
    import hashlib

    summary = json.loads((digested_plan / "plan.json").read_text())
    digests = summary["sha256"]
    pairs = hashlib.sha256((digested_plan / "pairs.csv").read_bytes()).hexdigest()
    assert digests["files"] == {"pairs.csv": pairs}
    blade = str(digested_plan.parent / "blade.csv")
    assert digests["sources"] == {blade: hashlib.sha256(Path(blade).read_bytes()).hexdigest()}
    canonical = json.dumps(summary["inputs"], sort_keys=True, separators=(",", ":")).encode()
    assert digests["inputs"] == hashlib.sha256(canonical).hexdigest()


def test_verify_compares_the_digests(capsys, tmp_path, digested_plan):
    folder = _copy(digested_plan, tmp_path)
    code, out, _ = cli(capsys, "verify", folder)
    assert code == 0 and "files and inputs checked by their SHA-256 digests" in out, out
    summary = json.loads((folder / "plan.json").read_text())
    summary["inputs"]["h_safe"] *= 0.5  # (loosened after planning)
    (folder / "plan.json").write_text(json.dumps(summary))
    pairs = (folder / "pairs.csv").read_bytes()
    code, out, _ = cli(capsys, "verify", folder)
    assert code == 1 and "plan.json's inputs changed after planning" in out and "pairs.csv changed" not in out
    (folder / "pairs.csv").write_bytes(pairs[:-2] + bytes([pairs[-2] ^ 1]) + pairs[-1:])  # (one digit changed)
    code, out, _ = cli(capsys, "verify", folder)
    assert code == 1 and "pairs.csv changed after planning" in out, out


def test_labels_changed_in_a_cl_table_are_found(capsys, tmp_path, whole_plan):
    folder = _copy(whole_plan, tmp_path)
    lines = (folder / "left_cl.csv").read_text().splitlines()
    rows = [ln.split(",") for ln in lines[1:]]
    tip = next(k for k, r in enumerate(rows) if r[2] == "tip" and r[4] == "1")
    inner = next(k for k, r in enumerate(rows) if r[2] == "internal" and r[1] == "4" and r[4] == "1")
    rows[tip][2] = "internal"   # (the tip region relabelled)
    rows[inner][1] = "1"        # (a collaborative row given the tip region's leading step)
    (folder / "left_cl.csv").write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    code, out, _ = cli(capsys, "verify", folder)
    assert code == 1, out
    assert "cutting row is labelled internal, where pairs.csv has tip" in out
    assert "(collaborative) is labelled step 1" in out


def test_a_repeated_row_is_a_finding_without_numpy_warnings(capsys, tmp_path, whole_plan):
    import warnings

    folder = _copy(whole_plan, tmp_path)
    for side in ("left", "right"):
        lines = (folder / f"{side}_cl.csv").read_text().splitlines()
        lines.insert(50, lines[50])
        (folder / f"{side}_cl.csv").write_text("\n".join(lines) + "\n")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        code, out, err = cli(capsys, "verify", folder)
    assert code == 1 and "time column not strictly increasing" in out, out
    assert not [w for w in seen if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in seen]
    assert "RuntimeWarning" not in err


def test_reach_follows_the_plans_chord_tolerance():
    from core.verify.coverage import REACH_TOL, reach_tolerance

    assert reach_tolerance(None) == reach_tolerance(1e-3) == reach_tolerance(1e-5) == REACH_TOL
    assert reach_tolerance(0.5) == pytest.approx(REACH_TOL + 0.499)


@pytest.mark.slow
def test_a_long_period_warns_that_the_feed_is_cut(capsys, tmp_path):
    code, out, err = cli(capsys, "plan", *COARSE, "--period-ms", "100", "--no-axes", "--out", tmp_path / "o")
    assert code == 0, err
    fig = json.loads((tmp_path / "o" / "plan.json").read_text())["schedule"]
    total, at_feed = fig["total_time_s"], fig["machine"]["time_at_feed_s"]
    line = next(ln for ln in err.splitlines() if "so the feed is cut" in ln)
    assert f"takes {total / 60:.1f} min on the machines, {total / at_feed:.0f} times its" in line

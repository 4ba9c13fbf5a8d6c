"""Bad input gets a clean answer: every class of bad input tried against
the command line, run in-process through core.cli.main, ends with exit 0 and a finite output or exit 2
and one clear message (never a traceback), unsafe plans are refused unless --force, runaways are
refused up front, and a fuzz test over geometry tables, meshes, machine files and parameters holds it.
"""

from __future__ import annotations

import json
import math
import os
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from core.blade.source import sample_table_path
from core.machine.model import default_machine_path

from ..conftest import COARSE_ARGS, cli

SAMPLE = sample_table_path().read_text()
MACHINE = default_machine_path().read_text()
ROW_05 = "0.50,0.3099494,1.020,0.07174,0.0260,-1.4,0.0"
COARSE = [*COARSE_ARGS, "--workers", "1"]


def refused(code: int, err: str, *words: str) -> str:
    """Assert a clean refusal: exit 2, exactly one error line (after any warnings or usage), no
    traceback; the error line holds every one of ``words``. Returns that line."""
    errors = [ln for ln in err.splitlines() if "error:" in ln]
    assert code == 2 and len(errors) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in errors[0], errors[0]
    return errors[0]


def strict_json(text: str):
    """JSON that refuses NaN and Infinity (invalid JSON that Python would accept)."""
    def no(c):
        raise ValueError(f"non-finite number {c} in the output")
    return json.loads(text, parse_constant=no)


def table(tmp_path: Path, text: str, name: str = "t.csv") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def sample_with(old: str, new: str) -> str:
    assert old in SAMPLE
    return SAMPLE.replace(old, new, 1)


def _surface_stl(grid: np.ndarray, path: Path) -> None:
    """An open triangle surface through a (rows, cols, 3) grid of points, written as an ASCII STL."""
    import trimesh

    n, m, _ = grid.shape
    idx = np.arange(n * m).reshape(n, m)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    mesh = trimesh.Trimesh(grid.reshape(-1, 3), faces, process=False)
    path.write_text(mesh.export(file_type="stl_ascii"))


@pytest.fixture(scope="module")
def meshes(tmp_path_factory) -> dict[str, Path]:
    """The sample blade's face and back as two open STL surfaces (axis z), plus broken variants."""
    from core.blade.source import load_blade

    d = tmp_path_factory.mktemp("meshes")
    face, back = load_blade("sample").surface_grids(n_radii=14)
    out = {"face": d / "face.stl", "back": d / "back.stl", "far": d / "far.stl"}
    _surface_stl(face[:, ::4], out["face"])
    _surface_stl(back[:, ::4], out["back"])
    far = back[:, ::4].copy()
    far[3, 3] = (1e30, 0.0, 0.0)
    _surface_stl(far, out["far"])
    return out


@pytest.fixture(scope="module")
def plan_dir(coarse_plan) -> Path:
    """A small written plan (the session's coarse plan: copied before it is edited)."""
    return coarse_plan.folder


# ---- item 7: an unsafe plan is refused in every mode unless --force, and --force says what is unsafe ----

def test_unsafe_plan_refused_unless_forced_in_every_mode(capsys, tmp_path):
    out = tmp_path / "sym"
    refused(*cli(capsys, "plan", *COARSE, "--mode", "symmetric", "--no-axes", "--out", out)[::2],
            "symmetric schedule is unsafe", "collide", "--force")
    assert not out.exists()
    code, _, err = cli(capsys, "plan", *COARSE, "--mode", "symmetric", "--no-axes", "--force", "--out", out)
    assert code == 0 and out.is_dir()
    assert any(ln.startswith("warning: written with --force although the symmetric schedule is unsafe")
               and "clearance -" in ln for ln in err.splitlines()), err


@pytest.mark.parametrize("mode", ["collaborative", "single", "symmetric"])
def test_refusal_names_what_is_unsafe_whatever_the_mode(mode):
    from core.output.writer import _refusal
    from core.records import PlanParameters

    class Plan:
        params = PlanParameters(mode=mode).resolved()

    class Result:
        plan, safe, blocking_findings = Plan(), False, []
        figures = {"spacing_violations": 4, "min_tip_spacing_mm": 0.5, "min_tip_spacing_time_ms": 10.0,
                   "capsule_violations": 0, "min_capsule_clearance_mm": 0.2}

    reason = _refusal(Result())
    assert reason and f"the {mode} schedule is unsafe" in reason and "below h_safe" in reason and "--force" in reason


# ---- item 9: tracebacks ----

@pytest.mark.parametrize("old, new, words", [
    ("# blades: 5", "# blades: inf", ["'blades'", "finite"]),
    ("# diameter_mm: 458.72", "# diameter_mm: 5e-324", ["'diameter_mm'"]),
    (ROW_05, "0.50," + "3" * 140_000 + ",1.020,0.07174,0.0260,-1.4,0.0", ["line 14", "characters"]),
    (ROW_05, "0.50,\"0.3\nx\",1.020,0.07174,0.0260,-1.4,0.0", ["line"]),
])
def test_table_values_that_raised_get_one_message(capsys, tmp_path, old, new, words):
    p = table(tmp_path, sample_with(old, new))
    refused(*cli(capsys, "blade", "info", "--json", "--blade", p)[::2], str(p), *words)


@pytest.mark.parametrize("edit, words", [
    (lambda d: {}, ["no \"inputs\""]),
    (lambda d: [1, 2], ["not an object"]),
    (lambda d: {**d, "inputs": {k: v for k, v in d["inputs"].items() if k != "h_safe"}}, ["inputs.h_safe", "missing"]),
    (lambda d: {**d, "inputs": {**d["inputs"], "feed": "fast"}}, ["inputs.feed", "\"fast\""]),
    (lambda d: {**d, "inputs": {**d["inputs"], "tool_radius": None}}, ["inputs.tool_radius"]),
    (lambda d: {**d, "inputs": {**d["inputs"], "blade_source": 3}}, ["inputs.blade_source"]),
])
def test_verify_on_a_broken_plan_json(capsys, tmp_path, plan_dir, edit, words):
    import shutil

    folder = tmp_path / "p"
    shutil.copytree(plan_dir, folder)
    data = json.loads((folder / "plan.json").read_text())
    (folder / "plan.json").write_text(json.dumps(edit(data)))
    refused(*cli(capsys, "verify", folder)[::2], "plan.json", *words)


@pytest.mark.parametrize("cell", ["nan", "inf", "-inf", "NaN"])
def test_verify_on_a_non_finite_cl_cell(capsys, tmp_path, plan_dir, cell):
    import shutil

    folder = tmp_path / "p"
    shutil.copytree(plan_dir, folder)
    lines = (folder / "right_cl.csv").read_text().splitlines()
    cells = lines[5].split(",")
    cells[6] = cell
    lines[5] = ",".join(cells)
    (folder / "right_cl.csv").write_text("\n".join(lines) + "\n")
    refused(*cli(capsys, "verify", folder)[::2], "right_cl.csv, line 6", "finite")


def test_verify_on_tables_without_rows(capsys, tmp_path, plan_dir):
    import shutil

    folder = tmp_path / "p"
    shutil.copytree(plan_dir, folder)
    for side in ("left", "right"):
        head = (folder / f"{side}_cl.csv").read_text().splitlines()[0]
        (folder / f"{side}_cl.csv").write_text(head + "\n")
    refused(*cli(capsys, "verify", folder)[::2], "no rows")


# ---- item 10: runaways are refused up front, with the numbers and what to change ----

def _slow_machine(tmp_path: Path) -> Path:
    p = tmp_path / "slow.toml"
    text = MACHINE.replace("max_speed_mm_s = 50.0", "max_speed_mm_s = 0.1").replace("max_speed_mm_s = 25.0",
                                                                                  "max_speed_mm_s = 0.1")
    p.write_text(text)
    return p


@pytest.mark.parametrize("args, words", [
    (["--dr", "0.05"], ["contour points", "budget", "raise --dr to at least"]),
    (["--dd", "1e-3"], ["contour points", "raise --dd to at least"]),
    (["--dr", "0.03", "--paths-only"], ["contour points", "--dr"]),
    (["--period-ms", "1e-3"], ["rows in the time column", "raise --period-ms to at least"]),
    (["--machine", "SLOW"], ["rows in the time column", "speed limits"]),
])
def test_runaways_refused_before_any_work(capsys, tmp_path, args, words):
    args = [str(_slow_machine(tmp_path)) if a == "SLOW" else a for a in args]
    out = tmp_path / "out"
    t0 = time.perf_counter()
    refused(*cli(capsys, "plan", "--workers", "1", *args, "--out", out)[::2], "too big to compute", *words)
    assert time.perf_counter() - t0 < 10 and not out.exists()


@pytest.mark.parametrize("old, new, words", [
    ("# diameter_mm: 458.72", "# diameter_mm: 1e9", ["'diameter_mm'", "millimetres"]),
    ("0.30,0.2648675", "0.2500001,0.2648675", ["'r/R'", "remove one"]),
])
def test_runaway_tables_refused_as_what_they_are(capsys, tmp_path, old, new, words):
    p = table(tmp_path, sample_with(old, new))
    refused(*cli(capsys, "plan", "--workers", "1", "--blade", p, "--out", tmp_path / "o")[::2], *words)


def test_a_big_but_possible_blade_is_refused_by_the_budget(capsys, tmp_path):
    p = table(tmp_path, sample_with("# diameter_mm: 458.72", "# diameter_mm: 11000"))
    code, _, err = cli(capsys, "plan", "--workers", "1", "--blade", p, "--out", tmp_path / "o")
    refused(code, err, "too big to compute", "blade is large")


def test_the_budget_leaves_the_defaults_a_wide_margin():
    from core.blade.extent import path_extent
    from core.blade.source import load_blade
    from core.budget import POINTS_BUDGET, ROWS_BUDGET, TIME_FACTOR, check_work
    from core.records import PlanJob, PlanParameters, default_period

    p = PlanParameters().resolved()
    ext = path_extent(load_blade("sample"), p.dr, p.dd)
    rows = TIME_FACTOR * ext.points * p.dd / (p.feed / 60000.0) / default_period(p)
    assert ext.points * 5 < POINTS_BUDGET and rows * 5 < ROWS_BUDGET
    check_work(load_blade("sample"), PlanJob())  # (no error)


# ---- item 11: silent nonsense: bounds of physical plausibility ----

@pytest.mark.parametrize("old, new, words", [
    (ROW_05, "0.50,0.3099494,1.020,100,0.0260,-1.4,0.0", ["'t0/c'", "thicker than it is long"]),
    (ROW_05, "0.50,0.3099494,1.020,1e308,0.0260,-1.4,0.0", ["'t0/c'"]),
    (ROW_05, "0.50,0.3099494,0,0.07174,0.0260,-1.4,0.0", ["'P/D'"]),
    (ROW_05, "0.50,0.3099494,-1.0,0.07174,0.0260,-1.4,0.0", ["'P/D'"]),
    ("0.0140,20.0,0.0", "0.0140,179.9,0.0", ["'skew_deg'"]),
    (ROW_05, "0.50,5e-324,1.020,0.07174,0.0260,-1.4,0.0", ["'c/D'", "no section"]),
    (ROW_05, "0.50,0.3099494,1.020,0.07174,0.6,-1.4,0.0", ["'f0/c'"]),
    (ROW_05, "0.50,0.3099494,1.020,0.07174,0.0260,-1.4,3", ["'rake/D'"]),
    ("# blades: 5", "# blades: 2.5", ["'blades'", "whole number", "'2.5'"]),
    ("# blades: 5", "# blades: 5\n# blades: 3", ["'blades' is given twice"]),
    ("# hub_ratio: 0.2", "# hub_ratio: 0.2\n# hub_ratio: 0.2", ["given twice"]),
    ("0.95,0.0374302", "0.999999998,0.0374302", ["'r/R'"]),
])
def test_impossible_geometry_is_refused(capsys, tmp_path, old, new, words):
    p = table(tmp_path, sample_with(old, new))
    refused(*cli(capsys, "blade", "info", "--json", "--blade", p)[::2], str(p), *words)


def test_a_span_of_nothing_is_refused(capsys, tmp_path):
    head = SAMPLE[:SAMPLE.index("r/R,")]
    rows = "r/R,c/D,P/D,t0/c,f0/c,skew_deg,rake/D\n0.9999,0.1,1,0.1,0.02,0,0\n0.99995,0.1,1,0.1,0.02,0,0\n" \
           "1.0,0,1,0.1,0.02,0,0\n"
    p = table(tmp_path, head.replace("# hub_ratio: 0.2", "# hub_ratio: 0.9999") + rows)
    refused(*cli(capsys, "blade", "info", "--blade", p)[::2], "spans")


def test_rows_that_make_the_splines_swing_are_refused(capsys, tmp_path):
    head = SAMPLE[:SAMPLE.index("r/R,")]
    skew = [0, 40, -40, 40, -40, 0]
    r = [0.2, 0.2005, 0.201, 0.2015, 0.5, 1.0]
    rows = "".join(f"{x},{0.2 if x < 1 else 0},1,0.1,0.02,{s},0\n" for x, s in zip(r, skew, strict=True))
    p = table(tmp_path, head + "r/R,c/D,P/D,t0/c,f0/c,skew_deg,rake/D\n" + rows)
    refused(*cli(capsys, "blade", "info", "--blade", p)[::2], "between the rows", "swing")


@pytest.mark.parametrize("old, new, words", [
    (ROW_05, "0.50,0.3099494,1.020,0.4,0.0260,-1.4,0.0", "'t0/c' = 0.4"),
    ("0.0140,20.0,0.0", "0.0140,80.0,0.0", "'skew_deg' = 80"),
    ("# blades: 5", "# blades: 30", "30 blades"),
    ("# diameter_mm: 458.72", "# diameter_mm: 15", "'diameter_mm' = 15"),
])
def test_odd_but_possible_geometry_is_warned_and_used(capsys, tmp_path, old, new, words):
    p = table(tmp_path, sample_with(old, new))
    code, out, err = cli(capsys, "blade", "info", "--json", "--blade", p)
    assert code == 0 and "Traceback" not in err, err
    assert any(ln.startswith("warning:") and words in ln for ln in err.splitlines()), err
    strict_json(out)


def test_a_mesh_whose_face_is_its_back_is_refused(capsys, meshes):
    refused(*cli(capsys, "blade", "info", "--blade", f"{meshes['face']},{meshes['face']}")[::2], "coincide")
    code, out, err = cli(capsys, "blade", "info", "--json", "--blade", f"{meshes['face']},{meshes['back']}")
    assert code == 0, err
    assert strict_json(out)["max_thickness_mm"]["0.5"] > 1


# ---- item 12: messages that say what is wrong ----

def test_a_byte_order_mark_is_accepted(capsys, tmp_path):
    p = tmp_path / "excel.csv"
    p.write_text(SAMPLE, encoding="utf-8-sig")
    code, out, err = cli(capsys, "blade", "info", "--json", "--blade", p)
    assert code == 0, err
    assert strict_json(out)["chord_mm"]["0.5"] == pytest.approx(142.18, rel=0.005)
    m = tmp_path / "machine.toml"
    m.write_text(MACHINE, encoding="utf-8-sig")
    from core.machine.model import load_machine

    assert load_machine(m).limits.x.max_speed_mm_s == 50.0


@pytest.mark.parametrize("suffix", [".csv", ".stl"])
@pytest.mark.parametrize("kind, words", [("folder", "a folder"), ("fifo", "FIFO"), ("loop", "symbolic link loop"),
                                         ("dangling", "broken symbolic link"), ("missing", "not found")])
def test_a_path_that_is_no_file_is_named_for_what_it_is(capsys, tmp_path, suffix, kind, words):
    p = tmp_path / f"blade{suffix}"
    if kind == "folder":
        p.mkdir()
    elif kind == "fifo":
        os.mkfifo(p)
    elif kind == "loop":
        p.symlink_to(p.name)
    elif kind == "dangling":
        p.symlink_to(tmp_path / "gone.csv")
    refused(*cli(capsys, "blade", "info", "--blade", p)[::2], str(p), words)
    if kind in ("fifo", "folder"):
        refused(*cli(capsys, "plan", *COARSE, "--machine", p, "--out", tmp_path / "o")[::2], words)


@pytest.mark.parametrize("args, words", [
    (["--feed", "1e-6"], ["feed = 1e-06 mm/min"]),
    (["--feed", "1e9"], ["feed"]),
    (["--h-safe", "1e-9"], ["h_safe = 1e-09"]),
    (["--period-ms", "-3"], ["--period-ms"]),
])
def test_a_bad_parameter_is_named_as_itself(capsys, tmp_path, args, words):
    line = refused(*cli(capsys, "plan", *COARSE, *args, "--out", tmp_path / "o")[::2], *words)
    assert ("a_max" not in line) and ("period" not in line or "--period-ms" in args)


def test_half_a_blade_is_not_reported_as_zero(capsys, tmp_path):
    p = table(tmp_path, sample_with("# blades: 5", "# blades: 0.5"))
    line = refused(*cli(capsys, "blade", "info", "--blade", p)[::2], "'0.5'")
    assert "got 0\n" not in line + "\n"


def test_a_far_vertex_is_named_not_the_axis(capsys, meshes):
    line = refused(*cli(capsys, "blade", "info", "--blade", f"{meshes['face']},{meshes['far']}")[::2], "vertex")
    assert "axis" not in line


def test_a_wrong_axis_suggests_the_one_that_fits(capsys, meshes):
    # the sample's surfaces are about z: the x axis passes through them
    line = refused(*cli(capsys, "blade", "info", "--blade", f"{meshes['face']},{meshes['back']}", "--axis", "x")[::2])
    assert "--axis z" in line


# ---- item 13: the new user's command line ----

def test_bare_command_prints_the_help(capsys):
    code, out, _ = cli(capsys)
    assert code == 0 and "usage: bladecam" in out and "plan" in out and "verify" in out
    code, out, _ = cli(capsys, "blade")
    assert code == 0 and "info" in out


@pytest.mark.parametrize("args", [["--help"], ["plan", "--help"], ["verify", "--help"], ["blade", "info", "--help"]])
def test_help_is_plain_text(capsys, args):
    code, out, _ = cli(capsys, *args)
    assert code == 0 and "``" not in out
    if args[0] == "verify":
        assert "DIR" in out and "plan folder" in out.split("DIR", 2)[-1]


@pytest.mark.parametrize("args, hint", [
    (["plan", "--fead", "3", "--out", "x"], "--feed"),
    (["plan", "--period_ms", "3", "--out", "x"], "--period-ms"),
    (["blade", "info", "--jsn"], "--json"),
    (["verfy", "x"], "verify"),
])
def test_a_misspelt_option_suggests_the_right_one(capsys, args, hint):
    refused(*cli(capsys, *args)[::2], "did you mean", hint)


@pytest.mark.parametrize("n", ["0", "-1", "two", "100000"])
def test_workers_must_be_a_sane_count(capsys, tmp_path, n):
    refused(*cli(capsys, "plan", "--workers", n, "--out", tmp_path / "o")[::2], "--workers")


# ---- the fuzz test: tables, meshes, machine files and parameters ----

def _clean(code: int, out: str, err: str, folder: Path | None = None) -> None:
    """exit 0 with a finite output, or exit 2 with one clear message; never a traceback."""
    assert "Traceback" not in err, err
    if code == 2:
        refused(code, err)
        return
    assert code == 0, err
    if out.lstrip().startswith("{"):
        strict_json(out)
    if folder is not None:
        strict_json((folder / "plan.json").read_text())


NUMBERS = st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                    st.sampled_from([0.0, -0.0, 1e-9, 5e-324, 1e308, -1.0, 0.5, 2.5, 1e9, 179.9, 100.0]),
                    st.floats(-2, 2))
CELLS = st.one_of(NUMBERS.map(repr), st.sampled_from(["", "x", "1,2", "\ufeff1", "0x10", "1e", "  "]))
def fuzz(n: int):
    """Hypothesis settings of a fuzz test: n examples (derandomised by tests/conftest.py's profile), no
    deadline (a plan's time varies with the machine's load). The fuzz tests that plan have a _fast
    variant with fewer examples in make test; their full runs are marked slow."""
    return settings(max_examples=n, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@fuzz(300)
@given(edits=st.lists(st.tuples(st.integers(0, 11), st.integers(0, 6), CELLS), max_size=3),
       meta=st.lists(st.tuples(st.sampled_from(["blades", "diameter_mm", "hub_ratio", "meanline", "thickness"]),
                               CELLS), max_size=2),
       drop=st.sets(st.integers(0, 11), max_size=9))
def test_fuzz_geometry_tables(capsys, tmp_path_factory, edits, meta, drop):
    lines = SAMPLE.splitlines()
    first = lines.index("r/R,c/D,P/D,t0/c,f0/c,skew_deg,rake/D") + 1
    rows = [ln.split(",") for ln in lines[first:]]
    for i, j, v in edits:
        rows[i][j] = v
    body = [",".join(r) for k, r in enumerate(rows) if k not in drop]
    head = lines[:first]
    for key, v in meta:
        head = [f"# {key}: {v}" if ln.startswith(f"# {key}:") else ln for ln in head]
    p = tmp_path_factory.mktemp("fuzz") / "t.csv"
    p.write_text("\n".join(head + body) + "\n")
    _clean(*cli(capsys, "blade", "info", "--json", "--blade", p))


@fuzz(100)
@given(vertex=st.tuples(NUMBERS, NUMBERS, NUMBERS), k=st.integers(0, 40), axis=st.sampled_from("xyz"),
       swap=st.booleans())
def test_fuzz_meshes(capsys, meshes, tmp_path_factory, vertex, k, axis, swap):
    lines = meshes["back"].read_text().splitlines()
    at = [i for i, ln in enumerate(lines) if ln.strip().startswith("vertex")][k]
    lines[at] = "vertex " + " ".join(repr(float(c)) for c in vertex)
    p = tmp_path_factory.mktemp("fuzz") / "m.stl"
    p.write_text("\n".join(lines) + "\n")
    pair = [str(meshes["face"]), str(p)][::-1 if swap else 1]
    _clean(*cli(capsys, "blade", "info", "--json", "--blade", ",".join(pair), "--axis", axis))


MACHINE_KEYS = ["base_radius_mm", "platform_radius_mm", "home_height_mm", "gauge_length_mm", "max_tilt_deg",
                "min_mm", "max_mm", "max_speed_mm_s", "max_accel_mm_s2", "origin_mm"]


MACHINE_VALUES = st.one_of(NUMBERS.map(repr), st.sampled_from(["\"x\"", "[1, 2]", "true", "9" * 400]))
MACHINE_EDITS = st.lists(st.tuples(st.sampled_from(MACHINE_KEYS), st.integers(0, 5), MACHINE_VALUES), max_size=2)


@pytest.mark.slow
@fuzz(40)
@given(edits=MACHINE_EDITS)
def test_fuzz_machine_files(capsys, tmp_path_factory, edits):
    _plan_with_machine_edits(capsys, tmp_path_factory, edits)


@fuzz(8)
@given(edits=MACHINE_EDITS)
def test_fuzz_machine_files_fast(capsys, tmp_path_factory, edits):
    """The fuzz test above on fewer machine files, a whole plan each (make test; the full one is slow)."""
    _plan_with_machine_edits(capsys, tmp_path_factory, edits)


def _plan_with_machine_edits(capsys, tmp_path_factory, edits) -> None:
    lines = MACHINE.splitlines()
    for key, nth, value in edits:
        hits = [i for i, ln in enumerate(lines) if ln.startswith(f"{key} =")]
        i = hits[nth % len(hits)]
        lines[i] = f"{key} = {value}"
    d = tmp_path_factory.mktemp("fuzz")
    (d / "m.toml").write_text("\n".join(lines) + "\n")
    out = d / "o"
    code, o, err = cli(capsys, "plan", "--dr", "12", "--workers", "1", "--machine", d / "m.toml", "--force",
                       "--out", out)
    _clean(code, o, err, out if code == 0 else None)


PARAMS = ("--tool-radius", "--dr", "--dd", "--h-safe", "--k-max", "--feed", "--a-max", "--period-ms")
PARAM_VALUES = st.dictionaries(st.sampled_from(PARAMS), NUMBERS, max_size=3)
MODES = st.sampled_from(["collaborative", "symmetric", "single"])


@pytest.mark.slow
@fuzz(150)
@given(values=PARAM_VALUES, mode=MODES, whole=st.booleans())
def test_fuzz_plan_parameters(capsys, tmp_path_factory, values, mode, whole):
    _plan_with_parameters(capsys, tmp_path_factory, values, mode, whole)


@fuzz(40)
@given(values=PARAM_VALUES, mode=MODES, whole=st.booleans())
def test_fuzz_plan_parameters_fast(capsys, tmp_path_factory, values, mode, whole):
    """The fuzz test above on fewer parameter sets (make test; the full one is marked slow)."""
    _plan_with_parameters(capsys, tmp_path_factory, values, mode, whole)


def _plan_with_parameters(capsys, tmp_path_factory, values, mode, whole) -> None:
    values.setdefault("--dr", 8.0)
    if isinstance(values["--dr"], float) and math.isfinite(values["--dr"]) and 0 < values["--dr"] < 4:
        values["--dr"] = 4.0 + values["--dr"]  # (coarse: each plan well under a second)
    args = [a for k, v in values.items() for a in (k, repr(v))]
    out = tmp_path_factory.mktemp("fuzz") / "o"
    stop = ["--no-axes"] if whole else ["--paths-only"]
    code, o, err = cli(capsys, "plan", "--workers", "1", *stop, "--mode", mode, *args, "--out", out)
    _clean(code, o, err, out if code == 0 else None)
